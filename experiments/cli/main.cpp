// meltlab: command-line entry point. Each subcommand lives in its own file and only parses
// options and calls library functions.

#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>
#include <meltlab/version.h>

#include <fmt/format.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <map>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"

int main(int argc, char** argv) {
  using namespace meltlab;
  const std::vector<std::string> command_line(argv, argv + argc);

  CLI::App app{"meltlab: verification and validation of melting and sublimation visualization"};
  app.set_version_flag("--version", fmt::format("meltlab {} ({})", kVersion, kGitRevision));
  app.require_subcommand(1);
  // Resource limits on inputs (core/limits.h): given before or after the subcommand.
  std::string limits_text;
  app.add_option("--limits", limits_text,
                 fmt::format("Input limits name=value,... (defaults: {}; env MELTLAB_LIMITS)",
                             describe_input_limits(InputLimits{})))
      ->type_name("LIST");
  app.fallthrough();
  std::map<CLI::App*, cli::Run> runs;
  auto add = [&](cli::Run run) { runs[app.get_subcommands({}).back()] = std::move(run); };
  add(cli::add_simulate(app, command_line));
  add(cli::add_mesh_info(app));
  add(cli::add_dataset(app));
  add(cli::add_compare(app, command_line));
  add(cli::add_synth_sequence(app, command_line));
  add(cli::add_fit(app, command_line));
  add(cli::add_manufacture(app, command_line));
  add(cli::add_predict(app, command_line));
  add(cli::add_render(app, command_line));
  add(cli::add_reproduce(app));
  add(cli::add_volume(app, command_line));
  add(cli::add_fog(app, command_line));
  add(cli::add_sweep(app, command_line));
  add(cli::add_run_job(app, command_line));

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "meltlab: %s\n", e.what());
    return kExitBadInput;
  }
  try {
    if (!limits_text.empty()) set_input_limits(parse_input_limits(limits_text, input_limits(), "--limits"));
    for (auto& [sub, run] : runs)
      if (sub->parsed()) return run();
  } catch (const InputError& e) {
    std::fprintf(stderr, "meltlab: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::filesystem::filesystem_error& e) {
    // A file-system refusal on an input or output (a name too long, no permission, no space, a
    // file where a folder should be) is a problem of the input, not of meltlab.
    const std::string path = e.path1().empty() ? std::string() : e.path1().string() + ": ";
    std::fprintf(stderr, "meltlab: %s%s\n", path.c_str(), e.code().message().c_str());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "meltlab: out of memory (an input larger than this machine can hold? see --limits)\n");
    return kExitBadInput;
  } catch (const InvariantError& e) {
    std::fprintf(stderr, "meltlab: internal error: %s\n", e.what());
    return kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "meltlab: %s\n", e.what());
    return kExitInternal;
  }
  return kExitBadInput;
}

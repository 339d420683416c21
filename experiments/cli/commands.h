#pragma once
// Every subcommand registers itself on the app and returns the function that runs it.

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace meltlab::cli {

using Run = std::function<int()>;

Run add_simulate(CLI::App& app, const std::vector<std::string>& command_line);
Run add_mesh_info(CLI::App& app);
Run add_dataset(CLI::App& app);
Run add_compare(CLI::App& app, const std::vector<std::string>& command_line);
Run add_synth_sequence(CLI::App& app, const std::vector<std::string>& command_line);
Run add_fit(CLI::App& app, const std::vector<std::string>& command_line);
Run add_manufacture(CLI::App& app, const std::vector<std::string>& command_line);
Run add_predict(CLI::App& app, const std::vector<std::string>& command_line);
Run add_render(CLI::App& app, const std::vector<std::string>& command_line);
Run add_reproduce(CLI::App& app);

}  // namespace meltlab::cli

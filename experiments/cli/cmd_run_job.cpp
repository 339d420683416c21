// meltlab run-job: one step of a Slurm job written by `reproduce --executor slurm` or `sweep
// --executor slurm` (internal; the batch scripts call it, users do not).

#include <meltlab/experiments/reproduce.h>

#include "commands.h"

namespace meltlab::cli {

Run add_run_job(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand("run-job", "Internal: run one step of a Slurm job (written by reproduce/sweep)");
  sub->group("");  // not listed in --help: the batch scripts call it
  auto plan = std::make_shared<std::string>();
  auto job = std::make_shared<std::size_t>(0);
  sub->add_option("--plan", *plan, "The plan (OUT/<experiment>/slurm/plan.json)")->required();
  sub->add_option("--job", *job, "The job's index in the plan (array tasks: SLURM_ARRAY_TASK_ID picks the step)")
      ->required();
  return [=]() { return experiments::run_slurm_job(*plan, *job, command_line); };
}

}  // namespace meltlab::cli

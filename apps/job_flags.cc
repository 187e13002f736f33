#include "apps/job_flags.h"

namespace occgt {

void AddRootFlag(CLI::App* cmd, std::string* root) {
  cmd->add_option(
      "--root", *root,
      "Dataset root overriding the recipe's dataset.root (relative to the working folder)");
}

TaskFlags AddTaskFlags(CLI::App* cmd, int* task, int* tasks) {
  TaskFlags flags;
  flags.task = cmd->add_option(
      "--task", *task,
      "This task's index (0-based) when split in --tasks (default: from SLURM_ARRAY_TASK_ID)");
  flags.tasks = cmd->add_option(
      "--tasks", *tasks,
      "Number of tasks the run is split into (default: SLURM_ARRAY_TASK_COUNT, else 1)");
  return flags;
}

void AddDepthCacheFlag(CLI::App* cmd, size_t* depth_cache_mb) {
  cmd->add_option("--depth-cache-mb", *depth_cache_mb,
                  "Budget of decoded depth maps held per scene (LRU, default " +
                      std::to_string(*depth_cache_mb) + ")");
}

}  // namespace occgt

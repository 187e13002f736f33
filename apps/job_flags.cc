#include "apps/job_flags.h"

#include "apps/usage.h"
#include "libgt/core/error.h"

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

void TaskFlags::Check(int tasks_value) const {
  if (tasks->count() > 0 && task->count() == 0 && tasks_value > 1) {
    throw gt::InputError("--tasks", std::to_string(tasks_value) + " needs --task K (0 <= K < " +
                                        std::to_string(tasks_value) +
                                        "): alone it would run task 0 in every task");
  }
}

gt::datasets::ScanNetPPDevice DeviceFlag::Resolve(gt::DatasetFormat format) const {
  const gt::datasets::ScanNetPPDevice device = gt::datasets::ParseScanNetPPDevice(name, "--device");
  if (option != nullptr && option->count() > 0 && format != gt::DatasetFormat::kScanNetPP) {
    throw gt::InputError("--device", "only for the scannetpp format");
  }
  return device;
}

void AddDeviceFlag(CLI::App* cmd, DeviceFlag* flag) {
  flag->option = cmd->add_option("--device", flag->name, "ScanNet++'s camera: dslr or iphone")
                     ->capture_default_str();
}

void AddDepthCacheFlag(CLI::App* cmd, size_t* depth_cache_mb) {
  AtLeast(cmd->add_option("--depth-cache-mb", *depth_cache_mb,
                          "Budget of decoded depth maps held per scene (LRU, default " +
                              std::to_string(*depth_cache_mb) + ")"),
          1);
}

void AddThreadsFlag(CLI::App* cmd, int* threads, const std::string& what) {
  cmd->add_option("--threads", *threads, what + " (0 = all cores)");
}

std::unique_ptr<tbb::global_control> LimitThreads(int threads) {
  if (threads < 0) {
    throw gt::InputError("--threads", "expected an integer >= 0 (0 = all cores), got '" +
                                          std::to_string(threads) + "'");
  }
  if (threads == 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               threads);
}

}  // namespace occgt

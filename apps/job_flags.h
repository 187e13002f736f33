// Flags shared by the dataset jobs `occgt build`, `occgt covis` and `occgt tuples`: the
// dataset root override, the task of a split (--task/--tasks, else a Slurm array's) and the
// per-scene depth cache budget; --threads of every command with worker threads (build,
// covis, tuples, eval, merge, validate); --device of the commands that read a dataset given
// by --root/--format (scan, render). Help texts take their defaults from the options
// structs.
#pragma once

#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <cstddef>
#include <memory>
#include <string>

#include "libgt/core/frame.h"
#include "libgt/datasets/reader.h"

namespace occgt {

// --device: ScanNet++'s camera (dslr, the default, or iphone).
struct DeviceFlag {
  std::string name = "dslr";
  CLI::Option* option = nullptr;  // set by AddDeviceFlag
  // The device to read `format` with: InputError("--device", ...) for a name other than
  // dslr and iphone, or for the flag on the command line with a format other than scannetpp.
  gt::datasets::ScanNetPPDevice Resolve(gt::DatasetFormat format) const;
};
void AddDeviceFlag(CLI::App* cmd, DeviceFlag* flag);

// --root: the dataset root overriding the recipe's dataset.root.
void AddRootFlag(CLI::App* cmd, std::string* root);

// --task and --tasks into *task / *tasks.
struct TaskFlags {
  CLI::Option* task = nullptr;
  CLI::Option* tasks = nullptr;
  // Either flag on the command line (then Slurm's environment is ignored).
  bool Given() const { return task->count() > 0 || tasks->count() > 0; }
  // --tasks N > 1 without --task would run task 0 in every task of an array (Slurm's
  // variables are ignored once a task flag is given): InputError("--tasks", ...), a usage
  // error. `--tasks 1` alone (one task, whatever the environment) is fine.
  void Check(int tasks_value) const;
};
TaskFlags AddTaskFlags(CLI::App* cmd, int* task, int* tasks);

// --depth-cache-mb into *depth_cache_mb, whose value when the flag is added is the default
// shown in the help text.
void AddDepthCacheFlag(CLI::App* cmd, size_t* depth_cache_mb);

// --threads into *threads: `what` runs on that many threads, 0 = all cores (the default).
void AddThreadsFlag(CLI::App* cmd, int* threads, const std::string& what);
// The TBB limit --threads asks for, held while the command runs: nullptr for 0 (all cores);
// InputError("--threads", ...) below 0.
std::unique_ptr<tbb::global_control> LimitThreads(int threads);

}  // namespace occgt

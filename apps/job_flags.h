// Flags shared by the dataset jobs `occgt build`, `occgt covis` and `occgt tuples`: the
// dataset root override, the task of a split (--task/--tasks, else a Slurm array's) and the
// per-scene depth cache budget. Help texts take their defaults from the options structs.
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <string>

namespace occgt {

// --root: the dataset root overriding the recipe's dataset.root.
void AddRootFlag(CLI::App* cmd, std::string* root);

// --task and --tasks into *task / *tasks.
struct TaskFlags {
  CLI::Option* task = nullptr;
  CLI::Option* tasks = nullptr;
  // Either flag on the command line (then Slurm's environment is ignored).
  bool Given() const { return task->count() > 0 || tasks->count() > 0; }
};
TaskFlags AddTaskFlags(CLI::App* cmd, int* task, int* tasks);

// --depth-cache-mb into *depth_cache_mb, whose value when the flag is added is the default
// shown in the help text.
void AddDepthCacheFlag(CLI::App* cmd, size_t* depth_cache_mb);

}  // namespace occgt

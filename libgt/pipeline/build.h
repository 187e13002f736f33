// The `occgt build` job: recipe → per-scene pair selection → samples → shards → indices →
// summary (docs/USER_GUIDE.md; SCALE.md for the many-machine layout). It composes the
// layers below it: the select stage (select.h, over libgt/pairs), the write stage
// (write.h: truth::ComputePairTruth per sample, libgt/shards writer, merge, LoFTR export).
//
// Files under the output folder DIR:
//   DIR/recipe.json        the normalised recipe; a re-run with a recipe of another options
//                          digest into the same DIR is refused
//   DIR/selection/...      stage select (select.h); task k of N takes the sorted scenes i
//                          with i % N == k
//   DIR/parts/, shards     stage write (write.h); task k of N writes the shards s with
//                          s % N == k that are not complete yet
//   DIR/index.json, DIR/pairs.jsonl, DIR/loftr/   when every shard is complete
//   DIR/summary.json       the summary of the run that completed the split
// So any task layout gives the same files. Threads: TBB inside a scene (frame scan,
// scoring) and across samples; results are stored by index and written in order, so
// outputs never depend on the thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "libgt/io/folder_lock.h"
#include "libgt/pairs/selection.h"
#include "libgt/pipeline/recipe.h"

namespace gt::pipeline {

enum class Stage { kSelect, kWrite, kAll };  // "select" | "write" | "all"
Stage ParseStage(const std::string& text, const std::string& field);
const char* StageName(Stage stage);

struct BuildOptions {
  std::string out_dir;        // DIR
  int task = 0;               // this task's index, 0 <= task < tasks
  int tasks = 1;              // number of tasks the run is split into
  Stage stage = Stage::kAll;  // which stages run
  bool dry_run = false;       // select in memory, print the plan, write nothing
  size_t depth_cache_mb = pairs::kDefaultDepthCacheMb;  // per-scene LRU of decoded depth maps

  bool Check(std::string* error) const;
};

// One progress report: `done` of `total` units of `stage`: scenes for select, pairs
// (samples, reported after each shard) for write.
struct Progress {
  Stage stage = Stage::kSelect;
  int64_t done = 0;
  int64_t total = 0;
  double elapsed_s = 0;  // since the stage started
  // Of `done`, the units found complete (a resumed run's stored selections and shards):
  // they took no time, so a rate is (done - resumed) / elapsed_s.
  int64_t resumed = 0;
};
using ProgressFn = std::function<void(const Progress&)>;

// Runs the stages the options ask for and returns the summary (schemas/summary.schema.json;
// also written to DIR/summary.json when the split is complete, not in a dry run). Throws
// InputError for bad input (before any work where it can be detected up front).
nlohmann::json RunBuild(const Recipe& recipe, const BuildOptions& options,
                        const ProgressFn& progress);

// Estimated bytes of one sample under the recipe (for shards.target_mb): label maps, cell
// maps, occupancy, images (PNG ~ 2 bytes/pixel, JPG ~ 0.3), depth, ~64 kB of matches. With
// sample.compression: deflate the arrays count at the gzip ratios of the real samples
// (docs/PERFORMANCE.md "Sample compression"), rounded up: labels, cells and occupancy 0.06,
// depth DeflatedDepthShare, matches 0.9.
int64_t EstimatedSampleBytes(const Recipe& recipe);
// The share of a depth map's bytes left by deflate: 0.2 for sensor depth (whole millimetres
// as float32: 0.16-0.66 measured on the real samples), 0.8 for occgt's synthetic depth
// (exact ray-cast distances, whose low mantissa bits do not compress: 0.7-0.78 measured).
double DeflatedDepthShare(const Recipe& recipe);

// "" when 0 <= task < tasks and tasks >= 1, else the problem naming --task or --tasks (the
// task split of occgt build and occgt covis).
std::string TaskRangeError(int task, int tasks);

// One process per command, task and output folder: byte `task` of DIR/<lock_file> (an fcntl
// record lock, io::FileLock), held until the returned object is destroyed or the process
// ends. `occgt build` holds DIR/.tasks.lock, `occgt covis` DIR/.covis.lock, `occgt tuples`
// DIR/.tuples.lock (task 0): they write different files and may run together; a second run of
// one command and task into one DIR is refused with InputError(DIR, "another occgt <command>
// of task K (when tasks > 1) is writing this folder now (it holds byte K of <lock>); wait for it to
// finish, or <advice>"). Creates DIR when missing.
std::unique_ptr<io::FileLock> AcquireTaskLock(const std::string& out_dir,
                                              const std::string& lock_file,
                                              const std::string& command, int task, int tasks,
                                              const std::string& advice);

}  // namespace gt::pipeline

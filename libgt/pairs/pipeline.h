// The `occgt build` job: recipe → per-scene pair selection → samples → shards → indices →
// summary (docs/USER_GUIDE.md; SCALE.md for the many-machine layout).
//
// Stages and files under the output folder DIR:
//   DIR/recipe.json                  the normalised recipe; a re-run with a recipe of another
//                                    options digest into the same DIR is refused
//   phase 1 "select" (per scene; task k of N takes sorted scenes i with i % N == k):
//   DIR/selection/<scene>.jsonl      selected pairs in selection order, one JSON object each
//                                    {scene, frame0, frame1, number0, number1, score_metrics}
//   DIR/selection/<scene>.json       per-scene counts and drops; written last, it is the
//                                    scene's completion marker (a re-run skips the scene)
//   (<scene> is the scene name with every byte outside [A-Za-z0-9_-] replaced by '_'
//    and '/' by "__"; two scenes with the same file name are an error.)
//   phase 2 "write" (needs every scene's selection): the global list (scenes sorted, pairs in
//   selection order) is cut into shards of samples_per_shard consecutive samples; task k of
//   N writes the shards s with s % N == k that are not complete yet, through ShardOutput.
//   So any task layout gives the same files.
//   indices: when every shard is complete, ShardOutput::Finish writes index.json and
//   pairs.jsonl; with loftr_export the LoFTR-family index goes to DIR/loftr/.
//   DIR/summary.json                 BuildSummary of the run that completed the split.
//
// Threads: TBB inside a scene (frame scan, scoring) and inside a shard (samples); results
// are stored by index and written in order, so outputs never depend on the thread count.
// A shard is written on a writer thread while the next shard's samples are computed (at
// most one write in flight; its error is rethrown before the next write starts).
// The write stage depends on libgt/shards, which sits above this layer: it is reached only
// through the ShardOutput interface (apps/cmd_build.cc implements it with libgt/shards).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libgt/pairs/pair_sample.h"
#include "libgt/pairs/recipe.h"

namespace gt::pairs {

struct BuildOptions {
  std::string out_dir;          // DIR
  int task = 0;                 // this task's index, 0 <= task < tasks
  int tasks = 1;                // number of tasks the run is split into
  std::string stage = "all";    // select | write | all
  bool dry_run = false;         // select in memory, print the plan, write nothing
  size_t depth_cache_mb = 512;  // per-scene LRU of decoded depth maps

  bool Check(std::string* error) const;
};

// One pair of the LoFTR-family export (libgt/shards/loftr_export.h LoftrPair).
struct LoftrRow {
  std::string scene;
  int64_t frame0 = 0, frame1 = 0;           // frame numbers
  double score = 0;                         // aggregated overlap at score_stride
  std::array<double, 12> cam1_from_cam0{};  // T_0to1 row-major 3x4
};

// A shard being written sample by sample (ShardOutput::OpenShard): Add the samples in
// order, then Finish publishes the shard atomically with its completion record and returns
// its size in bytes. Destroyed without Finish (an error), it publishes nothing.
class ShardStream {
 public:
  virtual ~ShardStream() = default;
  // `last`: the shard's final sample (Finish follows). A stream may then leave work on the
  // sample's bytes (their digest) to Finish, where it overlaps the fsync's wait.
  virtual void Add(EncodedSample sample, bool last) = 0;
  virtual int64_t Finish() = 0;
};

// Where samples go. Implemented above this layer (apps/cmd_build.cc with libgt/shards).
class ShardOutput {
 public:
  virtual ~ShardOutput() = default;
  // The sample key of a pair ("<scene>/<frame0>_<frame1>", sanitised); throws InputError.
  virtual std::string SampleKey(const std::string& scene, const std::string& frame0,
                                const std::string& frame1) const = 0;
  // Publishes the split plan (shard sizes) once; refuses a different existing plan.
  virtual void WritePlan(const std::vector<int64_t>& shard_nsamples) = 0;
  virtual bool IsShardComplete(int64_t shard) const = 0;
  // Writes shard `shard` atomically with its completion record; returns its size in bytes.
  // Called (through the default OpenShard's Finish) on a writer thread, one call at a
  // time, while RunBuild goes on computing: it may run concurrently with OpenShard and Add
  // of the next shard's stream (IsShardComplete is called before the write pipeline), so
  // these must not share unsynchronised state.
  virtual int64_t WriteShard(int64_t shard, const std::vector<EncodedSample>& samples) = 0;
  // The same as a stream, which the build uses: each sample is written as soon as it is
  // computed, so only the last one and the publication are left when a shard completes.
  // The stream of shard s + 1 may be filled while shard s's Finish runs on another thread.
  // The default collects the samples and calls WriteShard from Finish.
  virtual std::unique_ptr<ShardStream> OpenShard(int64_t shard);
  // Every shard is complete: validates them and writes index.json and pairs.jsonl.
  virtual void Finish() = 0;
  // LoFTR-family index ("train" or "test") of every pair, K per scene at W×H. Called
  // concurrently with Finish (another thread): the two must not share unsynchronised state.
  virtual void ExportLoftr(const std::string& kind, const std::vector<LoftrRow>& rows,
                           const std::map<std::string, std::array<double, 9>>& intrinsics) = 0;
};

// One progress report: `done` of `total` units of `stage`: scenes for "select", pairs
// (samples, reported after each shard) for "write".
struct Progress {
  std::string stage;
  int64_t done = 0;
  int64_t total = 0;
  double elapsed_s = 0;  // since the stage started
};
using ProgressFn = std::function<void(const Progress&)>;

// Scene file name under DIR/selection (see above).
std::string SceneFileName(const std::string& scene);

// Runs the stages the options ask for and returns the summary (also written to
// DIR/summary.json when the split is complete, not in a dry run). Throws InputError for bad
// input (before any work where it can be detected up front).
nlohmann::json RunBuild(const Recipe& recipe, const BuildOptions& options, ShardOutput* output,
                        const ProgressFn& progress);

// Estimated bytes of one sample under the recipe (for shards.target_mb): label maps, cell
// maps, occupancy, images (PNG ~ 2 bytes/pixel, JPG ~ 0.3), depth, ~64 matches bytes.
int64_t EstimatedSampleBytes(const Recipe& recipe);

}  // namespace gt::pairs

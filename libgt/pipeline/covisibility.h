// The covisibility graph of each scene of a recipe (`occgt covis`, docs/MULTIVIEW.md): every
// frame pair that passes the recipe's pruning (selection.pruning: frustum intersection,
// camera distance, view angle; every pair of kept frames is a candidate, no frame-gap
// limit) scored in both directions by the pair scorer of the select stage
// (pairs::ScorePairs at selection.score_stride, labels resolved as the build resolves them).
//
// Files under the output folder DIR (docs/FORMATS.md "Covisibility graph"):
//   DIR/covisibility/<scene>.npz   sparse graph, one row per scored pair (i < j):
//       frame_ids  <U  [F]     ids of the kept frames (scene order); i, j index them
//       i, j       int32 [P]   the pair, i < j, in increasing (i, j)
//       c_ij, c_ji float32 [P] consistent_overlap (VISIBLE / sampled) of i → j and j → i
//       o_ij, o_ji float32 [P] overlap ((VISIBLE + OCCLUDED + INCONSISTENT + UNKNOWN) / valid)
//       self       float32 [F] consistent_overlap of each frame against itself (the diagonal)
//       score_stride int32 [], options_digest uint8 [32] (CovisibilityDigest, hex)
//     written last (temporary name, then rename): its presence completes the scene, and a
//     re-run skips it (a file of another recipe digest is refused).
//   DIR/covisibility/<scene>/pairwise_covisibility--FxF.npy   with dense: float32 [F, F],
//       C[i, j] = c_ij (row = source frame: the fraction of frame i's sampled pixels VISIBLE in
//       frame j, denominator the whole sampled grid, MapAnything's `denominator_mode: full`),
//       C[i, i] = self, 0 for pruned pairs.
// Tasks: task k of N takes the sorted scenes s with s % N == k (like the select stage), so
// any task layout gives the same files; a run holds byte k of DIR/.covis.lock
// (AcquireTaskLock, build.h): a second run of task k into DIR is refused while it runs; threads
// only inside a scene (ScorePairs), results stored by pair index: the bytes never depend on the
// thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libgt/datasets/reader.h"
#include "libgt/pairs/selection.h"
#include "libgt/pipeline/recipe.h"

namespace gt::pipeline {

struct SceneCovisibility {
  std::string scene;
  std::vector<std::string> frame_ids;  // kept frames in scene order
  std::vector<int32_t> i, j;           // scored pairs, i < j, increasing
  std::vector<float> c_ij, c_ji, o_ij, o_ji;
  std::vector<float> self;  // [F]
  int score_stride = 8;
  int64_t candidates = 0;   // pairs of kept frames before pruning
  pairs::DropCounts drops;  // scan.*, prune.*, score.*
};

// The graph of one scene under the recipe (its pruning, score stride, labels, frame stride,
// minimum valid depth fraction, working resolution).
SceneCovisibility ComputeSceneCovisibility(const Recipe& recipe, const Scene& scene,
                                           pairs::DepthCache* cache);

// md5 (hex) of the recipe options a graph depends on: resolution, dataset (its format,
// frame stride, minimum valid depth fraction, depth range; not its root or scene list),
// labels, selection.pruning, selection.score_stride and whether sample.image stores images
// (frames without colour are then not kept). A graph of another digest is refused.
std::string CovisibilityDigest(const Recipe& recipe);

// A scene's graph as `occgt covis` wrote it (the members above; candidates and drops are not
// stored); an InputError naming the file when it is missing, of another options digest, or
// malformed (a member of another dtype or number of dimensions, a score_stride other than
// `score_stride`, the recipe's, pairs or scores out of range).
SceneCovisibility ReadSceneCovisibility(const std::string& path, const std::string& digest,
                                        int score_stride);

// Checks a graph read by ReadSceneCovisibility against `scene` as the recipe's dataset has it
// now (the digest leaves out the dataset root, so a graph of other data under the same scene
// name, or of data changed since, gets here): its frame_ids must be the frames the recipe's
// scan (ScanRecipeFrames) keeps now, in scene order. Each id is a frame of the scene, usable,
// at a multiple of dataset.frame_stride, with colour when sample.image stores images, after
// the one before it; and no frame the graph lacks is kept now (only those frames' depth is
// decoded, through a cache of `depth_cache_mb`: the frames the graph holds are not scanned
// again). Otherwise an InputError naming `path` and the first differing frame, ending in what
// to do (delete the graph, re-run occgt covis). `occgt covis` (a complete scene) and
// `occgt tuples` both call it.
void CheckGraphFrames(const Recipe& recipe, const Scene& scene, const SceneCovisibility& graph,
                      const std::string& path, size_t depth_cache_mb);

// With CheckGraphFrames passed: each graph frame `frames` indexes (into graph.frame_ids) must
// still pass the recipe's scan (ScanRecipeFrames: its depth readable, with
// dataset.min_valid_depth_fraction valid pixels in the labels' depth range), which
// CheckGraphFrames does not decode again. `occgt tuples --shards` calls it with the views of
// its tuples before it writes anything. InputError naming `path` and the first such frame in
// graph order.
void CheckGraphFramesDepth(const Recipe& recipe, const Scene& scene, const SceneCovisibility& graph,
                           const std::vector<int32_t>& frames, const std::string& path,
                           size_t depth_cache_mb);

// The dense F×F matrix of a graph (the layout above).
std::vector<float> DenseCovisibility(const SceneCovisibility& graph);

struct CovisibilityOptions {
  std::string out_dir;                                  // DIR
  int task = 0, tasks = 1;                              // this task of the split, 0 <= task < tasks
  bool dense = false;                                   // also write pairwise_covisibility--FxF.npy
  size_t depth_cache_mb = pairs::kDefaultDepthCacheMb;  // per-scene LRU of decoded depth maps

  bool Check(std::string* error) const;
};

// What `occgt covis` and `occgt tuples` start from: the recipe with a synthetic dataset read
// as `generic` from DIR/data (unless dataset.root is set), generated there first when
// `generate` (once per folder, under DIR/.lock, as the build), the CovisibilityDigest of the
// recipe as given, its reader and its scenes in order.
struct SceneLoop {
  Recipe recipe;
  std::string digest;
  std::unique_ptr<datasets::DatasetReader> reader;
  std::vector<std::string> scenes;
};
SceneLoop StartSceneLoop(const Recipe& recipe, const std::string& out_dir, bool generate);

// Path of a scene's graph under DIR.
std::string CovisibilityPath(const std::string& out_dir, const std::string& scene);
void WriteSceneCovisibility(const std::string& path, const SceneCovisibility& graph,
                            const std::string& options_digest);

// Every scene of this task without a complete graph, in order; returns a summary
// {scenes, scenes_this_task, written, skipped_complete, pairs_scored, candidates, drops,
// seconds}. progress(done, total) after each scene.
nlohmann::json RunCovisibility(const Recipe& recipe, const CovisibilityOptions& options,
                               const std::function<void(int64_t, int64_t)>& progress);

}  // namespace gt::pipeline

// Pair selection within one scene (GROUND_TRUTH.md §6): frame scan → candidates → cheap
// pruning → scoring both directions → filters → seeded sampling.
//
// Every step is a plain function over indices into scene.frames and counts what it drops
// in a DropCounts map ("<stage>.<reason>" → pairs or frames), so that the counts of a
// scene add up: candidates = pruned + scored, scored = filtered + selected.
//
// Determinism: scoring runs in parallel (TBB) but results are stored by candidate index;
// sampling uses std::mt19937_64 seeded with SceneSeed(recipe seed, scene name) and its raw
// 64-bit outputs only (no std:: distributions, whose algorithms differ between standard
// libraries), so the selection depends on the inputs and the seed, never on the number of
// threads or on how scenes are split across tasks.
//
// Depth maps are used at the working resolution (nearest-neighbour resize, core/depth.h)
// and decoded through a DepthCache: an LRU of decoded maps bounded in bytes, so a
// 1000-frame scene (1000 × 640 × 480 × 4 B = 1.2 GB) is never held at once.
#pragma once

#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/frame.h"
#include "libgt/geometry/aggregate.h"
#include "libgt/geometry/labels.h"
#include "libgt/render/frame_depth.h"

namespace gt::pairs {

// Cheap tests before scoring (recipe key selection.pruning).
struct PruningOptions {
  double max_distance_m = 0.0;        // camera centre distance; 0 = no limit
  double max_view_angle_deg = 180.0;  // angle between optical axes; 180 = no limit
  bool frustum = true;                // drop pairs whose frustums do not intersect

  bool Check(std::string* error) const;
};

// A pair list imported instead of candidates (recipe key selection.import_pairs).
struct ImportPairsOptions {
  std::string format = "loftr-npz";  // or "loftr-megadepth" (pipeline/select.h ReadImportList)
  std::string path;                  // absolute after loading; "" = no import
};

// Recipe key selection (docs/RECIPES.md).
struct SelectionOptions {
  int max_frame_gap = 0;  // pairs (i < j) with j - i <= gap in kept-frame order; 0 = all pairs
  PruningOptions pruning;
  int score_stride = 8;                       // score on every n-th pixel in x and y
  double overlap_lo = 0.0, overlap_hi = 1.0;  // aggregated overlap must lie in [lo, hi]
  double occlusion_lo = 0.0, occlusion_hi = 1.0;
  OcclusionMetric occlusion_metric = OcclusionMetric::kImage;
  Aggregate aggregate = Aggregate::kMean;  // how the two directions are combined
  // Visible overlap (consistent_overlap = VISIBLE / sampled, the SuperGlue-style score) in
  // [lo, hi], its two directions combined with visible_aggregate: `overlap` counts occluded
  // pixels too, so an occlusion-heavy selection needs this to keep out pairs that only see
  // each other through walls. Default min: the weaker direction must see enough.
  double visible_overlap_lo = 0.0, visible_overlap_hi = 1.0;
  Aggregate visible_aggregate = Aggregate::kMin;
  int quota_per_scene = 0;  // max pairs per scene after filters; 0 = all
  int balance_bins = 0;     // sample evenly across overlap bins; 0 = off
  ImportPairsOptions import_pairs;

  bool Check(std::string* error) const;
};

// Ordered, so that printing and JSON are deterministic.
using DropCounts = std::map<std::string, int64_t>;
void AddCounts(const DropCounts& from, DropCounts* to);

// Thread-safe LRU of depth maps of one scene at the working resolution. Get() decodes
// on a miss (outside the lock; two threads may decode the same frame once each) and
// evicts least recently used maps while the total exceeds max_bytes (at least one map
// is always kept). A read error propagates as gt::InputError naming the file.
// The default size of a DepthCache in MiB (also the --depth-cache-mb default of build and
// covis: pipeline::BuildOptions, CovisibilityOptions).
inline constexpr size_t kDefaultDepthCacheMb = 512;

class DepthCache {
 public:
  // Maps from `depth.source` (render/frame_depth.h; the sensor's by default).
  DepthCache(const Scene& scene, int width, int height,
             size_t max_bytes = kDefaultDepthCacheMb << 20, render::FrameDepthOptions depth = {});
  std::shared_ptr<const DepthImage> Get(size_t frame_index);
  // Whether the frame's map is held now (a hint: another thread may add or drop it).
  bool Contains(size_t frame_index) const;
  int64_t hits() const;
  int64_t misses() const;
  size_t bytes() const;
  // How many maps of the working resolution fit in the budget (at least 1).
  size_t CapacityMaps() const;

 private:
  const Scene& scene_;
  int width_, height_;
  size_t max_bytes_;
  render::FrameDepthOptions depth_;
  mutable std::mutex mutex_;
  std::list<size_t> lru_;  // front = most recent
  std::unordered_map<size_t,
                     std::pair<std::shared_ptr<const DepthImage>, std::list<size_t>::iterator>>
      maps_;
  size_t bytes_ = 0;
  int64_t hits_ = 0, misses_ = 0;
};

struct FrameScanOptions {
  int frame_stride = 1;                    // keep frames at positions 0, s, 2s, ... of the scene
  double min_valid_depth_fraction = 0.1;   // at the working resolution
  double min_depth_m = kDefaultMinDepthM;  // validity range (depth.h IsValidDepth)
  double max_depth_m = kDefaultMaxDepthM;

  bool Check(std::string* error) const;
};

// Frames of a scene that may form pairs, with what the frustum test needs.
struct ScanResult {
  std::vector<size_t> kept;                 // indices into scene.frames, increasing
  std::map<size_t, double> median_depth_m;  // per kept frame: median valid depth
  int64_t frames_total = 0;
  DropCounts drops;  // "scan.stride", "scan.unusable", "scan.read_error", "scan.low_valid_depth"
  // The first frame (in scene order) whose depth could not be read: "<frame id>: <error>",
  // or "" (so that a missing mesh or file is named, not only counted).
  std::string first_read_error;
  // The same for "scan.color_error" (ScanRecipeFrames: a colour image whose header cannot
  // be read or gives another size, when the recipe stores images).
  std::string first_color_error;
  // The same for "scan.no_color" (a frame without a colour image when the recipe stores
  // images; the readers keep no path of a missing file): "<frame id>: no colour image ...".
  std::string first_no_color;
};
// Decodes each frame after the stride (through the cache). A frame whose depth cannot be
// read is skipped and counted, never fatal.
ScanResult ScanFrames(const Scene& scene, const FrameScanOptions& options, DepthCache* cache);

struct CandidatePair {
  size_t i0 = 0, i1 = 0;  // indices into scene.frames, i0 < i1
  bool operator==(const CandidatePair& o) const { return i0 == o.i0 && i1 == o.i1; }
};

// Pairs (a, b) of kept frames with a before b and (position of b) - (position of a) <=
// max_frame_gap in the kept list (0 = every pair), in lexicographic order.
std::vector<CandidatePair> GenerateCandidates(const std::vector<size_t>& kept, int max_frame_gap);

// Angle between the optical axes (camera z) of two poses, degrees in [0, 180].
double ViewAngleDeg(const Rigid3d& world_from_a, const Rigid3d& world_from_b);
// True when some of a few points of A's frustum (a 5 × 5 grid over the image at 0.5×, 1×
// and 2× depth_m) lies in front of B and inside B's pixel area. Symmetric use: the pruning tests
// both directions.
bool FrustumsIntersect(const Camera& cam_a, const Rigid3d& world_from_a, double depth_m_a,
                       const Camera& cam_b, const Rigid3d& world_from_b);

// Drops candidates by camera distance, view angle, then frustum test (each counted as
// "prune.distance", "prune.view_angle", "prune.frustum"). cameras[i] is frame i's camera
// at the working resolution (indexed like scene.frames).
std::vector<CandidatePair> PruneCandidates(const Scene& scene, const std::vector<Camera>& cameras,
                                           const std::vector<CandidatePair>& candidates,
                                           const std::map<size_t, double>& median_depth_m,
                                           const PruningOptions& options, DropCounts* drops);

struct ScoredPair {
  CandidatePair pair;
  DirectionMetrics m01, m10;  // 0→1 on the grid of frame i0, 1→0 on the grid of i1
};

// ScoreDirection both ways for every candidate, in parallel, results in candidate order.
// A candidate whose depth cannot be read is dropped and counted ("score.read_error"); the
// first such error in candidate order goes to `first_read_error` when given, as
// "<frame id>: <error>".
// Candidates are visited in blocks of frames (frame index / B for both frames, B a quarter
// of the cache capacity) so that the depth maps a block needs stay cached even for "all
// pairs" of a long scene: decodes grow like (frames / B)² · B, not like the pair count.
std::vector<ScoredPair> ScorePairs(const Scene& scene, const std::vector<Camera>& cameras,
                                   const std::vector<CandidatePair>& candidates,
                                   const LabelOptions& label_options, int score_stride,
                                   DepthCache* cache, DropCounts* drops,
                                   std::string* first_read_error = nullptr);

// The two directions combined (geometry/aggregate.h).
double PairOverlap(const ScoredPair& p, Aggregate aggregate);
double PairOcclusion(const ScoredPair& p, Aggregate aggregate, OcclusionMetric metric);
double PairVisibleOverlap(const ScoredPair& p, Aggregate aggregate);

// Seed of a scene: FNV-1a 64 of the name mixed with the recipe seed (SplitMix64).
uint64_t SceneSeed(uint64_t recipe_seed, const std::string& scene_name);
// Uniform integer in [0, n) from raw engine outputs (rejection sampling; portable).
uint64_t UniformBelow(uint64_t n, std::mt19937_64* rng);
// Fisher-Yates with UniformBelow: a portable seeded permutation.
void SeededShuffle(std::vector<size_t>* v, std::mt19937_64* rng);
// Round robin over bins (the balancing of pairs and of tuples): round k takes item k of
// every bin that has one, in bin order, until `target` items or `max_rounds` rounds; a
// round that the target ends part way takes its items from bins in a seeded order
// (SeededShuffle of that round's bins), so that no bin is favoured. The items, in order.
std::vector<size_t> TakeRoundRobin(const std::vector<std::vector<size_t>>& bins, size_t target,
                                   size_t max_rounds, std::mt19937_64* rng);

// Filters (overlap range "filter.overlap", visible overlap range "filter.visible_overlap",
// occlusion range "filter.occlusion", in this order), then
// optional balancing over `balance_bins` equal bins of the overlap range
// ("sample.balance"), then the per-scene quota ("sample.quota"). Returns indices into
// `scored` in selection order: increasing (i0, i1). Inclusive ranges.
std::vector<size_t> FilterAndSample(const std::vector<ScoredPair>& scored,
                                    const SelectionOptions& options, uint64_t scene_seed,
                                    DropCounts* drops);

}  // namespace gt::pairs

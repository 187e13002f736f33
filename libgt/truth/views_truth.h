// The dense ground truth of N posed depth views (docs/MULTIVIEW.md): for every pixel of every
// view, whether it is VISIBLE / OCCLUDED in each of the N views, and tracks of query pixels
// through all of them. Built from the pair labels only: for j != i, bit j of pixel p of view i
// is the pair label of p for the direction i → j (geometry/labels.h LabelDirection with
// b_from_a = RelativePose(world_from_cam_i, world_from_cam_j), the same kernel, so the bits
// equal `occgt pair`'s label01 of that pair bit for bit). The diagonal (bit i of view i) is
// not labelled: it is the view's own depth mask, VISIBLE exactly where `valid` (a view sees
// its own pixels); the pair labeller's answer for a view against itself agrees under the
// default preset, but under the truncating, strict-bounds presets (occ2net, loftr,
// occ2net-compat) its projection of the identity rounds to the neighbouring pixel or off
// the border (docs/MULTIVIEW.md).
//
// Layouts (row-major, N views of one size H × W, N <= 32):
//   visible_in, occluded_in  uint32 [N, H, W]  bit j of [i, v, u]: pixel (u, v) of view i is
//                            VISIBLE (OCCLUDED) in view j. A pixel with neither bit for j is
//                            OUT_OF_VIEW, NO_DEPTH, UNKNOWN or INCONSISTENT there (label01).
//   valid                    uint8 [N, H, W]    1 where the view's own depth is valid (the
//                            labels' depth range: core/depth.h IsValidDepth)
//   seen_by                  uint8 [N, H, W]    number of other views j != i in which the
//                            pixel is VISIBLE (popcount of visible_in without bit i)
//   seen_by_histogram        int64 [N, N]       [i, k]: valid pixels of view i seen by exactly
//                            k other views
// Tracks (VGGT's tracks with explicit states), Q query pixels (u, v) of view q = query_view:
//   queries      int32 [Q, 2]      the query pixels (given, or sampled: below)
//   track_xy     float32 [N, Q, 2] position in view j (LabelDirection's warped_xy of q → j at
//                                  the query pixel, bit for bit); NaN where not projected
//   track_depth  float32 [N, Q]    depth of the point in view j's camera (planar z, metres, as
//                                  the kernel computes it); NaN where not projected
//   track_state  uint8 [N, Q]      TrackState of the point in view j (from label q → j)
// In view q itself (the diagonal), a valid query is VISIBLE at its own pixel (u, v) with its
// own depth; a query without valid depth is NO_DEPTH there too, with NaN position and depth.
// Sampling: the valid pixels of view q in raster order, num_tracks of them drawn without
// replacement by a partial Fisher–Yates shuffle driven by std::mt19937_64(seed) (raw outputs,
// rejection for an unbiased index: portable), then sorted in raster order; all of them when
// there are no more than num_tracks.
//
// Work: one task per (view, block of rows) on TBB, each writing only its own rows, so the
// result is the same whatever the number of threads. The N (N − 1) directions are labelled.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "libgt/core/default_init_allocator.h"
#include "libgt/geometry/labels.h"
#include "libgt/truth/working_frame.h"

namespace gt::truth {

inline constexpr int kMaxViews = 32;  // the bits of a uint32 word

// State of a track in one view (stable uint8 codes, stored in files).
enum class TrackState : uint8_t {
  kVisible = 0,       // label VISIBLE: the view sees the point
  kOccluded = 1,      // label OCCLUDED: a surface of the view lies in front of it
  kOutOfView = 2,     // label OUT_OF_VIEW: behind the camera or outside the image
  kNoDepth = 3,       // NO_DEPTH at the query pixel, or UNKNOWN: the view has no depth there
  kInconsistent = 4,  // label INCONSISTENT: the view sees past the point (depth/pose error)
};
inline constexpr int kNumTrackStates = 5;
// "VISIBLE", "OCCLUDED", "OUT_OF_VIEW", "NO_DEPTH", "INCONSISTENT".
const char* TrackStateName(TrackState state);
TrackState TrackStateOf(PixelLabel label);

struct ViewsTruthOptions {
  LabelOptions labels;   // as the pair labels (truth::ResolvePairTruthOptions(...).labels)
  int num_tracks = 512;  // query pixels sampled when none are given (>= 0)
  int query_view = 0;    // the view whose pixels are the queries (< the number of views)
  uint64_t seed = 0;     // of the sampling

  bool Check(std::string* error) const;  // labels valid, num_tracks >= 0, query_view >= 0
};

struct ViewsTruth {
  int num_views = 0, width = 0, height = 0;
  // [N, H, W]; default-initialised storage (ComputeViewsTruth writes every element once)
  std::vector<uint32_t, DefaultInitAllocator<uint32_t>> visible_in, occluded_in;
  std::vector<uint8_t, DefaultInitAllocator<uint8_t>> valid, seen_by;
  std::vector<int64_t> seen_by_histogram;  // [N, N]
  int query_view = 0;
  std::vector<int32_t> queries;      // [Q, 2] (u, v)
  std::vector<float> track_xy;       // [N, Q, 2]
  std::vector<float> track_depth;    // [N, Q]
  std::vector<uint8_t> track_state;  // [N, Q] TrackState codes
  size_t num_queries() const { return queries.size() / 2; }
};

// views: 1..kMaxViews frames of one size (depth [H, W], K at W×H, rigid world_from_cam).
// queries_uv: [Q * 2] (u, v) pixels of the query view; nullopt: sample options.num_tracks.
// Throws InputError("views", ...) for 0 or more than 32 views, ("views[i].depth" / ".K" /
// ".world_from_cam", ...) naming the view for a size, camera or pose problem, ("options", ...)
// for options that fail Check or a query view out of range, ("queries", ...) for a pixel
// outside the image.
ViewsTruth ComputeViewsTruth(const std::vector<WorkingFrame>& views,
                             const ViewsTruthOptions& options,
                             const std::optional<std::vector<int32_t>>& queries_uv = std::nullopt);

// The sampled queries alone (the rule above): [Q * 2] (u, v).
std::vector<int32_t> SampleQueries(const DepthImage& depth, const LabelOptions& labels,
                                   int num_tracks, uint64_t seed);
// The same rule over a view's valid mask (uint8 [height, width], nonzero = valid depth):
// what a stored sample's `valid` gives (shards/views_sample_check.h).
std::vector<int32_t> SampleQueries(const uint8_t* valid, int width, int height, int num_tracks,
                                   uint64_t seed);

// seen_by and seen_by_histogram of stored bitmasks (an N-view shard's visible_in and valid),
// as ComputeViewsTruth returns them with those masks. visible_in uint32 and valid uint8, both
// [num_views, pixels_per_view]. Throws InputError("visible_in", ...) for num_views outside
// 1..32 or a bit set for a view >= num_views, ("valid", ...) for a value other than 0 and 1.
struct SeenBy {
  std::vector<uint8_t> seen_by;    // [N, H, W]
  std::vector<int64_t> histogram;  // [N, N]
};
SeenBy CountSeenBy(const uint32_t* visible_in, const uint8_t* valid, int num_views,
                   size_t pixels_per_view);

// Stored N-view ground truth (an N-view shard's members), checked for what every
// ComputeViewsTruth result satisfies, so that a damaged or hand-edited sample is refused
// rather than trained on: per pixel, no bit for a view >= num_views, `valid` 0 or 1, a
// pixel never both VISIBLE and OCCLUDED in one view, no bit at all where not valid, and the
// diagonal (bit i of view i) VISIBLE exactly where valid; per track and view, a state in
// 0..kNumTrackStates-1, x and y both NaN or both finite, and finite where VISIBLE, OCCLUDED
// or INCONSISTENT (LabelDirection's warped_xy). Arrays as in ViewsTruth: [N, pixels_per_view]
// and [N, num_queries(, 2)]. Throws InputError("<array>", "... at element k") naming the
// first element at fault (CountSeenBy's checks first: visible_in, valid; then occluded_in,
// visible_in, track_xy, track_state). Returns CountSeenBy of the arrays (checked once).
SeenBy CheckStoredViewsTruth(const uint32_t* visible_in, const uint32_t* occluded_in,
                             const uint8_t* valid, int num_views, size_t pixels_per_view,
                             const float* track_xy, const uint8_t* track_state, size_t num_queries);

}  // namespace gt::truth

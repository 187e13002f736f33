#include "libgt/truth/views_truth.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/core/pose.h"

namespace gt::truth {
namespace {

// Rows per task: with N targets per row, a block of 32 rows at 640 px is ~N · 0.03 ms of
// labelling, enough to hide the per-task setup (N kernels and their column terms).
constexpr int kRowsPerTask = 32;

// Uniform in [0, n) from the raw outputs of the generator (rejection: no modulo bias), so
// the draws are the same with every standard library.
uint64_t UniformBelow(uint64_t n, std::mt19937_64* rng) {
  const uint64_t limit =
      std::numeric_limits<uint64_t>::max() - std::numeric_limits<uint64_t>::max() % n;
  for (;;) {
    const uint64_t x = (*rng)();
    if (x < limit) return x % n;
  }
}

std::string ViewField(size_t i, const char* what) {
  return "views[" + std::to_string(i) + "]." + what;
}

// The first writes of rows [0, count) of one view, before the other views' bits are ORed
// in: valid[p] = IsValidDepth(depth[p]), the diagonal vis[p] = valid[p] << self (a view sees
// its own valid pixels) and occ[p] = 0. Branch-free, so that g++ vectorises it: IsValidDepth's
// four tests without short-circuits (a float widened to double exactly, the same
// comparisons).
void StartRows(const float* __restrict depth, const LabelOptions& lo, size_t count, int self,
               uint8_t* __restrict valid, uint32_t* __restrict vis, uint32_t* __restrict occ) {
  const double min_m = lo.min_depth_m, max_m = lo.max_depth_m;
  for (size_t p = 0; p < count; ++p) {
    const float d = depth[p];
    const double dd = d;
    const bool ok = (std::fabs(d) <= std::numeric_limits<float>::max()) &
                    (d >= kMinPositiveDepthM) & (dd >= min_m) & (dd <= max_m);
    valid[p] = ok ? 1 : 0;
    vis[p] = static_cast<uint32_t>(ok) << self;
    occ[p] = 0;
  }
}

// seen[p] = popcount(vis[p] & others) and hist[k] += the valid pixels with seen = k (k < bins),
// for p < count. The popcount by the bit-parallel sum (no POPCNT in the baseline x86-64, where
// __builtin_popcount is a libgcc call), so that the loop vectorises. The histogram is summed
// in four interleaved partial counts (one count bumped pixel after pixel is a chain through
// memory).
void SeenStats(const uint32_t* __restrict vis, uint32_t others, const uint8_t* __restrict valid,
               size_t count, uint8_t* __restrict seen, int bins, int64_t* __restrict hist) {
  for (size_t p = 0; p < count; ++p) {
    uint32_t x = vis[p] & others;
    x = x - ((x >> 1) & 0x55555555u);
    x = (x & 0x33333333u) + ((x >> 2) & 0x33333333u);
    x = (x + (x >> 4)) & 0x0F0F0F0Fu;
    seen[p] = static_cast<uint8_t>((x * 0x01010101u) >> 24);
  }
  int64_t partial[4][kMaxViews + 1] = {};
  size_t p = 0;
  for (; p + 4 <= count; p += 4) {
    for (int k = 0; k < 4; ++k) partial[k][seen[p + k]] += valid[p + k];
  }
  for (; p < count; ++p) partial[0][seen[p]] += valid[p];
  for (int k = 0; k <= kMaxViews; ++k) {
    const int64_t c = partial[0][k] + partial[1][k] + partial[2][k] + partial[3][k];
    GT_ASSERT(k < bins || c == 0);
    if (k < bins) hist[k] += c;
  }
}

void CheckViews(const std::vector<WorkingFrame>& views) {
  if (views.empty() || views.size() > static_cast<size_t>(kMaxViews)) {
    throw InputError("views", "expected 1.." + std::to_string(kMaxViews) + " views, got " +
                                  std::to_string(views.size()));
  }
  for (size_t i = 0; i < views.size(); ++i) {
    const WorkingFrame& f = views[i];
    if (!f.depth) throw InputError(ViewField(i, "depth"), "expected a depth map");
    const DepthImage& d = *f.depth;
    const DepthImage& d0 = *views[0].depth;
    if (d.width != d0.width || d.height != d0.height ||
        d.values_m.size() != static_cast<size_t>(d.width) * d.height) {
      std::ostringstream msg;
      msg << "expected " << d0.width << "x" << d0.height << " (the size of view 0), got " << d.width
          << "x" << d.height;
      throw InputError(ViewField(i, "depth"), msg.str());
    }
    std::string error;
    if (!f.camera.Check(&error)) throw InputError(ViewField(i, "K"), error);
    if (f.camera.width != d.width || f.camera.height != d.height) {
      std::ostringstream msg;
      msg << "expected a camera of the depth map's size " << d.width << "x" << d.height << ", got "
          << f.camera.width << "x" << f.camera.height;
      throw InputError(ViewField(i, "K"), msg.str());
    }
    if (const auto problem = PoseProblem(f.world_from_cam.matrix())) {
      throw InputError(ViewField(i, "world_from_cam"), *problem);
    }
  }
}

}  // namespace

const char* TrackStateName(TrackState state) {
  switch (state) {
    case TrackState::kVisible:
      return "VISIBLE";
    case TrackState::kOccluded:
      return "OCCLUDED";
    case TrackState::kOutOfView:
      return "OUT_OF_VIEW";
    case TrackState::kNoDepth:
      return "NO_DEPTH";
    case TrackState::kInconsistent:
      return "INCONSISTENT";
  }
  return "?";
}

TrackState TrackStateOf(PixelLabel label) {
  switch (label) {
    case PixelLabel::kVisible:
      return TrackState::kVisible;
    case PixelLabel::kOccluded:
      return TrackState::kOccluded;
    case PixelLabel::kOutOfView:
      return TrackState::kOutOfView;
    case PixelLabel::kInconsistent:
      return TrackState::kInconsistent;
    case PixelLabel::kNoDepth:
    case PixelLabel::kUnknown:
      return TrackState::kNoDepth;
  }
  GT_ASSERT(false);
  return TrackState::kNoDepth;
}

bool ViewsTruthOptions::Check(std::string* error) const {
  if (!labels.Check(error)) return false;
  if (num_tracks < 0) {
    *error = "num_tracks: expected >= 0, got " + std::to_string(num_tracks);
    return false;
  }
  if (query_view < 0) {
    *error = "query_view: expected >= 0, got " + std::to_string(query_view);
    return false;
  }
  return true;
}

namespace {

// num_tracks of the raster indices `valid` (ascending) drawn by the rule of views_truth.h,
// as (u, v) pairs.
std::vector<int32_t> SampleOfValid(std::vector<int32_t> valid, int width, int num_tracks,
                                   uint64_t seed) {
  const size_t k = std::min(valid.size(), static_cast<size_t>(std::max(num_tracks, 0)));
  if (k < valid.size()) {
    std::mt19937_64 rng(seed);
    for (size_t i = 0; i < k; ++i) {  // partial Fisher–Yates: valid[0 .. k) is the sample
      const size_t j = i + static_cast<size_t>(UniformBelow(valid.size() - i, &rng));
      std::swap(valid[i], valid[j]);
    }
    valid.resize(k);
    std::sort(valid.begin(), valid.end());
  }
  std::vector<int32_t> uv(2 * k);
  for (size_t i = 0; i < k; ++i) {
    uv[2 * i] = valid[i] % width;
    uv[2 * i + 1] = valid[i] / width;
  }
  return uv;
}

}  // namespace

std::vector<int32_t> SampleQueries(const DepthImage& depth, const LabelOptions& labels,
                                   int num_tracks, uint64_t seed) {
  std::vector<int32_t> valid;  // raster indices
  for (size_t p = 0; p < depth.values_m.size(); ++p) {
    if (IsValidDepth(depth.values_m[p], labels.min_depth_m, labels.max_depth_m)) {
      valid.push_back(static_cast<int32_t>(p));
    }
  }
  return SampleOfValid(std::move(valid), depth.width, num_tracks, seed);
}

std::vector<int32_t> SampleQueries(const uint8_t* valid, int width, int height, int num_tracks,
                                   uint64_t seed) {
  std::vector<int32_t> indices;
  const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
  for (size_t p = 0; p < n; ++p) {
    if (valid[p] != 0) indices.push_back(static_cast<int32_t>(p));
  }
  return SampleOfValid(std::move(indices), width, num_tracks, seed);
}

SeenBy CountSeenBy(const uint32_t* visible_in, const uint8_t* valid, int num_views,
                   size_t pixels_per_view) {
  if (num_views < 1 || num_views > kMaxViews) {
    throw InputError("visible_in", "expected 1.." + std::to_string(kMaxViews) + " views, got " +
                                       std::to_string(num_views));
  }
  const size_t total = pixels_per_view * static_cast<size_t>(num_views);
  const uint32_t views_mask = num_views == kMaxViews ? ~0u : (1u << num_views) - 1;
  for (size_t p = 0; p < total; ++p) {
    if ((visible_in[p] & ~views_mask) != 0) {
      throw InputError("visible_in", "bit for a view >= " + std::to_string(num_views) +
                                         " (the number of views) set at element " +
                                         std::to_string(p));
    }
    if (valid[p] > 1) {
      throw InputError("valid", "expected 0 or 1, got " + std::to_string(valid[p]) +
                                    " at element " + std::to_string(p));
    }
  }
  SeenBy out;
  out.seen_by.resize(total);
  out.histogram.assign(static_cast<size_t>(num_views) * num_views, 0);
  for (int i = 0; i < num_views; ++i) {
    const size_t p0 = pixels_per_view * i;
    SeenStats(visible_in + p0, ~(1u << i), valid + p0, pixels_per_view, out.seen_by.data() + p0,
              num_views, out.histogram.data() + static_cast<size_t>(i) * num_views);
  }
  return out;
}

SeenBy CheckStoredViewsTruth(const uint32_t* visible_in, const uint32_t* occluded_in,
                             const uint8_t* valid, int num_views, size_t pixels_per_view,
                             const float* track_xy, const uint8_t* track_state,
                             size_t num_queries) {
  // The view count, visible_in's bits and valid's values, with the statistics.
  SeenBy seen = CountSeenBy(visible_in, valid, num_views, pixels_per_view);
  const uint32_t views_mask = num_views == kMaxViews ? ~0u : (1u << num_views) - 1;
  const auto fail = [](const char* array, const std::string& what, size_t element) {
    throw InputError(array, what + " at element " + std::to_string(element));
  };
  const std::string beyond =
      "bit for a view >= " + std::to_string(num_views) + " (the number of views) set";
  for (int i = 0; i < num_views; ++i) {
    const uint32_t self = 1u << i;
    const size_t p0 = pixels_per_view * static_cast<size_t>(i);
    // A branch-free pass (vectorised) first; the element at fault is looked for only when
    // there is one. valid is 0 or 1 here (CountSeenBy).
    uint32_t fault = 0;
    for (size_t p = p0; p < p0 + pixels_per_view; ++p) {
      const uint32_t vis = visible_in[p], occ = occluded_in[p];
      const uint32_t none = valid[p] - 1u;  // all ones where not valid, else 0
      fault |= (occ & ~views_mask) | (vis & occ) | (none & (vis | occ)) | (~none & ~vis & self);
    }
    if (fault == 0) continue;
    for (size_t p = p0; p < p0 + pixels_per_view; ++p) {
      const uint32_t vis = visible_in[p], occ = occluded_in[p];
      if ((occ & ~views_mask) != 0) fail("occluded_in", beyond, p);
      if ((vis & occ) != 0) {
        fail("occluded_in", "a pixel both VISIBLE (visible_in) and OCCLUDED in one view", p);
      }
      if (valid[p] == 0 && (vis | occ) != 0) {
        fail(vis != 0 ? "visible_in" : "occluded_in",
             "a bit set for a pixel without valid depth (valid = 0)", p);
      }
      if (valid[p] == 1 && (vis & self) == 0) {
        fail("visible_in",
             "view " + std::to_string(i) + "'s own bit (the diagonal) not set for a valid pixel",
             p);
      }
    }
  }
  for (size_t k = 0; k < static_cast<size_t>(num_views) * num_queries; ++k) {
    const uint8_t state = track_state[k];
    if (state >= kNumTrackStates) {
      fail("track_state",
           "expected 0.." + std::to_string(kNumTrackStates - 1) + ", got " + std::to_string(state),
           k);
    }
    const float x = track_xy[2 * k], y = track_xy[2 * k + 1];
    if (std::isinf(x) || std::isinf(y) || std::isnan(x) != std::isnan(y)) {
      fail("track_xy", "expected (x, y) both finite or both NaN", 2 * k);
    }
    const auto s = static_cast<TrackState>(state);
    if (std::isnan(x) && (s == TrackState::kVisible || s == TrackState::kOccluded ||
                          s == TrackState::kInconsistent)) {
      fail("track_xy",
           std::string("NaN for a track whose state is ") + TrackStateName(s) +
               " (a projected point has a position)",
           2 * k);
    }
  }
  return seen;
}

ViewsTruth ComputeViewsTruth(const std::vector<WorkingFrame>& views,
                             const ViewsTruthOptions& options,
                             const std::optional<std::vector<int32_t>>& queries_uv) {
  std::string error;
  if (!options.Check(&error)) throw InputError("options", error);
  CheckViews(views);
  const int n = static_cast<int>(views.size());
  if (options.query_view >= n) {
    throw InputError("options", "query_view: expected < " + std::to_string(n) +
                                    " (the number of views), got " +
                                    std::to_string(options.query_view));
  }
  ViewsTruth out;
  out.num_views = n;
  out.width = views[0].depth->width;
  out.height = views[0].depth->height;
  const size_t hw = static_cast<size_t>(out.width) * out.height;
  const size_t total = hw * n;
  // Every element is written by the tasks below (StartRows, SeenStats): no zero fill.
  out.visible_in.resize(total);
  out.occluded_in.resize(total);
  out.valid.resize(total);
  out.seen_by.resize(total);
  out.seen_by_histogram.assign(static_cast<size_t>(n) * n, 0);

  // Targets of each source view i: every other view (bit j = view j); the diagonal bit i is
  // the view's own depth mask (StartRows), not labelled.
  std::vector<std::vector<BitTarget>> targets(n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      BitTarget t;
      t.depth_b = views[j].depth.get();
      t.cam_b = &views[j].camera;
      t.b_from_a = RelativePose(views[i].world_from_cam, views[j].world_from_cam);
      t.bit = j;
      targets[i].push_back(t);
    }
  }
  const int blocks = (out.height + kRowsPerTask - 1) / kRowsPerTask;
  // Per task: its rows' first writes (valid, the diagonal), the other views' bits, then the
  // rows' statistics (while the words are in cache); the histogram of a task is summed after
  // the loop in task order (integers: exact anyway).
  std::vector<int64_t> block_hist(static_cast<size_t>(n) * blocks * n, 0);
  const LabelOptions& lo = options.labels;
  tbb::parallel_for(tbb::blocked_range<int>(0, n * blocks), [&](const tbb::blocked_range<int>& r) {
    for (int task = r.begin(); task != r.end(); ++task) {
      const int i = task / blocks, block = task % blocks;
      const int row_begin = block * kRowsPerTask;
      const int row_end = std::min(out.height, row_begin + kRowsPerTask);
      const WorkingFrame& f = views[i];
      uint32_t* vis = out.visible_in.data() + hw * i;
      uint32_t* occ = out.occluded_in.data() + hw * i;
      uint8_t* valid = out.valid.data() + hw * i;
      const size_t p0 = static_cast<size_t>(row_begin) * out.width;
      const size_t p1 = static_cast<size_t>(row_end) * out.width;
      StartRows(f.depth->values_m.data() + p0, lo, p1 - p0, i, valid + p0, vis + p0, occ + p0);
      LabelDirectionBits(*f.depth, f.camera, targets[i], lo, row_begin, row_end, vis, occ);
      SeenStats(vis + p0, ~(1u << i), valid + p0, p1 - p0, out.seen_by.data() + hw * i + p0, n,
                block_hist.data() + static_cast<size_t>(task) * n);
    }
  });
  for (int task = 0; task < n * blocks; ++task) {
    const int i = task / blocks;
    for (int k = 0; k < n; ++k) {
      out.seen_by_histogram[static_cast<size_t>(i) * n + k] +=
          block_hist[static_cast<size_t>(task) * n + k];
    }
  }

  // Tracks: the query pixels of view q labelled in every view with the same kernel.
  const int q = options.query_view;
  out.query_view = q;
  const WorkingFrame& fq = views[q];
  out.queries =
      queries_uv ? *queries_uv : SampleQueries(*fq.depth, lo, options.num_tracks, options.seed);
  if (out.queries.size() % 2 != 0) throw InputError("queries", "expected (u, v) pairs");
  for (size_t k = 0; k < out.queries.size(); k += 2) {
    const int u = out.queries[k], v = out.queries[k + 1];
    if (u < 0 || u >= out.width || v < 0 || v >= out.height) {
      std::ostringstream msg;
      msg << "expected pixels (u, v) inside the " << out.width << "x" << out.height
          << " image, got (" << u << ", " << v << ") at row " << k / 2;
      throw InputError("queries", msg.str());
    }
  }
  const size_t nq = out.num_queries();
  out.track_xy.resize(static_cast<size_t>(n) * nq * 2);
  out.track_depth.resize(static_cast<size_t>(n) * nq);
  out.track_state.resize(static_cast<size_t>(n) * nq);
  tbb::parallel_for(0, n, [&](int j) {
    if (j == q) {  // the query view itself, as the diagonal: each valid query at its own pixel
      const float nan = std::numeric_limits<float>::quiet_NaN();
      const uint8_t* valid_q = out.valid.data() + hw * q;
      for (size_t k = 0; k < nq; ++k) {
        const int u = out.queries[2 * k], v = out.queries[2 * k + 1];
        const size_t p = static_cast<size_t>(v) * out.width + u;
        const bool ok = valid_q[p] == 1;
        const float d = fq.depth->values_m[p];
        out.track_xy[2 * (nq * j + k)] = ok ? static_cast<float>(u) : nan;
        out.track_xy[2 * (nq * j + k) + 1] = ok ? static_cast<float>(v) : nan;
        out.track_depth[nq * j + k] = ok ? d : nan;
        out.track_state[nq * j + k] =
            static_cast<uint8_t>(ok ? TrackState::kVisible : TrackState::kNoDepth);
      }
      return;
    }
    const WorkingFrame& fj = views[j];
    const PointLabels pts =
        LabelPoints(*fq.depth, fq.camera, *fj.depth, fj.camera,
                    RelativePose(fq.world_from_cam, fj.world_from_cam), lo, out.queries);
    std::copy(pts.xy.begin(), pts.xy.end(), out.track_xy.begin() + 2 * nq * j);
    std::copy(pts.z_m.begin(), pts.z_m.end(), out.track_depth.begin() + nq * j);
    for (size_t k = 0; k < nq; ++k) {
      out.track_state[nq * j + k] =
          static_cast<uint8_t>(TrackStateOf(static_cast<PixelLabel>(pts.labels[k])));
    }
  });
  return out;
}

}  // namespace gt::truth

#include "libgt/pairs/selection.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <random>

#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/truth/working_frame.h"

namespace gt::pairs {

void AddCounts(const DropCounts& from, DropCounts* to) {
  for (const auto& [k, v] : from) (*to)[k] += v;
}

// ---- DepthCache -------------------------------------------------------------------

DepthCache::DepthCache(const Scene& scene, int width, int height, size_t max_bytes,
                       render::FrameDepthOptions depth)
    : scene_(scene), width_(width), height_(height), max_bytes_(max_bytes), depth_(depth) {}

std::shared_ptr<const DepthImage> DepthCache::Get(size_t frame_index) {
  GT_ASSERT(frame_index < scene_.frames.size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = maps_.find(frame_index);
    if (it != maps_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.second);
      ++hits_;
      return it->second.first;
    }
    ++misses_;
  }
  auto map = std::make_shared<const DepthImage>(
      truth::LoadWorkingDepth(scene_, scene_.frames[frame_index], {width_, height_}, depth_));
  const size_t map_bytes = map->values_m.size() * sizeof(float);
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = maps_.find(frame_index);
  if (it != maps_.end()) return it->second.first;  // another thread decoded it meanwhile
  lru_.push_front(frame_index);
  maps_.emplace(frame_index, std::make_pair(map, lru_.begin()));
  bytes_ += map_bytes;
  while (bytes_ > max_bytes_ && lru_.size() > 1) {
    const size_t victim = lru_.back();
    lru_.pop_back();
    auto v = maps_.find(victim);
    bytes_ -= v->second.first->values_m.size() * sizeof(float);
    maps_.erase(v);
  }
  return map;
}

bool DepthCache::Contains(size_t frame_index) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return maps_.count(frame_index) != 0;
}

int64_t DepthCache::hits() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}
int64_t DepthCache::misses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return misses_;
}
size_t DepthCache::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

size_t DepthCache::CapacityMaps() const {
  const size_t map_bytes = static_cast<size_t>(width_) * height_ * sizeof(float);
  return std::max<size_t>(1, max_bytes_ / std::max<size_t>(1, map_bytes));
}

// ---- scan -------------------------------------------------------------------------

bool FrameScanOptions::Check(std::string* error) const {
  if (frame_stride < 1) return *error = "frame_stride: expected an integer >= 1", false;
  if (!(min_valid_depth_fraction >= 0 && min_valid_depth_fraction <= 1)) {
    return *error = "min_valid_depth_fraction: expected a number in [0, 1]", false;
  }
  if (!(min_depth_m >= 0 && max_depth_m > min_depth_m)) {
    return *error = "max_depth_m: expected 0 <= min_depth_m < max_depth_m", false;
  }
  return true;
}

namespace {
// Scanned frames whose depth files are read ahead of the scan (ScanFrames).
constexpr size_t kScanPrefetch = 64;
}  // namespace

ScanResult ScanFrames(const Scene& scene, const FrameScanOptions& options, DepthCache* cache) {
  std::string error;
  if (!options.Check(&error)) throw InputError("scan options", error);
  ScanResult result;
  result.frames_total = static_cast<int64_t>(scene.frames.size());
  const size_t n = scene.frames.size();
  std::vector<int> status(n, 0);  // 0 kept, 1 stride, 2 unusable, 3 read error, 4 low depth
  std::vector<double> medians(n, 0.0);
  std::vector<std::string> read_errors(n);  // per frame, for status 3
  // The depth files are read ahead (io::PrefetchDepth) kScanPrefetch scanned frames in
  // advance, so that a file missing from the page cache is read from disk while the
  // threads work on the frames before it, instead of stalling one of them.
  const size_t stride = static_cast<size_t>(options.frame_stride);
  auto prefetch = [&](size_t i) {
    if (i < n && scene.frames[i].usable) io::PrefetchDepth(scene.frames[i].depth);
  };
  for (size_t k = 0; k < kScanPrefetch; ++k) prefetch(k * stride);
  tbb::parallel_for(size_t{0}, n, [&](size_t i) {
    if (i % stride != 0) {
      status[i] = 1;
      return;
    }
    prefetch(i + kScanPrefetch * stride);
    if (!scene.frames[i].usable) {
      status[i] = 2;
      return;
    }
    std::shared_ptr<const DepthImage> depth;
    try {
      depth = cache->Get(i);
    } catch (const InputError& e) {
      status[i] = 3;
      read_errors[i] = e.what();
      return;
    }
    std::vector<float> valid;
    valid.reserve(depth->values_m.size());
    for (float d : depth->values_m) {
      if (IsValidDepth(d, options.min_depth_m, options.max_depth_m)) valid.push_back(d);
    }
    const double fraction =
        depth->values_m.empty() ? 0.0 : static_cast<double>(valid.size()) / depth->values_m.size();
    if (valid.empty() || fraction < options.min_valid_depth_fraction) {
      status[i] = 4;
      return;
    }
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    medians[i] = valid[valid.size() / 2];
  });
  static const char* kReasons[] = {"", "scan.stride", "scan.unusable", "scan.read_error",
                                   "scan.low_valid_depth"};
  for (size_t i = 0; i < n; ++i) {
    if (status[i] == 0) {
      result.kept.push_back(i);
      result.median_depth_m[i] = medians[i];
    } else {
      ++result.drops[kReasons[status[i]]];
      if (status[i] == 3 && result.first_read_error.empty()) {
        result.first_read_error = scene.frames[i].id + ": " + read_errors[i];
      }
    }
  }
  return result;
}

// ---- candidates and pruning --------------------------------------------------------

std::vector<CandidatePair> GenerateCandidates(const std::vector<size_t>& kept, int max_frame_gap) {
  std::vector<CandidatePair> out;
  const size_t n = kept.size();
  for (size_t a = 0; a < n; ++a) {
    const size_t last =
        max_frame_gap <= 0 ? n : std::min(n, a + 1 + static_cast<size_t>(max_frame_gap));
    for (size_t b = a + 1; b < last; ++b) out.push_back({kept[a], kept[b]});
  }
  return out;
}

double ViewAngleDeg(const Rigid3d& world_from_a, const Rigid3d& world_from_b) {
  const Eigen::Vector3d za = world_from_a.linear().col(2).normalized();
  const Eigen::Vector3d zb = world_from_b.linear().col(2).normalized();
  const double c = std::clamp(za.dot(zb), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

bool FrustumsIntersect(const Camera& cam_a, const Rigid3d& world_from_a, double depth_m_a,
                       const Camera& cam_b, const Rigid3d& world_from_b) {
  const Rigid3d b_from_a = RelativePose(world_from_a, world_from_b);
  static const double kFractions[] = {0.02, 0.25, 0.5, 0.75, 0.98};
  static const double kDepthScales[] = {0.5, 1.0, 2.0};
  for (double s : kDepthScales) {
    for (double fy : kFractions) {
      for (double fx : kFractions) {
        const double u = fx * cam_a.width - 0.5, v = fy * cam_a.height - 0.5;
        const Eigen::Vector3d p_in_b = b_from_a * cam_a.CamFromImg(u, v, s * depth_m_a);
        const auto x = cam_b.ImgFromCam(p_in_b, 0.0);
        if (x && cam_b.InPixelArea(x->x(), x->y())) return true;
      }
    }
  }
  return false;
}

std::vector<CandidatePair> PruneCandidates(const Scene& scene, const std::vector<Camera>& cameras,
                                           const std::vector<CandidatePair>& candidates,
                                           const std::map<size_t, double>& median_depth_m,
                                           const PruningOptions& options, DropCounts* drops) {
  std::vector<CandidatePair> out;
  out.reserve(candidates.size());
  int64_t by_distance = 0, by_angle = 0, by_frustum = 0;
  for (const CandidatePair& c : candidates) {
    const Rigid3d& wa = scene.frames[c.i0].world_from_cam;
    const Rigid3d& wb = scene.frames[c.i1].world_from_cam;
    if (options.max_distance_m > 0 &&
        (wa.translation() - wb.translation()).norm() > options.max_distance_m) {
      ++by_distance;
      continue;
    }
    if (options.max_view_angle_deg < 180 && ViewAngleDeg(wa, wb) > options.max_view_angle_deg) {
      ++by_angle;
      continue;
    }
    if (options.frustum) {
      auto da = median_depth_m.find(c.i0), db = median_depth_m.find(c.i1);
      GT_ASSERT(da != median_depth_m.end() && db != median_depth_m.end());
      if (!FrustumsIntersect(cameras[c.i0], wa, da->second, cameras[c.i1], wb) &&
          !FrustumsIntersect(cameras[c.i1], wb, db->second, cameras[c.i0], wa)) {
        ++by_frustum;
        continue;
      }
    }
    out.push_back(c);
  }
  if (by_distance) (*drops)["prune.distance"] += by_distance;
  if (by_angle) (*drops)["prune.view_angle"] += by_angle;
  if (by_frustum) (*drops)["prune.frustum"] += by_frustum;
  return out;
}

// ---- scoring ----------------------------------------------------------------------

std::vector<ScoredPair> ScorePairs(const Scene& scene, const std::vector<Camera>& cameras,
                                   const std::vector<CandidatePair>& candidates,
                                   const LabelOptions& label_options, int score_stride,
                                   DepthCache* cache, DropCounts* drops,
                                   std::string* first_read_error) {
  std::vector<std::optional<ScoredPair>> results(candidates.size());
  // The read error of the first failing candidate in candidate order (whatever the visit
  // order): "<frame id>: <error>".
  std::mutex error_mutex;
  size_t error_k = candidates.size();
  std::string error_text;

  // Visit order: by block of (i0 / B, i1 / B), then candidate order (results by index).
  const size_t block = std::max<size_t>(1, cache->CapacityMaps() / 4);
  std::vector<size_t> order(candidates.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const CandidatePair& ca = candidates[a];
    const CandidatePair& cb = candidates[b];
    const size_t a0 = ca.i0 / block, a1 = ca.i1 / block, b0 = cb.i0 / block, b1 = cb.i1 / block;
    return a0 != b0 ? a0 < b0 : a1 < b1;
  });
  tbb::parallel_for(size_t{0}, order.size(), [&](size_t position) {
    const size_t k = order[position];
    const CandidatePair& c = candidates[k];
    std::shared_ptr<const DepthImage> d0, d1;
    size_t reading = c.i0;
    try {
      d0 = cache->Get(c.i0);
      reading = c.i1;
      d1 = cache->Get(c.i1);
    } catch (const InputError& e) {
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (k < error_k) {
        error_k = k;
        error_text = scene.frames[reading].id + ": " + e.what();
      }
      return;
    }
    const Rigid3d& w0 = scene.frames[c.i0].world_from_cam;
    const Rigid3d& w1 = scene.frames[c.i1].world_from_cam;
    ScoredPair s;
    s.pair = c;
    s.m01 = ScoreDirection(*d0, cameras[c.i0], *d1, cameras[c.i1], RelativePose(w0, w1),
                           label_options, score_stride);
    s.m10 = ScoreDirection(*d1, cameras[c.i1], *d0, cameras[c.i0], RelativePose(w1, w0),
                           label_options, score_stride);
    results[k] = s;
  });
  std::vector<ScoredPair> out;
  out.reserve(results.size());
  int64_t errors = 0;
  for (auto& r : results) {
    if (r) {
      out.push_back(*r);
    } else {
      ++errors;
    }
  }
  if (errors && first_read_error != nullptr) *first_read_error = error_text;
  if (errors) (*drops)["score.read_error"] += errors;
  return out;
}

// ---- filters and sampling ------------------------------------------------------------

double PairOverlap(const ScoredPair& p, Aggregate aggregate) {
  return Combine(p.m01.overlap, p.m10.overlap, aggregate);
}

double PairOcclusion(const ScoredPair& p, Aggregate aggregate, OcclusionMetric metric) {
  return Combine(OcclusionOf(p.m01, metric), OcclusionOf(p.m10, metric), aggregate);
}

double PairVisibleOverlap(const ScoredPair& p, Aggregate aggregate) {
  return Combine(p.m01.consistent_overlap, p.m10.consistent_overlap, aggregate);
}

uint64_t SceneSeed(uint64_t recipe_seed, const std::string& scene_name) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a 64
  for (unsigned char ch : scene_name) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  uint64_t z = h ^ (recipe_seed + 0x9e3779b97f4a7c15ull);  // SplitMix64 finaliser
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

uint64_t UniformBelow(uint64_t n, std::mt19937_64* rng) {
  GT_ASSERT(n > 0);
  const uint64_t limit =
      std::numeric_limits<uint64_t>::max() - std::numeric_limits<uint64_t>::max() % n;
  uint64_t x;
  do {
    x = (*rng)();
  } while (x >= limit);
  return x % n;
}

void SeededShuffle(std::vector<size_t>* v, std::mt19937_64* rng) {
  for (size_t i = v->size(); i > 1; --i) {
    const size_t j = static_cast<size_t>(UniformBelow(i, rng));
    std::swap((*v)[i - 1], (*v)[j]);
  }
}

std::vector<size_t> TakeRoundRobin(const std::vector<std::vector<size_t>>& bins, size_t target,
                                   size_t max_rounds, std::mt19937_64* rng) {
  std::vector<size_t> taken, order;
  for (size_t round = 0; round < max_rounds && taken.size() < target; ++round) {
    order.clear();
    for (size_t b = 0; b < bins.size(); ++b) {
      if (round < bins[b].size()) order.push_back(b);
    }
    if (order.empty()) break;                                              // every bin is used up
    if (order.size() > target - taken.size()) SeededShuffle(&order, rng);  // a partial round
    for (size_t b : order) {
      if (taken.size() < target) taken.push_back(bins[b][round]);
    }
  }
  return taken;
}

std::vector<size_t> FilterAndSample(const std::vector<ScoredPair>& scored,
                                    const SelectionOptions& options, uint64_t scene_seed,
                                    DropCounts* drops) {
  std::vector<size_t> passed;
  int64_t by_overlap = 0, by_visible = 0, by_occlusion = 0;
  for (size_t k = 0; k < scored.size(); ++k) {
    const double ov = PairOverlap(scored[k], options.aggregate);
    if (!(ov >= options.overlap_lo && ov <= options.overlap_hi)) {
      ++by_overlap;
      continue;
    }
    const double vis = PairVisibleOverlap(scored[k], options.visible_aggregate);
    if (!(vis >= options.visible_overlap_lo && vis <= options.visible_overlap_hi)) {
      ++by_visible;
      continue;
    }
    const double oc = PairOcclusion(scored[k], options.aggregate, options.occlusion_metric);
    if (!(oc >= options.occlusion_lo && oc <= options.occlusion_hi)) {
      ++by_occlusion;
      continue;
    }
    passed.push_back(k);
  }
  if (by_overlap) (*drops)["filter.overlap"] += by_overlap;
  if (by_visible) (*drops)["filter.visible_overlap"] += by_visible;
  if (by_occlusion) (*drops)["filter.occlusion"] += by_occlusion;

  std::mt19937_64 rng(scene_seed);
  std::vector<size_t> chosen;
  const size_t quota =
      options.quota_per_scene > 0 ? static_cast<size_t>(options.quota_per_scene) : passed.size();
  if (options.balance_bins > 0 && !passed.empty()) {
    // Equal bins over [overlap_lo, overlap_hi]; each bin shuffled; round robin over bins
    // until the quota is met, each round visiting its bins in a seeded order (a quota met
    // part way through a round takes that round's last pairs from random bins: in a fixed
    // order they all came from the lowest-overlap bins). Without a quota every bin is capped
    // at the smallest non-empty bin's size.
    const int nb = options.balance_bins;
    std::vector<std::vector<size_t>> bins(nb);
    const double width = options.overlap_hi - options.overlap_lo;
    for (size_t k : passed) {
      const double ov = PairOverlap(scored[k], options.aggregate);
      int b = width > 0 ? static_cast<int>((ov - options.overlap_lo) / width * nb) : 0;
      bins[std::clamp(b, 0, nb - 1)].push_back(k);
    }
    size_t smallest = passed.size();
    for (auto& bin : bins) {
      SeededShuffle(&bin, &rng);
      if (!bin.empty()) smallest = std::min(smallest, bin.size());
    }
    const size_t cap = options.quota_per_scene > 0 ? passed.size() : smallest;
    chosen = TakeRoundRobin(bins, std::min(quota, passed.size()), cap, &rng);
    const int64_t balanced_out = static_cast<int64_t>(passed.size() - chosen.size());
    if (balanced_out) {
      // Attribute the drop to balancing, or to the quota when the quota alone was binding.
      (*drops)[options.quota_per_scene > 0 ? "sample.quota" : "sample.balance"] += balanced_out;
    }
  } else if (passed.size() > quota) {
    chosen = passed;
    SeededShuffle(&chosen, &rng);
    chosen.resize(quota);
    (*drops)["sample.quota"] += static_cast<int64_t>(passed.size() - quota);
  } else {
    chosen = passed;
  }
  std::sort(chosen.begin(), chosen.end(), [&](size_t a, size_t b) {
    const auto& pa = scored[a].pair;
    const auto& pb = scored[b].pair;
    return pa.i0 != pb.i0 ? pa.i0 < pb.i0 : pa.i1 < pb.i1;
  });
  return chosen;
}

bool PruningOptions::Check(std::string* error) const {
  if (!(max_distance_m >= 0))
    return *error = "selection.pruning.max_distance_m: expected >= 0", false;
  if (!(max_view_angle_deg >= 0 && max_view_angle_deg <= 180)) {
    return *error = "selection.pruning.max_view_angle_deg: expected a number in [0, 180]", false;
  }
  return true;
}

bool SelectionOptions::Check(std::string* error) const {
  auto range_ok = [](double lo, double hi) { return 0 <= lo && lo <= hi && hi <= 1; };
  if (max_frame_gap < 0) return *error = "selection.max_frame_gap: expected an integer >= 0", false;
  if (!pruning.Check(error)) return false;
  if (score_stride < 1) return *error = "selection.score_stride: expected an integer >= 1", false;
  if (!range_ok(overlap_lo, overlap_hi)) {
    return *error = "selection.overlap: expected [lo, hi] with 0 <= lo <= hi <= 1", false;
  }
  if (!range_ok(visible_overlap_lo, visible_overlap_hi)) {
    return *error = "selection.visible_overlap: expected [lo, hi] with 0 <= lo <= hi <= 1", false;
  }
  if (!range_ok(occlusion_lo, occlusion_hi)) {
    return *error = "selection.occlusion: expected [lo, hi] with 0 <= lo <= hi <= 1", false;
  }
  if (quota_per_scene < 0) return *error = "selection.quota_per_scene: expected >= 0", false;
  if (balance_bins < 0) return *error = "selection.balance_bins: expected >= 0", false;
  if (!import_pairs.path.empty() && import_pairs.format != "loftr-npz" &&
      import_pairs.format != "loftr-megadepth") {
    return *error = "selection.import_pairs.format: expected loftr-npz or loftr-megadepth", false;
  }
  return true;
}

}  // namespace gt::pairs

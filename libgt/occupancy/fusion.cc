// Fusion (fusion.h): own OctoMap-equivalent ray casting into a VoxelMap (voxel_map.h), or
// OctoMap's insertPointCloud as the reference engine. PCL and OctoMap are used only here.
#include "libgt/occupancy/fusion.h"

// PCL's filters are compiled here from its template headers (VoxelGrid and
// StatisticalOutlierRemoval of PointXYZ, with their k-d tree search) instead of being
// loaded from libpcl_filters: that library and its dependencies (sample consensus,
// search, k-d tree, octree) hold ~56000 symbol relocations, dynamic loading at every start
// of occgt (the start-up row of docs/PERFORMANCE.md, "Threads and tasks"). Only
// libpcl_common is linked.
#define PCL_NO_PRECOMPILE
#include <fcntl.h>
#include <octomap/OcTree.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <numeric>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/occupancy/voxel_map.h"

namespace gt::occupancy {

// Voxel indices accepted before insertion: OctoMap's checked range is [-2^15, 2^15); one
// voxel of margin on each side keeps rounding at the border harmless.
constexpr int64_t kMinSafeIndex = -32767;
constexpr int64_t kMaxSafeIndex = 32766;
constexpr int kKeyOffset = 32768;
// Voxels from the world origin that a frame's reach must fit in (KeyRangeHalfExtentM): the
// safe indices above less one more voxel, so that points within it, rounded to float, and
// the rays to them stay inside [kMinSafeIndex, kMaxSafeIndex].
constexpr double kReachVoxels = 32766.0;

// The map lives in one of two forms, the other built on first use: own engine -> VoxelMap
// (octree built for SaveBinary / NumLeafNodes); OctoMap engine -> the OcTree OctoMap's
// insertPointCloud built (voxel store built for binning and counts).
struct OccupancyMap::Impl {
  bool octomap_engine = false;
  FusionStats stats;
  std::unique_ptr<VoxelMap> voxels;
  std::unique_ptr<octomap::OcTree> tree;
  std::once_flag voxels_once, tree_once;

  double resolution_m() const { return voxels ? voxels->voxel_m() : tree->getResolution(); }
  const VoxelMap& Voxels();
  const octomap::OcTree& Tree();
};

namespace {

bool InsideKeyRange(const Eigen::Vector3d& p, double inv_res) {
  for (int a = 0; a < 3; ++a) {
    const double s = std::floor(p[a] * inv_res);
    if (!(s >= kMinSafeIndex && s <= kMaxSafeIndex)) return false;  // also rejects NaN
  }
  return true;
}

Eigen::Vector3i IndexOf(const Eigen::Vector3d& p, double inv_res) {
  return Eigen::Vector3i(static_cast<int>(std::floor(p.x() * inv_res)),
                         static_cast<int>(std::floor(p.y() * inv_res)),
                         static_cast<int>(std::floor(p.z() * inv_res)));
}

// Own bucketing: sort point indices by voxel, average each run (double accumulation).
std::vector<Eigen::Vector3f> BucketCentroids(const std::vector<Eigen::Vector3f>& points,
                                             double leaf_m) {
  const double inv = 1.0 / leaf_m;
  struct Item {
    int64_t ix, iy, iz;
    uint32_t i;
  };
  std::vector<Item> items(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    items[i] = {static_cast<int64_t>(std::floor(points[i].x() * inv)),
                static_cast<int64_t>(std::floor(points[i].y() * inv)),
                static_cast<int64_t>(std::floor(points[i].z() * inv)), static_cast<uint32_t>(i)};
  }
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    if (a.iz != b.iz) return a.iz < b.iz;
    if (a.iy != b.iy) return a.iy < b.iy;
    if (a.ix != b.ix) return a.ix < b.ix;
    return a.i < b.i;
  });
  std::vector<Eigen::Vector3f> out;
  for (size_t s = 0; s < items.size();) {
    size_t e = s;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    while (e < items.size() && items[e].ix == items[s].ix && items[e].iy == items[s].iy &&
           items[e].iz == items[s].iz) {
      sum += points[items[e].i].cast<double>();
      ++e;
    }
    out.push_back((sum / static_cast<double>(e - s)).cast<float>());
    s = e;
  }
  return out;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr ToPcl(const std::vector<Eigen::Vector3f>& points) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    (*cloud)[i] = pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z());
  }
  cloud->width = static_cast<uint32_t>(points.size());
  cloud->height = 1;
  cloud->is_dense = true;
  return cloud;
}

std::vector<Eigen::Vector3f> FromPcl(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  std::vector<Eigen::Vector3f> out(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) out[i] = {cloud[i].x, cloud[i].y, cloud[i].z};
  return out;
}

// max_a |c[a]| + reach_m: the half extent a frame needs around the world origin.
double NeededHalfExtentM(const Eigen::Vector3d& c, double reach_m) {
  return std::max({std::abs(c.x()), std::abs(c.y()), std::abs(c.z())}) + reach_m;
}

// %.3g of a value; Up: the smallest 3-significant-digit value >= v (so that a smallest voxel
// size printed works when given back).
std::string Significant3(double v) {
  if (v == 0) v = 0.0;  // no "-0"
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}
std::string Significant3Up(double v) {
  if (!(v > 0) || !std::isfinite(v)) return Significant3(v);
  std::string text = Significant3(v);
  if (std::strtod(text.c_str(), nullptr) >= v) return text;
  const double step = std::pow(10.0, std::floor(std::log10(v)) - 2);
  for (double up = (std::floor(v / step) + 1) * step;; up += step) {
    text = Significant3(up);
    if (std::strtod(text.c_str(), nullptr) >= v) return text;
  }
}

}  // namespace

double KeyRangeHalfExtentM(double voxel_m) { return kReachVoxels * voxel_m; }

double FusionReachM(const FusionInput& frame, const FusionOptions& options) {
  if (options.max_range_m > 0) return options.max_range_m;
  const Camera& c = frame.camera;
  const Eigen::Matrix3d R = frame.world_from_cam.linear();
  double longest = 0.0;  // |R * ray| per metre of planar depth, at the farthest corner
  for (const int u : {0, c.width - 1}) {
    for (const int v : {0, c.height - 1}) {
      const Eigen::Vector3d ray((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
      longest = std::max(longest, (R * ray).norm());
    }
  }
  return frame.max_depth_m * longest;
}

double MinVoxelSizeM(const Eigen::Vector3d& camera_centre, double reach_m) {
  const double needed = NeededHalfExtentM(camera_centre, reach_m);
  if (!std::isfinite(needed)) return std::numeric_limits<double>::infinity();
  if (needed <= 0) return 0.0;
  const double inf = std::numeric_limits<double>::infinity();
  double v = needed / kReachVoxels;
  while (KeyRangeHalfExtentM(v) < needed) v = std::nextafter(v, inf);
  while (KeyRangeHalfExtentM(std::nextafter(v, 0.0)) >= needed) v = std::nextafter(v, 0.0);
  return v;
}

void CheckKeyRange(const FusionInput& frame, const FusionOptions& options,
                   const std::string& frame_name) {
  const Eigen::Vector3d c = frame.world_from_cam.translation();
  const double reach_m = FusionReachM(frame, options);
  const double needed = NeededHalfExtentM(c, reach_m);
  const double held = KeyRangeHalfExtentM(options.voxel_m);
  if (held >= needed) return;  // false for NaN
  // The extents at 3 digits, or at as many as tell them apart (1638.3 against 1640.6 read
  // "holds +-1.64e+03 m ... needs +-1.64e+03 m").
  int digits = 3;
  const auto at = [](double v, int d) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", d, v == 0 ? 0.0 : v);
    return std::string(buf);
  };
  while (digits < 12 && at(held, digits) == at(needed, digits)) ++digits;
  std::ostringstream m;
  m << Significant3(options.voxel_m) << " m holds +-" << at(held, digits)
    << " m around the world origin (OctoMap's 16-bit keys); " << frame_name << "'s camera at ("
    << Significant3(c.x()) << ", " << Significant3(c.y()) << ", " << Significant3(c.z())
    << ") with ";
  if (options.max_range_m > 0) {
    m << "max_range_m " << Significant3(options.max_range_m);
  } else {
    m << "unlimited max_range_m and max_depth_m " << Significant3(frame.max_depth_m)
      << " (rays up to " << Significant3(reach_m) << " m through the image corners)";
  }
  m << " needs +-" << at(needed, digits) << " m";
  const double smallest = MinVoxelSizeM(c, reach_m);
  if (std::isfinite(smallest)) {
    m << ": use voxel_m >= " << Significant3Up(smallest);
    if (!(options.max_range_m > 0)) m << " or a max_range_m > 0";
  } else {
    m << ": no voxel size holds it";
    if (!(options.max_range_m > 0)) m << "; set a max_range_m > 0";
  }
  throw InputError("voxel_m", m.str());
}

bool FusionOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) return fail("voxel_m must be > 0");
  if (!std::isfinite(max_range_m)) return fail("max_range_m must be finite (<= 0: unlimited)");
  if (outlier_k < 1) return fail("outlier_k must be >= 1");
  if (!(outlier_stddev > 0.0) || !std::isfinite(outlier_stddev))
    return fail("outlier_stddev must be > 0");
  if (scope == FusionScope::kWindow && window < 1) return fail("window scope needs window >= 1");
  if (scope == FusionScope::kScene && scene_stride < 1)
    return fail("scene scope needs scene_stride >= 1");
  return true;
}

void ParseFusionScope(const std::string& text, FusionOptions* options) {
  auto parse_count = [&](const std::string& digits) {
    if (digits.empty() || digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw InputError("--scope",
                       "expected pair, window:N or scene:S with N, S >= 1, got '" + text + "'");
    const int n = std::stoi(digits);
    if (n < 1) throw InputError("--scope", "N and S must be >= 1, got '" + text + "'");
    return n;
  };
  if (text == "pair") {
    options->scope = FusionScope::kPair;
  } else if (text.rfind("window:", 0) == 0) {
    options->scope = FusionScope::kWindow;
    options->window = parse_count(text.substr(7));
  } else if (text.rfind("scene:", 0) == 0) {
    options->scope = FusionScope::kScene;
    options->scene_stride = parse_count(text.substr(6));
  } else {
    throw InputError("--scope", "expected pair, window:N or scene:S, got '" + text + "'");
  }
}

std::string FusionScopeName(const FusionOptions& options) {
  switch (options.scope) {
    case FusionScope::kPair:
      return "pair";
    case FusionScope::kWindow:
      return "window:" + std::to_string(options.window);
    case FusionScope::kScene:
      return "scene:" + std::to_string(options.scene_stride);
  }
  return "pair";
}

std::vector<size_t> ScopeFrameIndices(const Scene& scene, size_t i0, size_t i1,
                                      const FusionOptions& options, std::vector<size_t>* unusable) {
  const size_t n = scene.frames.size();
  if (i0 >= n || i1 >= n) throw InputError("--frames", "frame index outside the scene");
  if (unusable != nullptr) unusable->clear();
  std::vector<size_t> out;
  size_t usable = 0;  // usable frames before i
  for (size_t i = 0; i < n; ++i) {
    bool take = false;
    switch (options.scope) {
      case FusionScope::kPair:
        take = (i == i0 || i == i1);
        break;
      case FusionScope::kWindow: {
        const auto dist = [](size_t a, size_t b) { return a > b ? a - b : b - a; };
        const size_t w = static_cast<size_t>(std::max(options.window, 0));
        take = dist(i, i0) <= w || dist(i, i1) <= w;
        break;
      }
      case FusionScope::kScene:
        take = options.scene_stride > 0 && usable % static_cast<size_t>(options.scene_stride) == 0;
        break;
    }
    if (!scene.frames[i].usable) {
      // A scene scope's stride counts usable frames: every unusable one is left out of it.
      if (unusable != nullptr && (take || options.scope == FusionScope::kScene)) {
        unusable->push_back(i);
      }
      continue;
    }
    ++usable;
    if (take) out.push_back(i);
  }
  return out;
}

namespace {

// BackProjectValid, also giving the bounding box of the points (lo > hi when there are none).
std::vector<Eigen::Vector3f> BackProjectWithBounds(const FusionInput& frame, Eigen::Vector3f* lo,
                                                   Eigen::Vector3f* hi) {
  GT_ASSERT(frame.depth != nullptr);
  const DepthImage& d = *frame.depth;
  const Camera& c = frame.camera;
  const Eigen::Matrix3d R = frame.world_from_cam.linear();
  const Eigen::Vector3d t = frame.world_from_cam.translation();
  // The same arithmetic per point as (R * p + t) with p = ((u - cx) / fx * z, (v - cy) / fy * z,
  // z), with the per-column factor computed once and no growth checks per point.
  std::vector<double> x_of_u(d.width);
  for (int u = 0; u < d.width; ++u) x_of_u[u] = (u - c.cx) / c.fx;
  std::vector<Eigen::Vector3f> out(d.values_m.size());
  size_t n = 0;
  Eigen::Vector3f box_lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f box_hi = -box_lo;
  for (int v = 0; v < d.height; ++v) {
    const double y = (v - c.cy) / c.fy;
    const float* row = &d.values_m[static_cast<size_t>(v) * d.width];
    for (int u = 0; u < d.width; ++u) {
      const float z = row[u];
      if (!IsValidDepth(z, frame.min_depth_m, frame.max_depth_m)) continue;  // before transform
      const Eigen::Vector3d p_in_cam(x_of_u[u] * z, y * z, z);
      const Eigen::Vector3f p = (R * p_in_cam + t).cast<float>();
      out[n++] = p;
      box_lo = box_lo.cwiseMin(p);
      box_hi = box_hi.cwiseMax(p);
    }
  }
  out.resize(n);
  *lo = box_lo;
  *hi = box_hi;
  return out;
}

}  // namespace

std::vector<Eigen::Vector3f> BackProjectValid(const FusionInput& frame) {
  Eigen::Vector3f lo, hi;
  return BackProjectWithBounds(frame, &lo, &hi);
}

std::vector<Eigen::Vector3f> DownsampleVoxelCentroids(const std::vector<Eigen::Vector3f>& points,
                                                      double leaf_m, bool* used_fallback) {
  GT_ASSERT(leaf_m > 0.0);
  if (used_fallback) *used_fallback = false;
  if (points.empty()) return {};
  // pcl::VoxelGrid's own test: (dx * dy * dz) > INT32_MAX makes it warn and return the input
  // unfiltered. Replicate it (with a factor 2 of margin for float rounding) and bucket
  // ourselves instead.
  Eigen::Vector3f lo = points[0], hi = points[0];
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double inv = 1.0 / leaf_m;
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) cells *= std::floor((hi[a] - lo[a]) * inv) + 2.0;
  if (cells > static_cast<double>(std::numeric_limits<int32_t>::max()) / 2.0) {
    if (used_fallback) *used_fallback = true;
    return BucketCentroids(points, leaf_m);
  }
  auto cloud = ToPcl(points);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(cloud);
  const float leaf = static_cast<float>(leaf_m);
  grid.setLeafSize(leaf, leaf, leaf);
  pcl::PointCloud<pcl::PointXYZ> filtered;
  grid.filter(filtered);
  return FromPcl(filtered);
}

namespace {

LogOddsModel ModelOf(const octomap::OcTree& tree) {
  LogOddsModel m;
  m.hit = tree.getProbHitLog();
  m.miss = tree.getProbMissLog();
  m.clamp_min = tree.getClampingThresMinLog();
  m.clamp_max = tree.getClampingThresMaxLog();
  m.occupied_threshold = tree.getOccupancyThresLog();
  return m;
}

// OctoMap's defaults (hit 0.7, miss 0.4, clamping 0.1192 / 0.971, threshold 0.5), read from
// a default-constructed tree so the numbers are OctoMap's own floats.
const LogOddsModel& DefaultModel() {
  static const LogOddsModel model = ModelOf(octomap::OcTree(0.1));
  return model;
}

// Octree holding exactly the voxel log-odds of `voxels` (then pruned, inner nodes updated):
// the same tree OctoMap's own insertion builds, since a fully pruned tree depends only on its
// leaves' values.
std::unique_ptr<octomap::OcTree> ToOctree(const VoxelMap& voxels) {
  auto tree = std::make_unique<octomap::OcTree>(voxels.voxel_m());
  for (int32_t b = 0; b < voxels.num_blocks(); ++b) {
    const auto& c = voxels.block_coord(b);
    const float* l = voxels.log_odds(b);
    for (int i = 0; i < VoxelMap::kBlockVoxels; ++i) {
      if (std::isnan(l[i])) continue;
      const int ix = (c[0] * VoxelMap::kSide) + (i & (VoxelMap::kSide - 1));
      const int iy = (c[1] * VoxelMap::kSide) + ((i >> VoxelMap::kShift) & (VoxelMap::kSide - 1));
      const int iz = (c[2] * VoxelMap::kSide) + (i >> (2 * VoxelMap::kShift));
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(ix + kKeyOffset),
                                   static_cast<octomap::key_type>(iy + kKeyOffset),
                                   static_cast<octomap::key_type>(iz + kKeyOffset));
      tree->setNodeValue(key, l[i], /*lazy_eval=*/true);
    }
  }
  tree->updateInnerOccupancy();
  tree->prune();
  return tree;
}

// Voxel store of every finest-resolution voxel of the tree (pruned leaves expanded).
std::unique_ptr<VoxelMap> FromOctree(const octomap::OcTree& tree) {
  auto voxels = std::make_unique<VoxelMap>(tree.getResolution(), ModelOf(tree));
  const unsigned depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int side = 1 << (depth - it.getDepth());
    const octomap::OcTreeKey k0 = it.getIndexKey();
    const float l = it->getLogOdds();
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x)
          voxels->SetLogOdds(k0[0] - kKeyOffset + x, k0[1] - kKeyOffset + y, k0[2] - kKeyOffset + z,
                             l);
  }
  voxels->Finalize();
  return voxels;
}

}  // namespace

const VoxelMap& OccupancyMap::Impl::Voxels() {
  std::call_once(voxels_once, [this] {
    if (!voxels) voxels = FromOctree(*tree);
  });
  return *voxels;
}

const octomap::OcTree& OccupancyMap::Impl::Tree() {
  std::call_once(tree_once, [this] {
    if (!tree) tree = ToOctree(*voxels);
  });
  return *tree;
}

OccupancyMap::OccupancyMap() : impl_(std::make_unique<Impl>()) {
  impl_->voxels = std::make_unique<VoxelMap>(FusionOptions().voxel_m, DefaultModel());
  impl_->voxels->Finalize();
}
OccupancyMap::OccupancyMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;
OccupancyMap::~OccupancyMap() = default;

double OccupancyMap::resolution_m() const { return impl_->resolution_m(); }
int64_t OccupancyMap::NumLeafNodes() const {
  return static_cast<int64_t>(impl_->Tree().getNumLeafNodes());
}
int64_t OccupancyMap::NumOccupiedVoxels() const { return impl_->Voxels().num_occupied(); }
int64_t OccupancyMap::NumFreeVoxels() const { return impl_->Voxels().num_free(); }
const VoxelMap& OccupancyMap::voxels() const { return impl_->Voxels(); }

int OccupancyMap::StateAt(const Eigen::Vector3d& p_in_world) const {
  const double inv_res = 1.0 / impl_->resolution_m();
  if (!InsideKeyRange(p_in_world, inv_res)) return -1;
  if (impl_->octomap_engine) {  // the fused tree itself (the benchmark's naive baseline)
    const octomap::OcTree& tree = impl_->Tree();
    const octomap::OcTreeNode* node = tree.search(p_in_world.x(), p_in_world.y(), p_in_world.z());
    if (node == nullptr) return -1;
    return tree.isNodeOccupied(node) ? 1 : 0;
  }
  const Eigen::Vector3i i = IndexOf(p_in_world, inv_res);
  return impl_->Voxels().StateAt(i.x(), i.y(), i.z());
}

const FusionStats& OccupancyMap::stats() const { return impl_->stats; }

bool OccupancyMap::KnownIndexBounds(Eigen::Vector3i* min_index, Eigen::Vector3i* max_index) const {
  return impl_->Voxels().Bounds(min_index, max_index);
}

VoxelBlock OccupancyMap::ExtractBlock(const Eigen::Vector3i& min_index_in,
                                      const Eigen::Vector3i& max_index_in) const {
  const VoxelMap& vm = impl_->Voxels();
  VoxelBlock block;
  block.voxel_m = vm.voxel_m();
  const Eigen::Vector3i lo = min_index_in.cwiseMax(Eigen::Vector3i::Constant(-kKeyOffset));
  const Eigen::Vector3i hi = max_index_in.cwiseMin(Eigen::Vector3i::Constant(kKeyOffset - 1));
  if ((hi.array() < lo.array()).any()) return block;
  block.min_index = lo;
  block.size = hi - lo + Eigen::Vector3i::Ones();
  block.state.assign(static_cast<size_t>(block.size.x()) * block.size.y() * block.size.z(),
                     VoxelBlock::kUnknown);
  const int s = VoxelMap::kShift;
  for (int bz = lo.z() >> s; bz <= hi.z() >> s; ++bz) {
    for (int by = lo.y() >> s; by <= hi.y() >> s; ++by) {
      for (int bx = lo.x() >> s; bx <= hi.x() >> s; ++bx) {
        const int32_t b = vm.FindBlock(bx, by, bz);
        if (b < 0) continue;
        const int8_t* st = vm.states(b);
        for (int z = std::max(bz * (1 << s), lo.z()); z <= std::min(bz * (1 << s) + 7, hi.z());
             ++z) {
          for (int y = std::max(by * (1 << s), lo.y()); y <= std::min(by * (1 << s) + 7, hi.y());
               ++y) {
            int8_t* row =
                &block.state[(static_cast<size_t>(z - lo.z()) * block.size.y() + (y - lo.y())) *
                             block.size.x()];
            for (int x = std::max(bx * (1 << s), lo.x()); x <= std::min(bx * (1 << s) + 7, hi.x());
                 ++x)
              row[x - lo.x()] = st[VoxelMap::Local(x, y, z)];
          }
        }
      }
    }
  }
  return block;
}

void OccupancyMap::SaveBinary(const std::string& path) const {
  std::ostringstream out;
  {
    // Debian's liboctomap is built with its debug output on: writeBinaryConst fprintf's
    // " done." to stderr, a stray line among a command's errors. stderr goes to /dev/null
    // while the map is encoded (in memory; nothing else of the process prints meanwhile).
    struct QuietStderr {
      int saved = -1;
      QuietStderr() {
        std::fflush(stderr);
        const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
        if (null < 0) return;
        saved = ::dup(STDERR_FILENO);
        if (saved >= 0) ::dup2(null, STDERR_FILENO);
        ::close(null);
      }
      ~QuietStderr() {
        std::fflush(stderr);
        if (saved < 0) return;
        ::dup2(saved, STDERR_FILENO);
        ::close(saved);
      }
    } quiet;
    if (!impl_->Tree().writeBinaryConst(out))
      throw InputError(path, "OctoMap could not encode the map");
  }
  gt::io::WriteFileAtomic(path, out.str());
}

OccupancyMap FuseOccupancy(const std::vector<FusionInput>& frames, const FusionOptions& options) {
  std::string why;
  GT_ASSERT_MSG(options.Check(&why), why);
  auto impl = std::make_unique<OccupancyMap::Impl>();
  const bool octomap_engine = options.engine == FusionEngine::kOctomap;
  impl->octomap_engine = octomap_engine;
  if (octomap_engine) {
    impl->tree = std::make_unique<octomap::OcTree>(options.voxel_m);
  } else {
    impl->voxels = std::make_unique<VoxelMap>(options.voxel_m, DefaultModel());
  }
  // Every frame is checked before any fusion work (a voxel size too small for the range is
  // refused at once, not after fusing the frames before it).
  for (size_t f = 0; f < frames.size(); ++f) {
    const FusionInput& in = frames[f];
    const std::string where = "frame " + std::to_string(f);
    if (in.depth == nullptr) throw InputError(where, "no depth map");
    if (in.depth->width != in.camera.width || in.depth->height != in.camera.height)
      throw InputError(where, "depth size " + std::to_string(in.depth->width) + "x" +
                                  std::to_string(in.depth->height) + " differs from camera " +
                                  std::to_string(in.camera.width) + "x" +
                                  std::to_string(in.camera.height));
    if (in.depth->values_m.size() != static_cast<size_t>(in.depth->width) * in.depth->height)
      throw InputError(where, "depth buffer size does not match width * height");
    CheckKeyRange(in, options, where);
  }
  const double inv_res = 1.0 / options.voxel_m;
  const double max_range = options.max_range_m > 0 ? options.max_range_m : -1.0;
  FusionStats& st = impl->stats;
  for (const FusionInput& in : frames) {
    const Eigen::Vector3d origin = in.world_from_cam.translation();
    ++st.frames;
    st.pixels += static_cast<int64_t>(in.depth->values_m.size());
    Eigen::Vector3f lo, hi;
    std::vector<Eigen::Vector3f> points = BackProjectWithBounds(in, &lo, &hi);
    st.invalid_pixels += static_cast<int64_t>(in.depth->values_m.size() - points.size());
    // Key-range clipping: a point whose voxel index would wrap in OctoMap is, when it lies
    // beyond max_range_m, moved along its ray to just past max_range_m (a ray beyond the
    // range marks free space up to the range and no hit, wherever its end: the same update),
    // and dropped otherwise (or when even that point is outside the key range).
    const size_t before = points.size();
    if (!points
             .empty()) {  // per point only when the cloud's box is not inside (floor is monotonic)
      if (!InsideKeyRange(lo.cast<double>(), inv_res) ||
          !InsideKeyRange(hi.cast<double>(), inv_res)) {
        const double past_range_m = max_range > 0 ? max_range + 0.5 * options.voxel_m : 0.0;
        size_t kept = 0;
        for (const Eigen::Vector3f& p : points) {
          Eigen::Vector3d q = p.cast<double>();
          if (!InsideKeyRange(q, inv_res)) {
            const double dist = (q - origin).norm();
            if (!(max_range > 0) || !(dist > past_range_m)) continue;
            q = origin + (q - origin) * (past_range_m / dist);
            if (!InsideKeyRange(q, inv_res)) continue;
          }
          points[kept++] = q.cast<float>();
        }
        points.resize(kept);
      }
    }
    st.out_of_key_range += static_cast<int64_t>(before - points.size());
    if (options.downsample) {
      bool fallback = false;
      points = DownsampleVoxelCentroids(points, options.voxel_m, &fallback);
      st.downsample_fallbacks += fallback ? 1 : 0;
    }
    st.after_downsample += static_cast<int64_t>(points.size());
    if (options.remove_outliers && points.size() > static_cast<size_t>(options.outlier_k)) {
      auto cloud = ToPcl(points);
      pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
      sor.setInputCloud(cloud);
      sor.setMeanK(options.outlier_k);
      sor.setStddevMulThresh(options.outlier_stddev);
      pcl::PointCloud<pcl::PointXYZ> kept;
      sor.filter(kept);
      st.outliers_removed += static_cast<int64_t>(points.size() - kept.size());
      points = FromPcl(kept);
    }
    st.inserted_points += static_cast<int64_t>(points.size());
    const Eigen::Vector3f origin_f = origin.cast<float>();  // OctoMap's point3d is float
    if (octomap_engine) {
      octomap::Pointcloud scan;
      scan.reserve(points.size());
      for (const auto& p : points) scan.push_back(p.x(), p.y(), p.z());
      impl->tree->insertPointCloud(scan, octomap::point3d(origin_f.x(), origin_f.y(), origin_f.z()),
                                   max_range, /*lazy_eval=*/false, options.discretize);
    } else {
      // The box of the points, when they are still the back-projected ones, spares InsertScan
      // a pass over them (a box that is not the points' own would only size its block cache
      // wrongly; a point outside it is still found through the hash).
      const bool box_current =
          points.size() == before && !options.downsample && !options.remove_outliers;
      impl->voxels->InsertScan(points, origin_f, max_range, options.discretize,
                               box_current && !points.empty() ? &lo : nullptr,
                               box_current && !points.empty() ? &hi : nullptr);
    }
  }
  if (impl->voxels) impl->voxels->Finalize();
  return OccupancyMap(std::move(impl));
}

}  // namespace gt::occupancy

// Frustum binning (frustum.h): exact 3-D DDA or bin-centre sampling over a dense block of
// voxel states extracted from the map once per camera, and the two_point target.
#include "libgt/occupancy/frustum.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libgt/core/error.h"

namespace gt::occupancy {

bool BinOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (num_bins < 1 || num_bins > 64) return fail("num_bins must be in 1..64");
  if (!(near_m > 0.0) || !std::isfinite(near_m)) return fail("near_m must be > 0");
  if (!(far_m > near_m) || !std::isfinite(far_m)) return fail("far_m must be > near_m");
  return true;
}

BinSpacing ParseBinSpacing(const std::string& text) {
  if (text == "linear") return BinSpacing::kLinear;
  if (text == "log") return BinSpacing::kLog;
  if (text == "inverse") return BinSpacing::kInverse;
  throw InputError("--spacing", "expected linear, log or inverse, got '" + text + "'");
}

Traversal ParseTraversal(const std::string& text) {
  if (text == "exact") return Traversal::kExact;
  if (text == "center") return Traversal::kCenter;
  throw InputError("--traversal", "expected exact or center, got '" + text + "'");
}

std::string BinSpacingName(BinSpacing spacing) {
  switch (spacing) {
    case BinSpacing::kLinear:
      return "linear";
    case BinSpacing::kLog:
      return "log";
    case BinSpacing::kInverse:
      return "inverse";
  }
  return "linear";
}

std::string TraversalName(Traversal traversal) {
  return traversal == Traversal::kCenter ? "center" : "exact";
}

std::vector<double> BinEdges(const BinOptions& o) {
  std::string why;
  GT_ASSERT_MSG(o.Check(&why), why);
  const int D = o.num_bins;
  std::vector<double> e(D + 1);
  for (int k = 0; k <= D; ++k) {
    const double f = static_cast<double>(k) / D;
    switch (o.spacing) {
      case BinSpacing::kLinear:
        e[k] = o.near_m + f * (o.far_m - o.near_m);
        break;
      case BinSpacing::kLog:
        e[k] = o.near_m * std::pow(o.far_m / o.near_m, f);
        break;
      case BinSpacing::kInverse:
        e[k] = 1.0 / (1.0 / o.near_m + f * (1.0 / o.far_m - 1.0 / o.near_m));
        break;
    }
  }
  e.front() = o.near_m;  // exact end points despite rounding
  e.back() = o.far_m;
  return e;
}

int BinOfDepth(const std::vector<double>& edges_m, double z_m) {
  if (!(z_m >= edges_m.front() && z_m < edges_m.back())) return -1;
  // Largest k with e_k <= z.
  const auto it = std::upper_bound(edges_m.begin(), edges_m.end(), z_m);
  return static_cast<int>(it - edges_m.begin()) - 1;
}

VolumeCounts CountBins(const FrustumVolume& volume) {
  VolumeCounts c;
  const int D = volume.num_bins();
  for (size_t i = 0; i < volume.occ.size(); ++i) {
    const int occ = __builtin_popcountll(volume.occ[i]);
    const int known = __builtin_popcountll(volume.known[i]);
    c.occupied += occ;
    c.free += known - occ;
    c.unknown += D - known;
  }
  return c;
}

std::vector<uint8_t> DenseVolume(const FrustumVolume& volume) {
  const int D = volume.num_bins();
  const size_t plane = static_cast<size_t>(volume.width) * volume.height;
  std::vector<uint8_t> dense(plane * D, 255);
  for (int k = 0; k < D; ++k) {
    const uint64_t bit = uint64_t{1} << k;
    uint8_t* out = &dense[plane * k];
    for (size_t i = 0; i < plane; ++i) {
      if (volume.known[i] & bit) out[i] = (volume.occ[i] & bit) ? 1 : 0;
    }
  }
  return dense;
}

namespace {

// Bits lo..hi inclusive (0 <= lo <= hi <= 63).
inline uint64_t BitRange(int lo, int hi) {
  const uint64_t upto_hi = (hi >= 63) ? ~uint64_t{0} : ((uint64_t{1} << (hi + 1)) - 1);
  return upto_hi & ~((uint64_t{1} << lo) - 1);
}

// Range [z_lo, z_hi] of planar depth for which o + z d lies inside the box [lo, hi]
// (world metres); false when empty.
bool ClipToBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
               const Eigen::Vector3d& hi, double* z_lo, double* z_hi) {
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < lo[a] || o[a] > hi[a]) return false;
      continue;
    }
    double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    *z_lo = std::max(*z_lo, t0);
    *z_hi = std::min(*z_hi, t1);
  }
  return *z_lo < *z_hi;
}

struct RayBits {
  uint64_t occ = 0;
  uint64_t known = 0;
};

// Exact: every voxel of the block crossed by o + z d, z in [z0, z1) (clipped to the block),
// contributes its state to every bin its z-interval overlaps.
RayBits TraverseExact(const VoxelBlock& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      const std::vector<double>& e) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  const double res = b.voxel_size_m;
  const Eigen::Vector3d lo = b.min_index.cast<double>() * res;
  const Eigen::Vector3d hi = (b.min_index + b.size).cast<double>() * res;
  double z = e.front(), z_end = e.back();
  if (!ClipToBox(o, d, lo, hi, &z, &z_end)) return r;
  // Start voxel (block-local), clamped against rounding at the box faces.
  const Eigen::Vector3d p = o + z * d;
  int idx[3], step[3];
  double t_max[3], t_delta[3];
  for (int a = 0; a < 3; ++a) {
    idx[a] = static_cast<int>(std::floor(p[a] / res)) - b.min_index[a];
    idx[a] = std::clamp(idx[a], 0, b.size[a] - 1);
    if (d[a] > 0) {
      step[a] = 1;
      t_max[a] = ((idx[a] + b.min_index[a] + 1) * res - o[a]) / d[a];
      t_delta[a] = res / d[a];
    } else if (d[a] < 0) {
      step[a] = -1;
      t_max[a] = ((idx[a] + b.min_index[a]) * res - o[a]) / d[a];
      t_delta[a] = -res / d[a];
    } else {
      step[a] = 0;
      t_max[a] = std::numeric_limits<double>::infinity();
      t_delta[a] = std::numeric_limits<double>::infinity();
    }
  }
  const size_t sx = 1, sy = static_cast<size_t>(b.size.x()),
               sz = static_cast<size_t>(b.size.x()) * b.size.y();
  const size_t strides[3] = {sx, sy, sz};
  size_t lin = idx[2] * sz + idx[1] * sy + idx[0];
  int k = 0;  // first bin whose upper edge is above the current z
  while (true) {
    const int a =
        (t_max[0] < t_max[1]) ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    const double z_exit = std::min(t_max[a], z_end);
    const int8_t s = b.state[lin];
    if (s != VoxelBlock::kUnknown && z_exit > z) {
      while (k < D - 1 && e[k + 1] <= z) ++k;
      int kk = k;
      while (kk < D - 1 && e[kk + 1] < z_exit) ++kk;
      const uint64_t m = BitRange(k, kk);
      r.known |= m;
      if (s == VoxelBlock::kOccupied) r.occ |= m;
    }
    if (t_max[a] >= z_end) break;
    z = t_max[a];
    idx[a] += step[a];
    if (idx[a] < 0 || idx[a] >= b.size[a]) break;
    lin = (step[a] > 0) ? lin + strides[a] : lin - strides[a];
    t_max[a] += t_delta[a];
  }
  return r;
}

// Center: only the voxel at each bin's centre depth.
RayBits TraverseCenter(const VoxelBlock& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       const std::vector<double>& e) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  const double inv = 1.0 / b.voxel_size_m;
  for (int k = 0; k < D; ++k) {
    const Eigen::Vector3d p = o + (0.5 * (e[k] + e[k + 1])) * d;
    int ix = static_cast<int>(std::floor(p.x() * inv)) - b.min_index.x();
    int iy = static_cast<int>(std::floor(p.y() * inv)) - b.min_index.y();
    int iz = static_cast<int>(std::floor(p.z() * inv)) - b.min_index.z();
    if (ix < 0 || iy < 0 || iz < 0 || ix >= b.size.x() || iy >= b.size.y() || iz >= b.size.z())
      continue;
    const int8_t s = b.at(ix, iy, iz);
    if (s == VoxelBlock::kUnknown) continue;
    r.known |= uint64_t{1} << k;
    if (s == VoxelBlock::kOccupied) r.occ |= uint64_t{1} << k;
  }
  return r;
}

}  // namespace

FrustumVolume ProjectToFrustum(const OccupancyMap& map, const Camera& camera_full_res,
                               const Rigid3d& world_from_cam, const BinOptions& options) {
  std::string why;
  GT_ASSERT_MSG(options.Check(&why), why);
  const Camera cam = camera_full_res.HalfGrid();
  FrustumVolume vol;
  vol.width = cam.width;
  vol.height = cam.height;
  vol.edges_m = BinEdges(options);
  const size_t n = static_cast<size_t>(vol.width) * vol.height;
  vol.occ.assign(n, 0);
  vol.known.assign(n, 0);
  Eigen::Vector3i map_lo, map_hi;
  if (n == 0 || !map.KnownIndexBounds(&map_lo, &map_hi)) return vol;

  // Bounding box of the frustum (rays through the extreme ray centres, near to far).
  const double res = map.resolution_m();
  const Eigen::Matrix3d R = world_from_cam.linear();
  const Eigen::Vector3d o = world_from_cam.translation();
  Eigen::Vector3d f_lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d f_hi = -f_lo;
  for (double u : {0.0, vol.width - 1.0}) {
    for (double v : {0.0, vol.height - 1.0}) {
      for (double z : {options.near_m, options.far_m}) {
        const Eigen::Vector3d p = R * cam.CamFromImg(u, v, z) + o;
        f_lo = f_lo.cwiseMin(p);
        f_hi = f_hi.cwiseMax(p);
      }
    }
  }
  Eigen::Vector3i lo, hi;
  for (int a = 0; a < 3; ++a) {
    // Clamp in double before converting: a far plane can be outside int range.
    const double l = std::clamp(std::floor(f_lo[a] / res) - 1, -1e9, 1e9);
    const double h = std::clamp(std::floor(f_hi[a] / res) + 1, -1e9, 1e9);
    lo[a] = std::max(static_cast<int>(l), map_lo[a]);
    hi[a] = std::min(static_cast<int>(h), map_hi[a]);
  }
  if ((hi.array() < lo.array()).any()) return vol;
  const VoxelBlock block = map.ExtractBlock(lo, hi);
  if (block.empty()) return vol;

  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      const Eigen::Vector3d d =
          R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const RayBits r = options.traversal == Traversal::kExact
                            ? TraverseExact(block, o, d, vol.edges_m)
                            : TraverseCenter(block, o, d, vol.edges_m);
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      vol.occ[i] = r.occ;
      vol.known[i] = r.known;
    }
  }
  return vol;
}

FrustumVolume TwoPointVolume(const FusionInput& self, const FusionInput& other,
                             const BinOptions& options) {
  std::string why;
  GT_ASSERT_MSG(options.Check(&why), why);
  GT_ASSERT(self.depth != nullptr && other.depth != nullptr);
  const Camera cam = self.camera.HalfGrid();
  FrustumVolume vol;
  vol.width = cam.width;
  vol.height = cam.height;
  vol.edges_m = BinEdges(options);
  const size_t n = static_cast<size_t>(vol.width) * vol.height;
  vol.occ.assign(n, 0);
  vol.known.assign(n, 0);
  std::vector<uint8_t> hit(n, 0);
  // Own depth at full-resolution pixel (2u, 2v).
  const DepthImage& ds = *self.depth;
  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      if (2 * u >= ds.width || 2 * v >= ds.height) continue;
      const float z = ds.at(2 * u, 2 * v);
      if (!IsValidDepth(z, self.min_depth_m, self.max_depth_m)) continue;
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      hit[i] = 1;
      const int k = BinOfDepth(vol.edges_m, z);
      if (k >= 0) vol.occ[i] |= uint64_t{1} << k;
    }
  }
  // The other view's points warped into self's half grid.
  const Rigid3d self_from_other = RelativePose(other.world_from_cam, self.world_from_cam);
  const DepthImage& dother = *other.depth;
  const Camera& co = other.camera;
  for (int v = 0; v < dother.height; ++v) {
    for (int u = 0; u < dother.width; ++u) {
      const float z = dother.at(u, v);
      if (!IsValidDepth(z, other.min_depth_m, other.max_depth_m)) continue;
      const Eigen::Vector3d p_in_self = self_from_other * co.CamFromImg(u, v, z);
      const auto x = cam.ImgFromCam(p_in_self);
      if (!x || !cam.InPixelArea(x->x(), x->y())) continue;
      const int uu = static_cast<int>(std::floor(x->x() + 0.5));
      const int vv = static_cast<int>(std::floor(x->y() + 0.5));
      const size_t i = static_cast<size_t>(vv) * vol.width + uu;
      hit[i] = 1;
      const int k = BinOfDepth(vol.edges_m, p_in_self.z());
      if (k >= 0) vol.occ[i] |= uint64_t{1} << k;
    }
  }
  const uint64_t all = BitRange(0, vol.num_bins() - 1);
  for (size_t i = 0; i < n; ++i) vol.known[i] = hit[i] ? all : 0;
  return vol;
}

}  // namespace gt::occupancy

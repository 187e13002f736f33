// Frustum binning (frustum.h): exact 3-D DDA or bin-centre sampling directly over the map's
// voxel store (voxel_map.h; uniform 8^3 blocks are crossed in one step), and the two_point
// target.
#include "libgt/occupancy/frustum.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libgt/core/error.h"
#include "libgt/occupancy/voxel_map.h"

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
    const double inv = 1.0 / d[a];
    double t0 = (lo[a] - o[a]) * inv, t1 = (hi[a] - o[a]) * inv;
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

// The map as the traversals see it: voxel store, block table over the frustum, and the box
// (voxel indices and metres) outside which everything is unknown.
struct MapView {
  const VoxelMap* map;
  const BlockWindow* window;
  double res;
  Eigen::Vector3i lo, hi;      // inclusive voxel-index box
  Eigen::Vector3d lo_m, hi_m;  // the same box in metres
};

// Sets the bins overlapping the planar-depth interval [z0, z1) (empty: nothing). *k is a
// cursor, a bin with e_k <= every later z0 (z only grows and every later interval starts at
// or after z1); it is left at the last bin marked.
inline void MarkBins(const std::vector<double>& e, int num_bins, double z0, double z1,
                     bool occupied, int* k, RayBits* r) {
  if (!(z1 > z0)) return;
  while (*k < num_bins - 1 && e[*k + 1] <= z0) ++*k;
  int kk = *k;
  while (kk < num_bins - 1 && e[kk + 1] < z1) ++kk;
  const uint64_t m = BitRange(*k, kk);
  r->known |= m;
  if (occupied) r->occ |= m;
  *k = kk;  // e_kk < z1 <= every later z0
}

// Exact: every voxel crossed by o + z d, z in [e_0, e_D) (clipped to the box and to
// z_known_max, beyond which the caller guarantees that the ray meets no known voxel), contributes
// its state to every bin its z-interval overlaps. Two-level 3-D DDA (Amanatides & Woo 1987): over
// 8^3 blocks first; a block that is absent (all unknown) is skipped, a uniform one (all free /
// all occupied) contributes its whole z-interval at once, and only inside a mixed block are
// its voxels stepped through.
// Not inlined into the pixel loop of ProjectToFrustum: inlined there (next to TraverseCenter)
// the same code took ~20 % longer (tests/bench/occupancy_bench.cc, BM_ProjectExactBothCams
// against BM_ProjectExactReferenceBothCams, the same code compiled on its own).
__attribute__((noinline)) RayBits TraverseExact(const MapView& m, const Eigen::Vector3d& o,
                                                const Eigen::Vector3d& d,
                                                const std::vector<double>& e, double z_known_max) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  constexpr int S = VoxelMap::kShift, W = VoxelMap::kSide;
  double z = e.front(), z_end = std::min(e.back(), z_known_max);
  if (!(z < z_end) || !ClipToBox(o, d, m.lo_m, m.hi_m, &z, &z_end)) return r;
  const double res = m.res, inv_res = 1.0 / m.res, block_m = res * W;
  int step[3], bc[3], blo[3], bhi[3];
  double inv_d[3], t_next[3], t_delta[3], vox_step[3];  // block level; voxel parameter step
  const Eigen::Vector3d p = o + z * d;
  for (int a = 0; a < 3; ++a) {
    step[a] = d[a] > 0 ? 1 : (d[a] < 0 ? -1 : 0);
    inv_d[a] = step[a] != 0 ? 1.0 / d[a] : 0.0;
    blo[a] = m.lo[a] >> S;
    bhi[a] = m.hi[a] >> S;
    // Start block, clamped against rounding at the box faces.
    const int vi = std::clamp(static_cast<int>(std::floor(p[a] * inv_res)), m.lo[a], m.hi[a]);
    bc[a] = vi >> S;
    if (step[a] != 0) {
      t_next[a] = ((bc[a] + (step[a] > 0 ? 1 : 0)) * block_m - o[a]) * inv_d[a];
      t_delta[a] = block_m * std::abs(inv_d[a]);
      vox_step[a] = res * std::abs(inv_d[a]);
    } else {
      t_next[a] = t_delta[a] = vox_step[a] = std::numeric_limits<double>::infinity();
    }
  }
  int k = 0;
  while (true) {
    const int ax =
        (t_next[0] < t_next[1]) ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
    const double z_out = std::min(t_next[ax], z_end);  // the ray leaves this block at z_out
    const int32_t b = m.window->Find(bc[0], bc[1], bc[2]);
    if (b >= 0 && z_out > z) {
      const VoxelMap::Kind kind = m.map->kind(b);
      if (kind != VoxelMap::Kind::kMixed) {
        MarkBins(e, D, z, z_out, kind == VoxelMap::Kind::kAllOccupied, &k, &r);
      } else {
        // Voxel DDA inside the block, from z to z_out, on block-local coordinates (0..7) and
        // the linear index into the block's states (x fastest).
        const int8_t* states = m.map->states(b);
        const double zm = z + std::min(1e-6, 0.5 * (z_out - z));  // just inside the block
        int lx, ly, lz;
        double tx, ty, tz;
        {
          int l3[3];
          double t3[3];
          for (int a = 0; a < 3; ++a) {
            const int base = bc[a] * (1 << S);  // not bc << S: negative coordinates
            const int i = std::clamp(static_cast<int>(std::floor((o[a] + zm * d[a]) * inv_res)),
                                     base, base + W - 1);
            l3[a] = i - base;
            t3[a] = step[a] != 0 ? ((i + (step[a] > 0 ? 1 : 0)) * res - o[a]) * inv_d[a]
                                 : std::numeric_limits<double>::infinity();
          }
          lx = l3[0], ly = l3[1], lz = l3[2];
          tx = t3[0], ty = t3[1], tz = t3[2];
        }
        const double dx = vox_step[0], dy = vox_step[1], dz = vox_step[2];
        int lin = (lz << (2 * S)) | (ly << S) | lx;
        double zv = z;
        double edge = e[k + 1];  // upper edge of the cursor's bin
        bool to_block_loop = false;
        while (true) {
          const double t = std::min(std::min(tx, ty), tz);
          const double zx = std::min(t, z_end);
          const int8_t s = states[lin];
          if (s != VoxelMap::kUnknown && zx > zv) {
            if (zx <= edge) {  // the whole voxel within bin k (zv >= e_k, zv < zx)
              const uint64_t bit = uint64_t{1} << k;
              r.known |= bit;
              if (s == VoxelMap::kOccupied) r.occ |= bit;
            } else if (zv < edge && zx <= e[k + 2]) {  // in bins k and k + 1 (k + 1 < D,
              const uint64_t bits = uint64_t{3} << k;  // since zx > e_{k+1} and zx < e_D)
              r.known |= bits;
              if (s == VoxelMap::kOccupied) r.occ |= bits;
              ++k;  // e_{k+1} < zx <= every later zv
              edge = e[k + 1];
            } else {
              MarkBins(e, D, zv, zx, s == VoxelMap::kOccupied, &k, &r);
              edge = e[k + 1];
            }
          }
          if (t >= z_end) return r;
          zv = std::max(zv, t);
          int a, l;
          if (tx == t) {
            a = 0, l = (lx += step[0]);
            tx += dx;
          } else if (ty == t) {
            a = 1, l = (ly += step[1]);
            ty += dy;
          } else {
            a = 2, l = (lz += step[2]);
            tz += dz;
          }
          if (static_cast<unsigned>(l) < static_cast<unsigned>(W)) {
            lin += step[a] * (a == 0 ? 1 : (a == 1 ? W : W * W));
            continue;
          }
          // Entered the next block along a: keep the block-level DDA in step.
          bc[a] += step[a];
          t_next[a] += t_delta[a];
          z = zv;
          if (bc[a] < blo[a] || bc[a] > bhi[a]) return r;
          const int32_t nb = m.window->Find(bc[0], bc[1], bc[2]);
          if (nb < 0 || m.map->kind(nb) != VoxelMap::Kind::kMixed) {
            to_block_loop = true;  // uniform or absent: crossed whole by the block loop
            break;
          }
          states = m.map->states(nb);  // mixed again: carry on voxel by voxel
          (a == 0 ? lx : (a == 1 ? ly : lz)) = step[a] > 0 ? 0 : W - 1;
          lin = (lz << (2 * S)) | (ly << S) | lx;
        }
        if (to_block_loop) continue;
      }
    }
    if (t_next[ax] >= z_end) break;
    z = std::max(z, t_next[ax]);
    bc[ax] += step[ax];
    if (bc[ax] < blo[ax] || bc[ax] > bhi[ax]) break;
    t_next[ax] += t_delta[ax];
  }
  return r;
}

// Center: only the voxel at each bin's centre depth.
RayBits TraverseCenter(const MapView& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       const std::vector<double>& e) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  double z_lo = e.front(), z_hi = e.back();
  if (!ClipToBox(o, d, m.lo_m, m.hi_m, &z_lo, &z_hi)) return r;
  const double inv = 1.0 / m.res;
  constexpr int S = VoxelMap::kShift;
  for (int k = 0; k < D; ++k) {
    const double zc = 0.5 * (e[k] + e[k + 1]);
    if (zc < z_lo) continue;
    if (zc > z_hi) break;
    const Eigen::Vector3d p = o + zc * d;
    const int ix = static_cast<int>(std::floor(p.x() * inv));
    const int iy = static_cast<int>(std::floor(p.y() * inv));
    const int iz = static_cast<int>(std::floor(p.z() * inv));
    if (ix < m.lo.x() || iy < m.lo.y() || iz < m.lo.z() || ix > m.hi.x() || iy > m.hi.y() ||
        iz > m.hi.z())
      continue;
    const int32_t b = m.window->Find(ix >> S, iy >> S, iz >> S);
    if (b < 0) continue;
    const int8_t s = m.map->states(b)[VoxelMap::Local(ix, iy, iz)];
    if (s == VoxelMap::kUnknown) continue;
    r.known |= uint64_t{1} << k;
    if (s == VoxelMap::kOccupied) r.occ |= uint64_t{1} << k;
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
  const VoxelMap& voxels = map.voxels();
  const Eigen::Vector3i block_lo(lo.x() >> VoxelMap::kShift, lo.y() >> VoxelMap::kShift,
                                 lo.z() >> VoxelMap::kShift);
  const Eigen::Vector3i block_hi(hi.x() >> VoxelMap::kShift, hi.y() >> VoxelMap::kShift,
                                 hi.z() >> VoxelMap::kShift);
  const BlockWindow window(voxels, block_lo, block_hi);
  const MapView view{&voxels,
                     &window,
                     res,
                     lo,
                     hi,
                     lo.cast<double>() * res,
                     (hi + Eigen::Vector3i::Ones()).cast<double>() * res};

  // Farthest planar depth of a block of the map seen through each tile of kTile x kTile rays:
  // a ray meets no known voxel beyond the largest camera z of the corners of the blocks whose
  // image covers it, so the exact walk stops there (plus one voxel against rounding) instead
  // of crossing absent blocks to the far plane or the box. Conservative: a block reaching
  // the camera plane (z <= 0 at a corner) counts for every tile; the bins do not change.
  constexpr int kTile = 8;
  const int tiles_w = (vol.width + kTile - 1) / kTile, tiles_h = (vol.height + kTile - 1) / kTile;
  std::vector<double> tile_far(static_cast<size_t>(tiles_w) * tiles_h,
                               -std::numeric_limits<double>::infinity());
  if (options.traversal == Traversal::kExact) {
    const Eigen::Matrix3d Rt = R.transpose();
    const double block_m = res * VoxelMap::kSide;
    double everywhere = -std::numeric_limits<double>::infinity();
    for (int32_t b = 0; b < voxels.num_blocks(); ++b) {
      const auto& c = voxels.block_coord(b);
      if (c[0] < block_lo.x() || c[1] < block_lo.y() || c[2] < block_lo.z() ||
          c[0] > block_hi.x() || c[1] > block_hi.y() || c[2] > block_hi.z())
        continue;  // outside the box every ray is clipped to
      double z_min = std::numeric_limits<double>::infinity(), z_max = -z_min;
      double u_min = z_min, u_max = -z_min, v_min = z_min, v_max = -z_min;
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d w((c[0] + (corner & 1)) * block_m,
                                (c[1] + ((corner >> 1) & 1)) * block_m,
                                (c[2] + (corner >> 2)) * block_m);
        const Eigen::Vector3d pc = Rt * (w - o);
        z_min = std::min(z_min, pc.z());
        z_max = std::max(z_max, pc.z());
        if (pc.z() > 0) {
          const double u = cam.fx * pc.x() / pc.z() + cam.cx, v = cam.fy * pc.y() / pc.z() + cam.cy;
          u_min = std::min(u_min, u), u_max = std::max(u_max, u);
          v_min = std::min(v_min, v), v_max = std::max(v_max, v);
        }
      }
      if (z_max <= 0) continue;  // behind the camera: rays have z >= near_m > 0
      if (z_min <= 1e-6) {       // reaches the camera plane: no bounded image
        everywhere = std::max(everywhere, z_max);
        continue;
      }
      // Rays (u, v) inside the image of the block (the hull of its corners), one ray margin.
      const double u0 = std::max(std::floor(u_min) - 1, 0.0),
                   u1 = std::min(std::ceil(u_max) + 1, vol.width - 1.0);
      const double v0 = std::max(std::floor(v_min) - 1, 0.0),
                   v1 = std::min(std::ceil(v_max) + 1, vol.height - 1.0);
      if (!(u0 <= u1 && v0 <= v1)) continue;
      for (int ty = static_cast<int>(v0) / kTile; ty <= static_cast<int>(v1) / kTile; ++ty)
        for (int tx = static_cast<int>(u0) / kTile; tx <= static_cast<int>(u1) / kTile; ++tx) {
          double& f = tile_far[static_cast<size_t>(ty) * tiles_w + tx];
          f = std::max(f, z_max);
        }
    }
    for (double& f : tile_far) f = std::max(f, everywhere) + res;
  }

  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      const Eigen::Vector3d d =
          R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const RayBits r =
          options.traversal == Traversal::kExact
              ? TraverseExact(view, o, d, vol.edges_m,
                              tile_far[static_cast<size_t>(v / kTile) * tiles_w + u / kTile])
              : TraverseCenter(view, o, d, vol.edges_m);
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

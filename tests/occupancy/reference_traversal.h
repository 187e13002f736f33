// Test-only reference: the exact frustum traversal as it was before the cell-skipping fast
// path (libgt/occupancy/frustum.cc at commit 70b19d6, copied verbatim apart from names): a
// two-level DDA over 8^3 blocks that walks every voxel of a mixed block. The fast path must
// give the same occ/known words bin for bin (tests/occupancy/traversal_test.cc).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/voxel_map.h"

namespace gt::occupancy::reference {

// Bits lo..hi inclusive (0 <= lo <= hi <= 63).
inline uint64_t BitRange(int lo, int hi) {
  const uint64_t upto_hi = (hi >= 63) ? ~uint64_t{0} : ((uint64_t{1} << (hi + 1)) - 1);
  return upto_hi & ~((uint64_t{1} << lo) - 1);
}

// Range [z_lo, z_hi] of planar depth for which o + z d lies inside the box [lo, hi]
// (world metres); false when empty.
inline bool ClipToBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
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

// Sets the bins overlapping the planar-depth interval [z0, z1) (empty: nothing); *k is the
// first bin whose upper edge lies above the previous interval (a cursor: z only grows).
inline void MarkBins(const std::vector<double>& e, int num_bins, double z0, double z1,
                     bool occupied, int* k, RayBits* r) {
  if (!(z1 > z0)) return;
  while (*k < num_bins - 1 && e[*k + 1] <= z0) ++*k;
  int kk = *k;
  while (kk < num_bins - 1 && e[kk + 1] < z1) ++kk;
  const uint64_t m = BitRange(*k, kk);
  r->known |= m;
  if (occupied) r->occ |= m;
}

// Exact: every voxel crossed by o + z d, z in [e_0, e_D) (clipped to the box), contributes its
// state to every bin its z-interval overlaps. Two-level 3-D DDA (Amanatides & Woo 1987): over
// 8^3 blocks first; a block that is absent (all unknown) is skipped, a uniform one (all free /
// all occupied) contributes its whole z-interval at once, and only inside a mixed block are
// its voxels stepped through.
inline RayBits TraverseExact(const MapView& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             const std::vector<double>& e) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  constexpr int S = VoxelMap::kShift, W = VoxelMap::kSide;
  double z = e.front(), z_end = e.back();
  if (!ClipToBox(o, d, m.lo_m, m.hi_m, &z, &z_end)) return r;
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
            if (zv < edge && zx <= edge) {  // the whole voxel within bin k
              const uint64_t bit = uint64_t{1} << k;
              r.known |= bit;
              if (s == VoxelMap::kOccupied) r.occ |= bit;
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

inline FrustumVolume ProjectToFrustumReference(const OccupancyMap& map,
                                               const Camera& camera_full_res,
                                               const Rigid3d& world_from_cam,
                                               const BinOptions& options) {
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

  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      const Eigen::Vector3d d =
          R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const RayBits r = TraverseExact(view, o, d, vol.edges_m);  // exact only
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      vol.occ[i] = r.occ;
      vol.known[i] = r.known;
    }
  }
  return vol;
}

}  // namespace gt::occupancy::reference

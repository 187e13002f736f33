// Frustum binning (frustum.h): exact 3-D DDA or bin-centre sampling directly over the map's
// voxel store (voxel_map.h; uniform 8^3 blocks are crossed in one step), and the two_point
// target.
#include "libgt/occupancy/frustum.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <utility>

#include "libgt/core/bits.h"
#include "libgt/core/error.h"
#include "libgt/occupancy/edge_index.h"
#include "libgt/occupancy/splat_row.h"
#include "libgt/occupancy/voxel_map.h"

namespace gt::occupancy {

namespace {

std::vector<double> ComputeBinEdges(const BinOptions& o) {
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

}  // namespace

bool BinOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (num_bins < 1 || num_bins > 64) return fail("num_bins must be in 1..64");
  if (!(near_m > 0.0) || !std::isfinite(near_m)) return fail("near_m must be finite and > 0");
  if (!(far_m > near_m) || !std::isfinite(far_m)) return fail("far_m must be finite and > near_m");
  // The edges themselves: finite and increasing (far/near = 1e600 gave infinite log edges,
  // a near of 1e-309 zero inverse edges, and a bin narrower than a double's step none).
  const std::vector<double> e = ComputeBinEdges(*this);
  for (size_t k = 1; k < e.size(); ++k) {
    if (!(std::isfinite(e[k]) && e[k] > e[k - 1])) {
      std::ostringstream s;
      s << "the " << BinSpacingName(spacing) << " bin edges of near_m " << near_m << ", far_m "
        << far_m << " and " << num_bins << " bins are not finite and increasing (edge " << k
        << " is " << e[k] << "): use a narrower far_m / near_m ratio";
      return fail(s.str());
    }
  }
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
  return ComputeBinEdges(o);
}

int BinOfDepth(const std::vector<double>& edges_m, double z_m) {
  if (!(z_m >= edges_m.front() && z_m < edges_m.back())) return -1;
  // Largest k with e_k <= z.
  const auto it = std::upper_bound(edges_m.begin(), edges_m.end(), z_m);
  return static_cast<int>(it - edges_m.begin()) - 1;
}

namespace {

// A volume on the half grid of `camera_full_res` with the bins of `options` (checked by
// BinEdges), every word 0 (nothing known).
FrustumVolume EmptyVolume(const Camera& camera_full_res, const BinOptions& options) {
  const Camera cam = camera_full_res.HalfGrid();
  FrustumVolume vol;
  vol.width = cam.width;
  vol.height = cam.height;
  vol.edges_m = BinEdges(options);
  const size_t n = static_cast<size_t>(vol.width) * vol.height;
  vol.occ.assign(n, 0);
  vol.known.assign(n, 0);
  return vol;
}

int64_t SetBits(const std::vector<uint64_t>& words) {
  return CountSetBits(words.data(), words.size());
}

}  // namespace

VolumeCounts CountBins(const FrustumVolume& volume) {
  // Per ray: free = known - occupied, unknown = D - known; summed, from the two totals.
  const int64_t occupied = SetBits(volume.occ);
  const int64_t known = SetBits(volume.known);
  VolumeCounts c;
  c.occupied = occupied;
  c.free = known - occupied;
  c.unknown =
      static_cast<int64_t>(volume.num_bins()) * static_cast<int64_t>(volume.occ.size()) - known;
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

// Exact: every voxel crossed by o + z d, z in [e_0, e_D) (clipped to the box), contributes
// its state to every bin its z-interval overlaps. Two-level 3-D DDA (Amanatides & Woo 1987): over
// 8^3 blocks first; a block that is absent (all unknown) is skipped, a uniform one (all free /
// all occupied) contributes its whole z-interval at once, and only inside a mixed block are
// its voxels stepped through.
// Since the box splat (SplatExact) it walks only the rays that lie in a voxel face plane.
RayBits TraverseExact(const MapView& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      const std::vector<double>& e) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  constexpr int S = VoxelMap::kShift, W = VoxelMap::kSide;
  double z = e.front(), z_end = e.back();
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
// Beyond z_known_max the caller guarantees that the ray meets no known voxel.
RayBits TraverseCenter(const MapView& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       const std::vector<double>& e, double z_known_max) {
  RayBits r;
  const int D = static_cast<int>(e.size()) - 1;
  double z_lo = e.front(), z_hi = std::min(e.back(), z_known_max);
  if (!ClipToBox(o, d, m.lo_m, m.hi_m, &z_lo, &z_hi)) return r;
  const double inv = 1.0 / m.res;
  constexpr int S = VoxelMap::kShift;
  for (int k = 0; k < D; ++k) {
    const double zc = 0.5 * (e[k] + e[k + 1]);
    if (zc < z_lo) continue;
    if (zc > z_hi) break;
    const Eigen::Vector3d p = o + zc * d;
    int ix, iy, iz;
    if (!FloorInRange(p.x() * inv, m.lo.x(), m.hi.x(), &ix) ||
        !FloorInRange(p.y() * inv, m.lo.y(), m.hi.y(), &iy) ||
        !FloorInRange(p.z() * inv, m.lo.z(), m.hi.z(), &iz))
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

// Convex hull of points (Andrew's monotone chain), counter-clockwise, in place; returns the
// number of hull vertices.
__attribute__((noinline)) int ConvexHull(Eigen::Vector2d* p, int n) {
  std::sort(p, p + n, [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (n < 3) return n;
  Eigen::Vector2d h[2 * 24];
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  int k = 0;
  for (int i = 0; i < n; ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (int i = n - 2, t = k + 1; i >= 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (int i = 0; i < k - 1; ++i) p[i] = h[i];
  return k - 1;
}

// Marks the bins of one box (world metres [lo_m, hi_m], one state) in every ray that crosses
// it. Rays are tried only inside the image of the box's part at camera z >= e_0 (the convex
// hull of its projected vertices), widened by one ray against rounding; the slab test below
// decides.
void SplatBox(const Eigen::Vector3d& lo_m, const Eigen::Vector3d& hi_m, bool occupied,
              const Eigen::Vector3d& o, const Eigen::Matrix3d& Rt, const Camera& cam,
              const std::vector<double>& e, const EdgeIndex& bins, const SplatRays& rays,
              FrustumVolume* vol, std::vector<double>* spans) {
  const Eigen::Vector3d a = lo_m - o, b = hi_m - o;
  const double e0 = e.front(), eD = e.back();
  Eigen::Vector3d pc[8];
  double z_min = std::numeric_limits<double>::infinity(), z_max = -z_min;
  // Corners in the camera frame from the six products Rt.col(k) * {a_k, b_k} (a footprint
  // only: its rounding is covered by kEps below).
  const Eigen::Vector3d cx0 = Rt.col(0) * a.x(), cx1 = Rt.col(0) * b.x();
  const Eigen::Vector3d cy0 = Rt.col(1) * a.y(), cy1 = Rt.col(1) * b.y();
  const Eigen::Vector3d cz0 = Rt.col(2) * a.z(), cz1 = Rt.col(2) * b.z();
  for (int c = 0; c < 8; ++c) {
    pc[c] = ((c & 1) ? cx1 : cx0) + ((c & 2) ? cy1 : cy0) + ((c & 4) ? cz1 : cz0);
    z_min = std::min(z_min, pc[c].z());
    z_max = std::max(z_max, pc[c].z());
  }
  if (z_max < e0 || z_min >= eD) return;
  // Bins the box can reach (1e-9 m of margin: far beyond the rounding of these depths, which
  // are a few ulps of ~10 m): at most two means the cheap lookup (RowArgs).
  int k_first = -1, k_last = -1;
  {
    const double z_lo = std::max(z_min - 1e-9, e0), z_hi = std::min(z_max + 1e-9, eD);
    if (z_lo < eD && z_hi > e0) {
      const int f = bins.First(z_lo), l = bins.Last(z_hi);
      if (l <= f + 1) k_first = f, k_last = l;
    }
  }
  // Vertices of the box's part at z >= e_0: its corners there and the points where its
  // edges cross z = e_0 (at most 8 + 12), projected.
  Eigen::Vector2d q[24];
  int nq = 0;
  auto add = [&](const Eigen::Vector3d& p) {
    q[nq++] = Eigen::Vector2d(cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy);
  };
  for (int c = 0; c < 8; ++c) {
    if (pc[c].z() >= e0) add(pc[c]);
  }
  if (z_min < e0) {
    for (int c = 0; c < 8; ++c) {
      for (int bit = 1; bit < 8; bit <<= 1) {
        if (c & bit) continue;
        const Eigen::Vector3d &p = pc[c], &r = pc[c | bit];
        if ((p.z() < e0) == (r.z() < e0)) continue;
        const double f = (e0 - p.z()) / (r.z() - p.z());
        Eigen::Vector3d x = p + f * (r - p);
        x.z() = e0;
        add(x);
      }
    }
  }
  for (int i = 0; i < nq; ++i) {
    if (!q[i].allFinite()) return;  // degenerate: no box reaches z >= e_0 with extent
  }
  const int nh = ConvexHull(q, nq);
  if (nh == 0) return;
  // Rays (u, v) are the image points (u, v): row v is tried over the hull's intersection
  // with the line y = v, found by walking each edge over the rows it spans; kEps (pixels)
  // covers the rounding of the projections many times over.
  constexpr double kEps = 1e-3;
  double v_min = q[0].y(), v_max = q[0].y();
  for (int i = 1; i < nh; ++i) v_min = std::min(v_min, q[i].y()), v_max = std::max(v_max, q[i].y());
  // Every bound is clamped in double before its conversion: a voxel a hair in front of the
  // camera (near_m ~ 1e-10) projects to ~1e10 pixels, past int's range.
  const int v0 = static_cast<int>(std::clamp(std::ceil(v_min - kEps), 0.0, vol->height * 1.0));
  const int v1 = static_cast<int>(std::clamp(std::floor(v_max + kEps), -1.0, vol->height - 1.0));
  if (v0 > v1) return;
  const int width = vol->width;
  const size_t rows = static_cast<size_t>(v1 - v0 + 1);
  if (spans->size() < 2 * rows) spans->resize(2 * rows);
  double* lo_u = spans->data();
  double* hi_u = lo_u + rows;
  std::fill(lo_u, hi_u, std::numeric_limits<double>::infinity());
  std::fill(hi_u, hi_u + rows, -std::numeric_limits<double>::infinity());
  for (int i = 0; i < nh; ++i) {
    const Eigen::Vector2d& p = q[i];
    const Eigen::Vector2d& r = q[i + 1 < nh ? i + 1 : 0];
    const double y_lo = std::min(p.y(), r.y()), y_hi = std::max(p.y(), r.y());
    const int first = static_cast<int>(std::clamp(std::ceil(y_lo - kEps), v0 * 1.0, v1 + 1.0));
    const int last = static_cast<int>(std::clamp(std::floor(y_hi + kEps), v0 - 1.0, v1 * 1.0));
    if (y_hi - y_lo <= 0) {  // horizontal edge (or a single point)
      const double x_lo = std::min(p.x(), r.x()), x_hi = std::max(p.x(), r.x());
      for (int v = first; v <= last; ++v) {
        lo_u[v - v0] = std::min(lo_u[v - v0], x_lo);
        hi_u[v - v0] = std::max(hi_u[v - v0], x_hi);
      }
      continue;
    }
    const double slope = (r.x() - p.x()) / (r.y() - p.y());
    for (int v = first; v <= last; ++v) {
      const double y = std::clamp(static_cast<double>(v), y_lo, y_hi);
      const double x = p.x() + (y - p.y()) * slope;
      lo_u[v - v0] = std::min(lo_u[v - v0], x);
      hi_u[v - v0] = std::max(hi_u[v - v0], x);
    }
  }
  for (int v = v0; v <= v1; ++v) {
    const double u_lo = lo_u[v - v0], u_hi = hi_u[v - v0];
    if (!(u_lo <= u_hi)) continue;
    const int ua = static_cast<int>(std::clamp(std::ceil(u_lo - kEps), 0.0, width * 1.0));
    const int ub = static_cast<int>(std::clamp(std::floor(u_hi + kEps), -1.0, width - 1.0));
    if (ua > ub) continue;
    RowArgs args{&rays, &bins, vol,     &a,    &b, e0, eD, occupied, static_cast<size_t>(v) * width,
                 ua,    ub,    k_first, k_last};
    SplatRow(args);
  }
}

// Exact binning by splatting boxes of known voxels into the rays that cross them: the
// transpose of the walk (TraverseExact), with the same result up to ties. A ray's bin k is
// marked by a box when the ray's planar-depth interval inside the (closed) box, clipped to
// [e_0, e_D], has positive length and overlaps [e_k, e_{k+1}); this is what the walk marks
// voxel by voxel, as the boxes (VoxelMap::Boxes) are exact unions of voxels of one state.
// "Up to ties": a crossing shorter than ~1e-6 m, or a ray through a voxel edge, may come
// out differently by rounding here and in the walk (the walk, for one, starts each mixed
// block at a point 1e-6 m inside it); tests/occupancy/traversal_test.cc checks that every
// difference from the reference walk is such a tie.
// Rays with a zero (or denormal) direction component (a ray in a voxel face plane belongs to
// the voxel its floor() gives, on one side only) are walked by TraverseExact instead.
// Cost: per box, its projected hull; per ray it covers, one slab test and one bin lookup
// (four rays at a time with AVX2); no voxel-by-voxel stepping.
void SplatExact(const MapView& view, const Camera& cam, const Eigen::Matrix3d& R,
                const Eigen::Vector3d& o, FrustumVolume* vol) {
  const std::vector<double>& e = vol->edges_m;
  const EdgeIndex bins(e);
  const size_t n = vol->occ.size();
  SplatRays rays;
  rays.inv_x.resize(n), rays.inv_y.resize(n), rays.inv_z.resize(n);
  std::vector<std::pair<size_t, Eigen::Vector3d>> walk;  // ray index and direction
  for (int v = 0; v < vol->height; ++v) {
    for (int u = 0; u < vol->width; ++u) {
      const size_t i = static_cast<size_t>(v) * vol->width + u;
      const Eigen::Vector3d d =
          R * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const Eigen::Vector3d inv(1.0 / d.x(), 1.0 / d.y(), 1.0 / d.z());
      if (d.x() == 0 || d.y() == 0 || d.z() == 0 || !inv.allFinite()) {
        walk.emplace_back(i, d);
        rays.inv_x[i] = rays.inv_y[i] = rays.inv_z[i] = 0.0;  // z-interval empty: no box
      } else {
        rays.inv_x[i] = inv.x(), rays.inv_y[i] = inv.y(), rays.inv_z[i] = inv.z();
      }
    }
  }
  const Eigen::Matrix3d Rt = R.transpose();
  const VoxelMap& map = *view.map;
  constexpr int W = VoxelMap::kSide;
  const double res = view.res;
  std::vector<double> spans;
  const VoxelMap::BlockBoxes& boxes = map.Boxes();
  for (int32_t blk = 0; blk < map.num_blocks(); ++blk) {
    const auto& c = map.block_coord(blk);
    const Eigen::Vector3i base(c[0] * W, c[1] * W, c[2] * W);
    if ((base.array() + W - 1 < view.lo.array()).any() || (base.array() > view.hi.array()).any())
      continue;
    for (int32_t k = boxes.first[blk]; k < boxes.first[blk + 1]; ++k) {
      const VoxelMap::Box& bx = boxes.boxes[k];
      // Clipped to the voxel box of the view, as the walk clips its rays.
      const Eigen::Vector3i lo = base + Eigen::Vector3i(bx.x0, bx.y0, bx.z0);
      const Eigen::Vector3i hi = base + Eigen::Vector3i(bx.x1, bx.y1, bx.z1);  // exclusive
      const Eigen::Vector3i clo = lo.cwiseMax(view.lo);
      const Eigen::Vector3i chi = hi.cwiseMin(view.hi + Eigen::Vector3i::Ones());
      if ((chi.array() <= clo.array()).any()) continue;
      SplatBox(clo.cast<double>() * res, chi.cast<double>() * res, bx.occupied, o, Rt, cam, e, bins,
               rays, vol, &spans);
    }
  }
  for (const auto& [i, d] : walk) {
    const RayBits r = TraverseExact(view, o, d, e);
    vol->occ[i] = r.occ;
    vol->known[i] = r.known;
  }
}

}  // namespace

FrustumVolume ProjectToFrustum(const OccupancyMap& map, const Camera& camera_full_res,
                               const Rigid3d& world_from_cam, const BinOptions& options) {
  const Camera cam = camera_full_res.HalfGrid();
  FrustumVolume vol = EmptyVolume(camera_full_res, options);
  const size_t n = vol.occ.size();
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

  if (options.traversal == Traversal::kExact) {
    SplatExact(view, cam, R, o, &vol);
    return vol;
  }
  // Farthest planar depth of a block of the map seen through each tile of kTile x kTile rays:
  // a ray meets no known voxel beyond the largest camera z of the corners of the blocks whose
  // image covers it, so the bin-centre lookups stop there (plus one voxel against rounding)
  // instead of going on to the far plane or the box. Conservative: a block reaching the
  // camera plane (z <= 0 at a corner) counts for every tile; the bins do not change.
  constexpr int kTile = 8;
  const int tiles_w = (vol.width + kTile - 1) / kTile, tiles_h = (vol.height + kTile - 1) / kTile;
  std::vector<double> tile_far(static_cast<size_t>(tiles_w) * tiles_h,
                               -std::numeric_limits<double>::infinity());
  {
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
      const RayBits r = TraverseCenter(
          view, o, d, vol.edges_m, tile_far[static_cast<size_t>(v / kTile) * tiles_w + u / kTile]);
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      vol.occ[i] = r.occ;
      vol.known[i] = r.known;
    }
  }
  return vol;
}

FrustumVolume TwoPointVolume(const FusionInput& self, const FusionInput& other,
                             const BinOptions& options) {
  GT_ASSERT(self.depth != nullptr && other.depth != nullptr);
  const Camera cam = self.camera.HalfGrid();
  FrustumVolume vol = EmptyVolume(self.camera, options);
  const size_t n = vol.occ.size();
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

// Per-camera 64-bin frustum volumes (GROUND_TRUTH.md §5, "Frustum grid" and "Encoding").
//
// Rays go through the full-resolution pixels (2u, 2v), i.e. the half grid
// K_half = diag(1/2, 1/2, 1) K of size (W/2, H/2) (Camera::HalfGrid). Along ray (u, v) the
// planar depth z (camera z, metres; NOT the distance along the ray) is cut into num_bins bins
// by edges e_0 = near_m < e_1 < ... < e_D = far_m; bin k covers z in [e_k, e_{k+1}).
//   linear:  e_k = near + k (far - near) / D
//   log:     e_k = near (far / near)^(k / D)
//   inverse: 1 / e_k = 1/near + k (1/far - 1/near) / D   (uniform in disparity)
// State of bin k: OCCUPIED if the ray segment inside the bin meets an occupied voxel, else
// FREE if it meets a known free voxel, else UNKNOWN.
//   exact:  every finest-resolution voxel the segment crosses (computed by splatting boxes of
//           known voxels into the rays that cross them, frustum.cc; equal to a 3-D DDA walk
//           up to rounding ties);
//   center: only the voxel at the bin's centre z = (e_k + e_{k+1}) / 2 is looked up (no faster
//           than exact since the box splat; misses voxels thinner than a bin).
//
// Encoding, per ray: two uint64 words, bit k (value 1 << k) = bin k occupied (`occ`) / bin k
// known, i.e. occupied or free (`known`); occ is always a subset of known. Arrays are
// row-major [height, width] = [H/2, W/2], index v * width + u, little-endian when written.
// Dense form: uint8 [num_bins, H/2, W/2], 0 free, 1 occupied, 255 unknown.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/pose.h"
#include "libgt/occupancy/fusion.h"

namespace gt::occupancy {

enum class BinSpacing { kLinear, kLog, kInverse };  // "linear" | "log" | "inverse"
enum class Traversal { kExact, kCenter };           // "exact" | "center"

struct BinOptions {
  int num_bins = 64;    // D, 1..64 (one uint64 word per ray); the paper uses 64
  double near_m = 0.1;  // first edge (metres), > 0: indoor RGB-D sensors start ~0.1-0.5 m
  double far_m = kDefaultFarM;  // last edge (metres), > near_m (fusion.h)
  BinSpacing spacing = BinSpacing::kLinear;
  Traversal traversal = Traversal::kExact;

  bool Check(std::string* error) const;
};

// Parsers throw InputError("<flag>", ...) on unknown names; names are the strings above.
BinSpacing ParseBinSpacing(const std::string& text);
Traversal ParseTraversal(const std::string& text);
std::string BinSpacingName(BinSpacing spacing);
std::string TraversalName(Traversal traversal);

// num_bins + 1 increasing edges (metres); bin k covers [e_k, e_{k+1}).
std::vector<double> BinEdges(const BinOptions& options);
// Bin of planar depth z_m, or -1 when z_m is outside [e_0, e_D).
int BinOfDepth(const std::vector<double>& edges_m, double z_m);

struct FrustumVolume {
  int width = 0;                // W/2 (half grid)
  int height = 0;               // H/2
  std::vector<uint64_t> occ;    // [height * width], bit k: bin k occupied
  std::vector<uint64_t> known;  // [height * width], bit k: bin k occupied or free
  std::vector<double> edges_m;  // num_bins + 1 edges

  int num_bins() const { return static_cast<int>(edges_m.size()) - 1; }
};

// Counts of bins over the volume (num_bins * width * height in total).
struct VolumeCounts {
  int64_t occupied = 0;
  int64_t free = 0;
  int64_t unknown = 0;
};
VolumeCounts CountBins(const FrustumVolume& volume);

// Bins the map along the rays of camera_full_res.HalfGrid() posed at world_from_cam.
FrustumVolume ProjectToFrustum(const OccupancyMap& map, const Camera& camera_full_res,
                               const Rigid3d& world_from_cam, const BinOptions& options);

// Testing only: false makes the exact binning use its scalar kernels even where the CPU has
// AVX2 (both give identical words; tests/occupancy/traversal_test.cc). Default true.
void SetVectorKernelsForTesting(bool enabled);

// Dense uint8 [num_bins, height, width] (0 free, 1 occupied, 255 unknown).
std::vector<uint8_t> DenseVolume(const FrustumVolume& volume);

// The `two_point` target of the released Occ²Net code, for camera `self`: ray (u, v) is
// occupied at the bin of its own depth (self.depth at full-resolution pixel (2u, 2v)) and at
// the bin of every valid pixel of `other` warped into self's half grid (nearest ray,
// round(x), round(y), its planar depth in self); nothing else is occupied. known: all
// num_bins bits of a ray that received at least one point (the released target labels every
// other bin of such a ray 0, i.e. free); 0 for a ray that received none (no label).
FrustumVolume TwoPointVolume(const FusionInput& self, const FusionInput& other,
                             const BinOptions& options);

}  // namespace gt::occupancy

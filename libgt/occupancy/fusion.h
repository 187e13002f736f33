// Fusion of posed depth maps into one occupancy map (GROUND_TRUTH.md §5, "Fusion").
//
// Each frame's valid pixels (IsValidDepth with the frame's [min_depth_m, max_depth_m]) are
// back-projected with the frame's Camera (planar depth z in metres, OpenCV axes, pixel
// centres at integer coordinates) and moved to the world frame with world_from_cam.
// Invalid pixels are dropped BEFORE any transform: a zero depth would land on the camera
// centre and a NaN becomes the origin in PCL's transform. The cloud is optionally
// downsampled to one centroid per voxel of the map resolution and filtered by statistical
// outlier removal, then inserted as one scan with the camera centre as the sensor origin:
// the ray to every point marks free voxels, its end voxel is a hit, rays are truncated at
// max_range_m (OctoMap's ray model, default hit/miss probabilities 0.7/0.4, clamping
// 0.12/0.97, occupancy threshold 0.5).
//
// Engines: by default the scans are ray-cast by occgt's own code into a sparse voxel store
// (voxel_map.h) that reproduces OctoMap's OcTree::insertPointCloud exactly (same keys, same
// per-scan update rule, same float log-odds; tests/occupancy/equivalence_test.cc compares
// them voxel by voxel). The OctoMap OcTree is built from it only when asked for (SaveBinary,
// NumLeafNodes). FusionEngine::kOctomap runs OctoMap's own insertPointCloud instead (the
// reference of the tests and the benchmark's naive baseline).
//
// Key range: OctoMap keys are 16-bit per axis, so the map spans 2^16 * voxel_m per
// axis centred on the world origin (3276.8 m at 5 cm). Before any fusion work, every frame
// must fit in it (CheckKeyRange): its camera centre plus and minus its reach (FusionReachM:
// max_range_m, else its longest valid ray) on every axis, or InputError("voxel_m", ...)
// names the smallest voxel size that works. Points still outside (beyond max_range_m,
// whose rays are truncated inside) are dropped and counted before insertion, because
// OctoMap's unchecked key conversion wraps around.
//
// PCL and OctoMap types never appear here; OccupancyMap is an opaque handle.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/frame.h"
#include "libgt/core/pose.h"

namespace gt::occupancy {

// Which frames are fused for a pair (GROUND_TRUTH.md §5).
enum class FusionScope {
  kPair,    // "pair": the two frames of the pair only (paper, default)
  kWindow,  // "window:N": the pair plus the usable frames within N positions of either
  kScene,   // "scene:S": every S-th usable frame of the scene; one map reused by all pairs
};

// Who casts the rays (see the top of this file).
enum class FusionEngine {
  kOwn,      // occgt's OctoMap-equivalent ray casting into a sparse voxel store (fast)
  kOctomap,  // OctoMap's OcTree::insertPointCloud (reference for tests and benchmarks)
};

// The far end of the occupancy target: the last bin edge (frustum.h BinOptions::far_m) and,
// unless set apart, the fusion's ray range. 10 m covers indoor depth sensors (ScanNet and
// 7-Scenes read < 10 m).
inline constexpr double kDefaultFarM = 10.0;

struct FusionOptions {
  double voxel_m = 0.05;              // OctoMap resolution (metres), > 0
  double max_range_m = kDefaultFarM;  // ray truncation (metres); <= 0 means unlimited
  bool downsample = false;     // one centroid per voxel (pcl::VoxelGrid, overflow-guarded);
                               // off: with `discretize` every voxel gets one ray anyway
  bool discretize = true;      // OctoMap's discretized insertion (one ray per end voxel, to its
                               // centre); false = one ray per point (the naive baseline)
  FusionEngine engine = FusionEngine::kOwn;
  bool remove_outliers = false;  // pcl::StatisticalOutlierRemoval after downsampling
  int outlier_k = 20;            // neighbours for the mean distance, >= 1
  double outlier_stddev = 2.0;   // reject mean distance > mean + stddev * sigma, > 0
  FusionScope scope = FusionScope::kPair;
  int window = 2;         // kWindow: usable neighbours on each side of the pair, >= 1
  int scene_stride = 10;  // kScene: fuse every n-th frame (one map per scene), >= 1

  bool Check(std::string* error) const;
};

// "pair", "window:N", "scene:S" -> scope fields of *options; throws
// InputError("--scope", ...) on anything else.
void ParseFusionScope(const std::string& text, FusionOptions* options);
// Indices into scene.frames of the frames to fuse for the pair (i0, i1), sorted, usable only:
// kPair {i0, i1}; kWindow the usable frames within `window` positions (of scene.frames) of i0
// or i1; kScene every scene_stride-th usable frame (the usable frames numbered 0, S, 2S, ...
// in scene order: never none when the scene has a usable frame; independent of the pair, so
// the map is shared by all pairs of the scene, and it need not hold the pair's own frames).
// `unusable`, when given, receives the frames of the scope left out as unusable, sorted:
// kPair none beside the pair's own, kWindow those within `window` positions of i0 or i1,
// kScene every unusable frame of the scene (the stride numbers the usable frames only).
std::vector<size_t> ScopeFrameIndices(const Scene& scene, size_t i0, size_t i1,
                                      const FusionOptions& options,
                                      std::vector<size_t>* unusable = nullptr);
// Inverse of ParseFusionScope ("pair", "window:3", "scene:10").
std::string FusionScopeName(const FusionOptions& options);

// One posed depth map to fuse. `depth` is not owned and must outlive the call.
struct FusionInput {
  const DepthImage* depth = nullptr;
  Camera camera;  // K at the depth map's resolution
  Rigid3d world_from_cam = Rigid3d::Identity();
  double min_depth_m = kDefaultMinDepthM;  // validity range (depth.h IsValidDepth)
  double max_depth_m = kDefaultMaxDepthM;
};

// What happened to the points during fusion (summed over frames).
struct FusionStats {
  int64_t frames = 0;
  int64_t pixels = 0;                // width * height summed
  int64_t invalid_pixels = 0;        // dropped before back-projection
  int64_t out_of_key_range = 0;      // dropped: outside the map's key range
  int64_t after_downsample = 0;      // points after the voxel grid (== valid if off)
  int64_t downsample_fallbacks = 0;  // frames whose VoxelGrid would overflow int32
  int64_t outliers_removed = 0;
  int64_t inserted_points = 0;
};

// The half extent of the map's usable key range on each axis (metres): 32766 voxels
// around the world origin. OctoMap's checked keys are the voxel indices [-2^15, 2^15); one
// voxel is kept as a margin on each side, so that float points and rays rounded at the
// border never leave it.
double KeyRangeHalfExtentM(double voxel_m);

// How far from its camera centre the fusion of `frame` can mark voxels (metres, as a
// distance; so on every axis too): max_range_m when > 0 (rays are truncated there), else
// the frame's max_depth_m times its longest ray per metre of planar depth, the ray through
// the farthest image corner: max over the corner pixels (u, v) of
// |world_from_cam.linear() * ((u - cx) / fx, (v - cy) / fy, 1)| (exact for the pixels
// back-projected; the rotation is used as given).
double FusionReachM(const FusionInput& frame, const FusionOptions& options);

// The smallest voxel size whose key range holds camera_centre +- reach_m on every axis:
// the least v with KeyRangeHalfExtentM(v) >= max_a |camera_centre[a]| + reach_m (exact in
// double: v is accepted, the next smaller double is not); +inf when that is not finite.
double MinVoxelSizeM(const Eigen::Vector3d& camera_centre, double reach_m);

// The check FuseOccupancy runs on every frame before any fusion work: throws
// InputError("voxel_m", ...) unless KeyRangeHalfExtentM(options.voxel_m) holds the
// frame's camera centre plus and minus FusionReachM on every axis (a camera centre outside
// the key range fails it too). The one-line message gives the range held, the frame
// (`frame_name`, e.g. "frame 1"), its camera centre and reach, the range needed and the
// smallest voxel size that works (rounded up to 3 significant digits). Options must pass
// Check.
void CheckKeyRange(const FusionInput& frame, const FusionOptions& options,
                   const std::string& frame_name);

// Dense copy of a box of the map's finest-resolution voxel states. Voxel index
// i = floor(x / voxel_m) per world axis (voxel i covers [i, i + 1) * voxel_m; the
// OctoMap key is i + 2^15). state is row-major [size.z, size.y, size.x] (x fastest).
struct VoxelBlock {
  static constexpr int8_t kUnknown = -1, kFree = 0, kOccupied = 1;
  double voxel_m = 0.0;
  Eigen::Vector3i min_index = Eigen::Vector3i::Zero();  // index of element (0, 0, 0)
  Eigen::Vector3i size = Eigen::Vector3i::Zero();       // voxels along x, y, z
  std::vector<int8_t> state;

  bool empty() const { return state.empty(); }
  int8_t at(int ix, int iy, int iz) const {  // block-local indices, must be inside
    return state[(static_cast<size_t>(iz) * size.y() + iy) * size.x() + ix];
  }
};

class VoxelMap;  // voxel_map.h, internal to libgt/occupancy

// Opaque fused map: a sparse voxel store (voxel_map.h) and/or an octomap::OcTree, each
// derived from the other on first use. Read-only use is thread-safe.
class OccupancyMap {
 public:
  struct Impl;
  OccupancyMap();
  explicit OccupancyMap(std::unique_ptr<Impl> impl);
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;
  ~OccupancyMap();

  double resolution_m() const;
  // Leaf nodes of the (pruned) OcTree; a pruned leaf may cover many voxels. With the own
  // engine the OcTree is built on the first call (as for SaveBinary).
  int64_t NumLeafNodes() const;
  // Known voxels at the finest resolution (pruned leaves expanded), occupied and free.
  int64_t NumOccupiedVoxels() const;
  int64_t NumFreeVoxels() const;
  // Voxel state at a world point: 1 occupied, 0 free, -1 unknown or outside the key range.
  int StateAt(const Eigen::Vector3d& p_in_world) const;
  const FusionStats& stats() const;
  // Tight inclusive voxel-index bounds of the known (occupied or free) voxels; false when
  // none is known.
  bool KnownIndexBounds(Eigen::Vector3i* min_index, Eigen::Vector3i* max_index) const;
  // States of the voxels with index in [min_index, max_index] (inclusive; clipped to the
  // key range). Pruned leaves are expanded to their voxels.
  VoxelBlock ExtractBlock(const Eigen::Vector3i& min_index, const Eigen::Vector3i& max_index) const;
  // OctoMap binary (.bt, maximum-likelihood occupancy), which octovis opens; atomic write.
  // With the own engine the OcTree is built here (first call), from the voxel store.
  void SaveBinary(const std::string& path) const;
  // The voxel store, for libgt/occupancy's own use (frustum binning).
  const VoxelMap& voxels() const;

 private:
  std::unique_ptr<Impl> impl_;
};

// Fuses the frames (in order) into one map. Every frame is checked first, before any
// fusion work: throws InputError for a frame whose depth is missing or does not match its
// camera size, and InputError("voxel_m", ...) for one that does not fit in the key range
// (CheckKeyRange). Options must pass Check (GT_ASSERT otherwise).
OccupancyMap FuseOccupancy(const std::vector<FusionInput>& frames, const FusionOptions& options);

// Downsampling used by FuseOccupancy, exposed for tests: one centroid per voxel
// floor(p / leaf_m) (up to float rounding at voxel borders); output order is deterministic
// but unspecified (compare as sets). Uses pcl::VoxelGrid when its int32 leaf count does not
// overflow, otherwise an own sort-based bucketing; *used_fallback says which.
std::vector<Eigen::Vector3f> DownsampleVoxelCentroids(const std::vector<Eigen::Vector3f>& points,
                                                      double leaf_m, bool* used_fallback);

// Back-projects the valid pixels of one frame into the world frame (row-major pixel order).
std::vector<Eigen::Vector3f> BackProjectValid(const FusionInput& frame);

}  // namespace gt::occupancy

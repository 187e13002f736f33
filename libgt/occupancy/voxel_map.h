// Internal to libgt/occupancy: the fused map's own voxel store and ray casting.
//
// VoxelMap holds, at the finest resolution only, the float log-odds of every voxel that an
// insertion touched, in dense blocks of 8x8x8 voxels found through a hash of block
// coordinates. Voxel index i = floor(x / voxel_m) per world axis (OctoMap key
// i + 2^15); block coordinate = i >> 3 (floor). A voxel is unknown until first updated.
//
// InsertScan reproduces the per-scan update of OctoMap's
// OcTree::insertPointCloud(scan, origin, max_range, lazy_eval, discretize) exactly, with the
// same float/double arithmetic, so that the voxel states (and log-odds) are equal:
//   - discretize: the points are replaced by the centres (float) of their distinct voxels;
//   - a point p (or centre) with |p - origin| <= max_range (or max_range < 0) marks its own
//     voxel as a hit and the voxels crossed by the ray origin -> p as misses (3-D DDA of
//     Amanatides & Woo with OctoMap's stopping rule: the origin's voxel included, p's voxel
//     excluded; nothing when both are in the same voxel);
//   - a point farther than max_range casts a miss ray to origin + max_range * direction and
//     marks no hit;
//   - within one scan a voxel is updated at most once, as a hit if any ray ends in it, else
//     as a miss; log-odds l <- clamp(l + hit_or_miss, clamp_min, clamp_max), starting at 0.
// Keys outside OctoMap's checked range [-2^15, 2^15) are skipped as OctoMap's checked key
// conversion skips them (fusion.cc clips points before they get here).
//
// After the last scan, Finalize() derives the int8 state of every voxel (occupied when
// l >= occupied_threshold, else free; unknown when never updated), a per-block kind and the
// index bounds; the read accessors need it. Not thread-safe while inserting; read-only use
// after Finalize() is.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace gt::occupancy {

// OctoMap's sensor model (log-odds), read from an octomap::OcTree by fusion.cc.
struct LogOddsModel {
  float hit = 0.0f;
  float miss = 0.0f;
  float clamp_min = 0.0f;
  float clamp_max = 0.0f;
  float occupied_threshold = 0.0f;
};

// floor(s) into *out when it lies in [lo, hi] (integers); false otherwise (NaN too).
// floor(s) >= lo iff s >= lo, floor(s) <= hi iff s < hi + 1, and inside that range floor is
// the truncation minus one for negative non-integers: exact, without std::floor's libm call
// (baseline x86-64 has no rounding instruction). For the per-point and per-bin hot loops.
inline bool FloorInRange(double s, int lo, int hi, int* out) {
  if (!(s >= lo && s < hi + 1.0)) return false;
  const int t = static_cast<int>(s);
  *out = t - (s < t);
  return true;
}

class VoxelMap {
 public:
  static constexpr int kShift = 3;  // block side 2^3 = 8 voxels
  static constexpr int kSide = 1 << kShift;
  static constexpr int kBlockVoxels = kSide * kSide * kSide;
  static constexpr int kMinIndex = -32768, kMaxIndex = 32767;  // OctoMap's checked key range
  static constexpr int8_t kUnknown = -1, kFree = 0, kOccupied = 1;
  // Uniform blocks are skipped whole by the frustum traversal.
  enum class Kind : uint8_t { kMixed, kAllFree, kAllOccupied };

  VoxelMap(double voxel_m, const LogOddsModel& model);

  double voxel_m() const { return res_; }
  const LogOddsModel& model() const { return model_; }

  // One scan (world frame, float as OctoMap's Pointcloud); max_range_m < 0: unlimited.
  // points_lo/points_hi: the points' bounding box if the caller has it (else computed here).
  void InsertScan(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin,
                  double max_range_m, bool discretize, const Eigen::Vector3f* points_lo = nullptr,
                  const Eigen::Vector3f* points_hi = nullptr);
  // Sets the log-odds of one voxel (used to copy an octree); index inside the key range.
  void SetLogOdds(int ix, int iy, int iz, float log_odds);
  void Finalize();

  // --- read access, after Finalize() ---
  int32_t num_blocks() const { return static_cast<int32_t>(coords_.size()); }
  // Block number of block coordinate (bx, by, bz), -1 when absent (all unknown).
  int32_t FindBlock(int bx, int by, int bz) const;
  const std::array<int, 3>& block_coord(int32_t b) const { return coords_[b]; }
  Kind kind(int32_t b) const { return kinds_[b]; }
  const int8_t* states(int32_t b) const { return states_[b].data(); }
  const float* log_odds(int32_t b) const { return blocks_[b].log_odds.data(); }
  static int Local(int ix, int iy, int iz) {  // voxel within its block, x fastest
    return ((iz & (kSide - 1)) << (2 * kShift)) | ((iy & (kSide - 1)) << kShift) |
           (ix & (kSide - 1));
  }
  int8_t StateAt(int ix, int iy, int iz) const;  // kUnknown when absent
  // Inclusive index bounds of the known voxels; false when none is known.
  bool Bounds(Eigen::Vector3i* lo, Eigen::Vector3i* hi) const;
  int64_t num_occupied() const { return num_occupied_; }
  // Boxes of one state covering exactly the known voxels of each block (a uniform block is
  // one box; a mixed one is cut greedily: runs along x, grown along y, then along z), for
  // the exact frustum binning. Block b's boxes are boxes[first[b] .. first[b + 1]).
  // Computed on the first call after Finalize() (thread-safe) and kept.
  struct Box {
    uint8_t x0, y0, z0, x1, y1, z1;  // block-local voxel ranges [x0, x1) etc.
    bool occupied;
  };
  struct BlockBoxes {
    std::vector<Box> boxes;
    std::vector<int32_t> first;  // num_blocks() + 1
  };
  const BlockBoxes& Boxes() const;
  int64_t num_free() const { return num_free_; }

 private:
  struct Block {
    std::array<float, kBlockVoxels> log_odds;  // NaN: never updated
  };
  struct ScanBits {  // one bit per voxel of the block, for the scan being inserted
    std::array<uint64_t, kBlockVoxels / 64> hit{}, miss{}, seen{};
  };
  static uint64_t Pack(int bx, int by, int bz);
  int32_t FindOrAdd(int bx, int by, int bz);
  // Block of voxel (ix, iy, iz) for the scan being inserted (cached; window, else hash),
  // registered as touched by this scan.
  int32_t ScanBlock(int ix, int iy, int iz);
  void Mark(int ix, int iy, int iz, int which);  // 0 hit, 1 miss
  void CastMisses(const float origin[3], const float end[3]);
  void ApplyScan();

  double res_, inv_res_;
  LogOddsModel model_;
  std::unordered_map<uint64_t, int32_t> index_;
  std::vector<std::array<int, 3>> coords_;
  std::vector<Block> blocks_;
  std::vector<ScanBits> scan_;
  std::vector<uint8_t> touched_flag_;
  std::vector<int32_t> touched_;
  // Dense window of block numbers over the scan's block box (-1: not looked up yet).
  std::array<int, 3> win_lo_{}, win_size_{};
  std::vector<int32_t> window_;
  std::array<int, 3> last_block_{{INT32_MIN, 0, 0}};
  int32_t last_number_ = -1;
  // Finalized.
  bool final_ = false;
  std::vector<std::array<int8_t, kBlockVoxels>> states_;
  std::vector<Kind> kinds_;
  bool has_bounds_ = false;
  Eigen::Vector3i lo_ = Eigen::Vector3i::Zero(), hi_ = Eigen::Vector3i::Zero();
  int64_t num_occupied_ = 0, num_free_ = 0;
  mutable std::mutex boxes_mutex_;
  mutable std::unique_ptr<BlockBoxes> boxes_;
};

// Read-only dense table of the block numbers of a map over a box of block coordinates, for
// hot loops (frustum traversal). Coordinates outside the box fall back to the map's hash; a
// box larger than a fixed cap (16 M cells) is not tabulated at all.
class BlockWindow {
 public:
  BlockWindow(const VoxelMap& map, const Eigen::Vector3i& lo_block,
              const Eigen::Vector3i& hi_block);
  int32_t Find(int bx, int by, int bz) const {
    const unsigned x = static_cast<unsigned>(bx - lo_[0]), y = static_cast<unsigned>(by - lo_[1]),
                   z = static_cast<unsigned>(bz - lo_[2]);
    if (x >= size_[0] || y >= size_[1] || z >= size_[2]) return map_->FindBlock(bx, by, bz);
    return cells_[(static_cast<size_t>(z) * size_[1] + y) * size_[0] + x];
  }

 private:
  const VoxelMap* map_;
  int lo_[3] = {0, 0, 0};
  unsigned size_[3] = {0, 0, 0};
  std::vector<int32_t> cells_;
};

}  // namespace gt::occupancy

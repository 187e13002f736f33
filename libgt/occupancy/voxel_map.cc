// Own voxel store and OctoMap-equivalent scan insertion (voxel_map.h).
#include "libgt/occupancy/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libgt/core/error.h"

namespace gt::occupancy {

namespace {

constexpr size_t kMaxWindowCells = size_t{1} << 24;  // 64 MB of int32 at most
constexpr int kPackOffset = 1 << 20;

// OctoMap's checked key conversion, as a voxel index: floor(x / res) computed as
// floor((1 / res) * x) in double from the float coordinate, inside [-2^15, 2^15).
inline bool CheckedIndex(const float c[3], double inv_res, int idx[3]) {
  for (int a = 0; a < 3; ++a) {
    if (!FloorInRange(inv_res * static_cast<double>(c[a]), VoxelMap::kMinIndex, VoxelMap::kMaxIndex,
                      &idx[a]))
      return false;
  }
  return true;
}

// Length of a float 3-vector the way OctoMap's Vector3::norm computes it: squares summed in
// float, square root in double.
inline double FloatNorm(const float v[3]) {
  const float sq = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  return std::sqrt(static_cast<double>(sq));
}

inline void UpdateLogOdds(float* l, float update, const LogOddsModel& m) {
  float v = std::isnan(*l) ? 0.0f : *l;  // a new OctoMap node starts at log-odds 0
  v += update;
  if (v < m.clamp_min) {
    v = m.clamp_min;
  } else if (v > m.clamp_max) {
    v = m.clamp_max;
  }
  *l = v;
}

}  // namespace

VoxelMap::VoxelMap(double voxel_m, const LogOddsModel& model)
    : res_(voxel_m), inv_res_(1.0 / voxel_m), model_(model) {
  GT_ASSERT(voxel_m > 0.0);
}

uint64_t VoxelMap::Pack(int bx, int by, int bz) {
  return (static_cast<uint64_t>(bx + kPackOffset) << 42) |
         (static_cast<uint64_t>(by + kPackOffset) << 21) | static_cast<uint64_t>(bz + kPackOffset);
}

int32_t VoxelMap::FindBlock(int bx, int by, int bz) const {
  if (std::abs(bx) >= kPackOffset || std::abs(by) >= kPackOffset || std::abs(bz) >= kPackOffset)
    return -1;
  const auto it = index_.find(Pack(bx, by, bz));
  return it == index_.end() ? -1 : it->second;
}

int32_t VoxelMap::FindOrAdd(int bx, int by, int bz) {
  const auto [it, added] = index_.try_emplace(Pack(bx, by, bz), num_blocks());
  if (added) {
    coords_.push_back({bx, by, bz});
    blocks_.emplace_back();
    blocks_.back().log_odds.fill(std::numeric_limits<float>::quiet_NaN());
    scan_.emplace_back();
    touched_flag_.push_back(0);
  }
  return it->second;
}

int32_t VoxelMap::ScanBlock(int ix, int iy, int iz) {
  const int bx = ix >> kShift, by = iy >> kShift, bz = iz >> kShift;
  if (bx == last_block_[0] && by == last_block_[1] && bz == last_block_[2]) return last_number_;
  int32_t b;
  const unsigned x = static_cast<unsigned>(bx - win_lo_[0]),
                 y = static_cast<unsigned>(by - win_lo_[1]),
                 z = static_cast<unsigned>(bz - win_lo_[2]);
  if (x < static_cast<unsigned>(win_size_[0]) && y < static_cast<unsigned>(win_size_[1]) &&
      z < static_cast<unsigned>(win_size_[2])) {
    int32_t& cell = window_[(static_cast<size_t>(z) * win_size_[1] + y) * win_size_[0] + x];
    if (cell < 0) cell = FindOrAdd(bx, by, bz);
    b = cell;
  } else {
    b = FindOrAdd(bx, by, bz);
  }
  if (!touched_flag_[b]) {
    touched_flag_[b] = 1;
    touched_.push_back(b);
  }
  last_block_ = {bx, by, bz};
  last_number_ = b;
  return b;
}

void VoxelMap::Mark(int ix, int iy, int iz, int which) {
  const int32_t b = ScanBlock(ix, iy, iz);
  const int l = Local(ix, iy, iz);
  auto& words = which == 0 ? scan_[b].hit : scan_[b].miss;
  words[l >> 6] |= uint64_t{1} << (l & 63);
}

// The voxels of the ray origin -> end, origin's included and end's excluded, with the
// arithmetic of OctoMap's computeRayKeys (float direction, double crossing parameters, stop
// at the end voxel or when the next crossing lies beyond the float length).
void VoxelMap::CastMisses(const float origin[3], const float end[3]) {
  int ko[3], ke[3];
  if (!CheckedIndex(origin, inv_res_, ko) || !CheckedIndex(end, inv_res_, ke)) return;
  if (ko[0] == ke[0] && ko[1] == ke[1] && ko[2] == ke[2]) return;
  Mark(ko[0], ko[1], ko[2], 1);
  float dir[3] = {end[0] - origin[0], end[1] - origin[1], end[2] - origin[2]};
  const float length = static_cast<float>(FloatNorm(dir));
  for (float& c : dir) c /= length;
  int step[3];
  double t_max[3], t_delta[3];
  int cur[3] = {ko[0], ko[1], ko[2]};
  for (int a = 0; a < 3; ++a) {
    step[a] = dir[a] > 0.0f ? 1 : (dir[a] < 0.0f ? -1 : 0);
    if (step[a] != 0) {
      double border = (static_cast<double>(cur[a]) + 0.5) * res_;  // voxel centre
      border += static_cast<float>(step[a] * res_ * 0.5);          // its face ahead
      t_max[a] = (border - origin[a]) / dir[a];
      t_delta[a] = res_ / std::fabs(dir[a]);
    } else {
      t_max[a] = std::numeric_limits<double>::max();
      t_delta[a] = std::numeric_limits<double>::max();
    }
  }
  // Miss bits of the current block, and the voxel's place in it, followed incrementally.
  uint64_t* miss = scan_[ScanBlock(cur[0], cur[1], cur[2])].miss.data();
  int local = Local(cur[0], cur[1], cur[2]);
  constexpr int kStride[3] = {1, kSide, kSide * kSide};
  while (true) {
    const int a =
        t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    cur[a] += step[a];
    t_max[a] += t_delta[a];
    if (cur[0] == ke[0] && cur[1] == ke[1] && cur[2] == ke[2]) break;
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length) break;
    const int within = (cur[a] & (kSide - 1));
    if (within == (step[a] > 0 ? 0 : kSide - 1)) {  // entered the next block along a
      miss = scan_[ScanBlock(cur[0], cur[1], cur[2])].miss.data();
      local = Local(cur[0], cur[1], cur[2]);
    } else {
      local += step[a] * kStride[a];
    }
    miss[local >> 6] |= uint64_t{1} << (local & 63);
  }
}

void VoxelMap::InsertScan(const std::vector<Eigen::Vector3f>& points,
                          const Eigen::Vector3f& origin_in, double max_range_m, bool discretize,
                          const Eigen::Vector3f* points_lo, const Eigen::Vector3f* points_hi) {
  final_ = false;
  const float origin[3] = {origin_in.x(), origin_in.y(), origin_in.z()};
  // Block window over the scan: every ray stays within the box of its origin and end (one
  // block of margin for rounding; anything outside still works through the hash).
  int lo[3], hi[3], io[3];
  if (!CheckedIndex(origin, inv_res_, io)) return;  // OctoMap casts nothing from there
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = io[a];
  if (!points.empty()) {  // floor is monotonic: the index box is that of the extreme coordinates
    Eigen::Vector3f p_lo = points[0], p_hi = points[0];
    if (points_lo != nullptr && points_hi != nullptr) {
      p_lo = *points_lo;
      p_hi = *points_hi;
    } else {
      for (const auto& p : points) {
        p_lo = p_lo.cwiseMin(p);
        p_hi = p_hi.cwiseMax(p);
      }
    }
    for (int a = 0; a < 3; ++a) {
      const double l = std::floor(inv_res_ * static_cast<double>(p_lo[a]));
      const double h = std::floor(inv_res_ * static_cast<double>(p_hi[a]));
      lo[a] = std::min(lo[a], static_cast<int>(std::clamp<double>(l, kMinIndex, kMaxIndex)));
      hi[a] = std::max(hi[a], static_cast<int>(std::clamp<double>(h, kMinIndex, kMaxIndex)));
    }
  }
  size_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    win_lo_[a] = (lo[a] >> kShift) - 1;
    win_size_[a] = (hi[a] >> kShift) + 2 - win_lo_[a];
    cells *= static_cast<size_t>(win_size_[a]);
  }
  if (cells <= kMaxWindowCells) {
    window_.assign(cells, -1);
  } else {
    window_.clear();
    win_size_ = {0, 0, 0};
  }
  last_block_ = {INT32_MIN, 0, 0};

  int prev[3] = {INT32_MIN, 0, 0};  // voxel of the previous point (neighbouring pixels)
  for (const auto& p : points) {
    float end[3];
    if (discretize) {  // the centre of the point's voxel, once per voxel
      int ip[3];
      if (!CheckedIndex(p.data(), inv_res_, ip)) continue;
      if (ip[0] == prev[0] && ip[1] == prev[1] && ip[2] == prev[2]) continue;  // seen already
      prev[0] = ip[0], prev[1] = ip[1], prev[2] = ip[2];
      const int32_t b = ScanBlock(ip[0], ip[1], ip[2]);
      const int l = Local(ip[0], ip[1], ip[2]);
      uint64_t& seen = scan_[b].seen[l >> 6];
      const uint64_t bit = uint64_t{1} << (l & 63);
      if (seen & bit) continue;
      seen |= bit;
      for (int a = 0; a < 3; ++a)
        end[a] = static_cast<float>((static_cast<double>(ip[a]) + 0.5) * res_);
    } else {
      for (int a = 0; a < 3; ++a) end[a] = p[a];
    }
    const float diff[3] = {end[0] - origin[0], end[1] - origin[1], end[2] - origin[2]};
    const double dist = FloatNorm(diff);
    if (max_range_m < 0.0 || dist <= max_range_m) {
      CastMisses(origin, end);
      int ie[3];
      if (CheckedIndex(end, inv_res_, ie)) Mark(ie[0], ie[1], ie[2], 0);
    } else {  // truncated: free up to max_range along the ray, no hit
      float dir[3] = {diff[0], diff[1], diff[2]};
      if (dist > 0.0) {
        const float len = static_cast<float>(dist);
        for (float& c : dir) c /= len;
      }
      const float range = static_cast<float>(max_range_m);
      const float cut[3] = {origin[0] + dir[0] * range, origin[1] + dir[1] * range,
                            origin[2] + dir[2] * range};
      CastMisses(origin, cut);
    }
  }
  ApplyScan();
  window_.clear();
  window_.shrink_to_fit();
}

void VoxelMap::ApplyScan() {
  for (const int32_t b : touched_) {
    ScanBits& s = scan_[b];
    float* l = blocks_[b].log_odds.data();
    for (int w = 0; w < kBlockVoxels / 64; ++w) {
      uint64_t hit = s.hit[w];
      uint64_t miss = s.miss[w] & ~hit;  // a hit wins within one scan
      while (hit) {
        UpdateLogOdds(&l[w * 64 + __builtin_ctzll(hit)], model_.hit, model_);
        hit &= hit - 1;
      }
      while (miss) {
        UpdateLogOdds(&l[w * 64 + __builtin_ctzll(miss)], model_.miss, model_);
        miss &= miss - 1;
      }
    }
    s = ScanBits();
    touched_flag_[b] = 0;
  }
  touched_.clear();
}

void VoxelMap::SetLogOdds(int ix, int iy, int iz, float log_odds) {
  final_ = false;
  const int32_t b = FindOrAdd(ix >> kShift, iy >> kShift, iz >> kShift);
  blocks_[b].log_odds[Local(ix, iy, iz)] = log_odds;
}

void VoxelMap::Finalize() {
  {
    std::lock_guard<std::mutex> lock(boxes_mutex_);
    boxes_.reset();
  }
  const size_t n = coords_.size();
  states_.resize(n);
  kinds_.resize(n);
  has_bounds_ = false;
  num_occupied_ = num_free_ = 0;
  for (size_t b = 0; b < n; ++b) {
    const float* l = blocks_[b].log_odds.data();
    int8_t* s = states_[b].data();
    int occupied = 0, free = 0;
    for (int i = 0; i < kBlockVoxels; ++i) {
      if (std::isnan(l[i])) {
        s[i] = kUnknown;
      } else if (l[i] >= model_.occupied_threshold) {
        s[i] = kOccupied;
        ++occupied;
      } else {
        s[i] = kFree;
        ++free;
      }
    }
    num_occupied_ += occupied;
    num_free_ += free;
    kinds_[b] = occupied == kBlockVoxels ? Kind::kAllOccupied
                : free == kBlockVoxels   ? Kind::kAllFree
                                         : Kind::kMixed;
    if (occupied + free == 0) continue;
    const Eigen::Vector3i base(coords_[b][0] * kSide, coords_[b][1] * kSide,  // may be < 0
                               coords_[b][2] * kSide);
    Eigen::Vector3i blo, bhi;
    if (occupied + free == kBlockVoxels) {
      blo = base;
      bhi = base + Eigen::Vector3i::Constant(kSide - 1);
    } else {
      blo = Eigen::Vector3i::Constant(kSide);
      bhi = Eigen::Vector3i::Constant(-1);
      for (int i = 0; i < kBlockVoxels; ++i) {
        if (s[i] == kUnknown) continue;
        const Eigen::Vector3i v(i & (kSide - 1), (i >> kShift) & (kSide - 1), i >> (2 * kShift));
        blo = blo.cwiseMin(v);
        bhi = bhi.cwiseMax(v);
      }
      blo += base;
      bhi += base;
    }
    if (!has_bounds_) {
      lo_ = blo;
      hi_ = bhi;
      has_bounds_ = true;
    } else {
      lo_ = lo_.cwiseMin(blo);
      hi_ = hi_.cwiseMax(bhi);
    }
  }
  final_ = true;
}

namespace {

// Greedy cut of one mixed block into boxes of one state, on bit rows: rows[s][z][y] has bit x
// set when voxel (x, y, z) has state s (0 free, 1 occupied) and is not in a box yet.
void CutBlock(const int8_t* states, std::vector<VoxelMap::Box>* out) {
  constexpr int W = VoxelMap::kSide;
  static_assert(W == 8, "one byte per row");
  uint8_t rows[2][W][W] = {};
  for (int z = 0; z < W; ++z)
    for (int y = 0; y < W; ++y)
      for (int x = 0; x < W; ++x) {
        const int8_t s = states[(z * W + y) * W + x];
        if (s != VoxelMap::kUnknown) rows[s == VoxelMap::kOccupied][z][y] |= 1u << x;
      }
  for (int z = 0; z < W; ++z) {
    for (int y = 0; y < W; ++y) {
      for (int s = 0; s < 2; ++s) {
        uint8_t(*r)[W] = rows[s];
        while (r[z][y] != 0) {
          const unsigned m = r[z][y];
          const int x0 = __builtin_ctz(m);
          const int len = __builtin_ctz(~(m >> x0));
          const unsigned run = ((1u << len) - 1) << x0;
          int y1 = y + 1;
          while (y1 < W && (r[z][y1] & run) == run) ++y1;
          int z1 = z + 1;
          for (; z1 < W; ++z1) {
            bool all = true;
            for (int yy = y; yy < y1 && all; ++yy) all = (r[z1][yy] & run) == run;
            if (!all) break;
          }
          for (int zz = z; zz < z1; ++zz)
            for (int yy = y; yy < y1; ++yy) r[zz][yy] = static_cast<uint8_t>(r[zz][yy] & ~run);
          out->push_back({static_cast<uint8_t>(x0), static_cast<uint8_t>(y),
                          static_cast<uint8_t>(z), static_cast<uint8_t>(x0 + len),
                          static_cast<uint8_t>(y1), static_cast<uint8_t>(z1), s == 1});
        }
      }
    }
  }
}

}  // namespace

const VoxelMap::BlockBoxes& VoxelMap::Boxes() const {
  GT_ASSERT(final_);
  std::lock_guard<std::mutex> lock(boxes_mutex_);
  if (!boxes_) {
    auto b = std::make_unique<BlockBoxes>();
    b->first.reserve(coords_.size() + 1);
    for (size_t i = 0; i < coords_.size(); ++i) {
      b->first.push_back(static_cast<int32_t>(b->boxes.size()));
      if (kinds_[i] == Kind::kMixed) {
        CutBlock(states_[i].data(), &b->boxes);
      } else {
        b->boxes.push_back({0, 0, 0, kSide, kSide, kSide, kinds_[i] == Kind::kAllOccupied});
      }
    }
    b->first.push_back(static_cast<int32_t>(b->boxes.size()));
    boxes_ = std::move(b);
  }
  return *boxes_;
}

int8_t VoxelMap::StateAt(int ix, int iy, int iz) const {
  GT_ASSERT(final_);
  const int32_t b = FindBlock(ix >> kShift, iy >> kShift, iz >> kShift);
  return b < 0 ? kUnknown : states_[b][Local(ix, iy, iz)];
}

bool VoxelMap::Bounds(Eigen::Vector3i* lo, Eigen::Vector3i* hi) const {
  GT_ASSERT(final_);
  if (!has_bounds_) return false;
  *lo = lo_;
  *hi = hi_;
  return true;
}

BlockWindow::BlockWindow(const VoxelMap& map, const Eigen::Vector3i& lo_block,
                         const Eigen::Vector3i& hi_block)
    : map_(&map) {
  size_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    if (hi_block[a] < lo_block[a]) return;
    lo_[a] = lo_block[a];
    cells *= static_cast<size_t>(hi_block[a] - lo_block[a] + 1);
  }
  if (cells > kMaxWindowCells) return;  // every look-up goes to the hash
  for (int a = 0; a < 3; ++a) size_[a] = static_cast<unsigned>(hi_block[a] - lo_block[a] + 1);
  cells_.assign(cells, -1);
  if (static_cast<size_t>(map.num_blocks()) <= cells) {
    for (int32_t b = 0; b < map.num_blocks(); ++b) {
      const auto& c = map.block_coord(b);
      const unsigned x = static_cast<unsigned>(c[0] - lo_[0]),
                     y = static_cast<unsigned>(c[1] - lo_[1]),
                     z = static_cast<unsigned>(c[2] - lo_[2]);
      if (x < size_[0] && y < size_[1] && z < size_[2])
        cells_[(static_cast<size_t>(z) * size_[1] + y) * size_[0] + x] = b;
    }
  } else {
    size_t i = 0;
    for (unsigned z = 0; z < size_[2]; ++z)
      for (unsigned y = 0; y < size_[1]; ++y)
        for (unsigned x = 0; x < size_[0]; ++x)
          cells_[i++] = map.FindBlock(lo_[0] + static_cast<int>(x), lo_[1] + static_cast<int>(y),
                                      lo_[2] + static_cast<int>(z));
  }
}

}  // namespace gt::occupancy

// The inner kernel of the exact box splat (frustum.cc SplatBox): one row of rays of the
// half-resolution grid against one axis-aligned box of known voxels. Internal to
// libgt/occupancy. Two versions give identical bits: a scalar one, and an AVX2 one (four
// rays at a time) chosen at run time when the processor has AVX2 and the bin edges are
// uniform in the edge index (EdgeIndex::one_step).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "libgt/occupancy/edge_index.h"
#include "libgt/occupancy/frustum.h"

namespace gt::occupancy {

// Per ray of the half grid (row-major), 1 / d per world axis for the slab tests of the box
// splat; 0 on all three axes for the rays left to TraverseExact (their slab interval is then
// empty, so no box marks them).
struct SplatRays {
  std::vector<double> inv_x, inv_y, inv_z;
};

// One row of rays [ua, ub] against one box (corners a, b relative to the camera centre).
struct RowArgs {
  const SplatRays* rays;
  const EdgeIndex* bins;
  FrustumVolume* vol;
  const Eigen::Vector3d *a, *b;
  double e0, eD;
  bool occupied;
  size_t row;  // index of the row's first ray
  int ua, ub;
  // Bins any crossing of the box can overlap, from the planar depths of its corners, when
  // they are at most two (k_last <= k_first + 1): the bin lookup then reduces to comparing
  // with the one edge between them. Otherwise k_first = -1 (general lookup).
  int k_first, k_last;
};

// Marks the bins of r.ua..r.ub in r.vol (known, and occ when r.occupied).
void SplatRow(const RowArgs& r);

}  // namespace gt::occupancy

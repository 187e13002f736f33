// The exact frustum binning (ProjectToFrustum, Traversal::kExact: the box splat of
// frustum.cc) against the voxel walk kept in tests/occupancy/reference_traversal.h: the occ
// and known words must be equal ray for ray (so bin for bin) except for rounding ties, each
// checked against a brute-force bound (ExpectSameVolume), on the real pairs (TartanAir
// hospital 0/20, 7-Scenes 150/190) and on random scenes seen from the fused cameras and from
// other random poses, with several voxel sizes and bin spacings; the scalar and AVX2
// kernels must agree exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

#include "libgt/io/depth_io.h"
#include "libgt/datasets/reader.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "tests/occupancy/reference_traversal.h"
#include "tests/support/test_support.h"

namespace gt::occupancy {
namespace {

struct Bits {
  uint64_t occ = 0, known = 0;
};

// Known voxels of the map (index and state), for the brute-force check below.
struct KnownVoxel {
  Eigen::Vector3i index;
  bool occupied;
};

std::vector<KnownVoxel> KnownVoxels(const OccupancyMap& map) {
  std::vector<KnownVoxel> out;
  Eigen::Vector3i lo, hi;
  if (!map.KnownIndexBounds(&lo, &hi)) return out;
  const VoxelBlock block = map.ExtractBlock(lo, hi);
  for (int z = 0; z < block.size.z(); ++z)
    for (int y = 0; y < block.size.y(); ++y)
      for (int x = 0; x < block.size.x(); ++x) {
        const int8_t s = block.at(x, y, z);
        if (s != VoxelBlock::kUnknown)
          out.push_back({block.min_index + Eigen::Vector3i(x, y, z), s == VoxelBlock::kOccupied});
      }
  return out;
}

// The bins of one ray from every known voxel, by a slab test in long double, with every voxel
// box and every crossing's planar-depth interval grown (delta > 0: every bin a rounding of
// the crossing could touch) or shrunk (delta < 0: only bins no rounding can miss) by |delta|
// metres. Any correct traversal lies between the shrunk and the grown bits.
Bits BruteForceRay(const std::vector<KnownVoxel>& voxels, double res, const Eigen::Vector3d& o,
                   const Eigen::Vector3d& d, const std::vector<double>& e, long double delta) {
  Bits out;
  const int D = static_cast<int>(e.size()) - 1;
  const long double e0 = e.front(), eD = e.back();
  for (const KnownVoxel& v : voxels) {
    long double z0 = -1e30L, z1 = 1e30L;
    bool inside = true;
    for (int a = 0; a < 3 && inside; ++a) {
      const long double lo = static_cast<long double>(v.index[a]) * res - delta;
      const long double hi = static_cast<long double>(v.index[a] + 1) * res + delta;
      if (d[a] == 0) {
        inside = o[a] >= lo && o[a] <= hi;
        continue;
      }
      long double t0 = (lo - o[a]) / d[a], t1 = (hi - o[a]) / d[a];
      if (t0 > t1) std::swap(t0, t1);
      z0 = std::max(z0, t0);
      z1 = std::min(z1, t1);
    }
    if (!inside) continue;
    z0 = std::max(z0, e0) - delta;
    z1 = std::min(z1, eD) + delta;
    if (!(z1 > z0)) continue;
    uint64_t m = 0;
    for (int k = 0; k < D; ++k) {
      if (e[k] < z1 && e[k + 1] > z0) m |= uint64_t{1} << k;
    }
    out.known |= m;
    if (v.occupied) out.occ |= m;
  }
  return out;
}

// Compares the exact binning with the reference walk ray for ray. Rays may differ only by
// ties: crossings within ~1e-6 m of a voxel face or bin edge, which rounding decides
// differently in the two (e.g. the walk enters each mixed block 1e-6 m inside it). Every
// differing ray is checked to be one: both results must lie between the brute-force bits
// with voxels shrunk and grown by 1e-5 m. At most 1 in 10^4 rays may differ at all.
// Also checks that the scalar and AVX2 kernels give identical words. Returns the number of
// differing rays; prints the volume's counts.
int64_t ExpectSameVolume(const OccupancyMap& map, const Camera& cam, const Rigid3d& pose,
                         const BinOptions& bins, const std::string& what) {
  SCOPED_TRACE(what);
  BinOptions exact = bins;
  exact.traversal = Traversal::kExact;
  const FrustumVolume fast = ProjectToFrustum(map, cam, pose, exact);
  SetVectorKernelsForTesting(false);
  const FrustumVolume scalar = ProjectToFrustum(map, cam, pose, exact);
  SetVectorKernelsForTesting(true);
  EXPECT_TRUE(fast.occ == scalar.occ && fast.known == scalar.known)
      << "the scalar and vector kernels differ";
  const FrustumVolume ref = reference::ProjectToFrustumReference(map, cam, pose, exact);
  EXPECT_EQ(fast.width, ref.width);
  EXPECT_EQ(fast.height, ref.height);
  EXPECT_EQ(fast.edges_m, ref.edges_m);
  EXPECT_EQ(fast.occ.size(), ref.occ.size());
  int64_t differing = 0, not_ties = 0;
  std::vector<KnownVoxel> voxels;
  const Camera half = cam.HalfGrid();
  for (size_t i = 0; i < fast.occ.size() && i < ref.occ.size(); ++i) {
    if (fast.occ[i] == ref.occ[i] && fast.known[i] == ref.known[i]) continue;
    ++differing;
    if (voxels.empty()) voxels = KnownVoxels(map);
    const int u = static_cast<int>(i % fast.width), v = static_cast<int>(i / fast.width);
    const Eigen::Vector3d d =
        pose.linear() * Eigen::Vector3d((u - half.cx) / half.fx, (v - half.cy) / half.fy, 1.0);
    const Eigen::Vector3d o = pose.translation();
    const Bits lo = BruteForceRay(voxels, map.resolution_m(), o, d, fast.edges_m, -1e-5L);
    const Bits hi = BruteForceRay(voxels, map.resolution_m(), o, d, fast.edges_m, 1e-5L);
    for (const FrustumVolume* x : {&fast, &ref}) {
      const bool between = (lo.occ & ~x->occ[i]) == 0 && (x->occ[i] & ~hi.occ) == 0 &&
                           (lo.known & ~x->known[i]) == 0 && (x->known[i] & ~hi.known) == 0;
      if (!between && not_ties++ < 5) {
        ADD_FAILURE() << "ray " << i << " (" << (x == &fast ? "fast" : "reference")
                      << ") is not within the rounding bounds: occ " << std::hex << x->occ[i]
                      << " known " << x->known[i] << ", bounds occ " << lo.occ << ".." << hi.occ
                      << " known " << lo.known << ".." << hi.known;
      }
    }
  }
  const VolumeCounts c = CountBins(ref);
  std::printf("%s: occupied %lld free %lld unknown %lld, differing rays %lld (ties)\n",
              what.c_str(), static_cast<long long>(c.occupied), static_cast<long long>(c.free),
              static_cast<long long>(c.unknown), static_cast<long long>(differing));
  EXPECT_EQ(not_ties, 0);
  EXPECT_LE(differing * 10000, static_cast<int64_t>(fast.occ.size()) + 9999);
  return differing;
}

// Bin-centre sampling (Traversal::kCenter) against the definition: bin k of a ray is the
// state of the voxel (OccupancyMap::StateAt) at the ray's point of planar depth
// (e_k + e_{k+1}) / 2, looked up one by one. Returns the number of differing rays.
int64_t ExpectCenterIsStateAtBinCentres(const OccupancyMap& map, const Camera& cam,
                                        const Rigid3d& pose, const BinOptions& bins,
                                        const std::string& what) {
  SCOPED_TRACE(what + " (center)");
  BinOptions center = bins;
  center.traversal = Traversal::kCenter;
  const FrustumVolume vol = ProjectToFrustum(map, cam, pose, center);
  const Camera half = cam.HalfGrid();
  const std::vector<double>& e = vol.edges_m;
  int64_t differing = 0;
  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      const Eigen::Vector3d d =
          pose.linear() * Eigen::Vector3d((u - half.cx) / half.fx, (v - half.cy) / half.fy, 1.0);
      Bits want;
      for (int k = 0; k + 1 < static_cast<int>(e.size()); ++k) {
        const int s = map.StateAt(pose.translation() + 0.5 * (e[k] + e[k + 1]) * d);
        if (s >= 0) want.known |= uint64_t{1} << k;
        if (s == 1) want.occ |= uint64_t{1} << k;
      }
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      if (vol.occ[i] != want.occ || vol.known[i] != want.known) {
        if (differing < 5)
          ADD_FAILURE() << "ray " << i << ": occ " << std::hex << vol.occ[i] << " vs " << want.occ
                        << ", known " << vol.known[i] << " vs " << want.known;
        ++differing;
      }
    }
  }
  EXPECT_EQ(differing, 0);
  return differing;
}

std::vector<BinOptions> SomeBinOptions() {
  std::vector<BinOptions> out(5);
  out[1].spacing = BinSpacing::kLog;
  out[2].spacing = BinSpacing::kInverse;
  out[2].num_bins = 37;
  out[3].near_m = 0.3;
  out[3].far_m = 5.0;
  out[3].num_bins = 50;
  // Bins far narrower than the bin table's cap (first bin ~0.3 um): the lookup's loop path.
  out[4].spacing = BinSpacing::kLog;
  out[4].near_m = 1e-6;
  out[4].far_m = 10.0;
  return out;
}

struct Loaded {
  Scene scene;
  std::vector<DepthImage> depths;
};

Loaded Load(const std::string& format, const std::string& root) {
  Loaded l;
  l.scene = datasets::MakeReader(ParseDatasetFormat(format))->ReadScene(root, "");
  for (const Frame& f : l.scene.frames)
    l.depths.push_back(ResizeDepthNearest(io::ReadDepth(f.depth), 640, 480));
  return l;
}

FusionInput InputOf(const Loaded& l, int64_t number) {
  for (size_t i = 0; i < l.scene.frames.size(); ++i) {
    const Frame& f = l.scene.frames[i];
    if (f.number == number)
      return {&l.depths[i], f.depth_camera.Resized(640, 480), f.world_from_cam, l.scene.min_depth_m,
              l.scene.max_depth_m};
  }
  ADD_FAILURE() << "no frame " << number;
  return {};
}

void ExpectRealPair(const Loaded& l, int64_t n0, int64_t n1, const std::string& what) {
  const std::vector<FusionInput> frames = {InputOf(l, n0), InputOf(l, n1)};
  const OccupancyMap map = FuseOccupancy(frames, FusionOptions());
  const auto bins = SomeBinOptions();
  for (size_t b = 0; b < bins.size(); ++b) {
    for (size_t c = 0; c < frames.size(); ++c) {
      ExpectSameVolume(map, frames[c].camera, frames[c].world_from_cam, bins[b],
                       what + " cam" + std::to_string(c) + " bins" + std::to_string(b));
      ExpectCenterIsStateAtBinCentres(
          map, frames[c].camera, frames[c].world_from_cam, bins[b],
          what + " cam" + std::to_string(c) + " bins" + std::to_string(b));
    }
  }
}

TEST(ExactTraversal, SameAsReferenceOnTartanAirHospital0And20) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  if (root.empty()) return;
  ExpectRealPair(Load("tartanair", root), 0, 20, "tartanair 0/20");
}

TEST(ExactTraversal, SameAsReferenceOnSevenScenes150And190) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  if (root.empty()) return;
  ExpectRealPair(Load("sevenscenes", root), 150, 190, "7-scenes 150/190");
}

Camera TestCamera(int w, int h, double f) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fx = c.fy = f;
  c.cx = (w - 1) / 2.0;
  c.cy = (h - 1) / 2.0;
  return c;
}

Rigid3d RandomPose(std::mt19937* rng, double spread_m) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d axis(u(*rng), u(*rng), u(*rng));
  Rigid3d p = Rigid3d::Identity();
  p.linear() = Eigen::AngleAxisd(u(*rng) * 3.14159, axis.normalized()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(u(*rng), u(*rng), u(*rng)) * spread_m;
  return p;
}

// Smooth random surfaces with holes, steps and a few depths beyond max_range.
DepthImage RandomDepth(int w, int h, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double a = 0.4 + 3.0 * u(*rng), b = u(*rng) * 8.0, c = u(*rng) * 8.0;
  const int step_x = static_cast<int>(u(*rng) * w);
  DepthImage d(w, h, 0.0f);
  for (int v = 0; v < h; ++v) {
    for (int x = 0; x < w; ++x) {
      double z = a + 0.4 * std::sin(b * x / w) + 0.3 * std::cos(c * v / h);
      if (x > step_x) z += 0.7;
      const double r = u(*rng);
      if (r < 0.05) z = 0.0;
      if (r > 0.97) z = 12.0 + 30.0 * u(*rng);
      d.at(x, v) = static_cast<float>(z);
    }
  }
  return d;
}

TEST(ExactTraversal, SameAsReferenceOnRandomScenes) {
  std::mt19937 rng(2026);
  const auto bins = SomeBinOptions();
  for (int trial = 0; trial < 6; ++trial) {
    const Camera cam = TestCamera(160, 120, 130.0);
    std::vector<DepthImage> depths;
    std::vector<FusionInput> frames;
    for (int f = 0; f < 3; ++f) depths.push_back(RandomDepth(160, 120, &rng));
    for (int f = 0; f < 3; ++f)
      frames.push_back({&depths[f], cam, RandomPose(&rng, trial < 3 ? 0.3 : 1.5), 0.1, 100.0});
    FusionOptions o;
    o.voxel_m = trial % 3 == 0 ? 0.05 : (trial % 3 == 1 ? 0.03 : 0.1);
    o.max_range_m = trial == 5 ? 0 : 6.0;
    const OccupancyMap map = FuseOccupancy(frames, o);
    const std::string name = "random " + std::to_string(trial);
    for (int f = 0; f < 3; ++f)
      ExpectSameVolume(map, cam, frames[f].world_from_cam, bins[(trial + f) % bins.size()],
                       name + " cam" + std::to_string(f));
    // Views the map was not fused from (rays enter known space from anywhere).
    for (int extra = 0; extra < 3; ++extra) {
      const Rigid3d pose = RandomPose(&rng, 1.0);
      const BinOptions& b = bins[(trial + extra) % bins.size()];
      ExpectSameVolume(map, TestCamera(100, 80, 70.0), pose, b,
                       name + " other view " + std::to_string(extra));
      ExpectCenterIsStateAtBinCentres(map, TestCamera(100, 80, 70.0), pose, b,
                                      name + " other view " + std::to_string(extra));
    }
  }
}

}  // namespace
}  // namespace gt::occupancy

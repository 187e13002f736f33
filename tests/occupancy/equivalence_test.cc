// The own fusion engine (voxel_map.h) against OctoMap's own OcTree::insertPointCloud on the
// same clouds: the state of every voxel (occupied / free / unknown) must be equal, and so the
// saved .bt files (pruned trees) and the frustum volumes. Scenes: random depth maps from
// random poses (rays longer than max_range, several scans so that log-odds clamp, one ray
// per point as well as discretized), and the real samples (TartanAir hospital 0/20, 7-Scenes
// 150/190 and a 7-Scenes window of 11 frames).
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>

#include "libgt/io/depth_io.h"
#include "libgt/datasets/reader.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "tests/support/test_support.h"

namespace gt::occupancy {
namespace {

struct Comparison {
  int64_t known_own = 0, known_ref = 0, differing = 0;
};

// Voxel-by-voxel comparison over the union of both maps' known boxes.
Comparison Compare(const OccupancyMap& own, const OccupancyMap& ref) {
  Comparison c;
  Eigen::Vector3i lo_a, hi_a, lo_b, hi_b;
  const bool a = own.KnownIndexBounds(&lo_a, &hi_a), b = ref.KnownIndexBounds(&lo_b, &hi_b);
  EXPECT_EQ(a, b);
  if (!a || !b) return c;
  EXPECT_EQ(own.NumOccupiedVoxels(), ref.NumOccupiedVoxels());
  EXPECT_EQ(own.NumFreeVoxels(), ref.NumFreeVoxels());
  const Eigen::Vector3i lo = lo_a.cwiseMin(lo_b), hi = hi_a.cwiseMax(hi_b);
  // Slab by slab along z to bound memory on large scenes.
  for (int z = lo.z(); z <= hi.z(); z += 16) {
    const Eigen::Vector3i l(lo.x(), lo.y(), z), h(hi.x(), hi.y(), std::min(z + 15, hi.z()));
    const VoxelBlock x = own.ExtractBlock(l, h), y = ref.ExtractBlock(l, h);
    EXPECT_EQ(x.state.size(), y.state.size());
    for (size_t i = 0; i < x.state.size() && i < y.state.size(); ++i) {
      c.known_own += x.state[i] != VoxelBlock::kUnknown;
      c.known_ref += y.state[i] != VoxelBlock::kUnknown;
      c.differing += x.state[i] != y.state[i];
    }
  }
  return c;
}

std::string SavedBytes(const OccupancyMap& map, const std::string& name) {
  const std::string path = gt::test::ScratchDir("occupancy_equivalence") + "/" + name + ".bt";
  map.SaveBinary(path);
  std::ifstream f(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), {});
}

// Fuses with both engines and expects the same voxel states everywhere; with `bytes` also the
// same .bt file and leaf count (the pruned trees are the same).
Comparison ExpectSameMaps(const std::vector<FusionInput>& frames, FusionOptions options,
                          const std::string& what, bool bytes = true) {
  SCOPED_TRACE(what);
  options.engine = FusionEngine::kOwn;
  const OccupancyMap own = FuseOccupancy(frames, options);
  options.engine = FusionEngine::kOctomap;
  const OccupancyMap ref = FuseOccupancy(frames, options);
  const Comparison c = Compare(own, ref);
  std::printf("%s: known voxels own %lld, octomap %lld, differing %lld\n", what.c_str(),
              static_cast<long long>(c.known_own), static_cast<long long>(c.known_ref),
              static_cast<long long>(c.differing));
  EXPECT_GT(c.known_ref, 0);
  EXPECT_EQ(c.differing, 0);
  EXPECT_EQ(own.stats().inserted_points, ref.stats().inserted_points);
  if (bytes) {
    EXPECT_EQ(own.NumLeafNodes(), ref.NumLeafNodes());
    EXPECT_TRUE(SavedBytes(own, "own") == SavedBytes(ref, "ref")) << ".bt files differ";
  }
  return c;
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
  Eigen::Vector3d axis(u(*rng), u(*rng), u(*rng));
  Rigid3d p = Rigid3d::Identity();
  p.linear() = Eigen::AngleAxisd(u(*rng) * 3.14159, axis.normalized()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(u(*rng), u(*rng), u(*rng)) * spread_m;
  return p;
}

// Smooth random surfaces (sum of waves) with holes and a few far depths beyond max_range.
DepthImage RandomDepth(int w, int h, std::mt19937* rng, double far_fraction) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double a = 0.5 + 3.0 * u(*rng), b = u(*rng) * 6.0, c = u(*rng) * 6.0;
  DepthImage d(w, h, 0.0f);
  for (int v = 0; v < h; ++v) {
    for (int x = 0; x < w; ++x) {
      double z = a + 0.4 * std::sin(b * x / w) + 0.3 * std::cos(c * v / h);
      const double r = u(*rng);
      if (r < 0.05) z = 0.0;                                 // hole
      if (r > 1.0 - far_fraction) z = 12.0 + 30.0 * u(*rng);  // beyond max_range (10 m)
      d.at(x, v) = static_cast<float>(z);
    }
  }
  return d;
}

TEST(Equivalence, RandomScenesDiscretized) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    const Camera cam = TestCamera(96, 72, 80.0);
    std::vector<DepthImage> depths;
    std::vector<Rigid3d> poses;
    for (int f = 0; f < 3; ++f) {
      depths.push_back(RandomDepth(96, 72, &rng, 0.05));
      poses.push_back(RandomPose(&rng, 2.0));
    }
    std::vector<FusionInput> frames;
    for (int f = 0; f < 3; ++f) frames.push_back({&depths[f], cam, poses[f], 0.1, 100.0});
    FusionOptions o;
    o.voxel_m = trial % 2 == 0 ? 0.05 : 0.03;
    o.max_range_m = 5.0;  // the far depths (12-42 m) are truncated
    ExpectSameMaps(frames, o, "random discretized " + std::to_string(trial));
  }
}

TEST(Equivalence, RandomScenesOneRayPerPointAndUnlimitedRange) {
  std::mt19937 rng(11);
  const Camera cam = TestCamera(64, 48, 50.0);
  std::vector<DepthImage> depths;
  std::vector<FusionInput> frames;
  for (int f = 0; f < 2; ++f) depths.push_back(RandomDepth(64, 48, &rng, 0.1));
  for (int f = 0; f < 2; ++f) frames.push_back({&depths[f], cam, RandomPose(&rng, 1.0), 0.1, 100});
  FusionOptions o;
  o.discretize = false;
  ExpectSameMaps(frames, o, "one ray per point");
  o.discretize = true;
  o.max_range_m = 0;  // unlimited
  ExpectSameMaps(frames, o, "unlimited range");
}

// The same view inserted 12 times: hits reach the upper clamp, misses the lower one.
TEST(Equivalence, RepeatedScansClampLikeOctomap) {
  std::mt19937 rng(3);
  const Camera cam = TestCamera(48, 36, 40.0);
  const DepthImage depth = RandomDepth(48, 36, &rng, 0.0);
  const Rigid3d pose = RandomPose(&rng, 0.5);
  std::vector<FusionInput> frames(12, FusionInput{&depth, cam, pose, 0.1, 100});
  const DepthImage other = RandomDepth(48, 36, &rng, 0.0);
  frames.push_back({&other, cam, pose, 0.1, 100});  // moves some surfaces: flips from clamp
  ExpectSameMaps(frames, FusionOptions(), "repeated scans");
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
      return {&l.depths[i], f.depth_camera.Resized(640, 480), f.world_from_cam,
              l.scene.min_depth_m, l.scene.max_depth_m};
  }
  ADD_FAILURE() << "no frame " << number;
  return {};
}

// Real pair: equal maps, equal frustum volumes, and downsampling before the discretized
// insertion changes almost nothing (why it is off by default).
void ExpectRealPairEquivalent(const Loaded& l, int64_t n0, int64_t n1, const std::string& what) {
  const std::vector<FusionInput> frames = {InputOf(l, n0), InputOf(l, n1)};
  FusionOptions o;
  ExpectSameMaps(frames, o, what);
  o.engine = FusionEngine::kOctomap;
  const OccupancyMap ref = FuseOccupancy(frames, o);
  o.engine = FusionEngine::kOwn;
  const OccupancyMap own = FuseOccupancy(frames, o);
  for (const FusionInput& in : frames) {
    const FrustumVolume a = ProjectToFrustum(own, in.camera, in.world_from_cam, BinOptions());
    const FrustumVolume b = ProjectToFrustum(ref, in.camera, in.world_from_cam, BinOptions());
    EXPECT_TRUE(a.occ == b.occ && a.known == b.known) << what << ": volumes differ";
  }
  o.downsample = true;
  const OccupancyMap down = FuseOccupancy(frames, o);
  const Comparison c = Compare(down, own);
  std::printf("%s: downsample on vs off: %lld of %lld known voxels differ\n", what.c_str(),
              static_cast<long long>(c.differing), static_cast<long long>(c.known_own));
  EXPECT_LT(static_cast<double>(c.differing), 1e-3 * static_cast<double>(c.known_own));
}

TEST(Equivalence, RealTartanAirHospital0And20) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  if (root.empty()) return;
  ExpectRealPairEquivalent(Load("tartanair", root), 0, 20, "tartanair 0/20");
}

TEST(Equivalence, RealSevenScenes150And190) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  if (root.empty()) return;
  ExpectRealPairEquivalent(Load("sevenscenes", root), 150, 190, "7-scenes 150/190");
}

TEST(Equivalence, RealSevenScenesWindow) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  if (root.empty()) return;
  const Loaded l = Load("sevenscenes", root);
  std::vector<FusionInput> frames;
  for (size_t i = 0; i < l.scene.frames.size() && frames.size() < 11; ++i)
    if (l.scene.frames[i].usable) frames.push_back(InputOf(l, l.scene.frames[i].number));
  ASSERT_GE(frames.size(), 3u);
  ExpectSameMaps(frames, FusionOptions(), "7-scenes window of " + std::to_string(frames.size()));
}

}  // namespace
}  // namespace gt::occupancy

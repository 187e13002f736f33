// The exact frustum traversal (ProjectToFrustum, Traversal::kExact) against the previous
// implementation kept in tests/occupancy/reference_traversal.h: the occ and known words must
// be equal ray for ray (so bin for bin) on the real pairs (TartanAir hospital 0/20, 7-Scenes
// 150/190) and on random scenes seen from the fused cameras and from other random poses,
// with several voxel sizes and bin spacings.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "libgt/io/depth_io.h"
#include "libgt/io/reader.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "tests/occupancy/reference_traversal.h"
#include "tests/support/test_support.h"

namespace gt::occupancy {
namespace {

// Number of rays whose words differ; also prints the volume's counts.
int64_t ExpectSameVolume(const OccupancyMap& map, const Camera& cam, const Rigid3d& pose,
                         const BinOptions& bins, const std::string& what) {
  SCOPED_TRACE(what);
  BinOptions exact = bins;
  exact.traversal = Traversal::kExact;
  const FrustumVolume fast = ProjectToFrustum(map, cam, pose, exact);
  const FrustumVolume ref = reference::ProjectToFrustumReference(map, cam, pose, exact);
  EXPECT_EQ(fast.width, ref.width);
  EXPECT_EQ(fast.height, ref.height);
  EXPECT_EQ(fast.edges_m, ref.edges_m);
  EXPECT_EQ(fast.occ.size(), ref.occ.size());
  int64_t differing = 0;
  for (size_t i = 0; i < fast.occ.size() && i < ref.occ.size(); ++i) {
    const bool same = fast.occ[i] == ref.occ[i] && fast.known[i] == ref.known[i];
    if (!same && differing < 5)
      ADD_FAILURE() << "ray " << i << ": occ " << std::hex << fast.occ[i] << " vs " << ref.occ[i]
                    << ", known " << fast.known[i] << " vs " << ref.known[i];
    differing += !same;
  }
  const VolumeCounts c = CountBins(ref);
  std::printf("%s: occupied %lld free %lld unknown %lld, differing rays %lld\n", what.c_str(),
              static_cast<long long>(c.occupied), static_cast<long long>(c.free),
              static_cast<long long>(c.unknown), static_cast<long long>(differing));
  EXPECT_EQ(differing, 0);
  return differing;
}

std::vector<BinOptions> SomeBinOptions() {
  std::vector<BinOptions> out(4);
  out[1].spacing = BinSpacing::kLog;
  out[2].spacing = BinSpacing::kInverse;
  out[2].num_bins = 37;
  out[3].near_m = 0.3;
  out[3].far_m = 5.0;
  out[3].num_bins = 50;
  return out;
}

struct Loaded {
  Scene scene;
  std::vector<DepthImage> depths;
};

Loaded Load(const std::string& format, const std::string& root) {
  Loaded l;
  l.scene = io::MakeReader(format)->ReadScene(root, "");
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

void ExpectRealPair(const Loaded& l, int64_t n0, int64_t n1, const std::string& what) {
  const std::vector<FusionInput> frames = {InputOf(l, n0), InputOf(l, n1)};
  const OccupancyMap map = FuseOccupancy(frames, FusionOptions());
  const auto bins = SomeBinOptions();
  for (size_t b = 0; b < bins.size(); ++b) {
    for (size_t c = 0; c < frames.size(); ++c) {
      ExpectSameVolume(map, frames[c].camera, frames[c].world_from_cam, bins[b],
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
    o.voxel_size_m = trial % 3 == 0 ? 0.05 : (trial % 3 == 1 ? 0.03 : 0.1);
    o.max_range_m = trial == 5 ? 0 : 6.0;
    const OccupancyMap map = FuseOccupancy(frames, o);
    const std::string name = "random " + std::to_string(trial);
    for (int f = 0; f < 3; ++f)
      ExpectSameVolume(map, cam, frames[f].world_from_cam, bins[(trial + f) % bins.size()],
                       name + " cam" + std::to_string(f));
    // Views the map was not fused from (rays enter known space from anywhere).
    for (int extra = 0; extra < 3; ++extra)
      ExpectSameVolume(map, TestCamera(100, 80, 70.0), RandomPose(&rng, 1.0),
                       bins[(trial + extra) % bins.size()],
                       name + " other view " + std::to_string(extra));
  }
}

}  // namespace
}  // namespace gt::occupancy

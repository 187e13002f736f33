// Real samples (../shared/data): TartanAir hospital frames 0/20 and 7-Scenes frames 150/190
// run through fusion and binning and give plausible targets: some bins occupied, some free;
// each ray is occupied at (or next to) the bin of its own depth; bins in front of the ray's
// own surface are known; unknown bins are mostly behind the surface. Also the window scope
// adds knowledge, and two_point has exactly its documented structure.
#include <gtest/gtest.h>

#include <cstdio>

#include "libgt/io/depth_io.h"
#include "libgt/datasets/reader.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "tests/support/test_support.h"

namespace gt::occupancy {
namespace {

struct Loaded {
  Scene scene;
  std::vector<DepthImage> depths;
  std::vector<FusionInput> inputs;  // one per frame of `scene`
};

Loaded Load(const std::string& format, const std::string& root, const std::string& name) {
  Loaded l;
  l.scene = datasets::MakeReader(ParseDatasetFormat(format))->ReadScene(root, name);
  l.depths.resize(l.scene.frames.size());
  for (size_t i = 0; i < l.scene.frames.size(); ++i) {
    const Frame& f = l.scene.frames[i];
    l.depths[i] = ResizeDepthNearest(io::ReadDepth(f.depth), 640, 480);
  }
  for (size_t i = 0; i < l.scene.frames.size(); ++i) {
    const Frame& f = l.scene.frames[i];
    l.inputs.push_back({&l.depths[i], f.depth_camera.Resized(640, 480), f.world_from_cam,
                        l.scene.min_depth_m, l.scene.max_depth_m});
  }
  return l;
}

size_t IndexOf(const Scene& s, int64_t number) {
  for (size_t i = 0; i < s.frames.size(); ++i)
    if (s.frames[i].number == number) return i;
  ADD_FAILURE() << "no frame " << number;
  return 0;
}

struct RayChecks {
  int64_t rays_with_depth = 0, occupied_at_own_depth = 0;
  int64_t front_bins = 0, front_known = 0;
  int64_t unknown = 0, unknown_behind = 0;
};

RayChecks Check(const FrustumVolume& vol, const DepthImage& depth, const FusionInput& in) {
  RayChecks r;
  const auto& e = vol.edges_m;
  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      const float z = depth.at(2 * u, 2 * v);
      const int k = IsValidDepth(z, in.min_depth_m, in.max_depth_m) ? BinOfDepth(e, z) : -1;
      if (k < 0) continue;
      ++r.rays_with_depth;
      const uint64_t near_bits = (vol.occ[i] >> std::max(k - 1, 0)) & 0b111;
      r.occupied_at_own_depth += near_bits != 0;
      for (int b = 0; b < vol.num_bins(); ++b) {
        const bool known = (vol.known[i] >> b) & 1;
        if (b < k - 1) {
          ++r.front_bins;
          r.front_known += known;
        }
        if (!known) {
          ++r.unknown;
          r.unknown_behind += b > k;
        }
      }
    }
  }
  return r;
}

void ExpectPlausible(const Loaded& l, size_t i0, size_t i1, const char* what) {
  SCOPED_TRACE(what);
  const FusionOptions fo;
  const BinOptions bo;
  const PairOccupancy p =
      ComputePairOccupancy(l.inputs[i0], l.inputs[i1], fo, bo, OccupancyMode::kOctomap);
  int c = 0;
  for (const auto& [vol, idx] : {std::pair{&p.cam0, i0}, std::pair{&p.cam1, i1}}) {
    ASSERT_EQ(vol->width, 320);
    ASSERT_EQ(vol->height, 240);
    const VolumeCounts n = CountBins(*vol);
    const double total = n.occupied + n.free + n.unknown;
    const RayChecks r = Check(*vol, l.depths[idx], l.inputs[idx]);
    std::printf(
        "%s cam%d: occupied %.3f free %.3f unknown %.3f; own-depth hit %.3f, front known "
        "%.3f, unknown behind surface %.3f\n",
        what, c, n.occupied / total, n.free / total, n.unknown / total,
        double(r.occupied_at_own_depth) / r.rays_with_depth,
        double(r.front_known) / std::max<int64_t>(r.front_bins, 1),
        double(r.unknown_behind) / r.unknown);
    EXPECT_GT(n.occupied / total, 0.005);
    EXPECT_GT(n.free / total, 0.02);
    EXPECT_GT(n.unknown / total, 0.05);
    ASSERT_GT(r.rays_with_depth, vol->width * vol->height / 2);
    EXPECT_GT(double(r.occupied_at_own_depth) / r.rays_with_depth, 0.95);
    if (r.front_bins > 0) {
      EXPECT_GT(double(r.front_known) / r.front_bins, 0.95);
    }
    EXPECT_GT(double(r.unknown_behind) / r.unknown, 0.9);
    ++c;
  }
}

TEST(RealData, TartanAirHospital0And20) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  if (root.empty()) return;
  const Loaded l = Load("tartanair", root, "");
  ExpectPlausible(l, IndexOf(l.scene, 0), IndexOf(l.scene, 20), "tartanair 0/20");
}

TEST(RealData, SevenScenes150And190) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  if (root.empty()) return;
  const Loaded l = Load("sevenscenes", root, "");
  ExpectPlausible(l, IndexOf(l.scene, 150), IndexOf(l.scene, 190), "7-scenes 150/190");
}

// Fusing a window of frames knows at least as many bins of frame 150 (as free or occupied)
// as the pair alone: more views observe more space.
TEST(RealData, WindowScopeKnowsMoreThanThePair) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  if (root.empty()) return;
  const Loaded l = Load("sevenscenes", root, "");
  const size_t i0 = IndexOf(l.scene, 150), i1 = IndexOf(l.scene, 190);
  FusionOptions fo;
  ParseFusionScope("window:5", &fo);
  std::vector<FusionInput> inputs;
  for (size_t i : ScopeFrameIndices(l.scene, i0, i1, fo)) inputs.push_back(l.inputs[i]);
  ASSERT_GT(inputs.size(), 2u);
  const OccupancyMap window = FuseOccupancy(inputs, fo);
  const BinOptions bo;
  const PairOccupancy pw =
      ComputePairOccupancy(l.inputs[i0], l.inputs[i1], fo, bo, OccupancyMode::kOctomap, &window);
  const PairOccupancy pp = ComputePairOccupancy(l.inputs[i0], l.inputs[i1], FusionOptions(), bo,
                                                OccupancyMode::kOctomap);
  const VolumeCounts cw = CountBins(pw.cam0), cp = CountBins(pp.cam0);
  EXPECT_LT(cw.unknown, cp.unknown);
}

TEST(RealData, TwoPointIsOccupiedAtTheOwnDepthBinOfEveryRay) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  if (root.empty()) return;
  const Loaded l = Load("tartanair", root, "");
  const size_t i0 = IndexOf(l.scene, 0), i1 = IndexOf(l.scene, 20);
  const PairOccupancy p = ComputePairOccupancy(l.inputs[i0], l.inputs[i1], FusionOptions(),
                                               BinOptions(), OccupancyMode::kTwoPoint);
  const auto& e = p.cam0.edges_m;
  int64_t with_own = 0;
  for (int v = 0; v < p.cam0.height; ++v) {
    for (int u = 0; u < p.cam0.width; ++u) {
      const size_t i = static_cast<size_t>(v) * p.cam0.width + u;
      EXPECT_EQ(p.cam0.occ[i] & ~p.cam0.known[i], 0u);
      const float z = l.depths[i0].at(2 * u, 2 * v);
      const int k =
          IsValidDepth(z, l.scene.min_depth_m, l.scene.max_depth_m) ? BinOfDepth(e, z) : -1;
      if (k < 0) continue;
      ++with_own;
      EXPECT_TRUE((p.cam0.occ[i] >> k) & 1);
      EXPECT_EQ(p.cam0.known[i], ~uint64_t{0});
    }
  }
  EXPECT_GT(with_own, 1000);
}

}  // namespace
}  // namespace gt::occupancy

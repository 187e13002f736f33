// Fusion edge cases: invalid depth never becomes a point at the camera centre, OctoMap key-range
// clipping (a far point would wrap around), the pcl::VoxelGrid int32 overflow guard, bad input.
#include "libgt/occupancy/fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include "libgt/core/error.h"
#include "tests/support/test_support.h"

namespace gt::occupancy {
namespace {

Camera SmallCamera(int w, int h) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fx = c.fy = w;  // ~53 degree field of view
  c.cx = (w - 1) / 2.0;
  c.cy = (h - 1) / 2.0;
  return c;
}

// Camera at `centre`, OpenCV axes aligned with the world axes.
Rigid3d At(const Eigen::Vector3d& centre) {
  Rigid3d p = Rigid3d::Identity();
  p.translation() = centre;
  return p;
}

TEST(Fusion, InvalidDepthNeverBecomesAPointAtTheCameraCentre) {
  const Camera cam = SmallCamera(20, 16);
  DepthImage depth(20, 16, 0.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const float bad[] = {0.0f, nan, inf, -inf, -1.0f, 0.05f /*< min*/, 50.0f /*> max*/};
  int valid = 0;
  for (int v = 0; v < 16; ++v) {
    for (int u = 0; u < 20; ++u) {
      if ((u + v) % 2 == 0) {
        depth.at(u, v) = 3.0f;  // a wall 3 m ahead
        ++valid;
      } else {
        depth.at(u, v) = bad[(u * 7 + v) % 7];
      }
    }
  }
  const Eigen::Vector3d centre(1.0, 2.0, 3.0);
  FusionInput in{&depth, cam, At(centre), 0.1, 20.0};
  const auto points = BackProjectValid(in);
  ASSERT_EQ(static_cast<int>(points.size()), valid);
  for (const auto& p : points) {
    EXPECT_TRUE(p.allFinite());
    EXPECT_NEAR(p.z(), 6.0, 1e-5);  // every point on the wall, none at the centre or origin
  }
  FusionOptions opt;
  const OccupancyMap map = FuseOccupancy({in}, opt);
  EXPECT_EQ(map.stats().invalid_pixels, 20 * 16 - valid);
  EXPECT_NE(map.StateAt(centre), 1);
  EXPECT_NE(map.StateAt(Eigen::Vector3d::Zero()), 1);
  // Pixel (10, 8) sees the wall at (0.075, 0.075, 3) from the centre.
  const Eigen::Vector3d hit(0.075, 0.075, 3.0);
  EXPECT_EQ(map.StateAt(centre + 0.5 * hit), 0);   // free in front
  EXPECT_EQ(map.StateAt(centre + hit), 1);         // the wall
  EXPECT_EQ(map.StateAt(centre + 1.2 * hit), -1);  // behind it

  // All invalid: nothing occupied anywhere.
  DepthImage none(20, 16, 0.0f);
  none.at(3, 3) = nan;
  const OccupancyMap empty = FuseOccupancy({{&none, cam, At(centre), 0.1, 20.0}}, opt);
  EXPECT_EQ(empty.NumOccupiedVoxels(), 0);
  EXPECT_EQ(empty.NumFreeVoxels(), 0);
}

// A point beyond the 16-bit key range (3276.8 m at 5 cm) would wrap around in OctoMap's
// unchecked key conversion: x = 3277.825 m wraps to key index 20, i.e. x in [1.0, 1.05).
// The key-range check lets such a point through only beyond max_range_m (its ray is
// truncated inside the range): it is dropped and counted.
TEST(Fusion, PointsOutsideTheKeyRangeAreDroppedNotWrapped) {
  const Camera cam = SmallCamera(5, 5);
  DepthImage depth(5, 5, 0.0f);
  depth.at(2, 2) = 3277.825f;  // centre pixel: straight ahead
  depth.at(0, 0) = 2.0f;       // one ordinary point so the map is not empty
  // Camera at the origin looking along +x (cam z = world x, cam x = world -y, cam y = -z).
  Rigid3d world_from_cam = Rigid3d::Identity();
  world_from_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  FusionOptions opt;
  opt.max_range_m = 10;  // a wrapped key would land within it as a hit
  opt.downsample = false;
  const OccupancyMap map = FuseOccupancy({{&depth, cam, world_from_cam, 0.1, 1e5}}, opt);
  EXPECT_EQ(map.stats().pixels, 25);
  EXPECT_EQ(map.stats().invalid_pixels, 23);
  // Beyond max_range_m, the point is moved along its ray to just past the range (it marks
  // free space up to 10 m, as the same point inside the key range does), not dropped.
  EXPECT_EQ(map.stats().out_of_key_range, 0);
  EXPECT_EQ(map.stats().inserted_points, 2);
  EXPECT_NE(map.StateAt({1.025, 0.0, 0.0}), 1);  // where the wrapped hit would land
  EXPECT_EQ(map.NumOccupiedVoxels(), 1);
  EXPECT_EQ(map.StateAt({3277.825, 0.0, 0.0}), -1);  // outside: unknown, no crash
  EXPECT_EQ(map.StateAt({5.05, 0.0, 0.0}), 0);       // on the ray, within the range: free
  DepthImage inside = depth;
  inside.at(2, 2) = 500.0f;  // the same ray, its end inside the key range
  const OccupancyMap reference = FuseOccupancy({{&inside, cam, world_from_cam, 0.1, 1e5}}, opt);
  EXPECT_EQ(reference.stats().out_of_key_range, 0);
  for (double x = 0.05; x < 12.0; x += 0.1) {
    EXPECT_EQ(map.StateAt({x, 0.0, 0.0}), reference.StateAt({x, 0.0, 0.0})) << x;
  }
  EXPECT_EQ(map.NumOccupiedVoxels(), reference.NumOccupiedVoxels());

  // With an unlimited range the same frame could reach 1e5 m: refused before any work.
  opt.max_range_m = -1;
  EXPECT_THROW(FuseOccupancy({{&depth, cam, world_from_cam, 0.1, 1e5}}, opt), InputError);
  // A camera outside the key range is bad input, refused by the same check.
  opt.max_range_m = 10;
  try {
    FuseOccupancy({{&depth, cam, At({5000.0, 0, 0}), 0.1, 1e5}}, opt);
    ADD_FAILURE() << "a camera outside the key range was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "voxel_m");
    EXPECT_NE(std::string(e.what()).find("needs +-5.01e+03 m: use voxel_m >= 0.153"),
              std::string::npos)
        << e.what();
  }
}

std::string KeyRangeError(const FusionInput& in, const FusionOptions& opt) {
  try {
    CheckKeyRange(in, opt, "frame 0");
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "voxel_m");
    return e.what();
  }
  return "";
}

// The voxel size given back by a refusal ("use voxel_m >= X").
double SuggestedVoxel(const std::string& message) {
  const std::string key = "use voxel_m >= ";
  const size_t at = message.find(key);
  if (at == std::string::npos) return 0.0;
  return std::stod(message.substr(at + key.size()));
}

// The case: voxel 1e-6 m holds +-0.0328 m, and every point 3 m ahead would be
// dropped as out of the key range, leaving an empty map. Refused at once, naming the
// smallest voxel that works; the boundary is exact.
TEST(KeyRange, VoxelTooSmallForTheRangeIsRefusedWithTheSmallestThatWorks) {
  const Camera cam = SmallCamera(20, 16);
  DepthImage depth(20, 16, 3.0f);
  const FusionInput in{&depth, cam, Rigid3d::Identity(), 0.1, 20.0};
  FusionOptions opt;
  opt.voxel_m = 1e-6;
  opt.max_range_m = 10;
  const std::string e = KeyRangeError(in, opt);
  EXPECT_EQ(e,
            "voxel_m: 1e-06 m holds +-0.0328 m around the world origin (OctoMap's 16-bit keys); "
            "frame 0's camera at (0, 0, 0) with max_range_m 10 needs +-10 m: use voxel_m >= "
            "0.000306");
  EXPECT_THROW(FuseOccupancy({in}, opt), InputError);

  // The boundary: the smallest voxel size that works is accepted, the next smaller refused.
  const double smallest = MinVoxelSizeM(Eigen::Vector3d::Zero(), 10.0);
  EXPECT_NEAR(smallest, 10.0 / 32766, 1e-18);
  EXPECT_GE(KeyRangeHalfExtentM(smallest), 10.0);
  opt.voxel_m = smallest;
  EXPECT_EQ(KeyRangeError(in, opt), "");
  opt.voxel_m = std::nextafter(smallest, 0.0);
  EXPECT_NE(KeyRangeError(in, opt), "");
  // The suggested (rounded up) size works, and fuses a wall without dropping a point (a
  // small, near one: rays of 0.3 mm voxels are long).
  opt.voxel_m = SuggestedVoxel(e);
  EXPECT_EQ(opt.voxel_m, 0.000306);
  DepthImage near_wall(4, 4, 0.3f);
  const OccupancyMap map =
      FuseOccupancy({{&near_wall, SmallCamera(4, 4), Rigid3d::Identity(), 0.1, 20.0}}, opt);
  EXPECT_EQ(map.stats().out_of_key_range, 0);
  EXPECT_EQ(map.stats().inserted_points, 16);
  EXPECT_EQ(map.StateAt({-0.0375, -0.0375, 0.3}), 1);  // pixel (1, 1)
  EXPECT_EQ(map.StateAt({-0.01875, -0.01875, 0.15}), 0);
}

// When the held and the needed extents agree to 3 digits, the message gives as many as
// tell them apart ("holds +-1.64e+03 m ... needs +-1.64e+03 m" read as no problem).
TEST(KeyRange, CloseExtentsAreToldApart) {
  const Camera cam = SmallCamera(20, 16);
  DepthImage depth(20, 16, 3.0f);
  const FusionInput in{&depth, cam, At({1630.6, 0.0, 0.0}), 0.1, 20.0};
  const std::string e = KeyRangeError(in, FusionOptions{});  // 5 cm holds +-1638.3 m
  EXPECT_NE(e.find("0.05 m holds +-1638 m"), std::string::npos) << e;
  EXPECT_NE(e.find("needs +-1641 m"), std::string::npos) << e;
}

TEST(KeyRange, CameraFarFromTheOriginNeedsItsOffsetToo) {
  const Camera cam = SmallCamera(20, 16);
  DepthImage depth(20, 16, 3.0f);
  const Eigen::Vector3d centre(1000.0, -2000.0, 5.0);
  const FusionInput in{&depth, cam, At(centre), 0.1, 20.0};
  FusionOptions opt;  // 5 cm holds +-1638 m; the camera needs 2000 + 10 m on y
  const std::string e = KeyRangeError(in, opt);
  EXPECT_NE(e.find("voxel_m: 0.05 m holds +-1.64e+03 m"), std::string::npos) << e;
  EXPECT_NE(e.find("camera at (1e+03, -2e+03, 5) with max_range_m 10 needs +-2.01e+03 m: use "
                   "voxel_m >= 0.0614"),
            std::string::npos)
      << e;
  const double smallest = MinVoxelSizeM(centre, 10.0);
  EXPECT_NEAR(smallest, 2010.0 / 32766, 1e-15);
  opt.voxel_m = smallest;
  EXPECT_EQ(KeyRangeError(in, opt), "");
  opt.voxel_m = std::nextafter(smallest, 0.0);
  EXPECT_NE(KeyRangeError(in, opt), "");
  opt.voxel_m = SuggestedVoxel(e);
  const OccupancyMap map = FuseOccupancy({in}, opt);
  EXPECT_EQ(map.stats().out_of_key_range, 0);
  EXPECT_EQ(map.StateAt(centre + Eigen::Vector3d(0.075, 0.075, 3.0)), 1);  // pixel (10, 8)
  EXPECT_EQ(map.StateAt(centre + Eigen::Vector3d(0.0375, 0.0375, 1.5)), 0);
  // Every frame is checked before any is fused: a good frame first does not hide a bad one.
  opt.voxel_m = 0.05;
  const FusionInput near{&depth, cam, Rigid3d::Identity(), 0.1, 20.0};
  try {
    FuseOccupancy({near, in}, opt);
    ADD_FAILURE() << "the far frame was accepted";
  } catch (const InputError& e1) {
    EXPECT_NE(std::string(e1.what()).find("frame 1's camera"), std::string::npos) << e1.what();
  }
}

// Unlimited range: the reach is the valid depth bound times the longest corner ray (the
// pixel rays are longer than their planar depth), whatever the camera's orientation.
TEST(KeyRange, UnlimitedRangeUsesTheLongestValidRay) {
  const Camera cam = SmallCamera(5, 5);  // corner rays (+-0.4, +-0.4, 1) per metre of depth
  DepthImage depth(5, 5, 2.0f);
  Rigid3d world_from_cam = Rigid3d::Identity();
  world_from_cam.linear() =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  FusionOptions opt;
  opt.max_range_m = 0;  // unlimited
  const FusionInput in{&depth, cam, world_from_cam, 0.1, 1500.0};
  const double reach = FusionReachM(in, opt);
  EXPECT_NEAR(reach, 1500.0 * std::sqrt(1.32), 1e-9);
  // The reach bounds every point the frame can give: depth at the bound, every pixel.
  DepthImage far(5, 5, 1500.0f);
  const FusionInput far_in{&far, cam, world_from_cam, 0.1, 1500.0};
  double longest = 0;
  for (const auto& p : BackProjectValid(far_in))
    longest = std::max(longest, p.cast<double>().norm());
  EXPECT_NEAR(longest, reach, 1e-3);
  const std::string e = KeyRangeError(in, opt);  // 1723 m > 1638 m at 5 cm
  EXPECT_NE(e.find("unlimited max_range_m and max_depth_m 1.5e+03 (rays up to 1.72e+03 m "
                   "through the image corners) needs +-1.72e+03 m: use voxel_m >= 0.0526 or a "
                   "max_range_m > 0"),
            std::string::npos)
      << e;
  opt.voxel_m = SuggestedVoxel(e);
  EXPECT_EQ(KeyRangeError(in, opt), "");
  opt.max_range_m = 10;  // a range: its own reach
  opt.voxel_m = 0.05;
  EXPECT_EQ(FusionReachM(in, opt), 10.0);
  EXPECT_EQ(KeyRangeError(in, opt), "");
  // No voxel size holds an unbounded reach.
  opt.max_range_m = 0;
  const FusionInput unbounded{&depth, cam, world_from_cam, 0.1,
                              std::numeric_limits<double>::infinity()};
  EXPECT_NE(KeyRangeError(unbounded, opt).find("no voxel size holds it; set a max_range_m > 0"),
            std::string::npos);
}

// Every pixel is accounted for: invalid, outside the key range, or inserted.
TEST(Fusion, DroppedPointsAreCounted) {
  const Camera cam = SmallCamera(20, 16);
  DepthImage depth(20, 16, 3.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int invalid = 0;
  for (int v = 0; v < 16; ++v) {
    for (int u = 0; u < 20; ++u) {
      if ((u * 3 + v) % 5 == 0) {
        depth.at(u, v) = (u + v) % 2 ? nan : 0.0f;
        ++invalid;
      }
    }
  }
  depth.at(1, 1) = 30.0f;  // beyond max_depth_m: invalid too
  ++invalid;
  ASSERT_GT(invalid, 60);
  FusionOptions opt;
  const OccupancyMap map = FuseOccupancy(
      {{&depth, cam, Rigid3d::Identity(), 0.1, 20.0}, {&depth, cam, At({1, 0, 0}), 0.1, 20.0}},
      opt);
  const FusionStats& st = map.stats();
  EXPECT_EQ(st.frames, 2);
  EXPECT_EQ(st.pixels, 2 * 20 * 16);
  EXPECT_EQ(st.invalid_pixels, 2 * invalid);
  EXPECT_EQ(st.out_of_key_range, 0);
  EXPECT_EQ(st.inserted_points, st.pixels - st.invalid_pixels);
}

// Reference: centroid of each voxel floor(p / leaf), double accumulation.
std::map<std::tuple<int64_t, int64_t, int64_t>, Eigen::Vector3d> ReferenceCentroids(
    const std::vector<Eigen::Vector3f>& pts, double leaf) {
  std::map<std::tuple<int64_t, int64_t, int64_t>, std::pair<Eigen::Vector3d, int>> acc;
  for (const auto& p : pts) {
    auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.x() / leaf)),
                               static_cast<int64_t>(std::floor(p.y() / leaf)),
                               static_cast<int64_t>(std::floor(p.z() / leaf)));
    auto& a = acc[key];
    if (a.second == 0) a.first.setZero();
    a.first += p.cast<double>();
    a.second += 1;
  }
  std::map<std::tuple<int64_t, int64_t, int64_t>, Eigen::Vector3d> out;
  for (const auto& [k, a] : acc) out[k] = a.first / a.second;
  return out;
}

void ExpectCentroidsMatch(const std::vector<Eigen::Vector3f>& got,
                          const std::vector<Eigen::Vector3f>& input, double leaf) {
  const auto ref = ReferenceCentroids(input, leaf);
  ASSERT_EQ(got.size(), ref.size());
  for (const auto& p : got) {
    // The centroid lies in its own voxel, so its voxel finds the reference entry.
    auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.x() / leaf)),
                               static_cast<int64_t>(std::floor(p.y() / leaf)),
                               static_cast<int64_t>(std::floor(p.z() / leaf)));
    auto it = ref.find(key);
    ASSERT_TRUE(it != ref.end());
    EXPECT_LT((p.cast<double>() - it->second).norm(), 1e-3);
  }
}

std::vector<Eigen::Vector3f> Clusters(const std::vector<Eigen::Vector3f>& centres, int per,
                                      float spread, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(-spread, spread);
  std::vector<Eigen::Vector3f> pts;
  for (const auto& c : centres)
    for (int i = 0; i < per; ++i) pts.push_back(c + Eigen::Vector3f(d(rng), d(rng), d(rng)));
  return pts;
}

TEST(Downsample, SmallExtentUsesVoxelGridAndMatchesReference) {
  const auto pts = Clusters({{0.1f, 0.2f, 1.0f}, {1.5f, -0.3f, 2.2f}}, 2000, 0.3f, 1);
  bool fallback = true;
  const auto got = DownsampleVoxelCentroids(pts, 0.05, &fallback);
  EXPECT_FALSE(fallback);
  EXPECT_LT(got.size(), pts.size());
  ExpectCentroidsMatch(got, pts, 0.05);
}

TEST(Downsample, Int32LeafOverflowFallsBackInsteadOfReturningTheInput) {
  // 300 m per axis at 5 cm: 6000^3 leaves > INT32_MAX, where pcl::VoxelGrid would return the
  // unfiltered cloud.
  const auto pts =
      Clusters({{-150.f, -150.f, -150.f}, {150.f, 150.f, 150.f}, {0.f, 0.f, 0.f}}, 3000, 0.2f, 2);
  bool fallback = false;
  const auto got = DownsampleVoxelCentroids(pts, 0.05, &fallback);
  EXPECT_TRUE(fallback);
  EXPECT_LT(got.size(), pts.size() / 2);
  ExpectCentroidsMatch(got, pts, 0.05);
}

TEST(Fusion, OverflowGuardIsUsedDuringFusion) {
  // One frame seeing a near wall (2 m) and a far one (1000 m, inside the +-1638 m key range
  // at 5 cm) in its two halves.
  const Camera cam = SmallCamera(64, 48);
  DepthImage depth(64, 48, 0.0f);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) depth.at(u, v) = (u < 32) ? 2.0f : 1000.0f;
  FusionOptions opt;
  opt.downsample = true;  // off by default
  const OccupancyMap map = FuseOccupancy({{&depth, cam, Rigid3d::Identity(), 0.1, 1e4}}, opt);
  EXPECT_EQ(map.stats().out_of_key_range, 0);
  EXPECT_EQ(map.stats().downsample_fallbacks, 1);
  EXPECT_LT(map.stats().after_downsample, 64 * 48);
  EXPECT_EQ(map.StateAt({(10 - 31.5) / 64, (10 - 23.5) / 64, 1.0}), 0);  // pixel (10, 10)
  EXPECT_EQ(map.StateAt({(10 - 31.5) / 32, (10 - 23.5) / 32, 2.0}), 1);
}

TEST(Fusion, BadInputThrowsInputError) {
  const Camera cam = SmallCamera(8, 6);
  DepthImage wrong(9, 6, 1.0f);
  FusionOptions opt;
  EXPECT_THROW(FuseOccupancy({{&wrong, cam, Rigid3d::Identity(), 0.1, 10}}, opt), InputError);
  EXPECT_THROW(FuseOccupancy({{nullptr, cam, Rigid3d::Identity(), 0.1, 10}}, opt), InputError);
}

TEST(Fusion, SavedOctreeIsAnOctomapBinaryFile) {
  const Camera cam = SmallCamera(16, 12);
  DepthImage depth(16, 12, 2.0f);
  const OccupancyMap map = FuseOccupancy({{&depth, cam, Rigid3d::Identity(), 0.1, 10}}, {});
  const std::string dir = gt::test::ScratchDir("occupancy_save_bt");
  map.SaveBinary(dir + "/map.bt");
  std::ifstream f(dir + "/map.bt", std::ios::binary);
  std::string first;
  std::getline(f, first);
  EXPECT_EQ(first, "# Octomap OcTree binary file");
  std::string rest((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(rest.find("id OcTree"), std::string::npos);
  EXPECT_NE(rest.find("res 0.05"), std::string::npos);
}

TEST(Fusion, DeterministicForSameInput) {
  const Camera cam = SmallCamera(32, 24);
  DepthImage depth(32, 24);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> d(0.5f, 4.0f);
  for (auto& z : depth.values_m) z = d(rng);
  const FusionInput in{&depth, cam, At({0.3, -0.2, 0.1}), 0.1, 10};
  const OccupancyMap a = FuseOccupancy({in}, {}), b = FuseOccupancy({in}, {});
  const std::string dir = gt::test::ScratchDir("occupancy_determinism");
  a.SaveBinary(dir + "/a.bt");
  b.SaveBinary(dir + "/b.bt");
  std::ifstream fa(dir + "/a.bt", std::ios::binary), fb(dir + "/b.bt", std::ios::binary);
  std::string sa((std::istreambuf_iterator<char>(fa)), {}),
      sb((std::istreambuf_iterator<char>(fb)), {});
  EXPECT_FALSE(sa.empty());
  EXPECT_EQ(sa, sb);
}

}  // namespace
}  // namespace gt::occupancy

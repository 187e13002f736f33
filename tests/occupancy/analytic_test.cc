// Analytic scenes with closed-form answers: a room (inside of an axis-aligned box) with a box
// standing in it, seen from two poses. Depth is ray-cast exactly in the test; the expected
// state of every bin is computed here from the geometry (not from the map):
//   OCCUPIED  the bin's ray segment crosses a scene surface that some camera sees;
//   FREE      otherwise, some point of the segment lies in front of what a camera sees
//             (inside its image, closer than its depth along that pixel);
//   UNKNOWN   otherwise.
// Voxelisation makes bins within a voxel of a surface, or of the edge of what a camera sees
// (occlusion shadows, image borders), legitimately ambiguous; every wrong bin must be such a
// bin, and >= 99 % of all bins must be right.
// Also: the exact DDA against a slow reference (dense sampling + OctoMap search), and the
// thin-wall case where bin-centre sampling misses what exact traversal catches.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "libgt/occupancy/pair_occupancy.h"

namespace gt::occupancy {
namespace {

struct Box {
  Eigen::Vector3d lo, hi;
};

// Room interior and a box inside it (metres, world frame; y is down as in OpenCV).
const Box kRoom{{-2.5, -1.5, -1.0}, {2.5, 1.5, 5.0}};
const Box kBlock{{-0.5, -0.3, 2.0}, {0.3, 0.6, 2.6}};

// Ray o + t d (t > 0): first surface parameter; inf when none.
double RayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b, bool inside) {
  double t0 = -std::numeric_limits<double>::infinity(), t1 = -t0;
  for (int a = 0; a < 3; ++a) {
    double u = (b.lo[a] - o[a]) / d[a], w = (b.hi[a] - o[a]) / d[a];
    if (u > w) std::swap(u, w);
    t0 = std::max(t0, u);
    t1 = std::min(t1, w);
  }
  if (t0 > t1) return std::numeric_limits<double>::infinity();
  if (inside) return t1;  // leaving the room
  return t0 > 1e-9 ? t0 : std::numeric_limits<double>::infinity();
}

// Every parameter t > 0 where the ray crosses a surface of the scene (sorted).
std::vector<double> Crossings(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  std::vector<double> ts;
  ts.push_back(RayBox(o, d, kRoom, true));
  double t0 = -std::numeric_limits<double>::infinity(), t1 = -t0;
  for (int a = 0; a < 3; ++a) {
    double u = (kBlock.lo[a] - o[a]) / d[a], w = (kBlock.hi[a] - o[a]) / d[a];
    if (u > w) std::swap(u, w);
    t0 = std::max(t0, u);
    t1 = std::min(t1, w);
  }
  if (t0 <= t1) {
    if (t0 > 0) ts.push_back(t0);
    if (t1 > 0) ts.push_back(t1);
  }
  std::sort(ts.begin(), ts.end());
  return ts;
}

double SceneDepth(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  return std::min(RayBox(o, d, kRoom, true), RayBox(o, d, kBlock, false));
}

// Distance from p to the nearest surface of the scene.
double DistanceToSurface(const Eigen::Vector3d& p) {
  auto to_box_surface = [&](const Box& b) {
    const Eigen::Vector3d out = (b.lo - p).cwiseMax(p - b.hi).cwiseMax(Eigen::Vector3d::Zero());
    if (out.norm() > 0) return out.norm();
    return (p - b.lo).cwiseMin(b.hi - p).minCoeff();  // inside: nearest face
  };
  return std::min(to_box_surface(kRoom), to_box_surface(kBlock));
}

struct View {
  Camera cam;  // full resolution
  Rigid3d world_from_cam;
  DepthImage depth;
};

Rigid3d LookAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Rigid3d p = Rigid3d::Identity();
  p.linear().col(0) = x;
  p.linear().col(1) = y;
  p.linear().col(2) = z;
  p.translation() = centre;
  return p;
}

View Render(const Eigen::Vector3d& centre, const Eigen::Vector3d& target, int w, int h) {
  View v;
  v.cam.width = w;
  v.cam.height = h;
  v.cam.fx = v.cam.fy = 0.8 * w;
  v.cam.cx = (w - 1) / 2.0;
  v.cam.cy = (h - 1) / 2.0;
  v.world_from_cam = LookAt(centre, target);
  v.depth = DepthImage(w, h);
  const Eigen::Matrix3d R = v.world_from_cam.linear();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector3d d = R * v.cam.CamFromImg(x, y, 1.0);  // planar z = t
      v.depth.at(x, y) = static_cast<float>(SceneDepth(centre, d));
    }
  }
  return v;
}

// p lies in front of what view v sees along its nearest pixel.
bool SeenFree(const View& v, const Eigen::Vector3d& p, double max_range_m) {
  const Eigen::Vector3d q = v.world_from_cam.inverse() * p;
  const auto x = v.cam.ImgFromCam(q, 1e-6);
  if (!x || !v.cam.InPixelArea(x->x(), x->y())) return false;
  const int u = static_cast<int>(std::floor(x->x() + 0.5)),
            w = static_cast<int>(std::floor(x->y() + 0.5));
  if ((p - v.world_from_cam.translation()).norm() > max_range_m) return false;
  return q.z() < v.depth.at(u, w);
}

// p (on a surface) is what view v sees at its nearest pixel.
bool SeenSurface(const View& v, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = v.world_from_cam.inverse() * p;
  const auto x = v.cam.ImgFromCam(q, 1e-6);
  if (!x || !v.cam.InPixelArea(x->x(), x->y())) return false;
  const int u = static_cast<int>(std::floor(x->x() + 0.5)),
            w = static_cast<int>(std::floor(x->y() + 0.5));
  return std::abs(q.z() - v.depth.at(u, w)) < 0.02;
}

enum State { kFree = 0, kOcc = 1, kUnknown = 255 };

struct Expectation {
  int right = 0, wrong = 0, wrong_not_ambiguous = 0;
  int occ = 0, free = 0, unknown = 0;  // expected counts
};

// Compares one camera's volume with the geometric expectation.
Expectation CheckVolume(const FrustumVolume& vol, const View& self, const std::vector<View>& views,
                        double voxel_m, double max_range_m) {
  Expectation ex;
  const Camera half = self.cam.HalfGrid();
  const Eigen::Matrix3d R = self.world_from_cam.linear();
  const Eigen::Vector3d o = self.world_from_cam.translation();
  const auto& e = vol.edges_m;
  const int D = vol.num_bins();
  const double r = std::sqrt(3.0) * voxel_m;  // one voxel, diagonal
  auto seen_free_any = [&](const Eigen::Vector3d& p) {
    for (const auto& v : views)
      if (SeenFree(v, p, max_range_m)) return true;
    return false;
  };
  for (int v = 0; v < vol.height; ++v) {
    for (int u = 0; u < vol.width; ++u) {
      const Eigen::Vector3d d = R * half.CamFromImg(u, v, 1.0);
      const auto cross = Crossings(o, d);
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      for (int k = 0; k < D; ++k) {
        int expect = kUnknown;
        for (double t : cross) {
          if (t >= e[k] && t < e[k + 1]) {
            const Eigen::Vector3d p = o + t * d;
            for (const auto& view : views)
              if (SeenSurface(view, p)) expect = kOcc;
          }
        }
        const int n = 24;
        if (expect != kOcc) {
          for (int s = 0; s <= n && expect == kUnknown; ++s) {
            const double t = e[k] + (e[k + 1] - e[k]) * s / n;
            if (seen_free_any(o + t * d)) expect = kFree;
          }
        }
        const bool known = (vol.known[i] >> k) & 1, occ = (vol.occ[i] >> k) & 1;
        const int got = !known ? kUnknown : (occ ? kOcc : kFree);
        ex.occ += expect == kOcc;
        ex.free += expect == kFree;
        ex.unknown += expect == kUnknown;
        if (got == expect) {
          ++ex.right;
          continue;
        }
        ++ex.wrong;
        // Ambiguous: within one voxel of a surface, or of a change of what the cameras see.
        bool ambiguous = false;
        const double lo = e[k] - r, hi = e[k + 1] + r;
        for (int s = 0; s <= 4 * n && !ambiguous; ++s) {
          const double t = lo + (hi - lo) * s / (4 * n);
          const Eigen::Vector3d p = o + t * d;
          if (DistanceToSurface(p) <= r) ambiguous = true;
          const bool f = seen_free_any(p);
          for (int dx = -1; dx <= 1 && !ambiguous; ++dx)
            for (int dy = -1; dy <= 1 && !ambiguous; ++dy)
              for (int dz = -1; dz <= 1 && !ambiguous; ++dz)
                if (seen_free_any(p + r * Eigen::Vector3d(dx, dy, dz).normalized() *
                                          ((dx || dy || dz) ? 1.0 : 0.0)) != f)
                  ambiguous = true;
        }
        if (!ambiguous) {
          ++ex.wrong_not_ambiguous;
          if (ex.wrong_not_ambiguous <= 5)
            ADD_FAILURE() << "ray (" << u << ", " << v << ") bin " << k << " [" << e[k] << ", "
                          << e[k + 1] << ") got " << got << " expected " << expect;
        }
      }
    }
  }
  return ex;
}

// 2.5 cm voxels against 15.5 cm bins (64 linear bins in [0.1, 10) m, the defaults); the
// images are fine enough (2 cm per pixel at 5 m) for every visible surface voxel to be hit.
constexpr double kVoxel = 0.025;
constexpr int kWidth = 320, kHeight = 240;

class RoomAndBox : public ::testing::Test {
 protected:
  void SetUp() override {
    views_.push_back(Render({0.0, 0.0, 0.0}, {0.0, 0.1, 3.0}, kWidth, kHeight));
    views_.push_back(Render({1.6, -0.4, 0.5}, {-0.3, 0.2, 3.5}, kWidth, kHeight));
    for (const auto& v : views_) inputs_.push_back({&v.depth, v.cam, v.world_from_cam, 0.1, 20.0});
    fusion_.voxel_m = kVoxel;
    fusion_.max_range_m = 10.0;
    bins_.near_m = 0.1;
    bins_.far_m = 10.0;
  }
  std::vector<View> views_;
  std::vector<FusionInput> inputs_;
  FusionOptions fusion_;
  BinOptions bins_;
};

TEST_F(RoomAndBox, ExactBinsMatchTheGeometry) {
  // Sanity of the scene: camera 0 sees the box in the middle, camera 1 sees behind it.
  ASSERT_LT(views_[0].depth.at(kWidth / 2, kHeight / 2), 2.7);  // the box, not the back wall (~5 m)
  for (auto spacing : {BinSpacing::kLinear, BinSpacing::kInverse}) {
    bins_.spacing = spacing;
    const PairOccupancy pair =
        ComputePairOccupancy(inputs_[0], inputs_[1], fusion_, bins_, OccupancyMode::kOctomap);
    int c = 0;
    for (const FrustumVolume* vol : {&pair.cam0, &pair.cam1}) {
      ASSERT_EQ(vol->width, kWidth / 2);
      ASSERT_EQ(vol->height, kHeight / 2);
      const Expectation ex = CheckVolume(*vol, views_[c], views_, kVoxel, 10.0);
      const double total = ex.right + ex.wrong;
      SCOPED_TRACE("camera " + std::to_string(c) + " spacing " + BinSpacingName(spacing));
      EXPECT_EQ(ex.wrong_not_ambiguous, 0);
      if (spacing == BinSpacing::kLinear) {
        EXPECT_GE(ex.right / total, 0.99) << ex.wrong << " wrong of " << total;
        // The scene has all three states in quantity.
        EXPECT_GT(ex.occ, 0.01 * total);
        EXPECT_GT(ex.free, 0.1 * total);
        EXPECT_GT(ex.unknown, 0.1 * total);
      } else {
        // Inverse bins near the camera are thinner than a voxel (1.5 mm at 0.1 m), so more
        // bins are within a voxel of a surface; all wrong ones still must be ambiguous.
        EXPECT_GE(ex.right / total, 0.97) << ex.wrong << " wrong of " << total;
      }
      ++c;
    }
  }
}

// Occluded region: camera 0 cannot see the wall behind the box, camera 1 can. In camera 0's
// volume the rays through the box are occupied at the box and again at the back wall (seen
// by camera 1) and unknown between.
TEST_F(RoomAndBox, OtherViewFillsInBehindTheOccluder) {
  const PairOccupancy pair =
      ComputePairOccupancy(inputs_[0], inputs_[1], fusion_, bins_, OccupancyMode::kOctomap);
  const auto& e = pair.cam0.edges_m;
  int rays = 0, both = 0;
  const Camera half = views_[0].cam.HalfGrid();
  for (int v = 0; v < kHeight / 2; ++v) {
    for (int u = 0; u < kWidth / 2; ++u) {
      const Eigen::Vector3d d = half.CamFromImg(u, v, 1.0);
      const double t_box = RayBox(Eigen::Vector3d::Zero(), d, kBlock, false);
      const double t_wall = RayBox(Eigen::Vector3d::Zero(), d, kRoom, true);
      if (!std::isfinite(t_box)) continue;
      // Is the wall point behind the box seen by camera 1?
      if (!SeenSurface(views_[1], t_wall * d)) continue;
      ++rays;
      const size_t i = static_cast<size_t>(v) * (kWidth / 2) + u;
      const int kb = BinOfDepth(e, t_box), kw = BinOfDepth(e, t_wall);
      if (((pair.cam0.occ[i] >> kb) & 1) && ((pair.cam0.occ[i] >> kw) & 1)) ++both;
    }
  }
  ASSERT_GT(rays, 20);
  EXPECT_GE(both, 0.9 * rays) << both << " of " << rays;
}

// Slow reference: sample every bin densely and ask the octree (OccupancyMap::StateAt) at each
// sample. Everything the samples find, the exact DDA must find; overall they agree closely.
// `min_agree`: the share of bins where the two agree (exact only adds what the samples
// skip; a bin of metres, as the last one below, skips more).
void ExpectExactAgreesWithDenseSampling(const OccupancyMap& map, const View& view,
                                        const BinOptions& bin_options, double min_agree = 0.995,
                                        int ray_step = 3) {
  const FrustumVolume vol = ProjectToFrustum(map, view.cam, view.world_from_cam, bin_options);
  const Camera half = view.cam.HalfGrid();
  const Eigen::Matrix3d R = view.world_from_cam.linear();
  const Eigen::Vector3d o = view.world_from_cam.translation();
  const auto& e = vol.edges_m;
  int64_t bins = 0, agree = 0, missed_by_exact = 0;
  for (int v = 0; v < vol.height; v += ray_step) {
    for (int u = 0; u < vol.width; u += ray_step) {
      const Eigen::Vector3d d = R * half.CamFromImg(u, v, 1.0);
      const size_t i = static_cast<size_t>(v) * vol.width + u;
      for (int k = 0; k < vol.num_bins(); ++k) {
        bool any_occ = false, any_free = false;
        const int n = 64;
        for (int s = 0; s < n; ++s) {
          const double t = e[k] + (e[k + 1] - e[k]) * (s + 0.5) / n;
          const int st = map.StateAt(o + t * d);
          any_occ |= st == 1;
          any_free |= st == 0;
        }
        const int ref = any_occ ? 1 : (any_free ? 0 : 255);
        const bool known = (vol.known[i] >> k) & 1, occ = (vol.occ[i] >> k) & 1;
        const int got = !known ? 255 : (occ ? 1 : 0);
        ++bins;
        agree += got == ref;
        // Exact can only add (it sees corner-clipped voxels the samples skip): ref occupied
        // implies exact occupied, ref known implies exact known.
        if ((ref == 1 && got != 1) || (ref == 0 && got == 255)) ++missed_by_exact;
      }
    }
  }
  EXPECT_EQ(missed_by_exact, 0);
  EXPECT_GE(static_cast<double>(agree) / bins, min_agree) << agree << " of " << bins;
}

TEST_F(RoomAndBox, ExactTraversalAgreesWithDenseSamplingReference) {
  ExpectExactAgreesWithDenseSampling(FuseOccupancy(inputs_, fusion_), views_[1], bins_);
}

// A first edge a hair in front of the camera (near_m 1e-10, inverse spacing: the first bins
// are all tiny): the camera's own voxel projects to ~1e10 pixels, past int's range, and
// its bins came out unknown (an overflowing conversion) where the reference finds them free
// (48384 of 49152 bins missed). The last bin spans 6e-9 to 10 m, where the 64 samples skip
// more of what exact finds: a lower share of agreement, but nothing missed.
TEST_F(RoomAndBox, ExactTraversalWithANearEdgeAtTheCamera) {
  BinOptions tiny = bins_;
  tiny.near_m = 1e-10;
  tiny.spacing = BinSpacing::kInverse;
  // Every 6th ray (every ray lost its first bins): a quarter of the reference's work, which
  // counts under the sanitizers.
  ExpectExactAgreesWithDenseSampling(FuseOccupancy(inputs_, fusion_), views_[1], tiny, 0.98, 6);
}

// The own ray casting (the default engine) gives exactly the voxel states of OctoMap's own
// insertPointCloud on this scene (tests/occupancy/equivalence_test.cc does the same on random
// scenes and the real samples).
TEST_F(RoomAndBox, OwnFusionEqualsOctomapInsertionVoxelForVoxel) {
  FusionOptions own = fusion_, ref = fusion_;
  own.engine = FusionEngine::kOwn;
  ref.engine = FusionEngine::kOctomap;
  const OccupancyMap a = FuseOccupancy(inputs_, own), b = FuseOccupancy(inputs_, ref);
  Eigen::Vector3i lo_a, hi_a, lo_b, hi_b;
  ASSERT_TRUE(a.KnownIndexBounds(&lo_a, &hi_a));
  ASSERT_TRUE(b.KnownIndexBounds(&lo_b, &hi_b));
  EXPECT_EQ(lo_a, lo_b);
  EXPECT_EQ(hi_a, hi_b);
  const VoxelBlock x = a.ExtractBlock(lo_a, hi_a), y = b.ExtractBlock(lo_a, hi_a);
  ASSERT_EQ(x.state.size(), y.state.size());
  int64_t differing = 0, known = 0;
  for (size_t i = 0; i < x.state.size(); ++i) {
    differing += x.state[i] != y.state[i];
    known += y.state[i] != VoxelBlock::kUnknown;
  }
  EXPECT_GT(known, 100000);
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(a.NumOccupiedVoxels(), b.NumOccupiedVoxels());
  EXPECT_EQ(a.NumFreeVoxels(), b.NumFreeVoxels());
  EXPECT_EQ(a.NumLeafNodes(), b.NumLeafNodes());
}

// Camera looking down +z at a fronto-parallel wall 1.96 m away: the wall's voxels are
// [1.95, 2.00) in z, bin 12 of 64 linear bins in [0.1, 10) is [1.9563, 2.1109) with centre
// 2.0336, behind the wall. Bin-centre sampling misses the wall; exact traversal catches it.
TEST(Traversal, CenterSamplingMissesAThinWallThatExactCatches) {
  Camera cam;
  cam.width = 64;
  cam.height = 48;
  cam.fx = cam.fy = 60;
  cam.cx = 31.5;
  cam.cy = 23.5;
  DepthImage depth(64, 48, 1.96f);
  const FusionInput in{&depth, cam, Rigid3d::Identity(), 0.1, 20};
  const OccupancyMap map = FuseOccupancy({in}, FusionOptions());
  BinOptions bins;
  const auto e = BinEdges(bins);
  ASSERT_EQ(BinOfDepth(e, 1.96), 12);
  ASSERT_GT(0.5 * (e[12] + e[13]), 2.0);
  bins.traversal = Traversal::kExact;
  const FrustumVolume exact = ProjectToFrustum(map, cam, Rigid3d::Identity(), bins);
  bins.traversal = Traversal::kCenter;
  const FrustumVolume center = ProjectToFrustum(map, cam, Rigid3d::Identity(), bins);
  const size_t n = exact.occ.size();
  size_t exact_hits = 0, center_occupied_rays = 0;
  for (size_t i = 0; i < n; ++i) {
    exact_hits += (exact.occ[i] >> 12) & 1;
    center_occupied_rays += center.occ[i] != 0;
    // Both agree that the bins in front are free (known, not occupied).
    EXPECT_EQ(exact.known[i] & 0x7ff, 0x7ffu);
    EXPECT_EQ(center.known[i] & 0x7ff, 0x7ffu);
    EXPECT_EQ(exact.occ[i] & 0x7ff, 0u);
  }
  EXPECT_EQ(exact_hits, n);
  EXPECT_EQ(center_occupied_rays, 0u);
}

// two_point: each ray is occupied exactly at its own depth's bin and where the other view's
// points land; a single fronto-parallel wall seen twice from the same pose gives one bit.
TEST(TwoPoint, OwnAndWarpedDepthOnly) {
  Camera cam;
  cam.width = 40;
  cam.height = 30;
  cam.fx = cam.fy = 40;
  cam.cx = 19.5;
  cam.cy = 14.5;
  DepthImage wall(40, 30, 3.0f);
  wall.at(10, 10) = 0.0f;  // invalid own depth at full-res pixel (10, 10) -> half ray (5, 5)
  BinOptions bins;
  bins.near_m = 1.0;
  bins.far_m = 5.0;
  bins.num_bins = 8;  // 0.5 m bins: 3.0 m is bin 4
  const FusionInput self{&wall, cam, Rigid3d::Identity(), 0.1, 10};
  // The other camera 1 m behind self along z sees the same wall at 4 m.
  DepthImage far_wall(40, 30, 4.0f);
  Rigid3d back = Rigid3d::Identity();
  back.translation() = Eigen::Vector3d(0, 0, -1.0);
  const FusionInput other{&far_wall, cam, back, 0.1, 10};
  const FrustumVolume vol = TwoPointVolume(self, other, bins);
  ASSERT_EQ(vol.width, 20);
  for (size_t i = 0; i < vol.occ.size(); ++i) {
    const int u = static_cast<int>(i % 20), v = static_cast<int>(i / 20);
    if (vol.known[i] == 0) continue;
    EXPECT_EQ(vol.known[i], 0xffu);
    EXPECT_EQ(vol.occ[i], uint64_t{1} << 4) << u << "," << v;
  }
  // The ray with invalid own depth still gets the warped wall point (the other view sees
  // the whole image area at 3 m in self) -> known.
  EXPECT_EQ(vol.occ[5 * 20 + 5], uint64_t{1} << 4);
  // Warping a different depth: the other view behind a step gives a second bit.
  DepthImage step(40, 30, 4.0f);
  for (int v = 0; v < 30; ++v)
    for (int u = 0; u < 40; ++u) step.at(u, v) = 4.6f;  // 3.6 m in self: bin 5
  const FrustumVolume vol2 = TwoPointVolume(self, {&step, cam, back, 0.1, 10}, bins);
  int two_bits = 0;
  for (size_t i = 0; i < vol2.occ.size(); ++i) two_bits += vol2.occ[i] == 0b110000;
  EXPECT_GT(two_bits, static_cast<int>(vol2.occ.size() / 2));
}

}  // namespace
}  // namespace gt::occupancy

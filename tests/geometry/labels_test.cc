// Pixel labels on analytic scenes with closed-form answers, and the distinct behaviour of
// every preset (GROUND_TRUTH.md §2).
#include "libgt/geometry/labels.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "libgt/core/error.h"
#include "tests/geometry/reference.h"

namespace gt {
namespace {

using test::Rect;

Camera MakeCamera(int w, int h, double f) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fx = f;
  c.fy = f;
  c.cx = (w - 1) / 2.0;
  c.cy = (h - 1) / 2.0;
  return c;
}

Rigid3d Pose(double yaw_deg, const Eigen::Vector3d& t) {
  Rigid3d p = Rigid3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix();
  p.translation() = t;
  return p;
}

// A wall at z = 5 and a box x ∈ [-0.5, 0.5], y ∈ [-0.4, 0.4], z ∈ [2.5, 3.2].
std::vector<Rect> BoxInFrontOfWall() {
  std::vector<Rect> s;
  s.push_back(Rect{2, 5.0, {-1e9, -1e9}, {1e9, 1e9}});
  s.push_back(Rect{2, 2.5, {-0.5, -0.4}, {0.5, 0.4}});
  s.push_back(Rect{2, 3.2, {-0.5, -0.4}, {0.5, 0.4}});
  s.push_back(Rect{0, -0.5, {-0.4, 2.5}, {0.4, 3.2}});
  s.push_back(Rect{0, 0.5, {-0.4, 2.5}, {0.4, 3.2}});
  s.push_back(Rect{1, -0.4, {-0.5, 2.5}, {0.5, 3.2}});
  s.push_back(Rect{1, 0.4, {-0.5, 2.5}, {0.5, 3.2}});
  return s;
}

// Closed-form label of pixel (u, v) of A: the exact surface point seen by A, its exact
// projection into B, and an exact ray cast from B's centre to it.
PixelLabel ClosedFormLabel(const std::vector<Rect>& scene, const Camera& cam_a,
                           const Rigid3d& world_from_a, const Camera& cam_b,
                           const Rigid3d& world_from_b, const LabelOptions& o, int u, int v,
                           Eigen::Vector2d* x_in_b) {
  const Eigen::Vector3d dir = world_from_a.linear() * cam_a.CamFromImg(u, v, 1.0);
  const auto [t, id] = test::CastRay(scene, world_from_a.translation(), dir);
  if (id < 0) return PixelLabel::kNoDepth;
  const Eigen::Vector3d p_world = world_from_a.translation() + t * dir;
  const Eigen::Vector3d p_in_b = world_from_b.inverse(Eigen::Isometry) * p_world;
  const double z = p_in_b.z();
  if (z <= o.min_depth_m) return PixelLabel::kOutOfView;
  const auto x = cam_b.ImgFromCam(p_in_b);
  *x_in_b = *x;
  if (!cam_b.InPixelArea(x->x(), x->y())) return PixelLabel::kOutOfView;
  const Eigen::Vector3d o_b = world_from_b.translation();
  const auto [t_hit, hit] = test::CastRay(scene, o_b, p_world - o_b);
  const double d_hit = hit < 0 ? z : std::min(1.0, t_hit) * z;  // planar depth scales with t
  const double tol = std::max(o.abs_tol_m, o.rel_tol * z);
  if (std::abs(z - d_hit) <= tol) return PixelLabel::kVisible;
  return z > d_hit + tol ? PixelLabel::kOccluded : PixelLabel::kInconsistent;
}

// True when the 3x3 neighbourhood of the pixel nearest to x in B holds more than one
// surface (a silhouette or crease of the rendered scene, within one pixel).
bool NearSilhouette(const test::Rendered& b, const Camera& cam_b, const Eigen::Vector2d& x) {
  const int cu = static_cast<int>(std::floor(x.x() + 0.5));
  const int cv = static_cast<int>(std::floor(x.y() + 0.5));
  int first = -2;
  for (int dv = -1; dv <= 1; ++dv) {
    for (int du = -1; du <= 1; ++du) {
      const int uu = std::clamp(cu + du, 0, cam_b.width - 1);
      const int vv = std::clamp(cv + dv, 0, cam_b.height - 1);
      const int s = b.surface[static_cast<size_t>(vv) * cam_b.width + uu];
      if (first == -2) first = s;
      if (s != first) return true;
    }
  }
  return false;
}

void CheckBoxScene(const Rigid3d& world_from_a, const Rigid3d& world_from_b) {
  const Camera cam = MakeCamera(320, 240, 250.0);
  const auto scene = BoxInFrontOfWall();
  const auto ra = test::Render(scene, cam, world_from_a);
  const auto rb = test::Render(scene, cam, world_from_b);
  const LabelOptions o = LabelPreset("default");
  const DirectionLabels l =
      LabelDirection(ra.depth, cam, rb.depth, cam, RelativePose(world_from_a, world_from_b), o);
  std::array<int, kNumPixelLabels> expected_counts{};
  int mismatches = 0, excused = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      Eigen::Vector2d x(0, 0);
      const PixelLabel want =
          ClosedFormLabel(scene, cam, world_from_a, cam, world_from_b, o, u, v, &x);
      ++expected_counts[static_cast<int>(want)];
      if (l.at(u, v) == want) continue;
      if (NearSilhouette(rb, cam, x)) {
        ++excused;
      } else {
        ++mismatches;
        ADD_FAILURE() << "pixel (" << u << ", " << v << "): got " << PixelLabelName(l.at(u, v))
                      << ", closed form " << PixelLabelName(want) << " at x = " << x.transpose();
      }
      if (mismatches > 10) return;
    }
  }
  EXPECT_EQ(mismatches, 0);
  // The scene must exercise occlusion and out-of-view, and silhouettes stay thin.
  EXPECT_GT(expected_counts[static_cast<int>(PixelLabel::kOccluded)], 500);
  EXPECT_GT(expected_counts[static_cast<int>(PixelLabel::kOutOfView)], 500);
  EXPECT_GT(expected_counts[static_cast<int>(PixelLabel::kVisible)], 20000);
  EXPECT_LT(excused, cam.width * cam.height / 100);
}

TEST(BoxInFrontOfWall, MatchesClosedFormBothDirections) {
  const Rigid3d world_from_a = Pose(0, {0, 0, 0});
  const Rigid3d world_from_b = Pose(-9, {0.9, 0.1, -0.2});
  CheckBoxScene(world_from_a, world_from_b);
  CheckBoxScene(world_from_b, world_from_a);
}

TEST(BoxInFrontOfWall, MatchesClosedFormVerticalBaseline) {
  Rigid3d world_from_b = Rigid3d::Identity();
  world_from_b.linear() = Eigen::AngleAxisd(0.12, Eigen::Vector3d::UnitX()).matrix();
  world_from_b.translation() = Eigen::Vector3d(-0.2, -0.7, 0.3);
  CheckBoxScene(Pose(4, {0.1, 0, 0}), world_from_b);
}

TEST(Plane, IdentityPoseIsAllVisible) {
  const Camera cam = MakeCamera(64, 48, 50.0);
  const auto r = test::Render({Rect{2, 3.0, {-1e9, -1e9}, {1e9, 1e9}}}, cam, Rigid3d::Identity());
  for (const std::string preset : {"default", "superglue"}) {
    const auto l =
        LabelDirection(r.depth, cam, r.depth, cam, Rigid3d::Identity(), LabelPreset(preset));
    for (size_t i = 0; i < l.labels.size(); ++i) {
      ASSERT_EQ(l.labels[i], static_cast<uint8_t>(PixelLabel::kVisible)) << preset << " " << i;
      EXPECT_NEAR(l.warped_xy[2 * i], static_cast<double>(i % cam.width), 1e-4);
      EXPECT_NEAR(l.warped_xy[2 * i + 1], static_cast<double>(i / cam.width), 1e-4);
    }
  }
  // Strict bounds 0 < x < W-1: the first and last row/column are out of view, the rest
  // visible.
  for (const std::string preset : {"occ2net", "occ2net-compat", "loftr"}) {
    const auto l =
        LabelDirection(r.depth, cam, r.depth, cam, Rigid3d::Identity(), LabelPreset(preset));
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        // compat divides by z + 1e-4, which pulls every x slightly towards 0: the last
        // column lands at W-1-ε and stays inside (the release does the same).
        const bool compat = preset == "occ2net-compat";
        const bool border =
            u == 0 || v == 0 || (!compat && (u == cam.width - 1 || v == cam.height - 1));
        ASSERT_EQ(l.at(u, v), border ? PixelLabel::kOutOfView : PixelLabel::kVisible)
            << preset << " (" << u << ", " << v << ")";
      }
    }
  }
}

TEST(Cheirality, PointsBehindBAreNeverVisible) {
  // A sees a wall at 4 m; B stands 6 m ahead of A looking the same way: every point is 2 m
  // behind B. B's own depth is a constant 2 m.
  const Camera cam = MakeCamera(64, 48, 50.0);
  const DepthImage depth_a(64, 48, 4.0f), depth_b(64, 48, 2.0f);
  const Rigid3d b_from_a = RelativePose(Rigid3d::Identity(), Pose(0, {0, 0, 6}));
  const auto l = LabelDirection(depth_a, cam, depth_b, cam, b_from_a, LabelPreset("default"));
  for (size_t i = 0; i < l.labels.size(); ++i) {
    ASSERT_EQ(l.labels[i], static_cast<uint8_t>(PixelLabel::kOutOfView));
    ASSERT_TRUE(std::isnan(l.warped_xy[2 * i]));
  }
  for (const std::string preset : {"occ2net", "loftr", "superglue"}) {
    const auto lp = LabelDirection(depth_a, cam, depth_b, cam, b_from_a, LabelPreset(preset));
    for (uint8_t code : lp.labels) ASSERT_EQ(code, static_cast<uint8_t>(PixelLabel::kOutOfView));
  }
  // The release has no cheirality test: mirrored points land in view (the defect that
  // occ2net-compat reproduces on purpose); they are still never VISIBLE here.
  const auto lc =
      LabelDirection(depth_a, cam, depth_b, cam, b_from_a, LabelPreset("occ2net-compat"));
  EXPECT_EQ(lc.at(32, 24), PixelLabel::kInconsistent);
  EXPECT_NEAR(lc.warped_xy[2 * (24 * 64 + 20)], cam.cx - (20 - cam.cx) * 2.0, 1e-2);  // mirrored
  for (uint8_t code : lc.labels) ASSERT_NE(code, static_cast<uint8_t>(PixelLabel::kVisible));
}

TEST(MissingTarget, UnknownByDefaultOccludedInCompat) {
  const Camera cam = MakeCamera(40, 30, 40.0);
  const DepthImage depth_a(40, 30, 2.0f);
  DepthImage depth_b(40, 30, 2.0f);
  for (int v = 10; v < 20; ++v) {
    for (int u = 10; u < 20; ++u) depth_b.at(u, v) = (u % 2) ? 0.0f : NAN;
  }
  const auto ld =
      LabelDirection(depth_a, cam, depth_b, cam, Rigid3d::Identity(), LabelPreset("default"));
  const auto lo =
      LabelDirection(depth_a, cam, depth_b, cam, Rigid3d::Identity(), LabelPreset("occ2net"));
  const auto lc = LabelDirection(depth_a, cam, depth_b, cam, Rigid3d::Identity(),
                                 LabelPreset("occ2net-compat"));
  for (int v = 10; v < 20; ++v) {
    for (int u = 10; u < 20; ++u) {
      EXPECT_EQ(ld.at(u, v), PixelLabel::kUnknown);
      EXPECT_EQ(lo.at(u, v), PixelLabel::kUnknown);
      // compat: x = u·z/(z + 1e-4) is just below u, so truncation reads pixel (u-1, v-1),
      // as the release does; inside the hole that is missing → compared as 0 → z = 2 >
      // 0 + 0.1 → OCCLUDED.
      EXPECT_LT(lc.warped_xy[2 * (v * 40 + u)], u);
      EXPECT_GT(lc.warped_xy[2 * (v * 40 + u)], u - 1e-3);
      if (u > 10 && v > 10) {
        EXPECT_EQ(lc.at(u, v), PixelLabel::kOccluded);
      }
    }
  }
  EXPECT_EQ(lc.at(20, 20), PixelLabel::kOccluded);  // reads (19, 19), inside the hole
  EXPECT_EQ(ld.at(20, 20), PixelLabel::kVisible);
  EXPECT_EQ(lc.at(10, 15), PixelLabel::kVisible);  // reads (9, 14), outside the hole
  EXPECT_EQ(ld.at(5, 5), PixelLabel::kVisible);
  EXPECT_EQ(lc.at(5, 5), PixelLabel::kVisible);
  // Compat with a point closer than the tolerance: z = 0.05 <= 0 + 0.1 → VISIBLE, as the
  // release would say.
  const DepthImage near_a(40, 30, 0.05f);
  const auto ln =
      LabelDirection(near_a, cam, depth_b, cam, Rigid3d::Identity(), LabelPreset("occ2net-compat"));
  EXPECT_EQ(ln.at(15, 15), PixelLabel::kVisible);
}

TEST(MissingTarget, CompatComparesTheSkyLikeTheRelease) {
  // TartanAir's sky is ~1e4 m, past any dataset maximum: occ2net-compat (like the released
  // code) compares every finite depth > 0, so a sky pixel seen by both is VISIBLE there and
  // NO_DEPTH with another preset; the dataset's range does not apply to compat.
  const Camera cam = MakeCamera(16, 12, 20.0);
  const DepthImage sky(16, 12, 9000.0f);
  LabelOptions compat = LabelPreset("occ2net-compat");
  EXPECT_FALSE(compat.dataset_depth_range);
  EXPECT_EQ(compat.max_depth_m, std::numeric_limits<float>::max());
  ApplyDatasetDepthRange(0.05, 100.0, &compat);  // TartanAir's reader range: not applied
  EXPECT_EQ(compat.max_depth_m, std::numeric_limits<float>::max());
  EXPECT_EQ(LabelDirection(sky, cam, sky, cam, Rigid3d::Identity(), compat).at(8, 6),
            PixelLabel::kVisible);
  LabelOptions occ2net = LabelPreset("occ2net");
  EXPECT_TRUE(occ2net.dataset_depth_range);
  ApplyDatasetDepthRange(0.05, 100.0, &occ2net);
  EXPECT_EQ(occ2net.max_depth_m, 100.0);
  EXPECT_EQ(LabelDirection(sky, cam, sky, cam, Rigid3d::Identity(), occ2net).at(8, 6),
            PixelLabel::kNoDepth);
  // Still invalid for compat: 0, inf and NaN.
  DepthImage odd(16, 12, 9000.0f);
  odd.at(1, 1) = 0.0f;
  odd.at(2, 2) = std::numeric_limits<float>::infinity();
  odd.at(3, 3) = std::numeric_limits<float>::quiet_NaN();
  const DirectionLabels l = LabelDirection(odd, cam, sky, cam, Rigid3d::Identity(), compat);
  EXPECT_EQ(l.at(1, 1), PixelLabel::kNoDepth);
  EXPECT_EQ(l.at(2, 2), PixelLabel::kNoDepth);
  EXPECT_EQ(l.at(3, 3), PixelLabel::kNoDepth);
}

// Identity pose, A sees a plane at z = 4, B reports depth d_b everywhere.
PixelLabel LabelAgainst(float d_b, const LabelOptions& o) {
  const Camera cam = MakeCamera(16, 12, 20.0);
  const DepthImage a(16, 12, 4.0f), b(16, 12, d_b);
  return LabelDirection(a, cam, b, cam, Rigid3d::Identity(), o).at(8, 6);
}

TEST(Presets, TolerancesDiffer) {
  // d_b = 4.15: |diff| = 0.15.
  EXPECT_EQ(LabelAgainst(4.15f, LabelPreset("default")), PixelLabel::kVisible);       // τ = 0.2
  EXPECT_EQ(LabelAgainst(4.15f, LabelPreset("occ2net")), PixelLabel::kInconsistent);  // 0.1
  EXPECT_EQ(LabelAgainst(4.15f, LabelPreset("superglue")), PixelLabel::kVisible);     // 0.4
  EXPECT_EQ(LabelAgainst(4.15f, LabelPreset("loftr")), PixelLabel::kVisible);         // 0.83
  // d_b = 3.7: diff = +0.3 (a surface of B in front).
  EXPECT_EQ(LabelAgainst(3.7f, LabelPreset("default")), PixelLabel::kOccluded);
  EXPECT_EQ(LabelAgainst(3.7f, LabelPreset("occ2net")), PixelLabel::kOccluded);
  EXPECT_EQ(LabelAgainst(3.7f, LabelPreset("superglue")), PixelLabel::kVisible);
  EXPECT_EQ(LabelAgainst(3.7f, LabelPreset("loftr")), PixelLabel::kVisible);
  // d_b = 3.0: diff = 1.0; loftr τ = 0.6 → occluded; superglue τ = 0.4.
  EXPECT_EQ(LabelAgainst(3.0f, LabelPreset("loftr")), PixelLabel::kOccluded);
  EXPECT_EQ(LabelAgainst(3.0f, LabelPreset("superglue")), PixelLabel::kOccluded);
  // d_b = 3.5: diff = 0.5; megadepth τ = 0.15 · 4 = 0.6 → visible, superglue's 0.4 → occluded.
  EXPECT_EQ(LabelAgainst(3.5f, LabelPreset("megadepth")), PixelLabel::kVisible);
  EXPECT_EQ(LabelAgainst(3.5f, LabelPreset("superglue")), PixelLabel::kOccluded);
  EXPECT_EQ(LabelAgainst(3.3f, LabelPreset("megadepth")), PixelLabel::kOccluded);  // 0.7 > 0.6
  EXPECT_EQ(LabelAgainst(4.65f, LabelPreset("megadepth")), PixelLabel::kInconsistent);
  // d_b = 5.5: diff = -1.5, B sees past the point.
  for (const auto& p : PresetNames()) {
    EXPECT_EQ(LabelAgainst(5.5f, LabelPreset(p)), PixelLabel::kInconsistent) << p;
  }
}

TEST(Presets, ObservedVersusProjectedTolerance) {
  LabelOptions o = LabelPreset("superglue");  // τ = 0.1 · z = 0.4
  EXPECT_EQ(LabelAgainst(4.42f, o), PixelLabel::kInconsistent);
  o.relative_to = RelativeTo::kObserved;  // τ = 0.1 · 4.42 = 0.442
  EXPECT_EQ(LabelAgainst(4.42f, o), PixelLabel::kVisible);
  o.relative_to = RelativeTo::kProjected;
  EXPECT_EQ(LabelAgainst(3.62f, o), PixelLabel::kVisible);  // 0.38 <= 0.4
  o.relative_to = RelativeTo::kObserved;                    // 0.38 > 0.362
  EXPECT_EQ(LabelAgainst(3.62f, o), PixelLabel::kOccluded);
}

TEST(Presets, TruncateVersusNearestLookup) {
  // Fronto-parallel plane at 4 m; B is shifted so that pixel u lands on x = u + 0.7.
  // B's depth alternates 4 m (even columns) and 10 m (odd columns).
  const Camera cam = MakeCamera(32, 8, 500.0);
  const DepthImage a(32, 8, 4.0f);
  DepthImage b(32, 8, 4.0f);
  for (int v = 0; v < 8; ++v) {
    for (int u = 1; u < 32; u += 2) b.at(u, v) = 10.0f;
  }
  Rigid3d b_from_a = Rigid3d::Identity();
  b_from_a.translation() = Eigen::Vector3d(0.7 * 4.0 / 500.0, 0, 0);
  for (const auto& p : PresetNames()) {
    const LabelOptions o = LabelPreset(p);
    const auto l = LabelDirection(a, cam, b, cam, b_from_a, o);
    const int u = 10;
    EXPECT_NEAR(l.warped_xy[2 * (4 * 32 + u)], u + 0.7, 1e-3);
    // nearest: pixel 11 (10 m, inconsistent); truncate: pixel 10 (4 m, visible)
    EXPECT_EQ(l.at(u, 4), o.target_lookup == TargetLookup::kNearest ? PixelLabel::kInconsistent
                                                                    : PixelLabel::kVisible)
        << p;
  }
}

TEST(Presets, BoundsAtTheImageEdge) {
  // B shifted so that x = u - 0.3: pixel 0 lands at -0.3 (inside the pixel area of pixel
  // 0, outside strict bounds); pixel W-1 lands at W-1.3 (inside both).
  const Camera cam = MakeCamera(32, 8, 500.0);
  const DepthImage a(32, 8, 4.0f), b(32, 8, 4.0f);
  Rigid3d b_from_a = Rigid3d::Identity();
  b_from_a.translation() = Eigen::Vector3d(-0.3 * 4.0 / 500.0, 0, 0);
  const auto lp = LabelDirection(a, cam, b, cam, b_from_a, LabelPreset("default"));
  const auto ls = LabelDirection(a, cam, b, cam, b_from_a, LabelPreset("occ2net"));
  EXPECT_EQ(lp.at(0, 4), PixelLabel::kVisible);
  EXPECT_EQ(ls.at(0, 4), PixelLabel::kOutOfView);
  EXPECT_EQ(lp.at(31, 4), PixelLabel::kVisible);
  EXPECT_EQ(ls.at(31, 4), PixelLabel::kVisible);
  EXPECT_EQ(ls.at(1, 0), PixelLabel::kOutOfView);  // y = 0 is not > 0
  // The other way: x = u + 0.6 puts pixel 31 at 31.6 >= W - 0.5: out of the pixel area.
  b_from_a.translation() = Eigen::Vector3d(0.6 * 4.0 / 500.0, 0, 0);
  const auto l2 = LabelDirection(a, cam, b, cam, b_from_a, LabelPreset("default"));
  EXPECT_EQ(l2.at(31, 4), PixelLabel::kOutOfView);
  EXPECT_EQ(l2.at(30, 4), PixelLabel::kVisible);
}

TEST(Presets, NamesAndErrors) {
  EXPECT_EQ(PresetNames().size(), 6u);
  for (const auto& p : PresetNames()) {
    std::string error;
    EXPECT_TRUE(LabelPreset(p).Check(&error)) << p << ": " << error;
  }
  const LabelOptions c = LabelPreset("occ2net-compat");
  EXPECT_FALSE(c.cheirality);
  EXPECT_EQ(c.projection_eps_m, 1e-4);
  EXPECT_EQ(c.missing_target, MissingTarget::kAsZeroDepth);
  try {
    LabelPreset("occnet");
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--preset");
    EXPECT_NE(std::string(e.what()).find("occ2net-compat"), std::string::npos);
  }
  EXPECT_THROW(ParseBounds("pixel_area"), InputError);
  EXPECT_EQ(ParseBounds(BoundsName(Bounds::kStrict)), Bounds::kStrict);
  EXPECT_EQ(ParseTargetLookup("truncate"), TargetLookup::kTruncate);
  EXPECT_EQ(ParseRelativeTo("observed"), RelativeTo::kObserved);
  EXPECT_EQ(ParseMissingTarget("as-zero-depth"), MissingTarget::kAsZeroDepth);
  LabelOptions bad;
  bad.abs_tol_m = -1;
  std::string error;
  EXPECT_FALSE(bad.Check(&error));
  EXPECT_NE(error.find("abs_tol_m"), std::string::npos);
  bad = LabelOptions();
  bad.max_depth_m = 0;
  EXPECT_FALSE(bad.Check(&error));
}

TEST(Inputs, SizeMismatchThrows) {
  const Camera cam = MakeCamera(16, 12, 20.0);
  const DepthImage a(16, 12, 1.0f), wrong(12, 16, 1.0f);
  EXPECT_THROW(LabelDirection(a, cam, wrong, cam, Rigid3d::Identity(), {}), InputError);
  EXPECT_THROW(ScoreDirection(wrong, cam, a, cam, Rigid3d::Identity(), {}, 1), InputError);
  EXPECT_THROW(ScoreDirection(a, cam, a, cam, Rigid3d::Identity(), {}, 0), InputError);
  Camera bad = cam;
  bad.fx = 0;
  EXPECT_THROW(LabelDirection(a, bad, a, cam, Rigid3d::Identity(), {}), InputError);
}

TEST(Metrics, CountsOfAHandMadeLabelMap) {
  // 7×3 map, label of pixel (u, v) = (u + v) % 6: every code appears; counts in closed form.
  DirectionLabels l;
  l.width = 7;
  l.height = 3;
  for (int v = 0; v < l.height; ++v) {
    for (int u = 0; u < l.width; ++u) l.labels.push_back(static_cast<uint8_t>((u + v) % 6));
  }
  for (int stride : {1, 2, 3, 7, 8}) {
    std::array<int64_t, kNumPixelLabels> expect{};
    int64_t sampled = 0;
    for (int v = 0; v < l.height; v += stride) {
      for (int u = 0; u < l.width; u += stride) ++expect[(u + v) % 6], ++sampled;
    }
    const DirectionMetrics m = MetricsFromLabels(l, stride);
    EXPECT_EQ(m.sampled, sampled) << stride;
    for (int k = 0; k < kNumPixelLabels; ++k) EXPECT_EQ(m.counts[k], expect[k]) << stride;
  }
  l.labels[9] = kNumPixelLabels;  // (2, 1): not a code
  EXPECT_THROW(MetricsFromLabels(l, 1), InputError);
  EXPECT_NO_THROW(MetricsFromLabels(l, 2));  // (2, 1) is not sampled at stride 2
  EXPECT_THROW(MetricsFromLabels(l, 0), InputError);
}

TEST(Metrics, CountsOfLargeMapsEqualAPixelByPixelCount) {
  // Sizes around the contiguous counter's 16-byte lanes and 255-chunk flushes (4080 bytes),
  // with long runs of one code (a uint8 lane counter would wrap at 256 without the flush).
  for (const auto& [w, h] : {std::pair{1, 1}, {15, 1}, {17, 3}, {4080, 1}, {4081, 2}, {640, 480}}) {
    std::vector<uint8_t> codes(static_cast<size_t>(w) * h);
    uint32_t state = 12345;
    for (size_t p = 0; p < codes.size(); ++p) {
      state = state * 1664525u + 1013904223u;
      codes[p] = p < codes.size() / 2 ? 2 : static_cast<uint8_t>((state >> 24) % 6);
    }
    std::array<int64_t, kNumPixelLabels> expect{};
    for (uint8_t c : codes) ++expect[c];
    const DirectionMetrics m = MetricsFromLabelCodes(codes.data(), w, h, 1);
    EXPECT_EQ(m.sampled, static_cast<int64_t>(codes.size())) << w << "x" << h;
    for (int k = 0; k < kNumPixelLabels; ++k) EXPECT_EQ(m.counts[k], expect[k]) << w << "x" << h;
    for (size_t bad : {size_t{0}, codes.size() / 2, codes.size() - 1}) {  // lanes and tail
      std::vector<uint8_t> damaged = codes;
      damaged[bad] = 200;
      EXPECT_THROW(MetricsFromLabelCodes(damaged.data(), w, h, 1), InputError) << bad;
    }
  }
}

TEST(Symmetry, MirroredCamerasGiveMirroredLabels) {
  // Cameras at x = ∓0.6 toed in by ±7°, a box centred on x = 0: the scene is symmetric
  // under x → -x, so A→B at (u, v) equals B→A at (W-1-u, v).
  const Camera cam = MakeCamera(160, 120, 120.0);
  const auto scene = BoxInFrontOfWall();
  const Rigid3d world_from_a = Pose(7, {-0.6, 0, 0});
  const Rigid3d world_from_b = Pose(-7, {0.6, 0, 0});
  const auto ra = test::Render(scene, cam, world_from_a);
  const auto rb = test::Render(scene, cam, world_from_b);
  const LabelOptions o = LabelPreset("default");
  const auto lab =
      LabelDirection(ra.depth, cam, rb.depth, cam, RelativePose(world_from_a, world_from_b), o);
  const auto lba =
      LabelDirection(rb.depth, cam, ra.depth, cam, RelativePose(world_from_b, world_from_a), o);
  int differ = 0;
  std::array<int, kNumPixelLabels> counts{};
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      differ += lab.at(u, v) != lba.at(cam.width - 1 - u, v);
      ++counts[static_cast<int>(lab.at(u, v))];
    }
  }
  // Float rounding of the rendered depths may tip a handful of exact-boundary pixels.
  EXPECT_LE(differ, 2);
  EXPECT_GT(counts[static_cast<int>(PixelLabel::kOccluded)], 100);
  EXPECT_GT(counts[static_cast<int>(PixelLabel::kOutOfView)], 100);
}

}  // namespace
}  // namespace gt

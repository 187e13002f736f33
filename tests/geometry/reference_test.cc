// The fast labeller (libgt/geometry/labels.cc) against the slow per-pixel reference of
// tests/geometry/reference.h on random scenes, poses, cameras and options; and the fast
// ScoreDirection against MetricsFromLabels.
#include "tests/geometry/reference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <tuple>

#include "libgt/geometry/labels.h"

namespace gt {
namespace {

struct RandomScene {
  Camera cam_a, cam_b;
  DepthImage depth_a, depth_b;
  Rigid3d b_from_a;
};

// Smooth random depth (a tilted plane plus bumps) with holes and invalid markers, so that
// every label occurs; B looks at roughly the same region from a random nearby pose.
RandomScene MakeScene(std::mt19937_64* rng, int w, int h) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  auto rand = [&](double lo, double hi) { return lo + (hi - lo) * uni(*rng); };
  RandomScene s;
  for (Camera* c : {&s.cam_a, &s.cam_b}) {
    c->width = w;
    c->height = h;
    c->fx = rand(0.7, 1.3) * w;
    c->fy = c->fx * rand(0.95, 1.05);
    c->cx = w / 2.0 + rand(-3, 3);
    c->cy = h / 2.0 + rand(-3, 3);
  }
  const Eigen::Vector3d axis = Eigen::Vector3d(rand(-1, 1), rand(-1, 1), rand(-1, 1)).normalized();
  s.b_from_a = Rigid3d::Identity();
  s.b_from_a.linear() = Eigen::AngleAxisd(rand(0, 0.5), axis).matrix();
  s.b_from_a.translation() = Eigen::Vector3d(rand(-1, 1), rand(-0.5, 0.5), rand(-1.5, 1));
  for (DepthImage* d : {&s.depth_a, &s.depth_b}) {
    *d = DepthImage(w, h);
    const double base = rand(1.5, 6), gx = rand(-2, 2) / w, gy = rand(-2, 2) / h;
    const double f1 = rand(0.02, 0.2), f2 = rand(0.02, 0.2), amp = rand(0, 1.5);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        double z = base + gx * u + gy * v + amp * std::sin(f1 * u) * std::cos(f2 * v);
        const double r = uni(*rng);
        if (r < 0.03)
          z = 0;
        else if (r < 0.035)
          z = NAN;
        else if (r < 0.04)
          z = INFINITY;
        else if (r < 0.045)
          z = 2e4;  // sky
        else if (r < 0.10)
          z += rand(-0.5, 0.5);  // speckle around the tolerance
        d->at(u, v) = static_cast<float>(z);
      }
    }
  }
  return s;
}

LabelOptions RandomOptions(std::mt19937_64* rng, int k) {
  const auto names = PresetNames();
  LabelOptions o = LabelPreset(names[k % names.size()]);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  if (k >= static_cast<int>(names.size())) {  // perturbed options
    o.min_depth_m = uni(*rng) < 0.5 ? 0.0 : 0.3;
    o.max_depth_m = uni(*rng) < 0.5 ? 1000.0 : 6.0;
    o.abs_tol_m = uni(*rng) * 0.3;
    o.rel_tol = uni(*rng) * 0.2;
  }
  return o;
}

TEST(Reference, FastPathEqualsSlowReferenceOnRandomScenes) {
  std::mt19937_64 rng(12345);
  int64_t total = 0, label_diff = 0;
  std::array<int64_t, kNumPixelLabels> seen{};
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 64 + 16 * (trial % 4), h = 48 + 8 * (trial % 3);
    const RandomScene s = MakeScene(&rng, w, h);
    const LabelOptions o = RandomOptions(&rng, trial);
    const DirectionLabels fast =
        LabelDirection(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a, o);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const auto ref =
            test::ReferenceLabel(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a, o, u, v);
        const size_t i = static_cast<size_t>(v) * w + u;
        ++total;
        ++seen[static_cast<int>(ref.label)];
        if (fast.labels[i] != static_cast<uint8_t>(ref.label)) {
          ++label_diff;
          ADD_FAILURE() << "trial " << trial << " (" << u << ", " << v << "): fast "
                        << PixelLabelName(fast.at(u, v)) << ", reference "
                        << PixelLabelName(ref.label) << " x = " << ref.x << ", " << ref.y;
        }
        const float fx = fast.warped_xy[2 * i], fy = fast.warped_xy[2 * i + 1];
        const bool projected = ref.label != PixelLabel::kNoDepth && !std::isnan(ref.x);
        if (!projected) {
          EXPECT_TRUE(std::isnan(fx) && std::isnan(fy));
        } else if (std::isfinite(ref.x) && std::abs(ref.x) < 1e6 && std::abs(ref.y) < 1e6) {
          EXPECT_NEAR(fx, ref.x, 1e-4 * std::max(1.0, std::abs(ref.x)));
          EXPECT_NEAR(fy, ref.y, 1e-4 * std::max(1.0, std::abs(ref.y)));
        }
      }
    }
    ASSERT_LE(label_diff, 20) << "stopping early";
  }
  // Well-conditioned random scenes: no ties, so no difference at all.
  EXPECT_EQ(label_diff, 0) << "of " << total;
  for (int k = 0; k < kNumPixelLabels; ++k) {
    EXPECT_GT(seen[k], 100) << "label " << PixelLabelName(static_cast<PixelLabel>(k))
                            << " was not exercised";
  }
}

// How close the slow reference's decisions for pixel (u, v) are to their thresholds: the
// smallest relative distance of a compared quantity to its threshold, over the comparisons
// the reference made (cheirality, bounds, target pixel edges, depth test). Mirrors
// ReferenceLabel step by step.
double ReferenceMargin(const RandomScene& s, const LabelOptions& o, int u, int v) {
  const double inf = std::numeric_limits<double>::infinity();
  const double d_a = s.depth_a.at(u, v);
  if (!IsValidDepth(s.depth_a.at(u, v), o.min_depth_m, o.max_depth_m)) return inf;  // exact
  const Eigen::Vector3d p_in_b = s.b_from_a * s.cam_a.CamFromImg(u, v, d_a);
  const double z = p_in_b.z();
  double margin = inf;
  if (o.cheirality) {
    margin = std::abs(z - o.min_depth_m) / (1 + std::abs(z));
    if (z <= o.min_depth_m) return margin;
  }
  const Eigen::Vector3d h = s.cam_b.K() * p_in_b;
  const double x = h.x() / (h.z() + o.projection_eps_m), y = h.y() / (h.z() + o.projection_eps_m);
  const bool area = o.bounds == Bounds::kPixelArea;
  const double x_lo = area ? -0.5 : 0.0, y_lo = x_lo;
  const double x_hi = area ? s.cam_b.width - 0.5 : s.cam_b.width - 1.0;
  const double y_hi = area ? s.cam_b.height - 0.5 : s.cam_b.height - 1.0;
  for (const auto& [c, lo, hi] : {std::tuple{x, x_lo, x_hi}, std::tuple{y, y_lo, y_hi}}) {
    margin = std::min(
        {margin, std::abs(c - lo) / (1 + std::abs(c)), std::abs(c - hi) / (1 + std::abs(c))});
  }
  if (!(x >= x_lo && x < x_hi && y >= y_lo && y < y_hi)) return margin;
  const double offset = o.target_lookup == TargetLookup::kNearest ? 0.5 : 0.0;
  for (const double c : {x, y}) {
    const double t = c + offset;
    margin = std::min(margin, std::abs(t - std::round(t)) / (1 + std::abs(c)));
  }
  const int tu = static_cast<int>(o.target_lookup == TargetLookup::kNearest ? std::floor(x + 0.5)
                                                                            : std::trunc(x));
  const int tv = static_cast<int>(o.target_lookup == TargetLookup::kNearest ? std::floor(y + 0.5)
                                                                            : std::trunc(y));
  double d_b = s.depth_b.at(tu, tv);
  if (!IsValidDepth(s.depth_b.at(tu, tv), o.min_depth_m, o.max_depth_m)) {
    if (o.missing_target == MissingTarget::kUnknown) return margin;
    d_b = 0.0;
  }
  const double tol =
      std::max(o.abs_tol_m, o.rel_tol * (o.relative_to == RelativeTo::kProjected ? z : d_b));
  return std::min(margin, std::abs(std::abs(z - d_b) - tol) / (1 + std::abs(z) + d_b));
}

// The fast path computes in float32 (libgt/geometry/labels.cc); the reference in double. On
// many more pixels than the test above, every label that differs must be a tie: a
// comparison of the reference within a relative 2^-16 (1.5e-5) of its threshold, about
// 250 float32 units in the last place, far above the kernel's rounding error for these
// well-conditioned scenes and far below any physical meaning (1.5e-5 px per pixel of x, 15
// µm per metre of depth). docs/GROUND_TRUTH.md ("Arithmetic") documents this.
TEST(Reference, Float32FastPathDiffersFromDoubleReferenceOnlyAtTies) {
  constexpr double kTieWidth = 0x1p-16;
  std::mt19937_64 rng(2024);
  int64_t total = 0, differ = 0, ties_seen = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const int w = 320, h = 240;
    const RandomScene s = MakeScene(&rng, w, h);
    const LabelOptions o = RandomOptions(&rng, trial);
    const DirectionLabels fast =
        LabelDirection(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a, o);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        ++total;
        const double margin = ReferenceMargin(s, o, u, v);
        ties_seen += margin < kTieWidth;
        const auto ref =
            test::ReferenceLabel(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a, o, u, v);
        if (fast.at(u, v) == ref.label) continue;
        ++differ;
        EXPECT_LT(margin, kTieWidth) << "trial " << trial << " (" << u << ", " << v << "): fast "
                                     << PixelLabelName(fast.at(u, v)) << ", reference "
                                     << PixelLabelName(ref.label) << ", margin " << margin;
      }
    }
  }
  // The tie zone is narrow (under 2% of pixels, mostly target-pixel edges, whose width
  // grows with |x|), and nearly every tie still gets the reference's label: at most 1e-5
  // of all labels differ.
  EXPECT_LT(ties_seen, total / 50) << "of " << total;
  EXPECT_LE(differ, total / 100000) << "of " << total;
  std::cout << "float32 vs double: " << differ << " labels differ of " << total << " (" << ties_seen
            << " pixels within a tie width of a threshold)\n";
}

TEST(Reference, ScoreDirectionEqualsMetricsFromLabels) {
  std::mt19937_64 rng(777);
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 80 + trial, h = 60 + (trial % 7);
    const RandomScene s = MakeScene(&rng, w, h);
    const LabelOptions o = RandomOptions(&rng, trial);
    const DirectionLabels l = LabelDirection(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a, o);
    // The counts LabelDirection keeps are the label map's histogram.
    ASSERT_TRUE(l.counts.has_value());
    DirectionLabels uncounted = l;
    uncounted.counts.reset();
    EXPECT_EQ(*l.counts, MetricsFromLabels(uncounted, 1).counts) << "trial " << trial;
    for (int stride : {1, 2, 3, 8, 10}) {
      const DirectionMetrics a = MetricsFromLabels(l, stride);
      const DirectionMetrics b =
          ScoreDirection(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a, o, stride);
      const int64_t expect_sampled = ((w + stride - 1) / stride) * ((h + stride - 1) / stride);
      EXPECT_EQ(a.sampled, expect_sampled);
      EXPECT_EQ(b.sampled, expect_sampled);
      EXPECT_EQ(a.valid, b.valid);
      EXPECT_EQ(a.counts, b.counts) << "trial " << trial << " stride " << stride;
      EXPECT_EQ(a.overlap, b.overlap);
      EXPECT_EQ(a.consistent_overlap, b.consistent_overlap);
      EXPECT_EQ(a.occlusion_ratio, b.occlusion_ratio);
      EXPECT_EQ(a.occlusion_ratio_visible, b.occlusion_ratio_visible);
      // Definitions of GROUND_TRUTH.md §3, recomputed from the counts.
      const auto c = [&](PixelLabel p) {
        return static_cast<double>(a.counts[static_cast<int>(p)]);
      };
      const double valid = a.sampled - c(PixelLabel::kNoDepth);
      EXPECT_EQ(a.valid, static_cast<int64_t>(valid));
      if (valid > 0) {
        EXPECT_DOUBLE_EQ(a.overlap, (c(PixelLabel::kVisible) + c(PixelLabel::kOccluded) +
                                     c(PixelLabel::kInconsistent) + c(PixelLabel::kUnknown)) /
                                        valid);
      }
      EXPECT_DOUBLE_EQ(a.consistent_overlap, c(PixelLabel::kVisible) / a.sampled);
      EXPECT_DOUBLE_EQ(a.occlusion_ratio, c(PixelLabel::kOccluded) / a.sampled);
    }
  }
}

TEST(Property, IdentityPoseRoundTripsEveryPixel) {
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 10; ++trial) {
    RandomScene s = MakeScene(&rng, 96, 72);
    s.cam_b = s.cam_a;
    const auto l = LabelDirection(s.depth_a, s.cam_a, s.depth_a, s.cam_a, Rigid3d::Identity(),
                                  LabelPreset("default"));
    for (int v = 0; v < 72; ++v) {
      for (int u = 0; u < 96; ++u) {
        if (!IsValidDepth(s.depth_a.at(u, v), 0.0, 1000.0)) {
          ASSERT_EQ(l.at(u, v), PixelLabel::kNoDepth);
          continue;
        }
        ASSERT_EQ(l.at(u, v), PixelLabel::kVisible);
        const size_t i = static_cast<size_t>(v) * 96 + u;
        ASSERT_NEAR(l.warped_xy[2 * i], u, 1e-4);
        ASSERT_NEAR(l.warped_xy[2 * i + 1], v, 1e-4);
      }
    }
  }
}

TEST(Property, WarpThereAndBackReturnsThePixel) {
  // Depth of B rendered from A's points: each VISIBLE pixel's warp, warped back with
  // inverse(b_from_a), returns to the source pixel.
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const RandomScene s = MakeScene(&rng, 64, 48);
    const int u = 32 + static_cast<int>(20 * uni(rng)), v = 24 + static_cast<int>(15 * uni(rng));
    const float d = s.depth_a.at(u, v);
    if (!IsValidDepth(d, 0.0, 1000.0)) continue;
    const auto ref = test::ReferenceLabel(s.depth_a, s.cam_a, s.depth_b, s.cam_b, s.b_from_a,
                                          LabelPreset("default"), u, v);
    if (std::isnan(ref.x)) continue;
    const Eigen::Vector3d p_in_b = s.b_from_a * s.cam_a.CamFromImg(u, v, d);
    const Eigen::Vector3d back =
        s.b_from_a.inverse(Eigen::Isometry) * s.cam_b.CamFromImg(ref.x, ref.y, p_in_b.z());
    const auto px = s.cam_a.ImgFromCam(back);
    ASSERT_TRUE(px.has_value());
    EXPECT_NEAR(px->x(), u, 1e-6);
    EXPECT_NEAR(px->y(), v, 1e-6);
  }
}

}  // namespace
}  // namespace gt

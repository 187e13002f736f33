// Coarse patch matches (GROUND_TRUTH.md §4): hand-built label maps with known answers, a
// brute-force reference of the match rules over random labels, and a geometric pair.
#include "libgt/geometry/patches.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "libgt/core/error.h"
#include "libgt/geometry/pair.h"

namespace gt {
namespace {

constexpr uint8_t kVis = static_cast<uint8_t>(PixelLabel::kVisible);
constexpr uint8_t kOcc = static_cast<uint8_t>(PixelLabel::kOccluded);
constexpr uint8_t kOov = static_cast<uint8_t>(PixelLabel::kOutOfView);

DirectionLabels Uniform(int w, int h, uint8_t label) {
  DirectionLabels l;
  l.width = w;
  l.height = h;
  l.labels.assign(static_cast<size_t>(w) * h, label);
  l.warped_xy.assign(static_cast<size_t>(w) * h * 2, NAN);
  return l;
}
void Set(DirectionLabels* l, int u, int v, uint8_t label, float x, float y) {
  const size_t i = static_cast<size_t>(v) * l->width + u;
  l->labels[i] = label;
  l->warped_xy[2 * i] = x;
  l->warped_xy[2 * i + 1] = y;
}

TEST(Patches, MutualLoopBackAndOrder) {
  // 32x32 images, stride 8: 4x4 cells, centre anchors at pixel 8c + 4.
  DirectionLabels l01 = Uniform(32, 32, kOov), l10 = Uniform(32, 32, kOov);
  // cell 0 (anchor (4,4)) → (13.2, 5.1) in image 1 = cell 1; cell 1 anchor (12,4) → back
  // to (4.4, 3.9) = cell 0: mutual vv (0, 1).
  Set(&l01, 4, 4, kVis, 13.2f, 5.1f);
  Set(&l10, 12, 4, kVis, 4.4f, 3.9f);
  // cell 5 (anchor (12,12)) → cell 10 (anchor (20,20)) which warps back into cell 6:
  // not mutual.
  Set(&l01, 12, 12, kVis, 20.0f, 19.0f);
  Set(&l10, 20, 20, kVis, 20.0f, 12.0f);
  // cell 2 (anchor (20,4)) occluded, lands in cell 15: vo (2, 15).
  Set(&l01, 20, 4, kOcc, 27.0f, 30.0f);
  // cell 3 of image 1 (anchor (28,4)) occluded, lands in cell 4 of image 0: ov (4, 3).
  Set(&l10, 28, 4, kOcc, 2.0f, 9.0f);
  const PatchMatches m = ComputePatchMatches(l01, l10, PatchOptions{});
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(std::vector<int32_t>(m.matches.begin(), m.matches.end()),
            (std::vector<int32_t>{0, 1, 2, 15, 4, 3}));
  EXPECT_EQ(m.match_type, (std::vector<uint8_t>{0, 1, 2}));
  EXPECT_EQ(m.match_xy, (std::vector<float>{13.2f, 5.1f, 27.0f, 30.0f, 2.0f, 9.0f}));
  EXPECT_EQ(m.cells0.size(), 16u);
  EXPECT_EQ(m.cells0[0], kVis);
  EXPECT_EQ(m.cells0[2], kOcc);
  EXPECT_EQ(m.cells1[3], kOcc);
  EXPECT_EQ(m.cells1[10], kVis);
  // Without the loop-back check the (5, 10) match appears, in cell order.
  PatchOptions no_mutual;
  no_mutual.mutual = false;
  const PatchMatches n = ComputePatchMatches(l01, l10, no_mutual);
  ASSERT_EQ(n.size(), 4u);
  EXPECT_EQ(std::vector<int32_t>(n.matches.begin(), n.matches.begin() + 4),
            (std::vector<int32_t>{0, 1, 5, 10}));
}

TEST(Patches, TargetsOutsideTheGridNeverBecomeCellZero) {
  DirectionLabels l01 = Uniform(32, 32, kOov), l10 = Uniform(32, 32, kOov);
  Set(&l01, 4, 4, kOcc, -4.0f, 3.0f);    // floor((-4 + 0.5)/8) = -1
  Set(&l01, 12, 4, kOcc, 31.6f, 3.0f);   // floor(32.1/8) = 4 = outside 4 columns
  Set(&l01, 20, 4, kOcc, 3.0f, -0.6f);   // row -1
  Set(&l01, 28, 4, kOcc, NAN, NAN);      // no projection
  Set(&l01, 4, 12, kOcc, 1e30f, 3.0f);   // huge
  Set(&l10, 4, 4, kOcc, -100.0f, 1.0f);  // ov with outside target
  const PatchMatches m = ComputePatchMatches(l01, l10, PatchOptions{});
  EXPECT_EQ(m.size(), 0u);
  for (int32_t c : m.matches) EXPECT_NE(c, 0);
}

TEST(Patches, CornerVersusCentreAnchors) {
  DirectionLabels l01 = Uniform(32, 32, kOov), l10 = Uniform(32, 32, kOov);
  // Corner anchor of cell 0 is pixel (0, 0); centre anchor pixel (4, 4).
  Set(&l01, 0, 0, kOcc, 12.1f, 0.0f);  // corner: round(12.1/8) = 2; centre would say 1
  Set(&l01, 4, 4, kOcc, 12.1f, 0.0f);  // centre: floor(12.6/8) = 1
  PatchOptions corner;
  corner.anchor = Anchor::kCorner;
  const PatchMatches c = ComputePatchMatches(l01, l10, corner);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.matches[1], 2);
  const PatchMatches m = ComputePatchMatches(l01, l10, PatchOptions{});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m.matches[1], 1);
  // x = 11.9: both rules give cell 1 (corner: round(1.4875) = 1; centre: floor(12.4/8) = 1).
  Set(&l01, 0, 0, kOcc, 11.9f, 0.0f);
  EXPECT_EQ(ComputePatchMatches(l01, l10, corner).matches[1], 1);
  // Corner: a point just left of the image (x = -3.9) still rounds to corner 0.
  Set(&l01, 0, 0, kOcc, -3.9f, 0.0f);
  EXPECT_EQ(ComputePatchMatches(l01, l10, corner).matches[1], 0);
  Set(&l01, 0, 0, kOcc, -4.1f, 0.0f);
  EXPECT_EQ(ComputePatchMatches(l01, l10, corner).size(), 0u);
}

TEST(Patches, BadInputThrows) {
  DirectionLabels l = Uniform(32, 32, kOov);
  PatchOptions o;
  o.stride = 0;
  EXPECT_THROW(ComputePatchMatches(l, l, o), InputError);
  DirectionLabels tiny = Uniform(4, 4, kOov);
  EXPECT_THROW(ComputePatchMatches(tiny, l, PatchOptions{}), InputError);
  DirectionLabels broken = l;
  broken.warped_xy.pop_back();
  EXPECT_THROW(ComputePatchMatches(l, broken, PatchOptions{}), InputError);
}

// Brute force straight from the rules: every (i, j) pair of cells is tested.
using Match = std::tuple<int, int, int, float, float>;  // i, j, type, x, y
std::vector<Match> BruteForce(const DirectionLabels& l01, const DirectionLabels& l10,
                              const PatchOptions& o) {
  const int s = o.stride;
  const int w0 = l01.width / s, h0 = l01.height / s, w1 = l10.width / s, h1 = l10.height / s;
  auto anchor = [&](const DirectionLabels& l, int cell, int cw) {
    const int c = cell % cw, r = cell / cw;
    const int u = o.anchor == Anchor::kCenter ? s * c + s / 2 : s * c;
    const int v = o.anchor == Anchor::kCenter ? s * r + s / 2 : s * r;
    return static_cast<size_t>(v) * l.width + u;
  };
  auto lands_in = [&](const DirectionLabels& l, size_t p, int cell, int cw) {
    const double x = l.warped_xy[2 * p], y = l.warped_xy[2 * p + 1];
    const double c = cell % cw, r = cell / cw;
    if (o.anchor == Anchor::kCenter) {  // x within the cell's pixels' areas
      return x >= s * c - 0.5 && x < s * (c + 1) - 0.5 && y >= s * r - 0.5 && y < s * (r + 1) - 0.5;
    }
    return x >= s * (c - 0.5) && x < s * (c + 0.5) && y >= s * (r - 0.5) && y < s * (r + 0.5);
  };
  std::vector<Match> vv, vo, ov;
  for (int i = 0; i < w0 * h0; ++i) {
    const size_t pi = anchor(l01, i, w0);
    for (int j = 0; j < w1 * h1; ++j) {
      const size_t pj = anchor(l10, j, w1);
      const Match mi{i, j, 0, l01.warped_xy[2 * pi], l01.warped_xy[2 * pi + 1]};
      if (l01.labels[pi] == kVis && lands_in(l01, pi, j, w1) &&
          (!o.mutual || (l10.labels[pj] == kVis && lands_in(l10, pj, i, w0)))) {
        vv.push_back(mi);
      }
      if (l01.labels[pi] == kOcc && lands_in(l01, pi, j, w1)) {
        vo.push_back(mi);
        std::get<2>(vo.back()) = 1;
      }
      if (l10.labels[pj] == kOcc && lands_in(l10, pj, i, w0)) {
        ov.push_back({i, j, 2, l10.warped_xy[2 * pj], l10.warped_xy[2 * pj + 1]});
      }
    }
  }
  std::sort(ov.begin(), ov.end(),
            [](const Match& a, const Match& b) { return std::get<1>(a) < std::get<1>(b); });
  std::vector<Match> all = vv;
  all.insert(all.end(), vo.begin(), vo.end());
  all.insert(all.end(), ov.begin(), ov.end());
  return all;
}

TEST(Patches, EqualsBruteForceOnRandomLabels) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  for (int trial = 0; trial < 30; ++trial) {
    const int s = 4 + 2 * (trial % 3);
    const int w0 = 40 + trial % 5, h0 = 30 + trial % 4, w1 = 36, h1 = 28;
    auto random_labels = [&](int w, int h, int tw, int th) {
      DirectionLabels l = Uniform(w, h, kOov);
      for (size_t p = 0; p < l.labels.size(); ++p) {
        const float r = uni(rng);
        l.labels[p] = r < 0.5f ? kVis : r < 0.8f ? kOcc : kOov;
        l.warped_xy[2 * p] = -6.0f + (tw + 12.0f) * uni(rng);
        l.warped_xy[2 * p + 1] = -6.0f + (th + 12.0f) * uni(rng);
        if (uni(rng) < 0.05f) l.warped_xy[2 * p] = NAN;
      }
      return l;
    };
    const DirectionLabels l01 = random_labels(w0, h0, w1, h1);
    const DirectionLabels l10 = random_labels(w1, h1, w0, h0);
    for (Anchor a : {Anchor::kCenter, Anchor::kCorner}) {
      for (bool mutual : {true, false}) {
        PatchOptions o;
        o.stride = s;
        o.anchor = a;
        o.mutual = mutual;
        const PatchMatches m = ComputePatchMatches(l01, l10, o);
        std::vector<Match> got;
        for (size_t k = 0; k < m.size(); ++k) {
          got.push_back({m.matches[2 * k], m.matches[2 * k + 1], m.match_type[k], m.match_xy[2 * k],
                         m.match_xy[2 * k + 1]});
        }
        const auto want = BruteForce(l01, l10, o);
        ASSERT_EQ(got, want) << "trial " << trial << " anchor " << AnchorName(a) << " mutual "
                             << mutual;
        EXPECT_EQ(m.cells0.size(), static_cast<size_t>((w0 / s) * (h0 / s)));
      }
    }
  }
}

TEST(Patches, IdentityPairMatchesEveryCellToItself) {
  Camera cam;
  cam.width = 64;
  cam.height = 48;
  cam.fx = cam.fy = 60;
  cam.cx = 31.5;
  cam.cy = 23.5;
  const DepthImage d(64, 48, 3.0f);
  const PairLabels p = LabelPair(d, cam, Rigid3d::Identity(), d, cam, Rigid3d::Identity(),
                                 LabelPreset("default"), PatchOptions{});
  ASSERT_EQ(p.patches.size(), 48u);  // 8 x 6 cells, all vv
  for (size_t k = 0; k < p.patches.size(); ++k) {
    EXPECT_EQ(p.patches.matches[2 * k], static_cast<int32_t>(k));
    EXPECT_EQ(p.patches.matches[2 * k + 1], static_cast<int32_t>(k));
    EXPECT_EQ(p.patches.match_type[k], 0);
    // fine target = the warped anchor = the anchor itself
    EXPECT_NEAR(p.patches.match_xy[2 * k], 8 * (k % 8) + 4, 1e-4);
    EXPECT_NEAR(p.patches.match_xy[2 * k + 1], 8 * (k / 8) + 4, 1e-4);
  }
  EXPECT_EQ(p.m01.counts[static_cast<int>(PixelLabel::kVisible)], 64 * 48);
  EXPECT_DOUBLE_EQ(p.m10.overlap, 1.0);
}

TEST(Patches, SideBySideOcclusionGivesVoAndOvWithExactTargets) {
  // Identity pose. Image 0 sees a wall at 4 m everywhere; image 1 sees a plate at 1 m on
  // its left third (columns 0-15, cells 0-1 of each row) and the wall elsewhere. 0→1: the
  // wall behind the plate is OCCLUDED (vo), the rest VISIBLE (vv). 1→0: plate points (1 m)
  // where image 0 sees 4 m are INCONSISTENT, so there is no ov.
  Camera cam;
  cam.width = 48;
  cam.height = 32;
  cam.fx = cam.fy = 40;
  cam.cx = 23.5;
  cam.cy = 15.5;
  const DepthImage d0(48, 32, 4.0f);
  DepthImage d1(48, 32, 4.0f);
  for (int v = 0; v < 32; ++v) {
    for (int u = 0; u < 16; ++u) d1.at(u, v) = 1.0f;
  }
  const PairLabels p = LabelPair(d0, cam, Rigid3d::Identity(), d1, cam, Rigid3d::Identity(),
                                 LabelPreset("default"), PatchOptions{});
  int vv = 0, vo = 0, ov = 0;
  for (size_t k = 0; k < p.patches.size(); ++k) {
    const int i = p.patches.matches[2 * k], j = p.patches.matches[2 * k + 1];
    EXPECT_EQ(i, j);
    const bool under_plate = (i % 6) < 2;
    EXPECT_EQ(p.patches.match_type[k], under_plate ? 1 : 0) << i;
    vv += p.patches.match_type[k] == 0;
    vo += p.patches.match_type[k] == 1;
    ov += p.patches.match_type[k] == 2;
  }
  EXPECT_EQ(vo, 2 * 4);
  EXPECT_EQ(vv, 4 * 4);
  EXPECT_EQ(ov, 0);
  EXPECT_EQ(p.patches.cells1[0], static_cast<uint8_t>(PixelLabel::kInconsistent));
  // Swap the roles: now the occluded cells are ov, with the target in image 0.
  const PairLabels q = LabelPair(d1, cam, Rigid3d::Identity(), d0, cam, Rigid3d::Identity(),
                                 LabelPreset("default"), PatchOptions{});
  int ov2 = 0;
  for (size_t k = 0; k < q.patches.size(); ++k) ov2 += q.patches.match_type[k] == 2;
  EXPECT_EQ(ov2, 8);
}

}  // namespace
}  // namespace gt

// truth::ComputeLoftrSupervision on analytic scenes: a fronto-parallel plane seen with the
// identity pose (every cell matches itself), after a pure x-translation (a known shift of
// cells), from behind, and with cells without depth; the compat option against the fixes.
#include "libgt/truth/loftr_supervision.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "libgt/core/error.h"

namespace gt::truth {
namespace {

constexpr int kW = 640, kH = 480, kStride = 8, kCw = kW / kStride, kCh = kH / kStride;
constexpr double kFocal = 500.0, kPlaneZ = 2.0;

Eigen::Matrix3d TestK() {
  Eigen::Matrix3d K;
  K << kFocal, 0, 319.5, 0, kFocal, 239.5, 0, 0, 1;
  return K;
}

LoftrView View(const DepthImage* depth) {
  LoftrView v;
  if (depth != nullptr) v.SetDepth(*depth);
  v.K = TestK();
  v.image_width = kW;
  v.image_height = kH;
  return v;
}

Eigen::Matrix4d Translation(double tx) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(0, 3) = tx;
  return T;
}

LoftrSupervisionOptions Compat(bool compat) {
  LoftrSupervisionOptions o;
  o.compat = compat;
  return o;
}

int Cell(int c, int r) { return r * kCw + c; }

// Coordinates x, y of point i of an [L · 2] array (and (i, j) of match i).
template <typename T>
T X(const std::vector<T>& v, size_t i) {
  return v[2 * i];
}
template <typename T>
T Y(const std::vector<T>& v, size_t i) {
  return v[2 * i + 1];
}

TEST(LoftrSupervision, IdentityPoseMatchesEveryCellToItself) {
  const DepthImage plane(kW, kH, static_cast<float>(kPlaneZ));
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  const LoftrCoarseSupervision s =
      ComputeLoftrSupervision(View(&plane), View(&plane), I, I, Compat(false));
  EXPECT_EQ(s.cells_w0, kCw);
  EXPECT_EQ(s.cells_h1, kCh);
  ASSERT_EQ(s.size(), static_cast<size_t>(kCw * kCh));  // cell 0 included (a fix)
  for (int i = 0; i < kCw * kCh; ++i) {
    EXPECT_EQ(X(s.matches, i), i);
    EXPECT_EQ(Y(s.matches, i), i);
    EXPECT_EQ(s.status0[i], static_cast<uint8_t>(WarpStatus::kInGrid));
    // Corner anchors (c·8, r·8); the warp returns them up to LoFTR's z + 1e-4 (< 0.04 px).
    const int col = i % kCw, row = i / kCw;
    EXPECT_EQ(X(s.grid0, i), static_cast<float>(kStride * col));
    EXPECT_EQ(Y(s.grid0, i), static_cast<float>(kStride * row));
    EXPECT_NEAR(X(s.warped0, i), X(s.grid0, i), 0.04);
    EXPECT_NEAR(Y(s.warped0, i), Y(s.grid0, i), 0.04);
  }
  // compat: LoFTR ignores cell 0.
  const LoftrCoarseSupervision c =
      ComputeLoftrSupervision(View(&plane), View(&plane), I, I, Compat(true));
  ASSERT_EQ(c.size(), static_cast<size_t>(kCw * kCh - 1));
  EXPECT_EQ(c.matches[0], 1);
}

TEST(LoftrSupervision, XTranslationShiftsCellsByTwo) {
  // x1 = x0 + f·tx / Z = x0 + 500 · 0.064 / 2 = x0 + 16 px: two cells to the right.
  const DepthImage plane(kW, kH, static_cast<float>(kPlaneZ));
  for (bool compat : {false, true}) {
    SCOPED_TRACE(compat ? "compat" : "default");
    const LoftrCoarseSupervision s = ComputeLoftrSupervision(
        View(&plane), View(&plane), Translation(0.064), Translation(-0.064), Compat(compat));
    size_t m = 0;
    for (int r = 0; r < kCh; ++r) {
      for (int c = 0; c < kCw; ++c) {
        const int i = Cell(c, r);
        if (c + 2 < kCw) {
          EXPECT_EQ(s.target0[i], Cell(c + 2, r));
          EXPECT_NEAR(X(s.warped0, i), kStride * c + 16.0, 0.04);
          if (compat && i == 0) continue;  // LoFTR ignores cell 0
          ASSERT_LT(2 * m + 1, s.matches.size());
          EXPECT_EQ(X(s.matches, m), i);
          EXPECT_EQ(Y(s.matches, m), Cell(c + 2, r));
          ++m;
        } else {  // columns 78, 79 land right of the grid
          EXPECT_EQ(s.status0[i], static_cast<uint8_t>(WarpStatus::kOutOfGrid));
          EXPECT_EQ(s.target0[i], compat ? 0 : -1);
        }
        // Image 1 back: two cells to the left; columns 0, 1 out of the grid.
        EXPECT_EQ(s.target1[i], c >= 2 ? Cell(c - 2, r) : (compat ? 0 : -1));
      }
    }
    EXPECT_EQ(m, s.size());
    EXPECT_EQ(m, static_cast<size_t>((kCw - 2) * kCh - (compat ? 1 : 0)));
  }
}

TEST(LoftrSupervision, PaddedCellsOfLoftrMegaDepthBatches) {
  // The x-translation above with the last 10 columns of both grids marked as padding
  // (LoFTR's mask0/mask1). Default: padded cells have no target (status kPadded, NaN warp)
  // and a target on the other grid's padding is out of the grid, so image 0 matches only
  // columns 0..67 (their targets 2..69 are real). compat: every padded grid point is
  // (0, 0) and warps as cell 0 does.
  const DepthImage plane(kW, kH, static_cast<float>(kPlaneZ));
  constexpr int kRealCols = kCw - 10;
  std::vector<uint8_t> mask(static_cast<size_t>(kCw) * kCh, 1);
  for (int r = 0; r < kCh; ++r) {
    for (int c = kRealCols; c < kCw; ++c) mask[Cell(c, r)] = 0;
  }
  LoftrView v = View(&plane);
  v.cell_mask = mask.data();
  const LoftrCoarseSupervision s =
      ComputeLoftrSupervision(v, v, Translation(0.064), Translation(-0.064), Compat(false));
  for (int r = 0; r < kCh; ++r) {
    for (int c = 0; c < kCw; ++c) {
      const int i = Cell(c, r);
      if (c >= kRealCols) {
        EXPECT_EQ(s.status0[i], static_cast<uint8_t>(WarpStatus::kPadded));
        EXPECT_EQ(s.target0[i], -1);
        EXPECT_TRUE(std::isnan(X(s.warped0, i)));
        EXPECT_EQ(X(s.grid0, i), static_cast<float>(kStride * c));  // the corner stays
      } else if (c + 2 >= kRealCols) {
        EXPECT_EQ(s.status0[i], static_cast<uint8_t>(WarpStatus::kOutOfGrid));
      } else {
        EXPECT_EQ(s.target0[i], Cell(c + 2, r));
      }
    }
  }
  EXPECT_EQ(s.size(), static_cast<size_t>((kRealCols - 2) * kCh));
  for (size_t m = 0; m < s.size(); ++m) {
    EXPECT_EQ(mask[X(s.matches, m)], 1);
    EXPECT_EQ(mask[Y(s.matches, m)], 1);
  }
  const LoftrCoarseSupervision compat =
      ComputeLoftrSupervision(v, v, Translation(0.064), Translation(-0.064), Compat(true));
  for (int r = 0; r < kCh; ++r) {
    const int i = Cell(kCw - 1, r);
    EXPECT_EQ(X(compat.grid0, i), 0.0f);
    EXPECT_EQ(Y(compat.grid0, i), 0.0f);
    EXPECT_EQ(X(compat.warped0, i), X(compat.warped0, 0));
    EXPECT_EQ(compat.target0[i], compat.target0[0]);  // cell 2, as cell 0's
  }
}

TEST(LoftrSupervision, BehindTheOtherCameraGivesNothing) {
  // Camera 1 turned by 180 degrees about y: the plane is behind it (q.z = -Z). LoFTR divides
  // by q.z + 1e-4 and mirrors the points into view (x kept, y flipped).
  const DepthImage plane(kW, kH, static_cast<float>(kPlaneZ));
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(0, 0) = -1;
  T(2, 2) = -1;
  const LoftrCoarseSupervision s =
      ComputeLoftrSupervision(View(&plane), View(&plane), T, T, Compat(false));
  EXPECT_EQ(s.size(), 0u);
  for (size_t i = 0; i < s.status0.size(); ++i) {
    EXPECT_EQ(s.status0[i], static_cast<uint8_t>(WarpStatus::kBehind));
    EXPECT_EQ(s.target0[i], -1);
    EXPECT_TRUE(std::isnan(X(s.warped0, i)));
  }
  const LoftrCoarseSupervision c =
      ComputeLoftrSupervision(View(&plane), View(&plane), T, T, Compat(true));
  int mirrored = 0;
  for (int r = 1; r < kCh; ++r) {
    for (int col = 1; col < kCw; ++col) {
      const int i = Cell(col, r);
      EXPECT_EQ(c.status0[i], static_cast<uint8_t>(WarpStatus::kBehind));
      // y' = 2·239.5 − y; x' = x (both up to the 1e-4 term).
      EXPECT_NEAR(X(c.warped0, i), kStride * col, 0.04);
      EXPECT_NEAR(Y(c.warped0, i), 479.0 - kStride * r, 0.04);
      if (c.target0[i] > 0) ++mirrored;
    }
  }
  EXPECT_GT(mirrored, (kCw - 1) * (kCh - 2));
  EXPECT_GT(c.size(), 1000u);  // LoFTR matches the mirrored cells
}

TEST(LoftrSupervision, CellsWithoutDepthGiveNothing) {
  DepthImage plane0(kW, kH, static_cast<float>(kPlaneZ));
  const DepthImage plane1(kW, kH, static_cast<float>(kPlaneZ));
  const int zero = Cell(10, 5), nan = Cell(20, 7), inf = Cell(30, 9), negative = Cell(40, 11);
  plane0.at(80, 40) = 0.0f;
  plane0.at(160, 56) = std::numeric_limits<float>::quiet_NaN();
  plane0.at(240, 72) = std::numeric_limits<float>::infinity();
  plane0.at(320, 88) = -1.0f;
  plane0.at(81, 40) = 0.0f;  // not a grid point: no effect
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  const LoftrCoarseSupervision s =
      ComputeLoftrSupervision(View(&plane0), View(&plane1), I, I, Compat(false));
  ASSERT_EQ(s.size(), static_cast<size_t>(kCw * kCh - 4));
  for (int i : {zero, nan, inf, negative}) {
    EXPECT_EQ(s.status0[i], static_cast<uint8_t>(WarpStatus::kNoDepth)) << i;
    EXPECT_EQ(s.target0[i], -1);
    EXPECT_TRUE(std::isnan(X(s.warped0, i)));
    EXPECT_EQ(s.target1[i], i);  // image 1 still warps there; the loop-back fails
  }
  for (size_t m = 0; m < s.size(); ++m) {
    for (int i : {zero, nan, inf, negative}) EXPECT_NE(X(s.matches, m), i);
  }
  // compat: a zero depth unprojects to camera 0's centre, which projects to (0, 0) → cell 0;
  // NaN and inf are non-finite → cell 0; a negative depth is used as a depth.
  const LoftrCoarseSupervision c =
      ComputeLoftrSupervision(View(&plane0), View(&plane1), I, I, Compat(true));
  EXPECT_EQ(c.target0[zero], 0);
  EXPECT_EQ(X(c.warped0, zero), 0.0f);
  EXPECT_EQ(c.target0[nan], 0);
  EXPECT_EQ(c.target0[inf], 0);
  EXPECT_EQ(c.target0[negative], negative);  // -z projects to the same pixel
  EXPECT_EQ(c.status0[zero], static_cast<uint8_t>(WarpStatus::kNoDepth));
  EXPECT_EQ(c.size(), static_cast<size_t>(kCw * kCh - 1 - 3));
}

TEST(LoftrSupervision, ImageScaleAndDepthMapBounds) {
  // A 1280x960 depth map for a 640x480 image (scale 2): grid points every 16 depth pixels.
  const DepthImage big(2 * kW, 2 * kH, static_cast<float>(kPlaneZ));
  LoftrView v = View(&big);
  v.K << 2 * kFocal, 0, 639.5, 0, 2 * kFocal, 479.5, 0, 0, 1;
  v.scale_x = v.scale_y = 2.0;
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  const LoftrCoarseSupervision s = ComputeLoftrSupervision(v, v, I, I, Compat(false));
  EXPECT_EQ(s.size(), static_cast<size_t>(kCw * kCh));
  EXPECT_EQ(X(s.grid0, Cell(3, 2)), 48.0f);
  EXPECT_EQ(Y(s.grid0, Cell(3, 2)), 32.0f);
  // The depth map too small for the grid: outside it a point has no depth; compat throws.
  const DepthImage small(kW / 2, kH / 2, static_cast<float>(kPlaneZ));
  LoftrView w = View(&small);
  const LoftrCoarseSupervision t = ComputeLoftrSupervision(w, w, I, I, Compat(false));
  EXPECT_EQ(t.status0[Cell(kCw - 1, kCh - 1)], static_cast<uint8_t>(WarpStatus::kNoDepth));
  EXPECT_EQ(t.size(), static_cast<size_t>(kCw / 2 * kCh / 2));
  EXPECT_THROW(ComputeLoftrSupervision(w, w, I, I, Compat(true)), InputError);
}

TEST(LoftrSupervision, OptionsAndInputsAreChecked) {
  std::string error;
  LoftrSupervisionOptions o;
  EXPECT_TRUE(o.Check(&error));
  o.coarse_stride = 0;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_NE(error.find("coarse_stride"), std::string::npos);
  const DepthImage plane(kW, kH, 1.0f);
  const Eigen::Matrix4d I = Eigen::Matrix4d::Identity();
  EXPECT_THROW(ComputeLoftrSupervision(View(&plane), View(&plane), I, I, o), InputError);
  LoftrView bad = View(&plane);
  bad.scale_x = 0;
  EXPECT_THROW(ComputeLoftrSupervision(bad, View(&plane), I, I, {}), InputError);
  bad = View(&plane);
  bad.K.setZero();
  EXPECT_THROW(ComputeLoftrSupervision(bad, View(&plane), I, I, {}), InputError);
  bad = View(nullptr);
  EXPECT_THROW(ComputeLoftrSupervision(bad, View(&plane), I, I, {}), InputError);
  Eigen::Matrix4d nan_pose = I;
  nan_pose(0, 3) = std::nan("");
  EXPECT_THROW(ComputeLoftrSupervision(View(&plane), View(&plane), nan_pose, I, {}), InputError);
}

}  // namespace
}  // namespace gt::truth

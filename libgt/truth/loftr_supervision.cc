#include "libgt/truth/loftr_supervision.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <sstream>

#include "libgt/core/depth.h"
#include "libgt/core/error.h"

namespace gt::truth {

const char* WarpStatusName(WarpStatus s) {
  switch (s) {
    case WarpStatus::kInGrid:
      return "in_grid";
    case WarpStatus::kNoDepth:
      return "no_depth";
    case WarpStatus::kBehind:
      return "behind";
    case WarpStatus::kOutOfGrid:
      return "out_of_grid";
    case WarpStatus::kPadded:
      return "padded";
  }
  return "?";
}

bool LoftrSupervisionOptions::Check(std::string* error) const {
  if (coarse_stride < 1 || coarse_stride > 1024) {
    *error = "coarse_stride: expected 1..1024 pixels, got " + std::to_string(coarse_stride);
    return false;
  }
  return true;
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The per-axis float32 grid spacing σ = s · scale (LoFTR: RESOLUTION[0] * data['scale']).
struct Spacing {
  float x, y;
};

Spacing SpacingOf(const LoftrView& v, int stride) {
  return {static_cast<float>(stride) * static_cast<float>(v.scale_x),
          static_cast<float>(stride) * static_cast<float>(v.scale_y)};
}

void CheckView(const LoftrView& v, int stride, const std::string& name) {
  if (v.depth_m == nullptr || v.depth_width < 1 || v.depth_height < 1) {
    throw InputError(name, "no depth map");
  }
  if (v.image_width < stride || v.image_height < stride) {
    std::ostringstream m;
    m << "image " << v.image_width << "x" << v.image_height
      << " is smaller than one coarse cell of " << stride << " pixels";
    throw InputError(name, m.str());
  }
  if (!(std::isfinite(v.scale_x) && v.scale_x > 0 && std::isfinite(v.scale_y) && v.scale_y > 0)) {
    std::ostringstream m;
    m << "scale: expected finite factors > 0, got (" << v.scale_x << ", " << v.scale_y << ")";
    throw InputError(name, m.str());
  }
  if (!v.K.allFinite() || std::abs(v.K.determinant()) < 1e-300) {
    throw InputError(name, "K: expected a finite, invertible 3x3 matrix");
  }
}

// One direction A -> B: fills grid_a, warped_a, target_a, status_a.
void WarpGrid(const LoftrView& a, const LoftrView& b, const Eigen::Matrix4d& b_from_a, int stride,
              bool compat, const std::string& name_a, std::vector<float>* grid_a,
              std::vector<float>* warped_a, std::vector<int32_t>* target_a,
              std::vector<uint8_t>* status_a) {
  const int wa = a.image_width / stride, ha = a.image_height / stride;
  const int wb = b.image_width / stride, hb = b.image_height / stride;
  const Spacing sa = SpacingOf(a, stride), sb = SpacingOf(b, stride);
  const Eigen::Matrix3d Ka_inv = a.K.inverse();
  const Eigen::Matrix3d R = b_from_a.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = b_from_a.topRightCorner<3, 1>();
  const Eigen::Matrix3d& Kb = b.K;
  const size_t n = static_cast<size_t>(wa) * ha;
  grid_a->resize(2 * n);
  warped_a->resize(2 * n);
  target_a->resize(n);
  status_a->resize(n);
  const int32_t none = compat ? 0 : -1;
  for (int r = 0; r < ha; ++r) {
    for (int c = 0; c < wa; ++c) {
      const size_t i = static_cast<size_t>(r) * wa + c;
      const bool padded = a.cell_mask != nullptr && a.cell_mask[i] == 0;
      // compat: LoFTR moves the grid point of a padded cell to (0, 0) and warps it.
      const float gx = padded && compat ? 0.0f : sa.x * static_cast<float>(c);
      const float gy = padded && compat ? 0.0f : sa.y * static_cast<float>(r);
      (*grid_a)[2 * i] = gx;
      (*grid_a)[2 * i + 1] = gy;
      (*target_a)[i] = none;
      if (padded && !compat) {
        (*warped_a)[2 * i] = (*warped_a)[2 * i + 1] = kNaN;
        (*status_a)[i] = static_cast<uint8_t>(WarpStatus::kPadded);
        continue;
      }
      // The depth at the nearest pixel (torch's round: half to even, rint in the default
      // rounding mode; nearbyint is the same but saves and restores the FP environment).
      const double u = std::rint(static_cast<double>(gx));
      const double v = std::rint(static_cast<double>(gy));
      const bool inside = u >= 0 && u < a.depth_width && v >= 0 && v < a.depth_height;
      if (!inside && compat) {
        std::ostringstream m;
        m << "grid point (" << gx << ", " << gy << ") of cell " << i << " lies outside the "
          << a.depth_width << "x" << a.depth_height << " depth map (compat: LoFTR indexes it)";
        throw InputError(name_a, m.str());
      }
      const float d = inside
                          ? a.depth_m[static_cast<size_t>(v) * static_cast<size_t>(a.depth_width) +
                                      static_cast<size_t>(u)]
                          : 0.0f;
      const bool has_depth = inside && std::isfinite(d) && d >= kMinPositiveDepthM;
      const Eigen::Vector3d p =
          Ka_inv * Eigen::Vector3d(static_cast<double>(gx) * d, static_cast<double>(gy) * d, d);
      const Eigen::Vector3d q = R * p + t;
      const Eigen::Vector3d h = Kb * q;
      float x = static_cast<float>(h.x() / (h.z() + 1e-4));
      float y = static_cast<float>(h.y() / (h.z() + 1e-4));
      WarpStatus status = WarpStatus::kInGrid;
      if (!has_depth) {
        status = WarpStatus::kNoDepth;
      } else if (!(q.z() > 0)) {
        status = WarpStatus::kBehind;
      }
      if (status != WarpStatus::kInGrid && !compat) x = y = kNaN;
      (*warped_a)[2 * i] = x;
      (*warped_a)[2 * i + 1] = y;
      // Target cell: float32 division and rounding, as LoFTR's w_pt / scale; tested in
      // floating point first, so that non-finite or huge values are out of the grid.
      const float cx = std::rint(x / sb.x);
      const float cy = std::rint(y / sb.y);
      bool in_grid =
          cx >= 0 && cx < static_cast<float>(wb) && cy >= 0 && cy < static_cast<float>(hb);
      if (in_grid && !compat && b.cell_mask != nullptr &&
          b.cell_mask[static_cast<size_t>(cy) * wb + static_cast<size_t>(cx)] == 0) {
        in_grid = false;  // on the other image's padding
      }
      if (status == WarpStatus::kInGrid && !in_grid) status = WarpStatus::kOutOfGrid;
      (*status_a)[i] = static_cast<uint8_t>(status);
      if (in_grid && (compat || status == WarpStatus::kInGrid)) {
        (*target_a)[i] = static_cast<int32_t>(cy) * wb + static_cast<int32_t>(cx);
      }
    }
  }
}

}  // namespace

LoftrCoarseSupervision ComputeLoftrSupervision(const LoftrView& view0, const LoftrView& view1,
                                               const Eigen::Matrix4d& cam1_from_cam0,
                                               const Eigen::Matrix4d& cam0_from_cam1,
                                               const LoftrSupervisionOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("loftr supervision options", error);
  const int s = options.coarse_stride;
  CheckView(view0, s, "view0");
  CheckView(view1, s, "view1");
  if (!cam1_from_cam0.allFinite()) throw InputError("cam1_from_cam0", "expected finite values");
  if (!cam0_from_cam1.allFinite()) throw InputError("cam0_from_cam1", "expected finite values");

  LoftrCoarseSupervision out;
  out.cells_w0 = view0.image_width / s;
  out.cells_h0 = view0.image_height / s;
  out.cells_w1 = view1.image_width / s;
  out.cells_h1 = view1.image_height / s;
  WarpGrid(view0, view1, cam1_from_cam0, s, options.compat, "view0", &out.grid0, &out.warped0,
           &out.target0, &out.status0);
  WarpGrid(view1, view0, cam0_from_cam1, s, options.compat, "view1", &out.grid1, &out.warped1,
           &out.target1, &out.status1);
  // Mutual loop-back i -> j -> i. compat: every non-target is cell 0 and cell 0 of image 0
  // is ignored (LoFTR's `correct_0to1[:, 0] = False`).
  const int32_t n0 = static_cast<int32_t>(out.target0.size());
  for (int32_t i = 0; i < n0; ++i) {
    const int32_t j = out.target0[i];
    if (j < 0) continue;
    if (out.target1[j] != i) continue;
    if (options.compat && i == 0) continue;
    out.matches.push_back(i);
    out.matches.push_back(j);
  }
  return out;
}

}  // namespace gt::truth

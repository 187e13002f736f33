#include "libgt/eval/match_quality.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "libgt/core/error.h"

namespace gt::eval {

bool QualityOptions::Check(std::string* error) const {
  if (!(px > 0) || !std::isfinite(px)) {
    *error = "px: expected a finite number > 0 (pixels)";
    return false;
  }
  return true;
}

namespace {

constexpr uint8_t kVisible = 2, kOccluded = 3;

// Nearest pixel of a point inside the pixel area, clamped to the grid.
int Nearest(float x, int size) {
  const int i = static_cast<int>(std::lround(x));
  return i < 0 ? 0 : (i >= size ? size - 1 : i);
}

// Warps the sub-pixel point p of image a with depth d into image b; false when behind b.
bool Warp(float px, float py, double depth, const Eigen::Matrix3d& Ka, const Eigen::Matrix3d& R,
          const Eigen::Vector3d& t, const Eigen::Matrix3d& Kb, double* x, double* y) {
  const Eigen::Vector3d p_in_a(depth * (px - Ka(0, 2)) / Ka(0, 0),
                               depth * (py - Ka(1, 2)) / Ka(1, 1), depth);
  const Eigen::Vector3d p_in_b = R * p_in_a + t;
  if (!(p_in_b.z() > 0)) return false;
  *x = Kb(0, 0) * p_in_b.x() / p_in_b.z() + Kb(0, 2);
  *y = Kb(1, 1) * p_in_b.y() / p_in_b.z() + Kb(1, 2);
  return true;
}

}  // namespace

PairQuality ScoreMatches(const PairTruthView& truth, const std::vector<float>& kpts0,
                         const std::vector<float>& kpts1, const QualityOptions& options,
                         std::vector<MatchVerdict>* verdicts) {
  GT_ASSERT(kpts0.size() == kpts1.size() && kpts0.size() % 2 == 0);
  if (verdicts != nullptr) verdicts->assign(kpts0.size() / 2, MatchVerdict());
  const int w = truth.width, h = truth.height, s = truth.patch_stride;
  const int cols = w / s, rows = h / s;
  const Eigen::Matrix3d R10 = truth.cam1_from_cam0_R.transpose();
  const Eigen::Vector3d t10 = -R10 * truth.cam1_from_cam0_t;
  PairQuality q;
  // Source cells of correct predictions, per class (cell in image 0 for vv/vo, 1 for ov).
  std::array<std::unordered_set<int64_t>, 3> hit_cells;
  const double px2 = options.px * options.px;
  const size_t n = kpts0.size() / 2;
  for (size_t i = 0; i < n; ++i) {
    const float x0 = kpts0[2 * i], y0 = kpts0[2 * i + 1];
    const float x1 = kpts1[2 * i], y1 = kpts1[2 * i + 1];
    const int u0 = Nearest(x0, w), v0 = Nearest(y0, h);
    const int u1 = Nearest(x1, w), v1 = Nearest(y1, h);
    const uint8_t l0 = truth.label01[static_cast<size_t>(v0) * w + u0];
    const uint8_t l1 = truth.label10[static_cast<size_t>(v1) * w + u1];
    // Hypothesis 0 -> 1 (the point of q0 seen, or hidden, in image 1) and 1 -> 0 (the
    // point of q1 hidden in image 0); the match takes the class of the one it satisfies.
    double err01 = std::numeric_limits<double>::infinity(), err10 = err01;
    int cell0 = -1, cell1 = -1;
    double tx = 0, ty = 0;
    const bool from0 = l0 == kVisible || l0 == kOccluded;
    const bool from1 = l1 == kOccluded;
    if (from0) {
      const double d = truth.depth0[static_cast<size_t>(v0) * w + u0];
      if (Warp(x0, y0, d, truth.K0, truth.cam1_from_cam0_R, truth.cam1_from_cam0_t, truth.K1, &tx,
               &ty)) {
        err01 = (x1 - tx) * (x1 - tx) + (y1 - ty) * (y1 - ty);
      }
      if (u0 / s < cols && v0 / s < rows) cell0 = (v0 / s) * cols + u0 / s;
    }
    if (from1) {
      const double d = truth.depth1[static_cast<size_t>(v1) * w + u1];
      if (Warp(x1, y1, d, truth.K1, R10, t10, truth.K0, &tx, &ty)) {
        err10 = (x0 - tx) * (x0 - tx) + (y0 - ty) * (y0 - ty);
      }
      if (u1 / s < cols && v1 / s < rows) cell1 = (v1 / s) * cols + u1 / s;
    }
    int cls = kClassUnscored;
    double err2 = std::numeric_limits<double>::infinity();
    if (from0 && (err01 <= px2 || !(from1 && err10 <= px2))) {
      cls = l0 == kVisible ? kClassVV : kClassVO;
      err2 = err01;
    } else if (from1) {
      cls = kClassOV;
      err2 = err10;
    }
    if (cls == kClassUnscored) {
      ++q.unscored;
      ++q.unscored_by_label[l0 < 6 ? l0 : 5];
      continue;
    }
    ++q.types[cls].predicted;
    if (err2 <= px2) ++q.types[cls].correct;
    if (verdicts != nullptr) (*verdicts)[i] = {static_cast<uint8_t>(cls), err2 <= px2};
    // Recall: every hypothesis the match satisfies credits its source cell, whatever class
    // the match was given (a match near an occlusion edge can satisfy both).
    if (from0 && err01 <= px2 && cell0 >= 0)
      hit_cells[l0 == kVisible ? kClassVV : kClassVO].insert(cell0);
    if (from1 && err10 <= px2 && cell1 >= 0) hit_cells[kClassOV].insert(cell1);
  }
  for (int64_t m = 0; m < truth.num_matches; ++m) {
    const int type = truth.match_type[m];
    if (type < 0 || type > 2) continue;
    ++q.types[type].truth;
    const int64_t source_cell = type == kClassOV ? truth.matches[2 * m + 1] : truth.matches[2 * m];
    if (hit_cells[type].count(source_cell)) ++q.types[type].recalled;
  }
  return q;
}

}  // namespace gt::eval

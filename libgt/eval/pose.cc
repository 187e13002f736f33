#include "libgt/eval/pose.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "libgt/core/error.h"

namespace gt::eval {

bool PoseEstimatorOptions::Check(std::string* error) const {
  if (!(ransac_px > 0) || !std::isfinite(ransac_px)) {
    *error = "ransac_px: expected a finite number > 0 (pixels)";
    return false;
  }
  if (!(confidence > 0 && confidence < 1)) {
    *error = "confidence: expected a number in (0, 1)";
    return false;
  }
  if (min_matches < 5) {
    *error = "min_matches: expected an integer >= 5 (the five-point solver's minimum)";
    return false;
  }
  return true;
}

namespace {

// [N, 2] pixels -> N normalised points (x - cx) / fx, (y - cy) / fy, in double as LoFTR
// (NumPy float64 after subtracting K's entries).
cv::Mat Normalise(const std::vector<float>& kpts, const Eigen::Matrix3d& K) {
  const int n = static_cast<int>(kpts.size() / 2);
  cv::Mat out(n, 2, CV_64F);
  for (int i = 0; i < n; ++i) {
    out.at<double>(i, 0) = (static_cast<double>(kpts[2 * i]) - K(0, 2)) / K(0, 0);
    out.at<double>(i, 1) = (static_cast<double>(kpts[2 * i + 1]) - K(1, 2)) / K(1, 1);
  }
  return out;
}

double AngleDeg(double cosine) { return std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI; }

}  // namespace

std::optional<PoseEstimate> EstimateRelativePose(const std::vector<float>& kpts0,
                                                 const std::vector<float>& kpts1,
                                                 const Eigen::Matrix3d& K0,
                                                 const Eigen::Matrix3d& K1,
                                                 const PoseEstimatorOptions& options) {
  GT_ASSERT(kpts0.size() == kpts1.size() && kpts0.size() % 2 == 0);
  const int n = static_cast<int>(kpts0.size() / 2);
  if (n < options.min_matches) return std::nullopt;
  const double threshold = options.ransac_px / ((K0(0, 0) + K1(1, 1) + K0(0, 0) + K1(1, 1)) / 4.0);
  const cv::Mat p0 = Normalise(kpts0, K0);
  const cv::Mat p1 = Normalise(kpts1, K1);
  const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
  cv::Mat mask;
  const cv::Mat E =
      cv::findEssentialMat(p0, p1, identity, cv::RANSAC, options.confidence, threshold, mask);
  if (E.empty() || E.cols != 3 || E.rows % 3 != 0) return std::nullopt;
  std::optional<PoseEstimate> best;
  int best_inliers = 0;
  for (int k = 0; k < E.rows / 3; ++k) {
    const cv::Mat block = E.rowRange(3 * k, 3 * k + 3).clone();
    cv::Mat R, t;
    // The same mask object for every block: recoverPose narrows it in place (LoFTR's loop).
    const int inliers = cv::recoverPose(block, p0, p1, identity, R, t, 1e9, mask);
    if (inliers > best_inliers) {
      best_inliers = inliers;
      PoseEstimate estimate;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) estimate.cam1_from_cam0_R(r, c) = R.at<double>(r, c);
        estimate.cam1_from_cam0_t(r) = t.at<double>(r, 0);
      }
      estimate.inliers = inliers;
      best = estimate;
    }
  }
  return best;
}

PoseError RelativePoseError(const Eigen::Matrix3d& R_gt, const Eigen::Vector3d& t_gt,
                            const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  PoseError e;
  const double norms = t.norm() * t_gt.norm();
  if (t_gt.norm() == 0) {
    e.translation_deg = 0;
  } else if (norms == 0) {
    e.translation_deg = 90;
  } else {
    const double angle = AngleDeg(t.dot(t_gt) / norms);
    e.translation_deg = std::min(angle, 180.0 - angle);
  }
  e.rotation_deg = AngleDeg(((R.transpose() * R_gt).trace() - 1.0) / 2.0);
  e.max_deg = std::max(e.rotation_deg, e.translation_deg);
  return e;
}

PoseError NoPoseError() { return {kInfiniteError, kInfiniteError, kInfiniteError}; }

std::vector<double> PoseAuc(const std::vector<double>& errors,
                            const std::vector<double>& thresholds_deg) {
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const size_t n = sorted.size();
  std::vector<double> aucs;
  for (const double threshold : thresholds_deg) {
    if (n == 0) {
      aucs.push_back(0);
      continue;
    }
    // Points (e_0 = 0, r_0 = 0), (e_k, k / n) for the sorted errors below the threshold,
    // then (threshold, r_last): the trapezoid rule over them.
    double area = 0, prev_e = 0, prev_r = 0;
    size_t k = 0;
    for (; k < n && sorted[k] < threshold; ++k) {
      const double r = static_cast<double>(k + 1) / static_cast<double>(n);
      area += (sorted[k] - prev_e) * (r + prev_r) / 2.0;
      prev_e = sorted[k];
      prev_r = r;
    }
    area += (threshold - prev_e) * prev_r;
    aucs.push_back(area / threshold);
  }
  return aucs;
}

std::vector<double> SymmetricEpipolarDistances(const std::vector<float>& kpts0,
                                               const std::vector<float>& kpts1,
                                               const Eigen::Matrix3d& K0, const Eigen::Matrix3d& K1,
                                               const Eigen::Matrix3d& R_gt,
                                               const Eigen::Vector3d& t_gt) {
  GT_ASSERT(kpts0.size() == kpts1.size() && kpts0.size() % 2 == 0);
  Eigen::Matrix3d t_cross;
  t_cross << 0, -t_gt.z(), t_gt.y(), t_gt.z(), 0, -t_gt.x(), -t_gt.y(), t_gt.x(), 0;
  const Eigen::Matrix3d E = t_cross * R_gt;
  const size_t n = kpts0.size() / 2;
  std::vector<double> d(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d x0((kpts0[2 * i] - K0(0, 2)) / K0(0, 0),
                             (kpts0[2 * i + 1] - K0(1, 2)) / K0(1, 1), 1.0);
    const Eigen::Vector3d x1((kpts1[2 * i] - K1(0, 2)) / K1(0, 0),
                             (kpts1[2 * i + 1] - K1(1, 2)) / K1(1, 1), 1.0);
    const Eigen::Vector3d Ex0 = E * x0;
    const Eigen::Vector3d Etx1 = E.transpose() * x1;
    const double x1Ex0 = x1.dot(Ex0);
    d[i] =
        x1Ex0 * x1Ex0 *
        (1.0 / (Ex0(0) * Ex0(0) + Ex0(1) * Ex0(1)) + 1.0 / (Etx1(0) * Etx1(0) + Etx1(1) * Etx1(1)));
  }
  return d;
}

}  // namespace gt::eval

// Relative pose from matches and its error, the LoFTR/SuperGlue protocol
// (GROUND_TRUTH.md §7, docs/EVAL.md "Relative pose").
//
// Keypoints are pixels at the split's working resolution, pixel centres at integer
// coordinates (libgt/core/camera.h). They are normalised by K ((x - c) / f); the RANSAC
// threshold in pixels is divided by the mean of K0[0,0], K1[1,1], K0[0,0], K1[1,1];
// cv::findEssentialMat(RANSAC, prob = confidence) on the normalised points with K = I;
// cv::recoverPose(E_k, ..., I, distanceThresh 1e9, mask) on each 3x3 block E_k of E, the
// same mask passed on from block to block (OpenCV updates it in place, as LoFTR's Python
// loop does), the block with most inliers wins; fewer than `min_matches` matches, no E, or
// no block with an inlier -> no pose (pose error +inf). recoverPose is RecoverPose below:
// the same numbers, computed only where they count.
// Errors (degrees): rotation arccos(clip((tr(R^T R_gt) - 1) / 2, -1, 1)); translation the
// angle between t and t_gt folded to min(e, 180 - e) (t is known up to sign and scale);
// pose error = max of the two. AUC at threshold T: errors sorted with 0 prepended, recall
// k/N at the k-th, integrated by the trapezoid rule up to T, divided by T.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace gt::eval {

// The essential-matrix estimator and its settings; recorded with every result.
struct PoseEstimatorOptions {
  double ransac_px = 0.5;       // RANSAC inlier threshold in pixels (LoFTR 0.5, SuperGlue 1)
  double confidence = 0.99999;  // RANSAC confidence, in (0, 1)
  int min_matches = 5;          // fewer matches -> no pose (error +inf); >= 5
  bool Check(std::string* error) const;
};

struct PoseEstimate {
  Eigen::Matrix3d cam1_from_cam0_R;  // rotation of the winning block
  Eigen::Vector3d cam1_from_cam0_t;  // unit translation direction
  int inliers = 0;                   // recoverPose's count for the winning block
};

// kpts0, kpts1: row-major [N, 2] pixels (x, y) at the resolution of K0, K1.
// Deterministic (OpenCV's RANSAC seeds its own generator per call); thread-safe.
std::optional<PoseEstimate> EstimateRelativePose(const std::vector<float>& kpts0,
                                                 const std::vector<float>& kpts1,
                                                 const Eigen::Matrix3d& K0,
                                                 const Eigen::Matrix3d& K1,
                                                 const PoseEstimatorOptions& options);

// cv::recoverPose(E, p0, p1, I, R, t, distance_thresh, mask) of OpenCV 4.6 on normalised
// points p0, p1 (row-major [N, 2]), with the same result: E split by
// cv::decomposeEssentialMat into R1, R2, t; each point triangulated by OpenCV's DLT (the
// smallest right singular vector of the 4x4 system, by the same SVD routine, hence the
// same bits) for [R1|t] and [R2|t]; a point counts for a candidate when it lies in front
// of both cameras closer than distance_thresh; the candidate with most points wins, ties
// to the first of (R1, t), (R2, t), (R1, -t), (R2, -t). It differs in cost only:
//  - points whose mask entry is 0 are not triangulated (OpenCV ANDs them out after);
//  - [R|-t] is not triangulated again: its system is [R|t]'s with the last column
//    negated, whose solution is (X, -W) for [R|t]'s (X, W), so its depths are the
//    negatives of [R|t]'s, exactly.
// `mask` (N entries, or empty for all points) is narrowed in place to the winner's points,
// as OpenCV does. Checked against cv::recoverPose in tests/eval/pose_test.cc.
struct RecoveredPose {
  Eigen::Matrix3d cam1_from_cam0_R;
  Eigen::Vector3d cam1_from_cam0_t;
  int inliers = 0;
};
RecoveredPose RecoverPose(const Eigen::Matrix3d& E, const std::vector<double>& p0,
                          const std::vector<double>& p1, double distance_thresh,
                          std::vector<uint8_t>* mask);

struct PoseError {
  double rotation_deg = 0;     // +inf when no pose
  double translation_deg = 0;  // folded to [0, 90]; +inf when no pose
  double max_deg = 0;          // max of the two
};
inline constexpr double kInfiniteError = std::numeric_limits<double>::infinity();

// Error of an estimate against the ground truth cam1_from_cam0 = (R_gt, t_gt). When
// |t_gt| = 0 (a pure rotation: no direction to compare) the translation error is 0 and
// only the rotation is scored, as LoFTR's ignore_gt_t_thr does; a zero t gives 90.
PoseError RelativePoseError(const Eigen::Matrix3d& R_gt, const Eigen::Vector3d& t_gt,
                            const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
PoseError NoPoseError();  // all three +inf

// AUC of the error curve at each threshold (degrees), in [0, 1]. +inf errors count as
// pairs never recalled. Empty `errors` -> 0 for every threshold.
std::vector<double> PoseAuc(const std::vector<double>& errors,
                            const std::vector<double>& thresholds_deg);

// Symmetric epipolar distance of each match on K-normalised points (LoFTR's
// "symmetric_epipolar_distance"): with E = [t]x R of cam1_from_cam0, x0, x1 homogeneous
// normalised points, d = (x1^T E x0)^2 (1 / ((E x0)_0^2 + (E x0)_1^2) +
// 1 / ((E^T x1)_0^2 + (E^T x1)_1^2)). Returns [N].
std::vector<double> SymmetricEpipolarDistances(const std::vector<float>& kpts0,
                                               const std::vector<float>& kpts1,
                                               const Eigen::Matrix3d& K0, const Eigen::Matrix3d& K1,
                                               const Eigen::Matrix3d& R_gt,
                                               const Eigen::Vector3d& t_gt);

}  // namespace gt::eval

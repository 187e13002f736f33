// Relative pose from matches and its error, the LoFTR/SuperGlue protocol and the robust
// estimators of OpenCV 4.6 that other papers' evaluations use or come closest to
// (GROUND_TRUTH.md §7, docs/EVAL.md "Relative pose" and "Estimators and protocols").
//
// Keypoints are pixels at the split's working resolution, pixel centres at integer
// coordinates (libgt/core/camera.h). They are normalised by K ((x - c) / f); the threshold
// in pixels is divided by a mean focal length (FocalMean: LoFTR's mean of K0[0,0], K1[1,1],
// K0[0,0], K1[1,1], or glue-factory's mean of all four); cv::findEssentialMat(method,
// prob = confidence, maxIters) on the normalised points with K = I (USAC_PROSAC on the
// matches sorted by decreasing confidence, stable);
// cv::recoverPose(E_k, ..., I, distanceThresh 50, mask) on each 3x3 block E_k of E, the
// same mask passed on from block to block (OpenCV updates it in place, as LoFTR's Python
// loop does), the block with most inliers wins; fewer than `min_matches` matches, no E, or
// no block with an inlier -> no pose (pose error +inf). recoverPose is RecoverPose below:
// the same numbers, computed only where they count.
// Randomness: every findEssentialMat method of OpenCV 4.6 seeds its own generator on each
// call (RANSAC and LMEDS a cv::RNG(-1), USAC its fixed generator state), so the answer is
// a function of the inputs and their order; in addition cv::theRNG() of the calling thread
// is set to the caller's `rng_seed` before the call, so that nothing can depend on what
// ran before on that thread (tests/eval/pose_test.cc checks both).
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

// The distanceThresh of recoverPose in LoFTR's loop as it runs. Its Python line,
// `cv2.recoverPose(_E, kpts0, kpts1, np.eye(3), 1e9, mask=mask)`, reads as 1e9, but
// OpenCV's binding takes the overload without distanceThresh (the 1e9 lands in its R
// output; it returns 4 values, not 5), so OpenCV's default of 50 applies: a point
// triangulated farther than 50 baselines is no inlier. SuperGlue, EfficientLoFTR and
// glue-factory's OpenCV estimator make the same call.
inline constexpr double kLoftrRecoverPoseDistance = 50.0;

// The robust method of cv::findEssentialMat (OpenCV 4.6's flags).
enum class PoseMethod {
  kRansac,        // "ransac": cv::RANSAC (LoFTR, SuperGlue, glue-factory's "opencv")
  kLmeds,         // "lmeds": cv::LMEDS (least median; the threshold is not used)
  kUsacDefault,   // "usac_default": LO-RANSAC, MSAC score (closest to PoseLib's LO-RANSAC)
  kUsacAccurate,  // "usac_accurate": GC-RANSAC local optimisation, SPRT
  kUsacMagsac,    // "usac_magsac": MAGSAC++ (the threshold is the largest noise scale)
  kUsacProsac,    // "usac_prosac": PROSAC sampling; needs match confidences
};
PoseMethod ParsePoseMethod(const std::string& text, const std::string& field);  // InputError
const char* PoseMethodName(PoseMethod m);
int PoseMethodOpenCVFlag(PoseMethod m);  // cv::RANSAC, cv::LMEDS, cv::USAC_*

// The focal length that turns the pixel threshold into a normalised one.
enum class FocalMean {
  kLoftr,  // "loftr": mean(K0[0,0], K1[1,1], K0[0,0], K1[1,1]) (LoFTR, SuperGlue)
  kAll,    // "all": mean(K0[0,0], K0[1,1], K1[0,0], K1[1,1]) (glue-factory's OpenCV estimator)
};
FocalMean ParseFocalMean(const std::string& text, const std::string& field);
const char* FocalMeanName(FocalMean f);

// The essential-matrix estimator and its settings; recorded with every result.
struct PoseEstimatorOptions {
  PoseMethod method = PoseMethod::kRansac;
  double ransac_px = 0.5;       // inlier threshold in pixels (LoFTR 0.5, SuperGlue 1)
  double confidence = 0.99999;  // in (0, 1)
  int max_iters = 1000;         // iteration cap (OpenCV's default); >= 1
  int min_matches = 5;          // fewer matches -> no pose (error +inf); >= 5
  FocalMean focal_mean = FocalMean::kLoftr;
  bool Check(std::string* error) const;
};
// "opencv-<method> <px> px conf <c>" (+ " iters N" unless 1000, + " focal all" for kAll),
// e.g. "opencv-ransac 0.5 px conf 0.99999": the label of an estimator in eval.json, the
// summary and the report.
std::string PoseEstimatorName(const PoseEstimatorOptions& e);
// The seed occgt gives cv::theRNG() before estimating pair `key` with estimator number
// `estimator` (see above): FNV-1a 64 of the key's bytes, then of the estimator number's
// 8 little-endian bytes; 0 (which cv::RNG would replace) becomes 1.
uint64_t PairRngSeed(const std::string& key, uint64_t estimator);

struct PoseEstimate {
  Eigen::Matrix3d cam1_from_cam0_R;  // rotation of the winning block
  Eigen::Vector3d cam1_from_cam0_t;  // unit translation direction
  int inliers = 0;                   // recoverPose's count for the winning block
};

// kpts0, kpts1: row-major [N, 2] pixels (x, y) at the resolution of K0, K1. `confidence`
// ([N] or nullptr) orders the matches for kUsacProsac, which needs it (a bug otherwise).
// Deterministic (see above); thread-safe.
std::optional<PoseEstimate> EstimateRelativePose(
    const std::vector<float>& kpts0, const std::vector<float>& kpts1, const Eigen::Matrix3d& K0,
    const Eigen::Matrix3d& K1, const PoseEstimatorOptions& options,
    const std::vector<float>* confidence = nullptr, uint64_t rng_seed = 1);

// EstimateRelativePose for each of `estimators` on one pair (rng_seeds: one per estimator),
// with the same answers; cheaper: the points are normalised once, and every kRansac
// setting shares one run of FindEssentialRansac.
std::vector<std::optional<PoseEstimate>> EstimateRelativePoses(
    const std::vector<float>& kpts0, const std::vector<float>& kpts1, const Eigen::Matrix3d& K0,
    const Eigen::Matrix3d& K1, const std::vector<PoseEstimatorOptions>& estimators,
    const std::vector<float>* confidence, const std::vector<uint64_t>& rng_seeds);

// cv::findEssentialMat(p0, p1, I, cv::RANSAC, confidence, threshold, max_iters, mask) of
// OpenCV 4.6 on normalised points p0, p1 (row-major [N, 2]) for several settings at once,
// with the same E and mask for each, bit for bit. OpenCV's RANSAC seeds a fresh
// cv::RNG(~0) on every call, so every setting draws the same five-point samples in the
// same order and differs only in which solutions it keeps and when it stops: here each
// sample is drawn once, solved once (OpenCV's own five-point kernel: findEssentialMat on
// exactly five points returns all its solutions), the error of each solution (OpenCV's
// Sampson-like float error, the same operations in the same order) computed once, and
// each setting counts its inliers, keeps its best and updates its own iteration count by
// RANSACUpdateNumIters' rule, until every setting has stopped. N <= 5: findEssentialMat
// per setting. Checked against cv::findEssentialMat in tests/eval/pose_test.cc.
struct RansacSetting {
  double threshold = 0;      // normalised units (pixels / focal)
  double confidence = 0.99;  // in (0, 1)
  int max_iters = 1000;
};
struct EssentialEstimate {
  std::vector<double> E;      // row-major 3x3 blocks, 9 per block; empty: no E
  std::vector<uint8_t> mask;  // [N] 0/1 inliers of the winning E (empty when no E)
};
std::vector<EssentialEstimate> FindEssentialRansac(const std::vector<double>& p0,
                                                   const std::vector<double>& p1,
                                                   const std::vector<RansacSetting>& settings);

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
// only the rotation is scored: occgt's rule, not LoFTR's (its relative_pose_error is called
// with ignore_gt_t_thr 0.0, so its |t_gt| < thr test never fires and 0/0 gives a NaN
// error; protocol.cc records this difference); a zero t gives 90.
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

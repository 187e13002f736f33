// Predicted matches scored against occgt's pixel labels and depth (docs/EVAL.md
// "Per-type precision and recall"; GROUND_TRUTH.md §2, §4).
//
// Inputs are one shard sample's arrays: label01, label10 (uint8 [H, W], codes of §2),
// depth0, depth1 (float32 [H, W] planar metres), K0, K1 at W x H, cam1_from_cam0, and the
// coarse ground-truth matches (matches int32 [M, 2] cells, match_type uint8 [M]).
// A predicted match (p0, p1) has source pixels q0 = round(p0), q1 = round(p1) and labels
// l0 = label01[q0], l1 = label10[q1]. Two hypotheses:
//   0 -> 1 (when l0 is VISIBLE or OCCLUDED): target x1 = K1 (cam1_from_cam0
//          (depth0[q0] K0^-1 [p0, 1])) / z, error e01 = |p1 - x1| in image 1;
//   1 -> 0 (when l1 is OCCLUDED, a point of image 1 hidden in image 0): target x0 from p1
//          and depth1[q1] with cam0_from_cam1, error e10 = |p0 - x0| in image 0.
// Class: vv (l0 VISIBLE) or vo (l0 OCCLUDED) when 0 -> 1 applies and e01 <= px or 1 -> 0
// does not also hold; else ov when 1 -> 0 applies; else unscored, counted by l0 (NO_DEPTH,
// OUT_OF_VIEW, INCONSISTENT, UNKNOWN): there is no target to compare with.
// (An ov ground-truth match lands in image 0 on the occluder, whose own label is usually
// VISIBLE: testing 0 -> 1 alone would call it a wrong vv match.)
// The keypoint's own sub-pixel position is unprojected with the depth of its nearest
// pixel, so a ground-truth match (anchor pixel, match_xy) has error ~0.
// Correct: the error of its class <= px. Recall of type t: a ground-truth match of type t
// is recalled when some predicted match satisfies that type's hypothesis within px (0 -> 1
// with l0 VISIBLE for vv, OCCLUDED for vo; 1 -> 0 for ov) with its source keypoint
// (image 0 for vv and vo, image 1 for ov) in the match's source cell (cell0, resp. cell1;
// cells hold pixels s*c .. s*c+s-1, row-major on the floor(W/s) x floor(H/s) grid).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace gt::eval {

struct QualityOptions {
  double px = 8.0;  // a match is correct when its keypoint is within px of the target
  bool Check(std::string* error) const;
};

// Views of one sample's ground truth (arrays owned by the caller).
struct PairTruthView {
  int width = 0, height = 0;  // working resolution
  int patch_stride = 8;
  const uint8_t* label01 = nullptr;  // [H, W]
  const uint8_t* label10 = nullptr;  // [H, W]
  const float* depth0 = nullptr;     // [H, W]
  const float* depth1 = nullptr;     // [H, W]
  Eigen::Matrix3d K0, K1;
  Eigen::Matrix3d cam1_from_cam0_R;
  Eigen::Vector3d cam1_from_cam0_t;
  const int32_t* matches = nullptr;     // [M, 2] (cell in image 0, cell in image 1)
  const uint8_t* match_type = nullptr;  // [M] 0 vv, 1 vo, 2 ov
  int64_t num_matches = 0;
};

enum MatchClass : int { kClassVV = 0, kClassVO = 1, kClassOV = 2, kClassUnscored = 3 };

struct TypeCounts {
  int64_t predicted = 0;  // predicted matches of this class
  int64_t correct = 0;    // ... within px of the target
  int64_t truth = 0;      // ground-truth matches of this type
  int64_t recalled = 0;   // ... recalled (see above)
};

struct PairQuality {
  std::array<TypeCounts, 3> types;             // vv, vo, ov
  std::array<int64_t, 6> unscored_by_label{};  // unscored matches by l0's code
  int64_t unscored = 0;
};

// The verdict on one predicted match: its class and whether it lies within px of the
// target of its class (always false for kClassUnscored).
struct MatchVerdict {
  uint8_t match_class = kClassUnscored;  // MatchClass
  bool correct = false;
};

// kpts0, kpts1: [N, 2] pixels at the working resolution (inside the pixel area).
// verdicts (optional): resized to N, one verdict per predicted match in input order.
PairQuality ScoreMatches(const PairTruthView& truth, const std::vector<float>& kpts0,
                         const std::vector<float>& kpts1, const QualityOptions& options,
                         std::vector<MatchVerdict>* verdicts = nullptr);

}  // namespace gt::eval

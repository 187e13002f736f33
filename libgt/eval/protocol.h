// Named evaluation protocols: one name expands to the exact relative-pose settings of a
// paper's evaluation code (estimators, thresholds, confidence, iteration cap, how the
// threshold is normalised, how a figure is selected from a threshold sweep, what a failed
// pair counts as, at which resolution the keypoints are meant to be), so that one flag
// reproduces a table. The facts, with the files they come from and where occgt's setting
// differs (PoseLib is not in Debian; OpenCV's USAC is the closest), are in docs/EVAL.md
// "Estimators and protocols"; this header only encodes them.
#pragma once

#include <string>
#include <vector>

#include "libgt/eval/pose.h"

namespace gt::eval {

enum class ProtocolName {
  kLoftr,        // "loftr": LoFTR's test (OpenCV RANSAC 0.5 px, 0.99999); occgt's default
  kSuperglue,    // "superglue": SuperGlue's match_pairs.py (OpenCV RANSAC 1 px, 0.99999)
  kGluefactory,  // "gluefactory": glue-factory's RelativePosePipeline (two estimators x
                 // 0.5, 1.5, 2, 3 px, best by mean AUC)
  kEloftr,       // "eloftr": EfficientLoFTR's test, POSE_ESTIMATION_METHOD RANSAC
  kEloftrLo,     // "eloftr-lo": EfficientLoFTR's LO-RANSAC (PoseLib) at 2 px
  kCustom,       // "custom": the estimator flags as given (no paper)
};
ProtocolName ParseProtocolName(const std::string& text, const std::string& field);
const char* ProtocolNameText(ProtocolName p);

// How the reported pose figure of a prediction set is chosen.
enum class Selection {
  kEvery,       // "every": every estimator reported, none chosen
  kBestOfSweep  // "best-of-sweep": per estimator group (settings equal but the threshold)
                // the threshold with the best mean AUC (ties: the first listed), then the
                // group with the best mean AUC (ties: the last group), as glue-factory's
                // eval_poses and run_eval choose. Optimistic: chosen on the test pairs.
};
const char* SelectionName(Selection s);

struct Protocol {
  ProtocolName name = ProtocolName::kLoftr;
  std::vector<PoseEstimatorOptions> estimators;  // in order: group by group, thresholds inside
  Selection selection = Selection::kEvery;
  double failure_error_deg = 180;  // a failed pair's error inside means (AUC: never recalled)
  std::string resolution_rule;     // where the keypoints' pixels are meant to be
  std::string failure_rule;        // what the paper's code does with a failed pair
  std::string differences;         // where occgt's expansion differs from the paper's code
  std::string sources;             // repo:path of the code the settings come from
};

// The settings of a named protocol (not kCustom).
Protocol ExpandProtocol(ProtocolName name);

// glue-factory's threshold sweep (RelativePosePipeline, ransac_th -1), pixels.
const std::vector<double>& GluefactorySweepPx();

}  // namespace gt::eval

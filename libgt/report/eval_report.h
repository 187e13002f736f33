// The evaluation section of the split report (`occgt inspect split DIR --eval eval.json`,
// docs/EVAL.md "The report"): one or more eval.json files of `occgt eval` on that split
// (schemas/eval.schema.json), their prediction sets side by side.
//
// Checks: every file is an eval.json ("kind": "occgt-eval", version 2, or 1 read with its
// old key names, eval::UpgradeEvalJson) of this split (the same sample keys in the same
// order as DIR/pairs.jsonl), and all files agree on the AUC thresholds, the occlusion and
// consistent_overlap bins and the first occlusion definition
// (else the columns would not compare); set names repeated across files are shown as
// "<file stem>:<name>". Any other problem is an InputError naming the file and field.
//
// Content:
//  - a pose table: per set and estimator, AUC at each threshold, failures, missing pairs,
//    matches per pair, epipolar precision;
//  - a per-type table: precision and recall of vv, vo, ov (counts), unscored matches;
//  - plots (gnuplot, one line per set, first estimator): eval_cumulative.png (mean pose
//    error of the pairs with occlusion ratio <= x, the Occ²Net paper's curve, and their
//    number), eval_auc_by_occlusion.png and eval_auc_by_overlap.png (AUC at the middle
//    threshold per bin);
//  - a gallery per set of its worst pairs: largest pose error first (failures first, ties
//    by lower epipolar precision, then split order; pairs without a prediction are counted,
//    not shown), the predicted matches drawn over the ground-truth labels
//    (RenderPredictedMatches, at most 1300 pixels wide) with each match's verdict from
//    eval::ScoreSampleMatches. The predictions are read again from the set's "path" (as
//    written, else relative to the eval.json's folder), with the eval's min_confidence; a
//    set whose file is gone gets a warning line instead of its gallery.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libgt/report/page.h"
#include "libgt/report/split_report.h"

namespace gt::report {

struct EvalSetView {
  std::string label;       // set name, or "<file stem>:<name>" when names repeat
  std::string eval_path;   // the eval.json it comes from
  nlohmann::json set;      // its entry of "sets"
  nlohmann::json options;  // the file's "options"
  bool has_quality = false;
  std::string quality_reason;        // match_quality.reason when not available
  std::vector<double> error_deg;     // per pair (split order), first estimator; +inf = failure
  std::vector<double> epipolar;      // per pair, epipolar precision (0..1)
  std::vector<bool> predicted;       // per pair
  std::vector<nlohmann::json> pair;  // per pair, its entry of pairs[].sets
  std::vector<double> occlusion;     // per pair, its ratio under the first definition
};

// The two estimators of a set whose per-pair disagreement the report plots: with a
// best-of-sweep selection of two or more groups, the chosen thresholds of the first two
// groups; else the first estimator and the first one of another method (else the second).
// nullopt with a single estimator.
std::optional<std::pair<size_t, size_t>> DisagreementEstimators(const EvalSetView& set);

struct EvalReportData {
  std::vector<EvalSetView> sets;  // files in the given order, sets in file order
  std::vector<double> auc_thresholds_deg;
  std::vector<std::string> estimator_names;  // of the first file
  std::string occlusion_definition;          // the first of the first file
  std::vector<double> occlusion_bins, consistent_overlap_bins;
};

// Reads and checks the eval.json files against the split (see above).
EvalReportData LoadEvalReport(const std::vector<std::string>& eval_paths, const SplitData& split);

// Runs gnuplot once; the three plots in the order listed above.
std::vector<NamedImage> MakeEvalPlots(const EvalReportData& data, const SplitReportOptions& options,
                                      const std::string& scratch_dir);

// Indices into the split's pairs of a set's worst pairs (see above), at most `count`.
std::vector<size_t> PickWorstPairs(const EvalSetView& set, int count);

struct EvalGallery {
  std::string set_label;
  std::vector<std::string> warnings;  // e.g. the predictions file is gone
  std::vector<GalleryItem> items;
};
std::vector<EvalGallery> MakeEvalGalleries(const EvalReportData& data, const SplitData& split,
                                           const SplitReportOptions& options);

// The <h2>Evaluation</h2> section.
std::string RenderEvalSection(const EvalReportData& data, const std::vector<NamedImage>& plots,
                              const std::vector<EvalGallery>& galleries);

}  // namespace gt::report

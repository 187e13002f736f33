// `occgt eval`: a matcher's predictions on a split scored against occgt's ground truth
// (docs/EVAL.md; GROUND_TRUTH.md §7). Composes the pieces of this folder:
//  - relative pose by each estimator setting (pose.h), AUC at the thresholds;
//  - epipolar precision (symmetric epipolar distance < threshold, normalised points);
//  - per-type precision and recall against the shards' labels and depth (match_quality.h);
//  - all of it per occlusion-ratio bin (each definition asked for), per consistent_overlap bin,
//    and the cumulative curve over the occlusion ratio (mean/median pose error, pairs).
// Split input: DIR/index.json (shards), DIR/pairs.jsonl (keys), DIR/recipe.json
// ("resolution"), and per sample its json (K0, K1, T_0to1, metrics), label01/label10,
// depth0/depth1, matches, match_type members (per-type scores need labels and depth; a
// split without them gets "match_quality": {"available": false, "reason": ...} and null
// per-type figures).
// Work: shards are read in parallel (TBB) and each sample is scored as it streams by; then
// every (pair, prediction set, estimator group) pose is estimated in parallel (the kRansac
// settings of a pair share one RANSAC run, pose.h FindEssentialRansac). Results are
// stored by index and summed in pair order: the output is the same at any thread count.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "libgt/eval/match_quality.h"
#include "libgt/eval/pose.h"
#include "libgt/eval/predictions.h"
#include "libgt/eval/protocol.h"
#include "libgt/geometry/aggregate.h"
#include "libgt/io/npy.h"

namespace gt::eval {

// How a pair's occlusion ratio is read from its sample metrics (both directions combined
// with EvalOptions::aggregate).
enum class OcclusionDefinition {
  kImage,    // "image": OCCLUDED / (W*H), the paper's (metrics occlusion_ratio)
  kVisible,  // "visible": OCCLUDED / (VISIBLE + OCCLUDED), the released training code's
  kValid,    // "valid": OCCLUDED / valid-depth pixels, the released test code's
};
OcclusionDefinition ParseOcclusionDefinition(const std::string& text, const std::string& field);
const char* OcclusionDefinitionName(OcclusionDefinition d);

// The finest cumulative curve: 1000 points over the occlusion ratio (a finer step only
// grows eval.json; 1e-9 asked for 10^9 points and ran out of memory).
inline constexpr double kMinCurveStep = 0.001;

struct EvalOptions {
  std::vector<PoseEstimatorOptions> estimators{PoseEstimatorOptions{}};  // >= 1
  // The protocol the estimators came from (recorded; kCustom: set by hand) and how a
  // set's pose figure is chosen among them (protocol.h).
  ProtocolName protocol = ProtocolName::kLoftr;
  Selection selection = Selection::kEvery;
  std::vector<double> auc_thresholds_deg{5, 10, 20};  // increasing, in (0, 180]
  double epipolar_threshold = 5e-4;  // symmetric epipolar distance (LoFTR ScanNet; 1e-4 MegaDepth)
  QualityOptions quality;            // px for per-type precision/recall
  std::vector<OcclusionDefinition> occlusion_definitions{OcclusionDefinition::kImage,
                                                         OcclusionDefinition::kVisible};
  std::vector<double> occlusion_bins{0, 0.05, 0.1, 0.15, 0.2, 0.3, 1.0};    // edges, increasing
  std::vector<double> consistent_overlap_bins{0, 0.2, 0.4, 0.6, 0.8, 1.0};  // consistent_overlap
  Aggregate aggregate = Aggregate::kMean;  // both directions of a metric -> the pair's value
  double curve_step =
      0.05;  // cumulative curve sampled at step, 2*step, ... (ratio), >= kMinCurveStep
  double failure_error_deg = 180;  // a failed pair's error inside means (medians use +inf)
  // Matches under this confidence were dropped before scoring (FilterByConfidence, by the
  // caller); recorded in eval.json so that its readers (the report) drop the same.
  double min_confidence = 0;
  bool Check(std::string* error) const;
};

// What the evaluation needs of a split before reading any shard.
struct SplitIndex {
  std::string dir, name;
  std::vector<std::string> shard_urls;  // index.json order
  std::vector<int64_t> shard_nsamples;  // index.json's count of each shard
  std::vector<std::string> keys;        // pairs.jsonl order
  int width = 0, height = 0;            // recipe.json "resolution"
  // Other names of every pair of pairs.jsonl -> its sample key: the LoFTR pair name
  // (predictions.h LoftrPairName, with the scene's LoFTR folder, shards::LoftrSceneFolders)
  // and the name of occgt's torch datasets (predictions.h DatasetPairName).
  std::map<std::string, std::string> pair_names;
};
// Throws InputError naming the file and field.
SplitIndex LoadSplitIndex(const std::string& dir);

struct SetPairResult {
  bool predicted = false;  // false: missing from the set (a failure)
  int64_t matches = 0;
  std::vector<PoseError> pose;    // one per estimator
  std::vector<int> inliers;       // one per estimator (0 without pose)
  double epipolar_precision = 0;  // share of matches under the threshold (0 without matches)
  PairQuality quality;
  double occluded_share = 0;  // (vo + ov) / matches: Occ²Net's test-time statistic; NaN
                              // without matches (null in eval.json)
};

struct PairInfo {
  std::string key, scene;
  std::vector<double> occlusion;    // one per EvalOptions::occlusion_definitions
  double consistent_overlap = 0;    // consistent_overlap, aggregated
  double overlap = 0;               // overlap, aggregated
  std::vector<SetPairResult> sets;  // one per prediction set
};

struct EvalResult {
  SplitIndex split;
  EvalOptions options;
  std::vector<std::string> set_names, set_paths, set_layouts;
  std::vector<PairInfo> pairs;  // the split's order
  bool has_quality = false;     // labels and depth in every sample
  std::string quality_missing_reason;
};

// The ground truth of one sample for ScoreMatches: `meta` is its json (patch_options.stride),
// `arrays` its label01/label10/depth0/depth1/matches/match_type members at width x height
// (referenced, not copied; K and pose are left to the caller). Returns "" when usable, else
// why not ("<key> has no <member> member ..."). Throws InputError("<tar>:<key>.<member>")
// on a wrong shape or dtype.
std::string SampleTruthArrays(const nlohmann::json& meta,
                              const std::map<std::string, io::NpyArray>& arrays, int width,
                              int height, const std::string& tar, const std::string& key,
                              PairTruthView* truth);

// One prediction scored on sample `key` of shard `tar` (split resolution width x height),
// with a verdict per match (the report's gallery of worst pairs). Throws InputError when
// the sample lacks the ground truth (labels, depth, matches) or is malformed.
PairQuality ScoreSampleMatches(const std::string& tar, const std::string& key, int width,
                               int height, const PairPrediction& prediction,
                               const QualityOptions& options, std::vector<MatchVerdict>* verdicts);

// Best-of-sweep selection (protocol.h Selection::kBestOfSweep) of one set over all pairs:
// estimators grouped by equal settings but the threshold, in order of first appearance.
struct SweepSelection {
  std::vector<double> mean_auc_percent;     // per estimator: mean of its overall AUCs
  std::vector<std::vector<size_t>> groups;  // estimator indices per group
  std::vector<size_t> group_best;           // per group: the chosen estimator
  size_t best = 0;                          // the chosen estimator
};
SweepSelection SelectBestOfSweep(const EvalResult& result, size_t set);

// Scores every prediction set on the split. Throws InputError on a broken shard or sample,
// and when a set lacks the confidences a usac_prosac estimator needs.
EvalResult Evaluate(const SplitIndex& split, const std::vector<PredictionSet>& sets,
                    const EvalOptions& options);

// eval.json (schemas/eval.schema.json): sorted keys, deterministic; "version" is
// kEvalJsonVersion.
constexpr int kEvalJsonVersion = 2;
std::string EvalJson(const EvalResult& result);
// An eval.json document read by a tool (the report) brought to the current version, in
// place: version 1 named the pair metric consistent_overlap (VISIBLE / sampled pixels)
// otherwise: "options.overlap_bins" (now consistent_overlap_bins), "sets[].by_visible_overlap"
// (by_consistent_overlap) and "pairs[].visible_overlap" (consistent_overlap); those keys are
// renamed and "version" set to kEvalJsonVersion. A current document is left as it is.
// Returns false, the document untouched, when it is not an object or its "version" is
// neither (missing keys are left to the reader, which names them).
bool UpgradeEvalJson(nlohmann::json* doc);
// The one-screen summary printed by `occgt eval`.
std::string EvalSummary(const EvalResult& result);

}  // namespace gt::eval

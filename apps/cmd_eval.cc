// occgt eval SPLIT_DIR --predictions P [--predictions Q ...] --out eval.json: scores a
// matcher's predictions against the split's ground truth (docs/EVAL.md): relative pose AUC
// (LoFTR's protocol by default; other estimators, threshold sweeps and named protocols), epipolar
// precision, per-type precision and recall, all stratified by occlusion ratio and
// consistent_overlap.
// Prints a one-screen summary; writes eval.json (schemas/eval.schema.json) atomically.
#include <strings.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/job_flags.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/eval/evaluate.h"
#include "libgt/eval/pose.h"
#include "libgt/eval/protocol.h"
#include "libgt/geometry/aggregate.h"
#include "libgt/io/atomic_file.h"

namespace occgt {
namespace {

// Decimal numbers only: [+-]digits[.digits][e[+-]digits]. std::stod alone also takes a
// leading space, hexadecimal ("0x10" is 16), "inf" and "nan".
bool IsDecimalNumber(const std::string& item) {
  size_t i = item.empty() || (item[0] != '+' && item[0] != '-') ? 0 : 1;
  auto digits = [&] {
    const size_t from = i;
    while (i < item.size() && item[i] >= '0' && item[i] <= '9') ++i;
    return i - from;
  };
  size_t mantissa = digits();
  if (i < item.size() && item[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < item.size() && (item[i] == 'e' || item[i] == 'E')) {
    ++i;
    if (i < item.size() && (item[i] == '+' || item[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == item.size();
}

std::vector<double> ParseList(const std::string& text, const std::string& flag) {
  std::vector<double> out;
  for (const std::string& item : SplitList(text, flag, "numbers")) {
    size_t used = 0;
    double v = 0;
    try {
      if (IsDecimalNumber(item)) v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || !std::isfinite(v)) {
      throw gt::InputError(flag, "expected comma-separated numbers, got '" + text + "'");
    }
    for (const double earlier : out) {
      if (earlier == v) throw gt::InputError(flag, "'" + item + "' given twice in '" + text + "'");
    }
    out.push_back(v);
  }
  return out;
}

// "5,10,20": a list flag's text form of its default.
std::string JoinNumbers(const std::vector<double>& values) {
  std::ostringstream out;
  for (size_t i = 0; i < values.size(); ++i) out << (i ? "," : "") << values[i];
  return out.str();
}
std::string JoinOcclusionNames(const std::vector<gt::eval::OcclusionDefinition>& values) {
  std::string out;
  for (const auto d : values)
    out += (out.empty() ? "" : ",") + std::string(gt::eval::OcclusionDefinitionName(d));
  return out;
}

struct Args {
  std::string split_dir, out;
  std::vector<std::string> predictions;
  // Every flag's default is EvalOptions' own (LoFTR's protocol), here in the flag's form.
  gt::eval::EvalOptions options;
  std::string protocol;
  std::string estimator = gt::eval::PoseMethodName(options.estimators[0].method);
  std::string ransac_px = JoinNumbers({options.estimators[0].ransac_px});
  double ransac_conf = options.estimators[0].confidence;
  int ransac_iters = options.estimators[0].max_iters;
  std::string focal_mean = gt::eval::FocalMeanName(options.estimators[0].focal_mean);
  std::string auc = JoinNumbers(options.auc_thresholds_deg);
  std::string occlusion = JoinOcclusionNames(options.occlusion_definitions);
  std::string occlusion_bins, consistent_overlap_bins;  // "" = EvalOptions' own
  std::string aggregate = gt::AggregateName(options.aggregate);
  int threads = 0;
  // Estimator and failure flags given on the command line (they conflict with --protocol).
  std::vector<std::string> estimator_flags;
  // Every flag given on the command line: a bad option value is a usage error (exit 2)
  // naming its flag only when that flag was given (apps/usage.h ThrowOptionsError).
  std::set<std::string> given;
};

// The estimator settings: a named protocol's, or --estimator x --ransac-px (each method
// at each threshold, method-major) with --ransac-conf, --ransac-iters, --focal-mean.
void SetEstimators(const Args& args, gt::eval::EvalOptions* options) {
  if (!args.protocol.empty()) {
    if (!args.estimator_flags.empty()) {
      throw gt::InputError("--protocol", args.protocol +
                                             " fixes the estimators and the failure rule; drop " +
                                             args.estimator_flags[0]);
    }
    const gt::eval::Protocol p =
        gt::eval::ExpandProtocol(gt::eval::ParseProtocolName(args.protocol, "--protocol"));
    options->protocol = p.name;
    options->estimators = p.estimators;
    options->selection = p.selection;
    options->failure_error_deg = p.failure_error_deg;
    return;
  }
  std::vector<double> thresholds;
  if (args.ransac_px == "sweep") {
    thresholds = gt::eval::GluefactorySweepPx();
    options->selection = gt::eval::Selection::kBestOfSweep;
  } else {
    thresholds = ParseList(args.ransac_px, "--ransac-px");
  }
  options->estimators.clear();
  for (const std::string& m : SplitList(args.estimator, "--estimator", "methods")) {
    for (const double px : thresholds) {
      gt::eval::PoseEstimatorOptions e;
      e.method = gt::eval::ParsePoseMethod(m, "--estimator");
      e.ransac_px = px;
      e.confidence = args.ransac_conf;
      e.max_iters = args.ransac_iters;
      e.focal_mean = gt::eval::ParseFocalMean(args.focal_mean, "--focal-mean");
      options->estimators.push_back(e);
    }
  }
  if (options->estimators.empty()) throw gt::InputError("--estimator", "expected a method");
  // LoFTR's protocol exactly (the defaults: its estimator and its failure error) is recorded
  // as such; any other estimator setting or --failure-error makes it a custom one.
  const gt::eval::Protocol loftr_protocol =
      gt::eval::ExpandProtocol(gt::eval::ProtocolName::kLoftr);
  const auto same = [](const gt::eval::PoseEstimatorOptions& a,
                       const gt::eval::PoseEstimatorOptions& b) {
    return a.method == b.method && a.ransac_px == b.ransac_px && a.confidence == b.confidence &&
           a.max_iters == b.max_iters && a.min_matches == b.min_matches &&
           a.focal_mean == b.focal_mean;
  };
  const bool loftr = options->estimators.size() == 1 && loftr_protocol.estimators.size() == 1 &&
                     same(options->estimators[0], loftr_protocol.estimators[0]) &&
                     options->selection == loftr_protocol.selection &&
                     options->failure_error_deg == loftr_protocol.failure_error_deg;
  options->protocol = loftr ? gt::eval::ProtocolName::kLoftr : gt::eval::ProtocolName::kCustom;
}

// --out must take a new file, and not one this run reads (the predictions, the split's
// index, pair list, recipe or shards): checked before any work.
void CheckOut(const Args& args, const gt::eval::SplitIndex& split,
              const std::vector<std::string>& prediction_paths) {
  std::error_code ec;
  if (!std::filesystem::exists(args.out, ec)) return;
  std::vector<std::string> inputs = prediction_paths;
  for (const char* f : {"index.json", "pairs.jsonl", "recipe.json"}) {
    inputs.push_back(split.dir + "/" + f);
  }
  for (const std::string& url : split.shard_urls) inputs.push_back(split.dir + "/" + url);
  for (const std::string& input : inputs) {
    if (std::filesystem::equivalent(args.out, input, ec)) {
      throw gt::InputError("--out", "'" + args.out + "' is " + input +
                                        ", an input of this run: expected another file");
    }
  }
}

void Run(const Args& args) {
  if (const std::string problem = gt::io::OutputFileProblem(args.out); !problem.empty()) {
    throw gt::InputError("--out", "'" + args.out + "' " + problem);
  }
  gt::eval::EvalOptions options = args.options;
  SetEstimators(args, &options);
  options.auc_thresholds_deg = ParseList(args.auc, "--auc");
  if (!args.occlusion_bins.empty()) {
    options.occlusion_bins = ParseList(args.occlusion_bins, "--occlusion-bins");
  }
  // --overlap-bins: the earlier spelling of --consistent-overlap-bins, named as given.
  const char* const consistent_overlap_flag =
      args.given.count("--overlap-bins") ? "--overlap-bins" : "--consistent-overlap-bins";
  if (!args.consistent_overlap_bins.empty()) {
    options.consistent_overlap_bins =
        ParseList(args.consistent_overlap_bins, consistent_overlap_flag);
  }
  options.occlusion_definitions.clear();
  for (const std::string& d : SplitList(args.occlusion, "--occlusion", "definitions")) {
    options.occlusion_definitions.push_back(gt::eval::ParseOcclusionDefinition(d, "--occlusion"));
  }
  options.aggregate = gt::ParseAggregate(args.aggregate, "--aggregate");
  std::string error;
  if (!options.Check(&error)) {
    // The option's field name -> the flag that set it: a usage error naming that flag when
    // it was given (exit 2), else bad input of the command (exit 1).
    const auto flag = [&args](const char* field, const char* name) {
      return FieldFlag{field, name, args.given.count(name) > 0};
    };
    ThrowOptionsError(
        error, "occgt eval",
        {flag("estimators", "--estimator"), flag("ransac_px", "--ransac-px"),
         flag("confidence", "--ransac-conf"), flag("max_iters", "--ransac-iters"),
         flag("auc_thresholds_deg", "--auc"), flag("epipolar_threshold", "--epipolar-threshold"),
         flag("px", "--px"), flag("occlusion_definitions", "--occlusion"),
         flag("occlusion_bins", "--occlusion-bins"),
         flag("consistent_overlap_bins", consistent_overlap_flag),
         flag("curve_step", "--curve-step"), flag("failure_error_deg", "--failure-error"),
         flag("min_confidence", "--min-confidence")});
  }
  const std::unique_ptr<tbb::global_control> limit = LimitThreads(args.threads);
  const gt::eval::SplitIndex split = gt::eval::LoadSplitIndex(args.split_dir);
  const std::set<std::string> keys(split.keys.begin(), split.keys.end());
  std::vector<std::string> set_names, prediction_paths;
  std::set<std::string> names;
  for (const std::string& arg : args.predictions) {
    // NAME=PATH names the set; else its file or folder name without ".npz".
    std::string name, path = arg;
    const size_t eq = arg.find('=');
    if (eq != std::string::npos && arg.find('/') > eq) {
      name = arg.substr(0, eq);
      path = arg.substr(eq + 1);
    } else {
      std::string base = arg;
      while (base.size() > 1 && base.back() == '/') base.pop_back();
      base = base.substr(base.rfind('/') == std::string::npos ? 0 : base.rfind('/') + 1);
      if (base.size() > 4 && strcasecmp(base.c_str() + base.size() - 4, ".npz") == 0) {
        base.resize(base.size() - 4);  // any case: "S.NPZ" names the set "S"
      }
      name = base;
    }
    if (path.empty()) {
      throw gt::InputError("--predictions", "'" + arg + "': expected [NAME=]PATH with a path");
    }
    const bool blank = name.find_first_not_of(" \t") == std::string::npos;
    const bool control = std::any_of(name.begin(), name.end(), [](char c) {
      return static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) == 0x7f;
    });
    if (blank || control) {
      throw gt::InputError("--predictions", "'" + arg + "': the set name '" + name + "' is " +
                                                (blank ? "blank" : "not printable") +
                                                " (use NAME=PATH)");
    }
    if (!names.insert(name).second) {
      throw gt::InputError("--predictions", "'" + arg + "': the set name '" + name +
                                                "' is given twice (use NAME=PATH to tell the "
                                                "sets apart)");
    }
    set_names.push_back(name);
    prediction_paths.push_back(path);
  }
  CheckOut(args, split, prediction_paths);
  std::vector<gt::eval::PredictionSet> sets;
  std::vector<std::string> problems;
  std::vector<std::string> problem_paths;  // per problem: the predictions path it came from
  for (size_t s = 0; s < set_names.size(); ++s) {
    const std::string& path = prediction_paths[s];
    sets.push_back(gt::eval::ReadPredictions(set_names[s], path, keys, split.width, split.height,
                                             &problems, split.pair_names));
    gt::eval::FilterByConfidence(options.min_confidence, &sets.back(), &problems);
    problem_paths.resize(problems.size(), path);
  }
  if (problems.size() == 1) {
    // The one line "<file>[:<member>]: <problem>" (docs/EVAL.md) as it is: split after the
    // file's path at the first ": " into where and what.
    const std::string& line = problems[0];
    const std::string& file = problem_paths[0];
    const size_t sep = line.find(": ", line.rfind(file, 0) == 0 ? file.size() : 0);
    if (sep == std::string::npos) throw gt::InputError(file, line);
    throw gt::InputError(line.substr(0, sep), line.substr(sep + 2));
  }
  if (!problems.empty()) {
    // The first 20, so that a wrong folder (thousands of files) stays readable.
    constexpr size_t kListed = 20;
    for (size_t k = 0; k < problems.size() && k < kListed; ++k) {
      std::fprintf(stderr, "occgt: error: %s\n", problems[k].c_str());
    }
    const std::string listed = problems.size() > kListed
                                   ? "the first " + std::to_string(kListed) + " listed above"
                                   : "listed above";
    throw gt::InputError("predictions", std::to_string(problems.size()) + " problems (" + listed +
                                            "); nothing written");
  }
  for (const gt::eval::PredictionSet& s : sets) {
    const size_t missing = keys.size() - s.pairs.size();
    if (missing == 0) continue;
    std::string first;
    for (const std::string& k : split.keys) {
      if (s.pairs.count(k) == 0) {
        first = k;
        break;
      }
    }
    std::fprintf(stderr,
                 "occgt: warning: %s: %zu of %zu pairs have no prediction (first: %s), counted "
                 "as failures (pose error inf, no matches); listed in eval.json\n",
                 s.path.c_str(), missing, keys.size(), first.c_str());
  }
  const gt::eval::EvalResult result = gt::eval::Evaluate(split, sets, options);
  gt::io::WriteFileAtomic(args.out, gt::eval::EvalJson(result));
  std::fputs(gt::eval::EvalSummary(result).c_str(), stdout);
  std::printf("wrote %s\n", args.out.c_str());
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("eval", "Score a matcher's predictions on a split (docs/EVAL.md)");
  cmd->add_option("split_dir", args->split_dir, "Split folder (index.json, pairs.jsonl, shards)")
      ->required();
  cmd->add_option("--predictions", args->predictions,
                  "[NAME=]PATH: a .npz, or a folder of <key>.npz, keyed by sample key (or "
                  "LoFTR pair name); repeat to compare sets")
      ->required()
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--out", args->out, "eval.json to write")->required();
  cmd->add_option("--protocol", args->protocol,
                  "A paper's settings: loftr (the default), superglue, gluefactory, eloftr, "
                  "eloftr-lo (docs/EVAL.md)");
  cmd->add_option("--estimator", args->estimator,
                  "Methods, each at every --ransac-px: ransac, lmeds, usac_default, "
                  "usac_accurate, usac_magsac, usac_prosac (needs confidence)")
      ->capture_default_str();
  cmd->add_option("--ransac-px", args->ransac_px,
                  "Thresholds in pixels, one estimator setting each (e.g. 0.5,1.0), or 'sweep' "
                  "(glue-factory's " +
                      JoinNumbers(gt::eval::GluefactorySweepPx()) + " and the best by mean AUC)")
      ->capture_default_str();
  cmd->add_option("--ransac-conf", args->ransac_conf, "RANSAC confidence")->capture_default_str();
  cmd->add_option("--ransac-iters", args->ransac_iters,
                  "Iteration cap of the robust estimator (OpenCV's default)")
      ->capture_default_str();
  cmd->add_option("--focal-mean", args->focal_mean,
                  "Pixel threshold / mean focal: loftr (K0 fx, K1 fy) or all (fx, fy "
                  "of both, glue-factory)")
      ->capture_default_str();
  cmd->add_option("--auc", args->auc, "AUC thresholds in degrees")->capture_default_str();
  cmd->add_option("--epipolar-threshold", args->options.epipolar_threshold,
                  "Symmetric epipolar distance threshold (MegaDepth 1e-4)")
      ->capture_default_str();
  cmd->add_option("--px", args->options.quality.px,
                  "Per-type precision/recall: correct within this many pixels")
      ->capture_default_str();
  cmd->add_option("--occlusion", args->occlusion,
                  "Occlusion-ratio definitions to stratify by: image,visible,valid")
      ->capture_default_str();
  cmd->add_option("--occlusion-bins", args->occlusion_bins, "Occlusion bin edges (comma list)");
  CLI::Option* const consistent_overlap_bins =
      cmd->add_option("--consistent-overlap-bins", args->consistent_overlap_bins,
                      "consistent_overlap (VISIBLE / sampled) bin edges (comma list)");
  cmd->add_option("--overlap-bins", args->consistent_overlap_bins,
                  "The earlier spelling of --consistent-overlap-bins")
      ->excludes(consistent_overlap_bins);
  cmd->add_option("--aggregate", args->aggregate, "Both directions -> pair value: min|mean|max")
      ->capture_default_str();
  cmd->add_option("--curve-step", args->options.curve_step,
                  "Cumulative curve step over the occlusion ratio")
      ->capture_default_str();
  cmd->add_option("--failure-error", args->options.failure_error_deg,
                  "Error (deg) of a failed pair inside means")
      ->capture_default_str();
  cmd->add_option("--min-confidence", args->options.min_confidence,
                  "Drop matches with confidence below this (needs 'confidence')");
  AddThreadsFlag(cmd, &args->threads, "Worker threads");
  cmd->callback([args, cmd] {
    args->given.clear();
    for (const CLI::Option* o : cmd->get_options()) {
      if (o->count() == 0) continue;
      for (const std::string& name : o->get_lnames()) args->given.insert("--" + name);
    }
    args->estimator_flags.clear();
    for (const char* flag : {"--estimator", "--ransac-px", "--ransac-conf", "--ransac-iters",
                             "--focal-mean", "--failure-error"}) {
      if (cmd->count(flag) > 0) args->estimator_flags.push_back(flag);
    }
    Run(*args);
  });
}

}  // namespace occgt

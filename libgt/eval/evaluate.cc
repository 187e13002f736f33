#include "libgt/eval/evaluate.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core/version.hpp>
#include <sstream>
#include <tuple>

#include "libgt/core/error.h"
#include "libgt/core/stats.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "libgt/shards/loftr_tree.h"
#include "libgt/shards/sample.h"
#include "libgt/shards/sample_check.h"
#include "libgt/shards/split.h"
#include "libgt/shards/tar_shard.h"

namespace gt::eval {

using nlohmann::json;

OcclusionDefinition ParseOcclusionDefinition(const std::string& text, const std::string& field) {
  if (text == "image") return OcclusionDefinition::kImage;
  if (text == "visible") return OcclusionDefinition::kVisible;
  if (text == "valid") return OcclusionDefinition::kValid;
  throw InputError(field, "expected image, visible or valid, got '" + text + "'");
}

const char* OcclusionDefinitionName(OcclusionDefinition d) {
  switch (d) {
    case OcclusionDefinition::kImage:
      return "image";
    case OcclusionDefinition::kVisible:
      return "visible";
    case OcclusionDefinition::kValid:
      return "valid";
  }
  return "?";
}

namespace {

bool CheckEdges(const std::vector<double>& edges, const char* name, std::string* error) {
  if (edges.size() < 2) {
    *error = std::string(name) + ": expected at least two bin edges";
    return false;
  }
  for (size_t i = 0; i < edges.size(); ++i) {
    if (!std::isfinite(edges[i]) || (i > 0 && !(edges[i] > edges[i - 1]))) {
      *error = std::string(name) + ": expected finite, strictly increasing bin edges";
      return false;
    }
  }
  return true;
}

}  // namespace

bool EvalOptions::Check(std::string* error) const {
  if (estimators.empty()) {
    *error = "estimators: expected at least one estimator setting";
    return false;
  }
  for (const PoseEstimatorOptions& e : estimators) {
    if (!e.Check(error)) return false;
  }
  if (auc_thresholds_deg.empty()) {
    *error = "auc_thresholds_deg: expected at least one threshold";
    return false;
  }
  for (size_t i = 0; i < auc_thresholds_deg.size(); ++i) {
    const double t = auc_thresholds_deg[i];
    if (!(t > 0 && t <= 180) || (i > 0 && !(t > auc_thresholds_deg[i - 1]))) {
      *error =
          "auc_thresholds_deg: expected increasing thresholds in (0, 180] (degrees; a pose "
          "error is at most 180)";
      return false;
    }
  }
  if (!(epipolar_threshold > 0) || !std::isfinite(epipolar_threshold)) {
    *error = "epipolar_threshold: expected a finite number > 0";
    return false;
  }
  if (!quality.Check(error)) return false;
  if (occlusion_definitions.empty()) {
    *error = "occlusion_definitions: expected at least one of image, visible, valid";
    return false;
  }
  for (size_t i = 0; i < occlusion_definitions.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (occlusion_definitions[i] == occlusion_definitions[j]) {
        *error = std::string(
                     "occlusion_definitions: expected each of image, visible, valid at "
                     "most once, got ") +
                 OcclusionDefinitionName(occlusion_definitions[i]) + " twice";
        return false;
      }
    }
  }
  if (!CheckEdges(occlusion_bins, "occlusion_bins", error)) return false;
  if (!CheckEdges(consistent_overlap_bins, "consistent_overlap_bins", error)) return false;
  if (!(curve_step >= kMinCurveStep && curve_step <= 1)) {
    *error = "curve_step: expected a number in [" + std::to_string(kMinCurveStep).substr(0, 5) +
             ", 1] (at most " + std::to_string(static_cast<int>(1 / kMinCurveStep)) +
             " curve points)";
    return false;
  }
  if (!(min_confidence >= 0) || !std::isfinite(min_confidence)) {
    *error = "min_confidence: expected a finite number >= 0";
    return false;
  }
  if (!(failure_error_deg >= 0 && failure_error_deg <= 180)) {
    *error = "failure_error_deg: expected a number in [0, 180]";
    return false;
  }
  return true;
}

SplitIndex LoadSplitIndex(const std::string& dir) {
  SplitIndex split;
  split.dir = dir;
  const shards::ShardIndex index = shards::ReadShardIndex(dir);
  split.name = index.name;
  int64_t indexed = 0;
  for (const shards::IndexedShard& s : index.shards) {
    split.shard_urls.push_back(s.url);
    split.shard_nsamples.push_back(s.nsamples);
    indexed += s.nsamples;
  }
  const std::string pairs_path = dir + "/pairs.jsonl";
  std::istringstream lines(io::ReadFileBytes(pairs_path));
  std::string line;
  std::set<std::string> seen;
  // (scene, number0, number1) of every key, for the LoFTR pair names.
  std::vector<std::tuple<std::string, int64_t, int64_t>> frames;
  std::vector<std::string> dataset_names;  // DatasetPairName of every key
  std::set<std::string> scenes;
  for (int n = 1; std::getline(lines, line); ++n) {
    if (line.empty()) continue;
    json j;
    try {
      j = json::parse(line);
    } catch (const json::exception&) {
      throw InputError(pairs_path + ":" + std::to_string(n), "not valid JSON");
    }
    if (!j.is_object() || !j.contains("key") || !j["key"].is_string()) {
      throw InputError(pairs_path + ":" + std::to_string(n), "expected a string 'key'");
    }
    const std::string key = j["key"].get<std::string>();
    if (!seen.insert(key).second) {
      throw InputError(pairs_path + ":" + std::to_string(n), "key " + key + " repeats");
    }
    split.keys.push_back(key);
    const json& f0 = j.contains("frame0") ? j["frame0"] : json();
    const json& f1 = j.contains("frame1") ? j["frame1"] : json();
    if (!j.contains("scene") || !j["scene"].is_string() || !f0.is_object() || !f1.is_object() ||
        !f0.contains("number") || !f0["number"].is_number_integer() || !f1.contains("number") ||
        !f1["number"].is_number_integer()) {
      throw InputError(pairs_path + ":" + std::to_string(n),
                       "expected 'scene' and 'frame0'/'frame1' with an integer 'number'");
    }
    frames.emplace_back(j["scene"].get<std::string>(), f0["number"].get<int64_t>(),
                        f1["number"].get<int64_t>());
    if (f0.contains("id") && f0["id"].is_string() && f1.contains("id") && f1["id"].is_string()) {
      dataset_names.push_back(DatasetPairName(
          j["scene"].get<std::string>(), f0["id"].get<std::string>(), f1["id"].get<std::string>()));
    } else {
      dataset_names.emplace_back();
    }
    scenes.insert(std::get<0>(frames.back()));
  }
  // The split itself first: a pairs.jsonl without a sample's line would otherwise be
  // reported as predictions of pairs that are not in the split.
  if (static_cast<int64_t>(split.keys.size()) != indexed) {
    throw InputError(pairs_path, std::to_string(split.keys.size()) + " sample lines, " +
                                     index.path + " counts " + std::to_string(indexed) +
                                     " samples: expected one line per sample");
  }
  std::map<std::string, std::string> folders;
  try {
    folders = shards::LoftrSceneFolders(scenes);
  } catch (const InputError&) {
    frames.clear();  // two scenes share a LoFTR folder: sample keys only
  }
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto& [scene, n0, n1] = frames[i];
    split.pair_names[LoftrPairName(folders.at(scene), n0, n1)] = split.keys[i];
  }
  for (size_t i = 0; i < dataset_names.size(); ++i) {
    if (!dataset_names[i].empty()) split.pair_names[dataset_names[i]] = split.keys[i];
  }
  const std::string recipe_path = dir + "/recipe.json";
  json recipe;
  try {
    recipe = json::parse(io::ReadFileBytes(recipe_path));
  } catch (const json::exception& e) {
    throw InputError(recipe_path, std::string("not valid JSON: ") + e.what());
  }
  const json& res = recipe.contains("resolution") ? recipe["resolution"] : json();
  if (!res.is_array() || res.size() != 2 || !res[0].is_number_integer() ||
      !res[1].is_number_integer() || res[0].get<int>() < 1 || res[1].get<int>() < 1) {
    throw InputError(recipe_path + ":resolution", "expected the working resolution [W, H]");
  }
  split.width = res[0].get<int>();
  split.height = res[1].get<int>();
  return split;
}

namespace {

// The fields of one sample that the evaluation reads.
struct SampleData {
  std::string key;
  std::string json_text;
  std::map<std::string, io::NpyArray> arrays;  // label01, label10, depth0, depth1, matches, ...
};

bool IsWantedField(const std::string& field) {
  return field == "json" || field == "label01.npy" || field == "label10.npy" ||
         field == "depth0.npy" || field == "depth1.npy" || field == "matches.npy" ||
         field == "match_type.npy";
}

Eigen::Matrix3d Mat3(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw InputError(where, "expected a 3x3 matrix");
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    if (!j[r].is_array() || j[r].size() != 3) throw InputError(where, "expected a 3x3 matrix");
    for (int c = 0; c < 3; ++c) m(r, c) = j[r][c].get<double>();
  }
  return m;
}

// Per pair geometry kept for the pose stage.
struct PairGeometry {
  Eigen::Matrix3d K0, K1, R;
  Eigen::Vector3d t;
};

double DirectionOcclusion(const json& m, OcclusionDefinition d) {
  switch (d) {
    case OcclusionDefinition::kImage:
      return m.at("occlusion_ratio").get<double>();
    case OcclusionDefinition::kVisible:
      return m.at("occlusion_ratio_visible").get<double>();
    case OcclusionDefinition::kValid: {
      const double valid = m.at("valid").get<double>();
      return valid > 0 ? m.at("counts").at("OCCLUDED").get<double>() / valid : 0.0;
    }
  }
  return 0;
}

}  // namespace

std::string SampleTruthArrays(const json& meta, const std::map<std::string, io::NpyArray>& arrays,
                              int width, int height, const std::string& tar, const std::string& key,
                              PairTruthView* truth) {
  const std::string where = tar + ":" + key;
  truth->width = width;
  truth->height = height;
  try {
    truth->patch_stride = meta.at("patch_options").at("stride").get<int>();
  } catch (const json::exception&) {
    throw InputError(where + ".json", "expected \"patch_options\": {\"stride\": ...}");
  }
  auto find = [&](const char* field) -> const io::NpyArray* {
    auto it = arrays.find(field);
    return it == arrays.end() ? nullptr : &it->second;
  };
  const std::vector<int64_t> image_shape{height, width};
  for (const char* f : {"label01.npy", "label10.npy", "depth0.npy", "depth1.npy"}) {
    const io::NpyArray* a = find(f);
    if (a == nullptr) {
      const std::string key = where.substr(where.find(':') + 1);
      return key + " has no " + f + " member (build with sample.labels and sample.depth)";
    }
    if (a->shape != image_shape) throw InputError(where + "." + f, "expected [H, W]");
  }
  const io::NpyArray* matches = find("matches.npy");
  const io::NpyArray* types = find("match_type.npy");
  if (matches == nullptr || types == nullptr) {
    return key + " has no matches.npy / match_type.npy member";
  }
  truth->label01 = find("label01.npy")->As<uint8_t>(where + ".label01.npy");
  truth->label10 = find("label10.npy")->As<uint8_t>(where + ".label10.npy");
  truth->depth0 = find("depth0.npy")->As<float>(where + ".depth0.npy");
  truth->depth1 = find("depth1.npy")->As<float>(where + ".depth1.npy");
  if (matches->shape.size() != 2 || matches->shape[1] != 2 || types->shape.size() != 1 ||
      types->shape[0] != matches->shape[0]) {
    throw InputError(where + ".matches.npy", "expected [M, 2] with match_type [M]");
  }
  truth->matches = matches->As<int32_t>(where + ".matches.npy");
  truth->match_type = types->As<uint8_t>(where + ".match_type.npy");
  truth->num_matches = matches->shape[0];
  // The members' values against the json and each other (label codes and counts, depth
  // against NO_DEPTH, match rules; shards/sample_check.h, the rules of occgt validate): a
  // damaged sample would otherwise score silently wrong.
  const std::vector<std::string> problems = shards::CheckPairSampleValues(meta, arrays);
  if (!problems.empty()) {
    const std::string& p = problems.front();
    const size_t colon = p.find(": ");
    throw InputError(where + "." + p.substr(0, colon), p.substr(colon + 2));
  }
  return "";
}

namespace {

// Scores one sample for every set; fills info and geometry. Returns "" when labels and
// depth were usable, else why per-type scores are not available for it.
std::string ProcessSample(const std::string& tar, const SampleData& s, const SplitIndex& split,
                          const std::vector<PredictionSet>& sets, const EvalOptions& options,
                          PairInfo* info, PairGeometry* geometry) {
  const std::string where = tar + ":" + s.key + ".json";
  if (s.json_text.empty()) throw InputError(tar + ":" + s.key, "no json member");
  json j;
  try {
    j = json::parse(s.json_text);
  } catch (const json::exception&) {
    throw InputError(where, "not valid JSON");
  }
  try {
    geometry->K0 = Mat3(j.at("K0"), where + ":K0");
    geometry->K1 = Mat3(j.at("K1"), where + ":K1");
    const json& T = j.at("T_0to1");
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) geometry->R(r, c) = T.at(r).at(c).get<double>();
      geometry->t(r) = T.at(r).at(3).get<double>();
    }
    const json& res = j.at("resolution");
    if (res.at(0).get<int>() != split.width || res.at(1).get<int>() != split.height) {
      throw InputError(where + ":resolution", "differs from the split's recipe.json resolution");
    }
    info->scene = j.at("scene").get<std::string>();
    const json& m01 = j.at("metrics").at("01");
    const json& m10 = j.at("metrics").at("10");
    for (const OcclusionDefinition d : options.occlusion_definitions) {
      info->occlusion.push_back(
          Combine(DirectionOcclusion(m01, d), DirectionOcclusion(m10, d), options.aggregate));
    }
    info->consistent_overlap =
        Combine(m01.at("consistent_overlap").get<double>(),
                m10.at("consistent_overlap").get<double>(), options.aggregate);
    info->overlap = Combine(m01.at("overlap").get<double>(), m10.at("overlap").get<double>(),
                            options.aggregate);
  } catch (const json::exception& e) {
    throw InputError(where, std::string("unexpected sample metadata: ") + e.what());
  }
  // Per-type ground truth, when the sample has it.
  PairTruthView truth;
  truth.K0 = geometry->K0;
  truth.K1 = geometry->K1;
  truth.cam1_from_cam0_R = geometry->R;
  truth.cam1_from_cam0_t = geometry->t;
  const std::string missing =
      SampleTruthArrays(j, s.arrays, split.width, split.height, tar, s.key, &truth);
  info->sets.resize(sets.size());
  for (size_t k = 0; k < sets.size(); ++k) {
    SetPairResult& r = info->sets[k];
    r.pose.assign(options.estimators.size(), NoPoseError());
    r.inliers.assign(options.estimators.size(), 0);
    auto it = sets[k].pairs.find(s.key);
    if (it == sets[k].pairs.end()) continue;
    const PairPrediction& p = it->second;
    r.predicted = true;
    r.matches = p.size();
    if (r.matches > 0) {
      const std::vector<double> d = SymmetricEpipolarDistances(
          p.kpts0, p.kpts1, geometry->K0, geometry->K1, geometry->R, geometry->t);
      int64_t under = 0;
      for (const double x : d) under += x < options.epipolar_threshold ? 1 : 0;
      r.epipolar_precision = static_cast<double>(under) / static_cast<double>(d.size());
    }
    if (missing.empty()) {
      r.quality = ScoreMatches(truth, p.kpts0, p.kpts1, options.quality);
      r.occluded_share = r.matches > 0 ? static_cast<double>(r.quality.types[kClassVO].predicted +
                                                             r.quality.types[kClassOV].predicted) /
                                             static_cast<double>(r.matches)
                                       : std::nan("");  // 0 / 0: null in eval.json
    } else {
      r.quality = PairQuality();
    }
    // Ground-truth counts are the same for a missing prediction; they are filled below.
  }
  if (missing.empty()) {
    // Ground-truth match counts for sets without a prediction of this pair (recall's
    // denominator counts every pair of the split).
    PairQuality empty = ScoreMatches(truth, {}, {}, options.quality);
    for (size_t k = 0; k < sets.size(); ++k) {
      if (!info->sets[k].predicted) info->sets[k].quality = empty;
    }
  }
  return missing;
}

}  // namespace

PairQuality ScoreSampleMatches(const std::string& tar, const std::string& key, int width,
                               int height, const PairPrediction& prediction,
                               const QualityOptions& options, std::vector<MatchVerdict>* verdicts) {
  const shards::Sample sample = shards::ReadShardSample(tar, key);
  std::map<std::string, io::NpyArray> arrays;
  json meta;
  for (const shards::SampleField& f : sample.fields) {
    if (f.name == "json") {
      try {
        meta = json::parse(f.bytes);
      } catch (const json::exception&) {
        throw InputError(tar + ":" + key + ".json", "not valid JSON");
      }
    } else if (IsWantedField(f.name)) {
      arrays[f.name] = io::ParseNpy(f.bytes, tar + ":" + key + "." + f.name);
    }
  }
  const std::string where = tar + ":" + key + ".json";
  PairTruthView truth;
  try {
    truth.K0 = Mat3(meta.at("K0"), where + ":K0");
    truth.K1 = Mat3(meta.at("K1"), where + ":K1");
    const json& T = meta.at("T_0to1");
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) truth.cam1_from_cam0_R(r, c) = T.at(r).at(c).get<double>();
      truth.cam1_from_cam0_t(r) = T.at(r).at(3).get<double>();
    }
  } catch (const json::exception& e) {
    throw InputError(where, std::string("unexpected sample metadata: ") + e.what());
  }
  const std::string missing = SampleTruthArrays(meta, arrays, width, height, tar, key, &truth);
  if (!missing.empty()) throw InputError(tar, missing);
  return ScoreMatches(truth, prediction.kpts0, prediction.kpts1, options, verdicts);
}

EvalResult Evaluate(const SplitIndex& split, const std::vector<PredictionSet>& sets,
                    const EvalOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("eval options", error);
  EvalResult result;
  result.split = split;
  result.options = options;
  for (const PredictionSet& s : sets) {
    result.set_names.push_back(s.name);
    result.set_paths.push_back(s.path);
    result.set_layouts.push_back(s.layout);
  }
  std::map<std::string, size_t> index_of;
  for (size_t i = 0; i < split.keys.size(); ++i) index_of[split.keys[i]] = i;
  const size_t n = split.keys.size();
  result.pairs.resize(n);
  std::vector<PairGeometry> geometry(n);
  std::vector<std::atomic<int>> seen(n);
  std::vector<std::string> missing_reason(n);
  // Stage 1: shards in parallel, each sample scored as it streams by. Errors are kept per
  // shard and the first in shard order is thrown, whatever the thread count.
  const size_t nshards = split.shard_urls.size();
  std::vector<std::string> shard_error(nshards);
  tbb::parallel_for(size_t{0}, nshards, size_t{1}, [&](size_t sh) {
    const std::string tar = split.dir + "/" + split.shard_urls[sh];
    try {
      int64_t samples = 0;
      SampleData current;
      auto flush = [&] {
        if (current.key.empty()) return;
        auto it = index_of.find(current.key);
        if (it == index_of.end()) {
          throw InputError(tar, "sample " + current.key + " is not in pairs.jsonl");
        }
        const size_t i = it->second;
        if (seen[i]++ != 0) throw InputError(tar, "sample " + current.key + " repeats");
        ++samples;
        result.pairs[i].key = current.key;
        missing_reason[i] =
            ProcessSample(tar, current, split, sets, options, &result.pairs[i], &geometry[i]);
        current = SampleData();
      };
      shards::ForEachTarMember(tar, [&](const shards::TarMemberInfo& m, std::string_view data) {
        if (!m.regular_file) return;
        std::string key, field;
        if (!shards::SplitMemberPath(m.path, &key, &field)) return;
        const size_t slash = key.rfind('/');
        if (key.compare(slash == std::string::npos ? 0 : slash + 1, 2, "__") == 0) {
          return;  // not a sample (WebDataset's "__" names)
        }
        if (key != current.key) flush();
        current.key = key;
        // A compressed member is inflated only when its field is wanted.
        if (!IsWantedField(std::string(shards::PlainFieldName(field)))) return;
        const std::string bytes = shards::DecodeMember(&field, data, tar + ":" + m.path);
        if (field == "json") {
          current.json_text = bytes;
        } else {
          current.arrays[field] = io::ParseNpy(bytes, tar + ":" + m.path);
        }
      });
      flush();
      if (samples != split.shard_nsamples[sh]) {
        throw InputError(tar, "holds " + std::to_string(samples) + " samples, index.json says " +
                                  std::to_string(split.shard_nsamples[sh]));
      }
    } catch (const InputError& e) {
      shard_error[sh] = e.what();
    }
  });
  for (const std::string& e : shard_error) {
    if (!e.empty()) throw InputError("eval", e);
  }
  for (size_t i = 0; i < n; ++i) {
    if (seen[i] == 0) {
      throw InputError(split.dir + "/pairs.jsonl", "pair " + split.keys[i] + " is in no shard");
    }
  }
  result.has_quality = true;
  for (size_t i = 0; i < n; ++i) {
    if (!missing_reason[i].empty()) {
      result.has_quality = false;
      result.quality_missing_reason = missing_reason[i];
      break;
    }
  }
  // Stage 2: every (pair, set, estimator group) pose in parallel, results by index.
  const size_t nsets = sets.size(), nest = options.estimators.size();
  std::vector<const PairPrediction*> prediction(n * nsets, nullptr);
  for (size_t i = 0; i < n; ++i) {
    for (size_t k = 0; k < nsets; ++k) {
      auto it = sets[k].pairs.find(split.keys[i]);
      if (it != sets[k].pairs.end()) prediction[i * nsets + k] = &it->second;
    }
  }
  bool prosac = false;
  for (const PoseEstimatorOptions& e : options.estimators) {
    prosac = prosac || e.method == PoseMethod::kUsacProsac;
  }
  for (size_t k = 0; prosac && k < nsets; ++k) {
    for (size_t i = 0; i < n; ++i) {
      const PairPrediction* p = prediction[i * nsets + k];
      if (p != nullptr && !p->has_confidence) {
        throw InputError(sets[k].path, "usac_prosac orders matches by confidence, but pair " +
                                           split.keys[i] + " has no 'confidence'");
      }
    }
  }
  // Estimators in groups: every kRansac setting in one (EstimateRelativePoses shares one
  // RANSAC run between them, with each one's own answer), each other setting alone.
  std::vector<std::vector<size_t>> groups;
  std::vector<size_t> ransac;
  for (size_t e = 0; e < nest; ++e) {
    if (options.estimators[e].method == PoseMethod::kRansac) {
      ransac.push_back(e);
    } else {
      groups.push_back({e});
    }
  }
  if (!ransac.empty()) groups.insert(groups.begin(), ransac);
  const size_t ngroups = groups.size();
  // Each estimator seeds cv::theRNG() with PairRngSeed(key, estimator) (pose.h): the same
  // numbers whichever thread runs it, and after whatever ran before.
  tbb::parallel_for(size_t{0}, n * nsets * ngroups, size_t{1}, [&](size_t task) {
    const size_t gi = task % ngroups, k = (task / ngroups) % nsets, i = task / (ngroups * nsets);
    const PairPrediction* p = prediction[i * nsets + k];
    if (p == nullptr) return;
    const PairGeometry& g = geometry[i];
    std::vector<PoseEstimatorOptions> group_options;
    std::vector<uint64_t> seeds;
    for (const size_t e : groups[gi]) {
      group_options.push_back(options.estimators[e]);
      seeds.push_back(PairRngSeed(split.keys[i], e));
    }
    const std::vector<std::optional<PoseEstimate>> poses =
        EstimateRelativePoses(p->kpts0, p->kpts1, g.K0, g.K1, group_options,
                              p->has_confidence ? &p->confidence : nullptr, seeds);
    SetPairResult& r = result.pairs[i].sets[k];
    for (size_t j = 0; j < groups[gi].size(); ++j) {
      const size_t e = groups[gi][j];
      if (poses[j]) {
        r.pose[e] =
            RelativePoseError(g.R, g.t, poses[j]->cam1_from_cam0_R, poses[j]->cam1_from_cam0_t);
        r.inliers[e] = poses[j]->inliers;
      }
    }
  });
  return result;
}

namespace {

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return SortedMedian(v);
}

// The pose errors of estimator e over `pairs` (a non-finite error is a failure) and their
// summary as every table of eval.json gives it: the mean with each failure counted as
// failure_error_deg, the median (null when undefined) and the number of failures.
struct PoseErrors {
  std::vector<double> errors;
  json mean, median;
  int64_t failures = 0;
};
PoseErrors SummarisePoseErrors(const EvalResult& r, size_t set, size_t e,
                               const std::vector<size_t>& pairs) {
  PoseErrors out;
  double sum = 0;
  for (const size_t i : pairs) {
    const double err = r.pairs[i].sets[set].pose[e].max_deg;
    out.errors.push_back(err);
    if (std::isfinite(err)) {
      sum += err;
    } else {
      ++out.failures;
      sum += r.options.failure_error_deg;
    }
  }
  out.mean = pairs.empty() ? json(nullptr) : json(sum / pairs.size());
  out.median = Number(Median(out.errors));
  return out;
}

const char* const kTypeNames[] = {"vv", "vo", "ov"};
const char* const kLabelNames[] = {"NO_DEPTH", "OUT_OF_VIEW",  "VISIBLE",
                                   "OCCLUDED", "INCONSISTENT", "UNKNOWN"};

// Statistics of one set over a subset of pairs.
json Stats(const EvalResult& r, size_t set, const std::vector<size_t>& pairs) {
  const EvalOptions& o = r.options;
  json out;
  out["pairs"] = pairs.size();
  json pose = json::array();
  for (size_t e = 0; e < o.estimators.size(); ++e) {
    const PoseErrors pe = SummarisePoseErrors(r, set, e, pairs);
    json p;
    json auc = json::array();
    for (const double a : PoseAuc(pe.errors, o.auc_thresholds_deg)) {
      auc.push_back(pairs.empty() ? json(nullptr) : json(a * 100.0));  // no pair, no AUC
    }
    p["auc_percent"] = auc;
    p["failures"] = pe.failures;
    p["mean_error_deg"] = pe.mean;
    p["median_error_deg"] = pe.median;
    pose.push_back(p);
  }
  out["pose"] = pose;
  double prec = 0, matches = 0;
  for (const size_t i : pairs) {
    prec += r.pairs[i].sets[set].epipolar_precision;
    matches += static_cast<double>(r.pairs[i].sets[set].matches);
  }
  out["epipolar_precision_percent"] =
      pairs.empty() ? json(nullptr) : json(100.0 * prec / pairs.size());
  out["matches_mean"] = pairs.empty() ? json(nullptr) : json(matches / pairs.size());
  if (!r.has_quality) {
    out["types"] = nullptr;
    return out;
  }
  json types;
  int64_t scored = 0, correct = 0, all = 0;
  for (int t = 0; t < 3; ++t) {
    TypeCounts c;
    for (const size_t i : pairs) {
      const TypeCounts& x = r.pairs[i].sets[set].quality.types[t];
      c.predicted += x.predicted;
      c.correct += x.correct;
      c.truth += x.truth;
      c.recalled += x.recalled;
    }
    scored += c.predicted;
    correct += c.correct;
    types[kTypeNames[t]] = {
        {"predicted", c.predicted},
        {"correct", c.correct},
        {"precision_percent", c.predicted ? json(100.0 * c.correct / c.predicted) : json(nullptr)},
        {"truth", c.truth},
        {"recalled", c.recalled},
        {"recall_percent", c.truth ? json(100.0 * c.recalled / c.truth) : json(nullptr)}};
  }
  json by_label;
  int64_t unscored = 0;
  for (int l = 0; l < 6; ++l) {
    int64_t k = 0;
    for (const size_t i : pairs) k += r.pairs[i].sets[set].quality.unscored_by_label[l];
    if (l != 2 && l != 3) by_label[kLabelNames[l]] = k;
    unscored += k;
  }
  all = scored + unscored;
  types["unscored"] = {{"count", unscored}, {"by_label0", by_label}};
  types["all"] = {
      {"scored", scored},
      {"correct", correct},
      {"precision_scored_percent", scored ? json(100.0 * correct / scored) : json(nullptr)},
      {"precision_all_percent", all ? json(100.0 * correct / all) : json(nullptr)}};
  out["types"] = types;
  return out;
}

// Pairs whose value lies in [lo, hi) (the last bin: [lo, hi]).
json Binned(const EvalResult& r, size_t set, const std::vector<double>& edges,
            const std::function<double(const PairInfo&)>& value) {
  json bins = json::array();
  for (size_t b = 0; b + 1 < edges.size(); ++b) {
    const bool last = b + 2 == edges.size();
    std::vector<size_t> in;
    for (size_t i = 0; i < r.pairs.size(); ++i) {
      const double v = value(r.pairs[i]);
      if (v >= edges[b] && (v < edges[b + 1] || (last && v == edges[b + 1]))) in.push_back(i);
    }
    json s = Stats(r, set, in);
    s["lo"] = edges[b];
    s["hi"] = edges[b + 1];
    bins.push_back(s);
  }
  return bins;
}

json Cumulative(const EvalResult& r, size_t set, size_t def) {
  const EvalOptions& o = r.options;
  double top = 0;
  for (const PairInfo& p : r.pairs) top = std::max(top, p.occlusion[def]);
  json points = json::array();
  const int steps = std::max(1, static_cast<int>(std::ceil(top / o.curve_step - 1e-9)));
  for (int k = 1; k <= steps; ++k) {
    const double x = std::min(1.0, k * o.curve_step);
    std::vector<size_t> in;
    for (size_t i = 0; i < r.pairs.size(); ++i) {
      if (r.pairs[i].occlusion[def] <= x + 1e-12) in.push_back(i);
    }
    json pt;
    pt["max_occlusion"] = x;
    pt["pairs"] = in.size();
    json mean = json::array(), median = json::array(), failures = json::array();
    for (size_t e = 0; e < o.estimators.size(); ++e) {
      const PoseErrors pe = SummarisePoseErrors(r, set, e, in);
      mean.push_back(pe.mean);
      median.push_back(pe.median);
      failures.push_back(pe.failures);
    }
    pt["mean_error_deg"] = mean;
    pt["median_error_deg"] = median;
    pt["failures"] = failures;
    points.push_back(pt);
  }
  return points;
}

}  // namespace

SweepSelection SelectBestOfSweep(const EvalResult& r, size_t set) {
  const EvalOptions& o = r.options;
  SweepSelection out;
  std::vector<double> errors(r.pairs.size());
  for (size_t e = 0; e < o.estimators.size(); ++e) {
    for (size_t i = 0; i < r.pairs.size(); ++i) errors[i] = r.pairs[i].sets[set].pose[e].max_deg;
    const std::vector<double> auc = PoseAuc(errors, o.auc_thresholds_deg);
    double sum = 0;
    for (const double a : auc) sum += a;
    out.mean_auc_percent.push_back(100.0 * sum / static_cast<double>(auc.size()));
    // Its group: the first earlier estimator with the same settings but the threshold.
    const PoseEstimatorOptions& x = o.estimators[e];
    size_t g = 0;
    for (; g < out.groups.size(); ++g) {
      const PoseEstimatorOptions& y = o.estimators[out.groups[g][0]];
      if (x.method == y.method && x.confidence == y.confidence && x.max_iters == y.max_iters &&
          x.min_matches == y.min_matches && x.focal_mean == y.focal_mean) {
        break;
      }
    }
    if (g == out.groups.size()) out.groups.emplace_back();
    out.groups[g].push_back(e);
  }
  // glue-factory: max over a dict in threshold order (the first maximum), then the last
  // group reaching the maximum (its dict keyed by mean AUC keeps the last writer).
  double best_value = -1;
  for (const std::vector<size_t>& group : out.groups) {
    size_t b = group[0];
    for (const size_t e : group) {
      if (out.mean_auc_percent[e] > out.mean_auc_percent[b]) b = e;
    }
    out.group_best.push_back(b);
    if (out.mean_auc_percent[b] >= best_value) {
      best_value = out.mean_auc_percent[b];
      out.best = b;
    }
  }
  return out;
}

std::string EvalJson(const EvalResult& r) {
  const EvalOptions& o = r.options;
  json doc;
  doc["kind"] = "occgt-eval";
  doc["version"] = kEvalJsonVersion;
  doc["split"] = {{"dir", r.split.dir},
                  {"name", r.split.name},
                  {"pairs", r.pairs.size()},
                  {"resolution", {r.split.width, r.split.height}}};
  json estimators = json::array();
  for (const PoseEstimatorOptions& e : o.estimators) {
    const bool prosac = e.method == PoseMethod::kUsacProsac;
    estimators.push_back(
        {{"name", PoseEstimatorName(e)},
         {"estimator", PoseMethodName(e.method)},
         {"method", std::string("cv::findEssentialMat(") +
                        (e.method == PoseMethod::kRansac ? "RANSAC" : PoseMethodName(e.method)) +
                        ", prob, threshold, maxIters) on K-normalised points" +
                        (prosac ? " sorted by decreasing confidence" : "") +
                        ", cv::recoverPose (distanceThresh 50) per 3x3 block, most inliers"},
         {"opencv_version", CV_VERSION},
         {"ransac_px", e.ransac_px},
         {"confidence", e.confidence},
         {"max_iters", e.max_iters},
         {"focal_mean", FocalMeanName(e.focal_mean)},
         {"min_matches", e.min_matches}});
  }
  json protocol = {{"name", ProtocolNameText(o.protocol)}};
  if (o.protocol == ProtocolName::kCustom) {
    protocol["resolution_rule"] = nullptr;
    protocol["failure_rule"] = nullptr;
    protocol["differences"] = nullptr;
    protocol["sources"] = nullptr;
  } else {
    const Protocol p = ExpandProtocol(o.protocol);
    protocol["resolution_rule"] = p.resolution_rule;
    protocol["failure_rule"] = p.failure_rule;
    protocol["differences"] = p.differences;
    protocol["sources"] = p.sources;
  }
  json defs = json::array();
  for (const OcclusionDefinition d : o.occlusion_definitions)
    defs.push_back(OcclusionDefinitionName(d));
  doc["options"] = {{"estimators", estimators},
                    {"auc_thresholds_deg", o.auc_thresholds_deg},
                    {"epipolar_threshold", o.epipolar_threshold},
                    {"px", o.quality.px},
                    {"occlusion_definitions", defs},
                    {"occlusion_bins", o.occlusion_bins},
                    {"consistent_overlap_bins", o.consistent_overlap_bins},
                    {"aggregate", AggregateName(o.aggregate)},
                    {"curve_step", o.curve_step},
                    {"failure_error_deg", o.failure_error_deg},
                    {"min_confidence", o.min_confidence},
                    {"protocol", protocol},
                    {"selection", SelectionName(o.selection)},
                    {"opencv_version", CV_VERSION},
                    {"rng_seed",
                     "cv::theRNG() set per (pair, estimator) to FNV-1a 64 of the sample key "
                     "then of the estimator index (8 bytes, little-endian); OpenCV 4.6's "
                     "findEssentialMat methods also seed their own generators per call"}};
  doc["match_quality"] = r.has_quality
                             ? json({{"available", true}, {"reason", nullptr}})
                             : json({{"available", false}, {"reason", r.quality_missing_reason}});
  std::vector<size_t> all(r.pairs.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  json sets = json::array();
  for (size_t k = 0; k < r.set_names.size(); ++k) {
    json s;
    s["name"] = r.set_names[k];
    s["path"] = r.set_paths[k];
    s["layout"] = r.set_layouts[k];
    json missing = json::array();
    for (const PairInfo& p : r.pairs) {
      if (!p.sets[k].predicted) missing.push_back(p.key);
    }
    s["pairs_missing"] = missing.size();
    s["missing_keys"] = missing;
    s["overall"] = Stats(r, k, all);
    json by_occ;
    json cumulative;
    for (size_t d = 0; d < o.occlusion_definitions.size(); ++d) {
      const char* name = OcclusionDefinitionName(o.occlusion_definitions[d]);
      by_occ[name] =
          Binned(r, k, o.occlusion_bins, [d](const PairInfo& p) { return p.occlusion[d]; });
      cumulative[name] = Cumulative(r, k, d);
    }
    s["by_occlusion"] = by_occ;
    s["cumulative"] = cumulative;
    s["by_consistent_overlap"] = Binned(r, k, o.consistent_overlap_bins,
                                        [](const PairInfo& p) { return p.consistent_overlap; });
    if (o.selection == Selection::kBestOfSweep) {
      const SweepSelection sel = SelectBestOfSweep(r, k);
      json groups = json::array();
      for (size_t g = 0; g < sel.groups.size(); ++g) {
        groups.push_back({{"estimators", sel.groups[g]}, {"best", sel.group_best[g]}});
      }
      const json& best = s["overall"]["pose"][sel.best];
      s["selection"] = {
          {"rule", SelectionName(o.selection)},
          {"mean_auc_percent", sel.mean_auc_percent},
          {"groups", groups},
          {"best", sel.best},
          {"estimator", PoseEstimatorName(o.estimators[sel.best])},
          {"ransac_px", o.estimators[sel.best].ransac_px},
          {"auc_percent", best["auc_percent"]},
          {"optimistic", true},
          {"note",
           "the threshold and estimator were chosen on these pairs by their own mean AUC: an "
           "optimistic figure, not a held-out one"}};
    } else {
      s["selection"] = nullptr;
    }
    sets.push_back(s);
  }
  doc["sets"] = sets;
  json pairs = json::array();
  for (const PairInfo& p : r.pairs) {
    json j;
    j["key"] = p.key;
    j["scene"] = p.scene;
    json occ;
    for (size_t d = 0; d < o.occlusion_definitions.size(); ++d) {
      occ[OcclusionDefinitionName(o.occlusion_definitions[d])] = p.occlusion[d];
    }
    j["occlusion"] = occ;
    j["consistent_overlap"] = p.consistent_overlap;
    j["overlap"] = p.overlap;
    json per_set = json::array();
    for (const SetPairResult& s : p.sets) {
      json x;
      x["predicted"] = s.predicted;
      x["matches"] = s.matches;
      json pose = json::array();
      for (size_t e = 0; e < s.pose.size(); ++e) {
        pose.push_back({{"rotation_deg", Number(s.pose[e].rotation_deg)},
                        {"translation_deg", Number(s.pose[e].translation_deg)},
                        {"error_deg", Number(s.pose[e].max_deg)},
                        {"inliers", s.inliers[e]}});
      }
      x["pose"] = pose;
      x["epipolar_precision"] = s.epipolar_precision;
      if (r.has_quality) {
        json t;
        for (int c = 0; c < 3; ++c) {
          t[kTypeNames[c]] = {s.quality.types[c].predicted, s.quality.types[c].correct,
                              s.quality.types[c].truth, s.quality.types[c].recalled};
        }
        t["unscored"] = s.quality.unscored;
        x["types"] = t;
        x["occluded_share"] = Number(s.occluded_share);  // null without matches (0 / 0)
      } else {
        x["types"] = nullptr;
        x["occluded_share"] = nullptr;
      }
      per_set.push_back(x);
    }
    j["sets"] = per_set;
    pairs.push_back(j);
  }
  doc["pairs"] = pairs;
  return doc.dump(1) + "\n";
}

bool UpgradeEvalJson(json* doc) {
  if (!doc->is_object()) return false;
  const auto version = doc->find("version");
  if (version == doc->end() || !version->is_number_integer()) return false;
  if (version->get<int64_t>() == kEvalJsonVersion) return true;
  if (version->get<int64_t>() != 1) return false;
  // Version 1 -> 2: the pair metric consistent_overlap under its own name.
  const auto rename = [](json& object, const char* from, const char* to) {
    if (!object.is_object() || !object.contains(from) || object.contains(to)) return;
    object[to] = std::move(object[from]);
    object.erase(from);
  };
  const auto each = [](json* doc, const char* array, const auto& f) {
    const auto it = doc->find(array);
    if (it == doc->end() || !it->is_array()) return;
    for (json& x : *it) f(x);
  };
  if (doc->contains("options")) {
    rename((*doc)["options"], "overlap_bins", "consistent_overlap_bins");
  }
  each(doc, "sets", [&](json& s) { rename(s, "by_visible_overlap", "by_consistent_overlap"); });
  each(doc, "pairs", [&](json& p) { rename(p, "visible_overlap", "consistent_overlap"); });
  (*doc)["version"] = kEvalJsonVersion;
  return true;
}

std::string EvalSummary(const EvalResult& r) {
  const EvalOptions& o = r.options;
  std::ostringstream s;
  char buf[512];
  std::snprintf(buf, sizeof buf, "occgt eval: split %s (%zu pairs, %dx%d), %zu prediction set(s)\n",
                r.split.name.c_str(), r.pairs.size(), r.split.width, r.split.height,
                r.set_names.size());
  s << buf;
  std::vector<size_t> all(r.pairs.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  s << "protocol: " << ProtocolNameText(o.protocol) << " (" << o.estimators.size()
    << " estimator setting(s), selection " << SelectionName(o.selection) << ", OpenCV "
    << CV_VERSION << ")\n";
  if (o.protocol != ProtocolName::kCustom) {
    const Protocol p = ExpandProtocol(o.protocol);
    s << "  keypoints at: " << p.resolution_rule << "; failed pair: " << p.failure_rule
      << "; differs from the paper's code: " << p.differences << "\n";
  }
  s << "pose AUC (%) at";
  for (const double t : o.auc_thresholds_deg) s << " " << t;
  s << " deg; epipolar precision (%) at " << o.epipolar_threshold << "; per-type precision / "
    << "recall (%) at " << o.quality.px << " px\n";
  for (size_t k = 0; k < r.set_names.size(); ++k) {
    const json st = Stats(r, k, all);
    int64_t missing = 0;
    for (const PairInfo& p : r.pairs) missing += p.sets[k].predicted ? 0 : 1;
    std::snprintf(buf, sizeof buf, "%s: %lld missing pair(s), %.1f matches/pair, epipolar %.1f\n",
                  r.set_names[k].c_str(), static_cast<long long>(missing),
                  st["matches_mean"].is_null() ? 0.0 : st["matches_mean"].get<double>(),
                  st["epipolar_precision_percent"].is_null()
                      ? 0.0
                      : st["epipolar_precision_percent"].get<double>());
    s << buf;
    for (size_t e = 0; e < o.estimators.size(); ++e) {
      s << "  " << PoseEstimatorName(o.estimators[e]) << ": AUC";
      for (const json& a : st["pose"][e]["auc_percent"]) {
        if (a.is_null()) {
          s << " -";
          continue;
        }
        std::snprintf(buf, sizeof buf, " %.2f", a.get<double>());
        s << buf;
      }
      s << ", failures " << st["pose"][e]["failures"].get<int64_t>() << "\n";
    }
    if (o.selection == Selection::kBestOfSweep) {
      const SweepSelection sel = SelectBestOfSweep(r, k);
      s << "  best of sweep by mean AUC (optimistic: chosen on these pairs): "
        << PoseEstimatorName(o.estimators[sel.best]) << ": AUC";
      for (const json& a : st["pose"][sel.best]["auc_percent"]) {
        if (a.is_null()) {
          s << " -";
          continue;
        }
        std::snprintf(buf, sizeof buf, " %.2f", a.get<double>());
        s << buf;
      }
      s << "\n";
    }
    if (st["types"].is_null()) {
      s << "  per-type: not available (" << r.quality_missing_reason << ")\n";
    } else {
      s << "  per-type";
      for (const char* t : kTypeNames) {
        const json& x = st["types"][t];
        auto pct = [](const json& v) {
          char b[32];
          if (v.is_null()) return std::string("-");
          std::snprintf(b, sizeof b, "%.1f", v.get<double>());
          return std::string(b);
        };
        s << " " << t << " " << pct(x["precision_percent"]) << "/" << pct(x["recall_percent"])
          << " (" << x["predicted"].get<int64_t>() << ")";
      }
      s << ", unscored " << st["types"]["unscored"]["count"].get<int64_t>() << "\n";
    }
    // AUC at the middle threshold per occlusion bin, first definition, first estimator
    // (named: with several, it is not the best of a sweep); bins half-open but the last.
    const size_t mid = o.auc_thresholds_deg.size() / 2;
    s << "  AUC@" << o.auc_thresholds_deg[mid] << " by occlusion ("
      << OcclusionDefinitionName(o.occlusion_definitions[0])
      << (o.estimators.size() > 1 ? ", " + PoseEstimatorName(o.estimators[0]) : "") << "):";
    const json bins =
        Binned(r, k, o.occlusion_bins, [](const PairInfo& p) { return p.occlusion[0]; });
    for (size_t b = 0; b < bins.size(); ++b) {
      if (bins[b]["pairs"].get<size_t>() == 0) continue;
      std::snprintf(buf, sizeof buf, " [%.4g,%.4g%c %.1f (%zu)", bins[b]["lo"].get<double>(),
                    bins[b]["hi"].get<double>(), b + 1 == bins.size() ? ']' : ')',
                    bins[b]["pose"][0]["auc_percent"][mid].get<double>(),
                    bins[b]["pairs"].get<size_t>());
      s << buf;
    }
    s << "\n";
  }
  return s.str();
}

}  // namespace gt::eval

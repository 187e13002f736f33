#include "libgt/report/eval_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/eval/evaluate.h"
#include "libgt/eval/predictions.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/report/pair_source.h"

namespace gt::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxGalleryWidth = 1300;

std::vector<double> Doubles(const json& j) {
  std::vector<double> out;
  for (const json& x : j) out.push_back(x.get<double>());
  return out;
}

// "12.3" for a number, "-" for null.
std::string Cell(const json& v, int decimals = 1) {
  if (!v.is_number()) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v.get<double>());
  return buf;
}

std::string BinLabel(double lo, double hi, bool last) {
  return "[" + Num(lo, 3) + ", " + Num(hi, 3) + (last ? "]" : ")");
}

}  // namespace

EvalReportData LoadEvalReport(const std::vector<std::string>& eval_paths, const SplitData& split) {
  EvalReportData data;
  std::vector<std::string> split_keys;
  for (const SplitPair& p : split.pairs) split_keys.push_back(p.key);
  std::map<std::string, int> name_count;
  std::vector<EvalSetView> sets;
  for (size_t f = 0; f < eval_paths.size(); ++f) {
    const std::string& path = eval_paths[f];
    if (!gt::io::FileExists(path)) throw InputError(path, "missing: expected an eval.json");
    json doc;
    try {
      doc = json::parse(gt::io::ReadFileBytes(path));
    } catch (const json::exception&) {
      throw InputError(path, "not valid JSON: expected an eval.json of `occgt eval`");
    }
    std::string field = "kind";
    try {
      // Version 1 is read with its old key names (eval::UpgradeEvalJson).
      if (!doc.is_object() || doc.value("kind", "") != "occgt-eval" ||
          !gt::eval::UpgradeEvalJson(&doc)) {
        throw InputError(path,
                         "kind/version: expected an eval.json of `occgt eval` (\"kind\": "
                         "\"occgt-eval\", \"version\": 1 or 2)");
      }
      field = "pairs";
      const json& pairs = doc.at("pairs");
      std::vector<std::string> keys;
      for (const json& p : pairs) keys.push_back(p.at("key").get<std::string>());
      if (keys != split_keys) {
        throw InputError(path, "pairs: evaluated split '" + doc.at("split").value("dir", "") +
                                   "' (" + std::to_string(keys.size()) + " pairs), not " +
                                   split.dir + " (" + std::to_string(split_keys.size()) +
                                   " pairs, pairs.jsonl order)");
      }
      field = "options";
      const json& o = doc.at("options");
      const std::vector<double> thresholds = Doubles(o.at("auc_thresholds_deg"));
      const std::vector<double> occ_bins = Doubles(o.at("occlusion_bins"));
      const std::vector<double> ov_bins = Doubles(o.at("consistent_overlap_bins"));
      const std::string def = o.at("occlusion_definitions").at(0).get<std::string>();
      if (f == 0) {
        data.auc_thresholds_deg = thresholds;
        data.occlusion_bins = occ_bins;
        data.consistent_overlap_bins = ov_bins;
        data.occlusion_definition = def;
        for (const json& e : o.at("estimators")) {
          data.estimator_names.push_back(e.at("name").get<std::string>());
        }
      } else if (thresholds != data.auc_thresholds_deg || occ_bins != data.occlusion_bins ||
                 ov_bins != data.consistent_overlap_bins || def != data.occlusion_definition) {
        throw InputError(path,
                         "options: AUC thresholds, bins or first occlusion definition "
                         "differ from " +
                             eval_paths[0] +
                             "'s; evaluate with the same options to compare the sets");
      }
      field = "sets";
      const json& quality = doc.at("match_quality");
      for (size_t k = 0; k < doc.at("sets").size(); ++k) {
        EvalSetView v;
        v.set = doc["sets"][k];
        v.label = v.set.at("name").get<std::string>();
        v.eval_path = path;
        v.options = o;
        v.has_quality = quality.at("available").get<bool>();
        v.quality_reason =
            quality.at("reason").is_string() ? quality["reason"].get<std::string>() : "";
        // Every field the section reads, so that a malformed file fails here, named.
        const size_t estimators = o.at("estimators").size();
        const json& overall = v.set.at("overall");
        auto pose_fields = [&](const json& stats) {
          for (size_t e = 0; e < estimators; ++e) {
            const json& pose = stats.at("pose").at(e);
            if (pose.at("auc_percent").size() != thresholds.size()) {
              throw json::other_error::create(501, "auc_percent: one per threshold", &pose);
            }
            (void)pose.at("failures").get<int64_t>();
          }
          (void)stats.at("pairs").get<int64_t>();
        };
        pose_fields(overall);
        (void)overall.at("matches_mean");
        (void)overall.at("epipolar_precision_percent");
        (void)v.set.at("pairs_missing").get<int64_t>();
        (void)v.set.at("path").get<std::string>();
        const json& types = overall.at("types");
        if (!types.is_null()) {
          for (const char* t : {"vv", "vo", "ov"}) {
            for (const char* f : {"predicted", "correct", "truth", "recalled"}) {
              (void)types.at(t).at(f).get<int64_t>();
            }
            (void)types.at(t).at("precision_percent");
            (void)types.at(t).at("recall_percent");
          }
          (void)types.at("unscored").at("count").get<int64_t>();
          (void)types.at("all").at("precision_scored_percent");
        }
        for (const auto& [bins, edges] : {std::pair<const json*, const std::vector<double>*>{
                                              &v.set.at("by_occlusion").at(def), &occ_bins},
                                          {&v.set.at("by_consistent_overlap"), &ov_bins}}) {
          if (bins->size() + 1 != edges->size()) {
            throw json::other_error::create(501, "one entry per bin", bins);
          }
          for (const json& bin : *bins) pose_fields(bin);
        }
        for (const json& pt : v.set.at("cumulative").at(def)) {
          (void)pt.at("max_occlusion").get<double>();
          (void)pt.at("mean_error_deg").at(0);
          (void)pt.at("pairs").get<int64_t>();
        }
        for (const json& p : pairs) {
          const json& s = p.at("sets").at(k);
          const json& err = s.at("pose").at(0).at("error_deg");
          (void)s.at("pose").at(0).at("rotation_deg");
          (void)s.at("pose").at(0).at("translation_deg");
          (void)s.at("pose").at(0).at("inliers").get<int64_t>();
          (void)s.at("matches").get<int64_t>();
          v.error_deg.push_back(err.is_number() ? err.get<double>() : kInf);
          v.epipolar.push_back(s.at("epipolar_precision").get<double>());
          v.predicted.push_back(s.at("predicted").get<bool>());
          v.occlusion.push_back(p.at("occlusion").at(def).get<double>());
          for (const json& e : s.at("pose")) (void)e.at("error_deg");
          if (s.at("pose").size() != estimators) {
            throw json::other_error::create(501, "pose: one per estimator", &s);
          }
          v.pair.push_back(s);
        }
        ++name_count[v.label];
        sets.push_back(std::move(v));
      }
    } catch (const json::exception& e) {
      throw InputError(path, field + ": not as schemas/eval.schema.json expects (" +
                                 std::string(e.what()) + ")");
    }
  }
  for (EvalSetView& v : sets) {
    if (name_count[v.label] > 1) v.label = fs::path(v.eval_path).stem().string() + ":" + v.label;
  }
  std::set<std::string> labels;
  for (const EvalSetView& v : sets) {
    if (!labels.insert(v.label).second) {
      throw InputError(v.eval_path, "sets: set '" + v.label + "' is given twice");
    }
  }
  data.sets = std::move(sets);
  return data;
}

std::optional<std::pair<size_t, size_t>> DisagreementEstimators(const EvalSetView& v) {
  const json& estimators = v.options.at("estimators");
  if (estimators.size() < 2) return std::nullopt;
  const json& sel = v.set.value("selection", json());
  if (sel.is_object() && sel.at("groups").size() >= 2) {
    return std::make_pair(sel["groups"][0].at("best").get<size_t>(),
                          sel["groups"][1].at("best").get<size_t>());
  }
  const std::string first = estimators[0].value("estimator", "ransac");
  for (size_t e = 1; e < estimators.size(); ++e) {
    if (estimators[e].value("estimator", "ransac") != first) return std::make_pair(size_t{0}, e);
  }
  return std::make_pair(size_t{0}, size_t{1});
}

std::vector<NamedImage> MakeEvalPlots(const EvalReportData& data, const SplitReportOptions& options,
                                      const std::string& scratch_dir) {
  fs::create_directories(scratch_dir);
  auto write = [&](const std::string& name, const std::string& text) {
    gt::io::WriteFileAtomic((fs::path(scratch_dir) / name).string(), text);
  };
  const size_t mid = data.auc_thresholds_deg.size() / 2;
  const std::string auc_name = "AUC@" + Num(data.auc_thresholds_deg[mid]) + " deg (%)";
  const std::string def = data.occlusion_definition;
  // Data files: one per set and plot; "NaN" where a bin has no pairs (gnuplot skips it).
  for (size_t k = 0; k < data.sets.size(); ++k) {
    const json& s = data.sets[k].set;
    std::string cum;
    for (const json& pt : s.at("cumulative").at(def)) {
      const json& mean = pt.at("mean_error_deg").at(0);
      cum += Num(pt.at("max_occlusion").get<double>(), 8) + " " +
             (mean.is_number() ? Num(mean.get<double>(), 8) : "NaN") + " " +
             std::to_string(pt.at("pairs").get<int64_t>()) + "\n";
    }
    write("cum" + std::to_string(k) + ".dat", cum.empty() ? "NaN NaN NaN\n" : cum);
    for (const auto& [file, bins] :
         {std::pair<std::string, const json*>{"occ", &s.at("by_occlusion").at(def)},
          {"ovl", &s.at("by_consistent_overlap")}}) {
      std::string text;
      for (size_t b = 0; b < bins->size(); ++b) {
        const json& bin = (*bins)[b];
        const bool empty = bin.at("pairs").get<int64_t>() == 0;
        text +=
            std::to_string(b) + " " +
            (empty ? "NaN" : Num(bin.at("pose").at(0).at("auc_percent").at(mid).get<double>(), 8)) +
            "\n";
      }
      write(file + std::to_string(k) + ".dat", text);
    }
  }
  // Bin labels with the number of pairs in the bin (the same for every set).
  auto xtics = [](const std::vector<double>& edges, const json& bins) {
    std::string t = "set xtics (";
    for (size_t b = 0; b + 1 < edges.size(); ++b) {
      if (b) t += ", ";
      t += GnuplotString(BinLabel(edges[b], edges[b + 1], b + 2 == edges.size()) +
                         " n=" + std::to_string(bins.at(b).at("pairs").get<int64_t>())) +
           " " + std::to_string(b);
    }
    return t + ") rotate by 30 right\n";
  };
  auto plot_sets = [&](const std::string& prefix, const std::string& using_cols) {
    std::string t = "plot ";
    for (size_t k = 0; k < data.sets.size(); ++k) {
      if (k) t += ", ";
      t += "'" + prefix + std::to_string(k) + ".dat' using " + using_cols +
           " with linespoints lw 2 pt 7 title " + GnuplotString(data.sets[k].label);
    }
    return t;
  };
  const std::string estimator =
      data.estimator_names.empty() ? std::string() : data.estimator_names[0];
  std::ostringstream gp;
  gp << "set terminal pngcairo size " << options.plot_width_px << "," << options.plot_height_px
     << " font \"DejaVu Sans,11\" noenhanced\n"
     << "set encoding utf8\nset grid ytics lc rgb '#dddddd'\nset border 3\n"
     << "set xtics nomirror\nset ytics nomirror\nset key below horizontal\n";
  // The curve of eval.json is sampled at --curve-step of `occgt eval` up to the largest ratio:
  // with a step not below the data's largest ratio it is one point, which the title says
  // (with the step that would give 10 points); x spans the points, not [0, 1].
  size_t curve_points = 0;
  double curve_end = 0, largest = 0;
  for (const EvalSetView& v : data.sets) {
    const json& cum = v.set.at("cumulative").at(def);
    curve_points = std::max(curve_points, cum.size());
    for (const json& pt : cum)
      curve_end = std::max(curve_end, pt.at("max_occlusion").get<double>());
    for (const double r : v.occlusion) largest = std::max(largest, r);
  }
  std::string curve_note;
  if (curve_points < 3 && !data.sets.empty()) {
    const double step = data.sets[0].options.value("curve_step", 0.0);
    curve_note =
        "; " + std::to_string(curve_points) + (curve_points == 1 ? " point" : " points") +
        ": occgt eval --curve-step " + Num(step) + ", largest ratio " + Num(largest, 3) +
        (largest > 0 ? "; --curve-step " + Num(std::max(0.001, largest / 10), 1) + " gives about 10"
                     : std::string());
  }
  gp << "set output 'eval_cumulative.png'\nset title "
     << GnuplotString("Mean pose error of the pairs with occlusion ratio <= x (" + def + ", " +
                      estimator + ")" + curve_note)
     << "\nset xrange [0:" << Num(curve_end > 0 ? curve_end : 1, 8) << "]"
     << "\nset xlabel " << GnuplotString("occlusion ratio (" + def + ")")
     << "\nset ylabel 'mean pose error (deg)'\nset y2label 'pairs'\nset y2tics\n"
     << "set yrange [0:*]\nset y2range [0:*]\n"
     << plot_sets("cum", "1:2") << ", 'cum0.dat' using 1:3 axes x1y2 with steps lc rgb '#999999' "
     << "dt 2 title 'pairs (right axis)'\n"
     << "unset y2label\nunset y2tics\n";
  gp << "set output 'eval_auc_by_occlusion.png'\nset title "
     << GnuplotString(auc_name + " per occlusion-ratio bin (" + def + ")") << "\nset xlabel "
     << GnuplotString("occlusion ratio (" + def + ")") << "\nset ylabel " << GnuplotString(auc_name)
     << "\nset yrange [0:100]\nset xrange [-0.5:" << Num(data.occlusion_bins.size() - 1.5, 8)
     << "]\n"
     << xtics(data.occlusion_bins, data.sets[0].set.at("by_occlusion").at(def))
     << plot_sets("occ", "1:2") << "\n";
  gp << "set output 'eval_auc_by_overlap.png'\nset title "
     << GnuplotString(auc_name + " per visible-overlap bin")
     << "\nset xlabel 'visible overlap (consistent_overlap)'\nset xrange [-0.5:"
     << Num(data.consistent_overlap_bins.size() - 1.5, 8) << "]\n"
     << xtics(data.consistent_overlap_bins, data.sets[0].set.at("by_consistent_overlap"))
     << plot_sets("ovl", "1:2") << "\n";
  // Per-pair disagreement of two estimators (DisagreementEstimators) over the occlusion
  // ratio: error(B) - error(A), a failure counted as 180 degrees, clipped to +-30.
  std::vector<std::string> outputs{"eval_cumulative.png", "eval_auc_by_occlusion.png",
                                   "eval_auc_by_overlap.png"};
  std::string dis_plot;
  for (size_t k = 0; k < data.sets.size(); ++k) {
    const EvalSetView& v = data.sets[k];
    const auto ab = DisagreementEstimators(v);
    if (!ab) continue;
    std::string text;
    for (size_t i = 0; i < v.pair.size(); ++i) {
      if (!v.predicted[i]) continue;
      auto err = [&](size_t e) {
        const json& x = v.pair[i].at("pose").at(e).at("error_deg");
        return x.is_number() ? x.get<double>() : 180.0;
      };
      const double d = std::clamp(err(ab->second) - err(ab->first), -30.0, 30.0);
      text += Num(v.occlusion[i], 8) + " " + Num(d, 8) + "\n";
    }
    write("dis" + std::to_string(k) + ".dat", text.empty() ? "NaN NaN\n" : text);
    const json& est = v.options.at("estimators");
    const std::string label = v.label + ": B " + est[ab->second].at("name").get<std::string>() +
                              ", A " + est[ab->first].at("name").get<std::string>();
    dis_plot += std::string(dis_plot.empty() ? "plot " : ", ") + "'dis" + std::to_string(k) +
                ".dat' using 1:2 with points pt 7 ps 0.6 title " + GnuplotString(label);
  }
  if (!dis_plot.empty()) {
    gp << "set output 'eval_estimator_disagreement.png'\nset title "
       << GnuplotString("Per pair: pose error of B minus A (failure = 180 deg, clipped to +-30)")
       << "\nset xlabel " << GnuplotString("occlusion ratio (" + def + ")")
       << "\nset ylabel 'error(B) - error(A) (deg); below 0: B is better'\n"
       << "set xtics auto norotate\nset autoscale x\nset yrange [-31:31]\n"
       << dis_plot << ", 0 with lines lc rgb '#999999' dt 2 notitle\n";
    outputs.push_back("eval_estimator_disagreement.png");
  }
  gt::io::WriteFileAtomic((fs::path(scratch_dir) / "eval.gp").string(), gp.str());
  return RunGnuplot(options.gnuplot, scratch_dir, "eval.gp", outputs);
}

std::vector<size_t> PickWorstPairs(const EvalSetView& set, int count) {
  std::vector<size_t> idx;
  for (size_t i = 0; i < set.error_deg.size(); ++i) {
    if (set.predicted[i]) idx.push_back(i);
  }
  std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) {
    if (set.error_deg[a] != set.error_deg[b]) return set.error_deg[a] > set.error_deg[b];
    return set.epipolar[a] < set.epipolar[b];
  });
  if (idx.size() > static_cast<size_t>(std::max(count, 0))) idx.resize(std::max(count, 0));
  return idx;
}

namespace {

// The set's predictions file: as written, else relative to the eval.json's folder.
std::string ResolvePredictions(const EvalSetView& v) {
  const std::string path = v.set.at("path").get<std::string>();
  if (fs::exists(path)) return path;
  const fs::path beside = fs::path(v.eval_path).parent_path() / path;
  if (!fs::path(path).is_absolute() && fs::exists(beside)) return beside.string();
  return "";
}

std::string Degrees(const json& v) { return v.is_number() ? Cell(v, 2) + "°" : "failed"; }

}  // namespace

std::vector<EvalGallery> MakeEvalGalleries(const EvalReportData& data, const SplitData& split,
                                           const SplitReportOptions& options) {
  std::vector<EvalGallery> out;
  if (options.eval_gallery_pairs == 0) return out;
  const gt::eval::SplitIndex index = gt::eval::LoadSplitIndex(split.dir);
  const std::set<std::string> keys(index.keys.begin(), index.keys.end());
  for (const EvalSetView& v : data.sets) {
    EvalGallery g;
    g.set_label = v.label;
    int64_t missing = 0;
    for (const bool p : v.predicted) missing += p ? 0 : 1;
    if (missing > 0) {
      g.warnings.push_back(std::to_string(missing) +
                           " pair(s) without a prediction are not shown (each is a failure).");
    }
    if (!v.has_quality) {
      g.warnings.push_back("No gallery: the split has no per-type ground truth (" +
                           v.quality_reason + ").");
      out.push_back(std::move(g));
      continue;
    }
    const std::string path = ResolvePredictions(v);
    if (path.empty()) {
      g.warnings.push_back("No gallery: the predictions '" + v.set.at("path").get<std::string>() +
                           "' were not found (as written, nor next to " + v.eval_path + ").");
      out.push_back(std::move(g));
      continue;
    }
    std::vector<std::string> problems;
    gt::eval::PredictionSet set = gt::eval::ReadPredictions(
        v.label, path, keys, index.width, index.height, &problems, index.pair_names);
    gt::eval::FilterByConfidence(v.options.value("min_confidence", 0.0), &set, &problems);
    if (!problems.empty()) {
      throw InputError(path, problems[0] + (problems.size() > 1
                                                ? " (and " + std::to_string(problems.size() - 1) +
                                                      " more problems)"
                                                : ""));
    }
    gt::eval::QualityOptions quality;
    quality.px = v.options.at("px").get<double>();
    for (const size_t i : PickWorstPairs(v, options.eval_gallery_pairs)) {
      const SplitPair& p = split.pairs[i];
      const json& r = v.pair[i];
      const json& pose = r.at("pose").at(0);
      GalleryItem item;
      item.caption = p.key + "  (pose error " + Degrees(pose.at("error_deg")) + ": R " +
                     Degrees(pose.at("rotation_deg")) + ", t " +
                     Degrees(pose.at("translation_deg")) + "; " +
                     std::to_string(r.at("matches").get<int64_t>()) + " matches, " +
                     std::to_string(pose.at("inliers").get<int64_t>()) + " inliers, epipolar " +
                     Cell(json(100.0 * v.epipolar[i])) + "%; occlusion " + Num(p.occlusion, 3) +
                     ", visible overlap " + Num(p.visible_min, 3) + ")";
      const std::string px_text = Num(quality.px);
      auto it = set.pairs.find(p.key);
      if (it == set.pairs.end()) {
        item.caption += " — no prediction of this pair in " + path;
        g.items.push_back(std::move(item));
        continue;
      }
      const std::string tar = (fs::path(split.dir) / p.shard).string();
      std::vector<gt::eval::MatchVerdict> verdicts;
      const gt::eval::PairQuality q = gt::eval::ScoreSampleMatches(
          tar, p.key, index.width, index.height, it->second, quality, &verdicts);
      item.caption += "; correct/predicted within " + px_text + " px:";
      for (int t = 0; t < 3; ++t) {
        item.caption += std::string(t ? "," : "") + " " +
                        (t == 0   ? "vv "
                         : t == 1 ? "vo "
                                  : "ov ") +
                        std::to_string(q.types[t].correct) + "/" +
                        std::to_string(q.types[t].predicted);
      }
      item.caption += ", unscored " + std::to_string(q.unscored);
      const PairData pair = LoadPairFromShard(tar, p.key);
      std::vector<PredictionVerdict> drawn(verdicts.size());
      for (size_t m = 0; m < verdicts.size(); ++m) {
        drawn[m] =
            verdicts[m].match_class == gt::eval::kClassUnscored
                ? PredictionVerdict::kUnscored
                : (verdicts[m].correct ? PredictionVerdict::kCorrect : PredictionVerdict::kWrong);
      }
      PredictionPictureOptions po;
      po.seed = options.seed;
      // At most kMaxGalleryWidth pixels wide, never enlarged (lines stay readable at 640x480);
      // the legend drawn larger by the downscale.
      const double scale =
          std::min(1.0, kMaxGalleryWidth / (pair.image0.cols + kPanelGap + pair.image1.cols));
      po.text_scale = std::min(4.0, 1.0 / scale);
      const cv::Mat picture =
          RenderPredictedMatches(pair.image0, pair.labels01, pair.image1, pair.labels10,
                                 it->second.kpts0, it->second.kpts1, drawn, po);
      cv::Mat small = picture;
      if (scale < 1.0) cv::resize(picture, small, cv::Size(), scale, scale, cv::INTER_AREA);
      item.images.push_back(
          {"predicted matches over the labels", "image/jpeg",
           gt::io::EncodeJpegBytes(small, gt::io::ChannelOrder::kBgr, 85, "eval gallery")});
      g.items.push_back(std::move(item));
    }
    out.push_back(std::move(g));
  }
  return out;
}

namespace {

// "Estimators side by side": per set, one row per estimator group (settings equal but the
// threshold), one column per threshold, AUC at each angle and their mean; the best-of-sweep
// choice starred. Empty when every set has a single estimator.
std::string EstimatorMatrix(const EvalReportData& data) {
  bool several = false;
  for (const EvalSetView& v : data.sets) several = several || v.options.at("estimators").size() > 1;
  if (!several) return "";
  std::ostringstream h;
  bool any_selection = false;
  h << "<h3>Estimators side by side</h3>\n<table class=\"eval-estimators\"><tr><th>set</th>"
    << "<th>estimator</th><th>threshold (px)</th><th>AUC@";
  for (size_t t = 0; t < data.auc_thresholds_deg.size(); ++t) {
    h << (t ? "/" : "") << Num(data.auc_thresholds_deg[t]);
  }
  h << "° (%)</th><th>mean AUC (%)</th></tr>\n";
  for (const EvalSetView& v : data.sets) {
    const json& est = v.options.at("estimators");
    const json& sel = v.set.value("selection", json());
    const int64_t best = sel.is_object() ? sel.at("best").get<int64_t>() : -1;
    any_selection = any_selection || sel.is_object();
    // Groups in order of first appearance.
    std::vector<std::string> group_names;
    std::vector<std::vector<size_t>> groups;
    for (size_t e = 0; e < est.size(); ++e) {
      const json& x = est[e];
      std::string g = "opencv-" + x.value("estimator", std::string("ransac")) + " conf " +
                      Num(x.at("confidence").get<double>(), 6);
      if (x.value("max_iters", 1000) != 1000)
        g += " iters " + std::to_string(x.value("max_iters", 1000));
      if (x.value("focal_mean", std::string("loftr")) != "loftr") {
        g += " focal " + x.value("focal_mean", std::string());
      }
      const auto it = std::find(group_names.begin(), group_names.end(), g);
      if (it == group_names.end()) {
        group_names.push_back(g);
        groups.push_back({e});
      } else {
        groups[it - group_names.begin()].push_back(e);
      }
    }
    for (size_t g = 0; g < groups.size(); ++g) {
      for (size_t j = 0; j < groups[g].size(); ++j) {
        const size_t e = groups[g][j];
        const json& auc = v.set.at("overall").at("pose").at(e).at("auc_percent");
        double sum = 0;
        std::string cells;
        for (size_t t = 0; t < auc.size(); ++t) {
          cells += (t ? " / " : "") + Cell(auc[t], 2);
          sum += auc[t].is_number() ? auc[t].get<double>() : 0.0;
        }
        const bool starred = static_cast<int64_t>(e) == best;
        h << "<tr data-set=\"" << HtmlEscape(v.label) << "\"" << (starred ? " class=\"best\"" : "")
          << "><td>" << HtmlEscape(v.label) << "</td><td>"
          << (j == 0 ? HtmlEscape(group_names[g]) : "") << "</td><td class=\"n\">"
          << Num(est[e].at("ransac_px").get<double>(), 6) << "</td><td class=\"n\">" << cells
          << "</td><td class=\"n\">" << Cell(json(auc.empty() ? 0.0 : sum / auc.size()), 2)
          << (starred ? " ★" : "") << "</td></tr>\n";
      }
    }
  }
  h << "</table>\n";
  if (any_selection) {
    h << "<p class=\"note\">★ best of the sweep by mean AUC (glue-factory's rule). This figure "
         "is optimistic: the threshold and the estimator were chosen on these same pairs, "
         "not on held-out ones.</p>\n";
  }
  return h.str();
}

}  // namespace

std::string RenderEvalSection(const EvalReportData& data, const std::vector<NamedImage>& plots,
                              const std::vector<EvalGallery>& galleries) {
  std::ostringstream h;
  std::set<std::string> files;
  std::string file_list;
  for (const EvalSetView& v : data.sets) {
    if (files.insert(v.eval_path).second) {
      file_list += (file_list.empty() ? "" : ", ") + HtmlEscape(v.eval_path);
    }
  }
  h << "<h2 id=\"eval\">Evaluation</h2>\n<p class=\"muted\">" << data.sets.size()
    << " prediction set(s) from " << file_list << " (`occgt eval`, docs/EVAL.md). Plots and "
    << "gallery use the first estimator (" << HtmlEscape(data.estimator_names.at(0))
    << ") and the occlusion ratio '" << HtmlEscape(data.occlusion_definition) << "'.</p>\n";
  // Pose table.
  h << "<table class=\"eval-pose\"><tr><th>set</th><th>estimator</th>";
  for (const double t : data.auc_thresholds_deg) h << "<th>AUC@" << Num(t) << "° (%)</th>";
  h << "<th>failures</th><th>missing pairs</th><th>matches / pair</th>"
       "<th>epipolar precision (%)</th></tr>\n";
  for (const EvalSetView& v : data.sets) {
    const json& overall = v.set.at("overall");
    const json& estimators = v.options.at("estimators");
    for (size_t e = 0; e < estimators.size(); ++e) {
      const json& pose = overall.at("pose").at(e);
      h << "<tr data-set=\"" << HtmlEscape(v.label) << "\"><td>" << HtmlEscape(v.label)
        << "</td><td>" << HtmlEscape(estimators[e].at("name").get<std::string>()) << "</td>";
      for (const json& a : pose.at("auc_percent")) h << "<td class=\"n\">" << Cell(a, 2) << "</td>";
      h << "<td class=\"n\">" << pose.at("failures").get<int64_t>() << "</td><td class=\"n\">"
        << v.set.at("pairs_missing").get<int64_t>() << "</td><td class=\"n\">"
        << Cell(overall.at("matches_mean")) << "</td><td class=\"n\">"
        << Cell(overall.at("epipolar_precision_percent")) << "</td></tr>\n";
    }
  }
  h << "</table>\n";
  h << EstimatorMatrix(data);
  // Per-type table.
  const std::string px = data.sets.empty() ? "" : Num(data.sets[0].options.at("px").get<double>());
  h << "<h3>Per-type precision and recall (within " << px << " px of the ground truth)</h3>\n"
    << "<table class=\"eval-types\"><tr><th>set</th>";
  for (const char* t : {"vv", "vo", "ov"}) {
    h << "<th>" << t << " precision (%)</th><th>" << t << " recall (%)</th>";
  }
  h << "<th>unscored</th><th>precision of scored (%)</th></tr>\n";
  for (const EvalSetView& v : data.sets) {
    const json& types = v.set.at("overall").at("types");
    h << "<tr data-set=\"" << HtmlEscape(v.label) << "\"><td>" << HtmlEscape(v.label) << "</td>";
    if (types.is_null()) {
      h << "<td colspan=\"8\" class=\"muted\">not available: " << HtmlEscape(v.quality_reason)
        << "</td></tr>\n";
      continue;
    }
    for (const char* t : {"vv", "vo", "ov"}) {
      const json& x = types.at(t);
      h << "<td class=\"n\">" << Cell(x.at("precision_percent")) << " ("
        << x.at("correct").get<int64_t>() << "/" << x.at("predicted").get<int64_t>()
        << ")</td><td class=\"n\">" << Cell(x.at("recall_percent")) << " ("
        << x.at("recalled").get<int64_t>() << "/" << x.at("truth").get<int64_t>() << ")</td>";
    }
    h << "<td class=\"n\">" << types.at("unscored").at("count").get<int64_t>()
      << "</td><td class=\"n\">" << Cell(types.at("all").at("precision_scored_percent"))
      << "</td></tr>\n";
  }
  h << "</table>\n<div class=\"plots\">\n";
  for (const auto& p : plots) {
    h << "<figure>" << ImgTag(p, PlotAlt(p.name)) << "<figcaption>" << HtmlEscape(p.name)
      << "</figcaption></figure>\n";
  }
  h << "</div>\n";
  for (const EvalGallery& g : galleries) {
    h << "<h3 class=\"eval-gallery\" data-set=\"" << HtmlEscape(g.set_label) << "\">Worst pairs of "
      << HtmlEscape(g.set_label) << "</h3>\n<p class=\"muted\">" << g.items.size()
      << " pair(s), largest pose error first. Predicted matches over the labels: correct cyan, "
         "wrong magenta, unscored (no ground-truth target) white; labels as in the gallery "
         "below.</p>\n";
    if (!g.warnings.empty()) {
      h << "<div class=\"warn\" role=\"alert\"><ul>\n";
      for (const auto& w : g.warnings) h << "<li>" << HtmlEscape(w) << "</li>\n";
      h << "</ul></div>\n";
    }
    for (const GalleryItem& item : g.items) {
      h << "<div class=\"pair eval-pair\"><h4>" << HtmlEscape(item.caption) << "</h4>\n";
      for (const auto& im : item.images) {
        h << "<figure>" << ImgTag(im, item.caption + ": " + im.name) << "<figcaption>"
          << HtmlEscape(im.name) << "</figcaption></figure>\n";
      }
      h << "</div>\n";
    }
  }
  return h.str();
}

}  // namespace gt::report

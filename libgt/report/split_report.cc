#include "libgt/report/split_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <unordered_map>

#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/core/stats.h"
#include "libgt/datasets/scan.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/report/eval_report.h"
#include "libgt/truth/pair_files.h"

namespace gt::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string JsonScalar(const json& v);

// A statistic that has no value (null in report.json and summary.json) on the page.
constexpr const char* kNoValue = "—";

// Where a field is: "<file>:<line>: <field path>", the path joined with dots
// ("pairs.jsonl:3: metrics.01.overlap"); `where` is "<file>:<line>" or already holds a path.
std::string FieldWhere(const std::string& where, const char* key) {
  return where + (where.rfind(": ") == std::string::npos ? ": " : ".") + key;
}

// "expected <what>, got a string" (null, an object, ...), or "missing: expected <what>".
std::string Expected(const json& j, const char* key, const std::string& what) {
  if (!j.is_object() || !j.contains(key)) return "missing: expected " + what;
  const json& v = j.at(key);
  const std::string type = v.type_name();
  return "expected " + what + ", got " +
         (v.is_null() ? type : (v.is_object() || v.is_array() ? "an " : "a ") + type);
}

double NeedNumber(const json& j, const char* key, const std::string& where) {
  if (!j.is_object() || !j.contains(key) || !j.at(key).is_number()) {
    throw InputError(FieldWhere(where, key), Expected(j, key, "a number"));
  }
  return j.at(key).get<double>();
}

// A number in [0, 1] (an overlap, an occlusion ratio, a share).
double NeedFraction(const json& j, const char* key, const std::string& where) {
  const double v = NeedNumber(j, key, where);
  if (!(v >= 0 && v <= 1)) {
    throw InputError(FieldWhere(where, key),
                     "expected a number in [0, 1], got " + JsonScalar(j.at(key)));
  }
  return v;
}

// The string `key` of an object, or "" when the object has none.
std::string OptionalString(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) return "";
  if (!j.at(key).is_string()) {
    throw InputError(FieldWhere(where, key), "expected a string, got " + JsonScalar(j.at(key)));
  }
  return j.at(key).get<std::string>();
}

std::string NeedString(const json& j, const char* key, const std::string& where) {
  if (!j.is_object() || !j.contains(key) || !j.at(key).is_string()) {
    throw InputError(FieldWhere(where, key), Expected(j, key, "a string"));
  }
  return j.at(key).get<std::string>();
}

// A frame record {"id": "...", "number": n}: its id.
std::string NeedFrameId(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || !j.at(key).is_object()) {
    throw InputError(FieldWhere(where, key),
                     Expected(j, key, "a frame record {\"id\": ..., \"number\": ...}"));
  }
  return NeedString(j.at(key), "id", FieldWhere(where, key));
}

std::string JsonScalar(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_float()) return Num(v.get<double>(), 6);
  return v.dump();
}

struct Stats {
  double min = 0, median = 0, mean = 0, max = 0;
};
// nullopt without a value (report.json's null): no pair, no statistic.
std::optional<Stats> Describe(std::vector<double> v) {
  if (v.empty()) return std::nullopt;
  Stats s;
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  s.median = SortedMedian(v);
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / v.size();
  return s;
}

}  // namespace

bool SplitReportOptions::Check(std::string* error) const {
  if (histogram_bins < 1 || histogram_bins > 200) {
    *error = "histogram_bins: expected 1..200";
    return false;
  }
  if (gallery_pairs < 0 || gallery_pairs > 100) {
    *error = "gallery_pairs: expected 0..100";
    return false;
  }
  if (!(gallery_scale > 0 && gallery_scale <= 1)) {
    *error = "gallery_scale: expected (0, 1]";
    return false;
  }
  if (eval_gallery_pairs < 0 || eval_gallery_pairs > 50) {
    *error = "eval_gallery_pairs: expected 0..50";
    return false;
  }
  if (gallery_tuples < 0 || gallery_tuples > 50) {
    *error = "gallery_tuples: expected 0..50";
    return false;
  }
  if (tuple_thumb_width_px < 32 || tuple_thumb_width_px > 1024) {
    *error = "tuple_thumb_width_px: expected 32..1024";
    return false;
  }
  if (gnuplot.empty()) {
    *error = "gnuplot: expected an executable name";
    return false;
  }
  if (plot_width_px < 200 || plot_height_px < 150 || plot_width_px > 4000 ||
      plot_height_px > 4000) {
    *error = "plot size: expected 200..4000 x 150..4000 pixels";
    return false;
  }
  return pictures.Check(error);
}

SplitData LoadSplit(const std::string& dir, const SplitReportOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("inspect options", error);
  SplitData split;
  split.dir = dir;
  const std::string pairs_path = (fs::path(dir) / "pairs.jsonl").string();
  split.tuples = LoadTupleSet(dir);
  split.has_pairs = gt::io::FileExists(pairs_path);
  if (!split.has_pairs && !split.tuples) {
    throw InputError(pairs_path,
                     "missing: expected the pairs.jsonl of an `occgt build` folder (or the "
                     "tuples.jsonl of `occgt tuples`)");
  }
  const std::vector<std::pair<std::string, json>> lines =
      split.has_pairs ? ReadJsonLines(pairs_path) : std::vector<std::pair<std::string, json>>();
  const char* occ_key = OcclusionMetricField(options.occlusion_metric);
  std::unordered_map<std::string, std::string> line_of_key;  // key -> its first line
  for (const auto& line : lines) {
    const std::string& where = line.first;  // a named reference: lambdas below capture it
    const json& j = line.second;
    SplitPair p;
    p.scene = NeedString(j, "scene", where);
    p.frame0 = NeedFrameId(j, "frame0", where);
    p.frame1 = NeedFrameId(j, "frame1", where);
    p.shard = OptionalString(j, "shard", where);
    p.key = OptionalString(j, "key", where);
    if (!p.key.empty()) {
      if (const auto [it, inserted] = line_of_key.emplace(p.key, where); !inserted) {
        throw InputError(where, "key " + p.key + " repeats " + it->second +
                                    " (pairs.jsonl holds each pair once)");
      }
    }
    if (!j.contains("metrics") || !j["metrics"].is_object()) {
      throw InputError(where, "expected \"metrics\": {\"01\": {...}, \"10\": {...}}");
    }
    const json& m = j["metrics"];
    const json m01 = m.value("01", json()), m10 = m.value("10", json());
    p.overlap01 = NeedFraction(m01, "overlap", where + ": metrics.01");
    p.overlap10 = NeedFraction(m10, "overlap", where + ": metrics.10");
    p.occlusion01 = NeedFraction(m01, occ_key, where + ": metrics.01");
    p.occlusion10 = NeedFraction(m10, occ_key, where + ": metrics.10");
    p.visible01 = NeedFraction(m01, "consistent_overlap", where + ": metrics.01");
    p.visible10 = NeedFraction(m10, "consistent_overlap", where + ": metrics.10");
    p.visible_min = std::min(p.visible01, p.visible10);
    const double valid = NeedNumber(m01, "valid", where + ": metrics.01") +
                         NeedNumber(m10, "valid", where + ": metrics.10");
    auto share = [&](const char* label) {
      const json c01 = m01.value("counts", json()), c10 = m10.value("counts", json());
      const double n = NeedNumber(c01, label, where + ": metrics.01.counts") +
                       NeedNumber(c10, label, where + ": metrics.10.counts");
      return valid > 0 ? n / valid : 0.0;
    };
    p.inconsistent_share = share("INCONSISTENT");
    p.unknown_share = share("UNKNOWN");
    p.overlap = Combine(p.overlap01, p.overlap10, options.aggregate);
    p.occlusion = Combine(p.occlusion01, p.occlusion10, options.aggregate);
    // The same on the selection's score grid (summary.json's selected_* statistics).
    if (!j.contains("score_metrics") || !j["score_metrics"].is_object()) {
      throw InputError(where, "expected \"score_metrics\": {\"01\": {...}, \"10\": {...}}");
    }
    const json& sm = j["score_metrics"];
    const json s01 = sm.value("01", json()), s10 = sm.value("10", json());
    p.score_overlap =
        Combine(NeedFraction(s01, "overlap", where + ": score_metrics.01"),
                NeedFraction(s10, "overlap", where + ": score_metrics.10"), options.aggregate);
    p.score_occlusion =
        Combine(NeedFraction(s01, occ_key, where + ": score_metrics.01"),
                NeedFraction(s10, occ_key, where + ": score_metrics.10"), options.aggregate);
    const double stride = NeedNumber(j, "score_stride", where);
    if (split.score_stride == 0) split.score_stride = static_cast<int>(stride);
    if (stride != split.score_stride) {
      throw InputError(where, "score_stride " + Num(stride) + " differs from the first line's " +
                                  std::to_string(split.score_stride));
    }
    split.pairs.push_back(std::move(p));
  }
  // Optional JSON objects beside pairs.jsonl: null when absent, an error when malformed.
  auto optional_object = [&](const char* name, const std::string& expected) {
    const std::string path = (fs::path(dir) / name).string();
    if (!gt::io::FileExists(path)) return json();
    json j;
    try {
      j = json::parse(gt::io::ReadFileBytes(path));
    } catch (const json::exception&) {
      throw InputError(path, expected);
    }
    if (!j.is_object()) throw InputError(path, expected);
    return j;
  };
  split.summary = optional_object("summary.json", "expected a JSON object");
  split.recipe = optional_object("recipe.json", "expected a JSON object (the resolved recipe)");
  // Without a line (no pair selected), the stride of the selection's grid is the recipe's.
  if (split.score_stride == 0 && split.recipe.is_object()) {
    const json selection = split.recipe.value("selection", json());
    if (selection.is_object() && selection.contains("score_stride")) {
      const json& stride = selection["score_stride"];
      if (!stride.is_number_integer() || stride.get<int64_t>() < 1) {
        throw InputError(
            (fs::path(dir) / "recipe.json").string(),
            "selection.score_stride: expected a positive integer, got " + JsonScalar(stride));
      }
      split.score_stride = static_cast<int>(stride.get<int64_t>());
    }
  }
  split.drops = json::object();
  if (split.summary.is_object() && split.summary.contains("drops")) {
    split.drops = split.summary["drops"];
  } else if (fs::is_directory(fs::path(dir) / "selection")) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(fs::path(dir) / "selection")) {
      if (e.path().extension() == ".json") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      const json sel = json::parse(gt::io::ReadFileBytes(f.string()), nullptr, false);
      if (!sel.is_object() || !sel.contains("drops") || !sel["drops"].is_object()) {
        throw InputError(f.string(), "expected a scene's selection record with \"drops\"");
      }
      for (auto it = sel["drops"].begin(); it != sel["drops"].end(); ++it) {
        if (!it.value().is_number_integer()) {
          throw InputError(f.string(), "drops." + it.key() + ": expected an integer");
        }
        split.drops[it.key()] = split.drops.value(it.key(), int64_t{0}) + it.value().get<int64_t>();
      }
    }
  }
  return split;
}

std::vector<std::string> SplitWarnings(const SplitData& split) {
  std::vector<std::string> w;
  if (split.has_pairs && split.pairs.empty()) {
    w.emplace_back("The split has no pairs (see the drops below).");
  }
  if (split.recipe.is_object()) {
    const json sample = split.recipe.value("sample", json::object());
    if (sample.is_object() && sample.value("image", "") == "none") {
      w.emplace_back(
          "No images are stored in this split (sample.image: none): a trainer must read the "
          "dataset's own colour files.");
    }
    const json dataset = split.recipe.value("dataset", json::object());
    if (dataset.is_object() && dataset.contains("format") && dataset["format"].is_string()) {
      const std::string name = dataset["format"].get<std::string>();
      for (const DatasetFormat f : kAllDatasetFormats) {  // "synthetic" has no caveats
        if (name != DatasetFormatName(f)) continue;
        for (auto& c : gt::datasets::DatasetCaveats(f)) w.push_back(c + ".");
      }
    }
  }
  if (split.summary.is_object()) {
    const json& drops = split.drops;
    if (drops.is_object()) {
      for (const char* reason : {"scan.no_color", "import.no_color"}) {
        if (drops.contains(reason) && drops[reason].is_number() &&
            drops[reason].get<double>() > 0) {
          const bool one = drops[reason].get<double>() == 1;
          const std::string what =
              std::string(reason) == "scan.no_color"
                  ? (one ? " frame was skipped" : " frames were skipped")
                  : (one ? " imported pair was skipped" : " imported pairs were skipped");
          w.push_back(JsonScalar(drops[reason]) + what + " for lack of a colour image (" + reason +
                      ").");
        }
      }
    }
  }
  return w;
}

namespace {
constexpr int kStepsPerUnit = 20;  // HistogramRange's step: 1 / 20 = 0.05
}  // namespace

std::pair<double, double> HistogramRange(const std::vector<double>& values) {
  double lo = 1.0, hi = 0.0;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, std::clamp(v, 0.0, 1.0));
    hi = std::max(hi, std::clamp(v, 0.0, 1.0));
  }
  if (lo > hi) return {0.0, 1.0};
  // Multiples of the step as integers, divided last, so that 0.35 stays 0.35 (7 * 0.05 is
  // 0.35000000000000003, 7 / 20.0 the double nearest 0.35).
  int a = static_cast<int>(std::floor(lo * kStepsPerUnit + 1e-9));
  int b = static_cast<int>(std::ceil(hi * kStepsPerUnit - 1e-9));
  if (b <= a) b = a + 1;
  if (b > kStepsPerUnit) a -= b - kStepsPerUnit, b = kStepsPerUnit;
  return {a / static_cast<double>(kStepsPerUnit), b / static_cast<double>(kStepsPerUnit)};
}

std::vector<double> HistogramEdges(std::pair<double, double> range, int bins) {
  GT_ASSERT(bins >= 1);
  const long a = std::lround(range.first * kStepsPerUnit);
  const long b = std::lround(range.second * kStepsPerUnit);
  GT_ASSERT_MSG(std::abs(range.first * kStepsPerUnit - a) < 1e-6 &&
                    std::abs(range.second * kStepsPerUnit - b) < 1e-6 && b > a,
                "HistogramEdges: expected a HistogramRange (multiples of 0.05)");
  // Edge k is (a·bins + k·(b − a)) / (20·bins): integers divided once, the double nearest
  // the exact edge (0.35 + 0.05 = 0.4 is the literal 0.4, not 0.39999999999999997).
  std::vector<double> edges(static_cast<size_t>(bins) + 1);
  for (int k = 0; k <= bins; ++k) {
    edges[static_cast<size_t>(k)] = static_cast<double>(a * bins + k * (b - a)) /
                                    static_cast<double>(static_cast<long>(kStepsPerUnit) * bins);
  }
  return edges;
}

int HistogramBin(double v, const std::vector<double>& edges) {
  GT_ASSERT(edges.size() >= 2);
  const int bins = static_cast<int>(edges.size()) - 1;
  if (!(v > edges.front())) return 0;  // below the range, on its first edge, or NaN
  // The last edge e with e <= v: left-closed bins, the last one closed.
  const int k = static_cast<int>(std::upper_bound(edges.begin(), edges.end(), v) - edges.begin());
  return std::min(bins - 1, k - 1);
}

std::vector<NamedImage> MakeSplitPlots(const SplitData& split, const SplitReportOptions& options,
                                       const std::string& scratch_dir) {
  std::string error;
  if (!options.Check(&error)) throw InputError("inspect options", error);
  fs::create_directories(scratch_dir);
  auto write = [&](const std::string& name, const std::string& text) {
    gt::io::WriteFileAtomic((fs::path(scratch_dir) / name).string(), text);
  };
  const size_t n = split.pairs.size();
  const int bins = options.histogram_bins;
  // Histograms over the range of the data (HistogramRange), `bins` bins.
  auto histogram = [&](const std::vector<double>& values, std::pair<double, double> range) {
    const std::vector<double> edges = HistogramEdges(range, bins);
    std::vector<int64_t> counts(bins, 0);
    for (double v : values) ++counts[HistogramBin(std::isfinite(v) ? v : 0.0, edges)];
    std::string text;
    for (int b = 0; b < bins; ++b) {
      text += Num(0.5 * (edges[b] + edges[b + 1]), 8) + " " + std::to_string(counts[b]) + "\n";
    }
    return text;
  };
  std::vector<double> overlaps, occlusions;
  for (const auto& p : split.pairs) {
    overlaps.push_back(p.overlap);
    occlusions.push_back(p.occlusion);
  }
  const auto overlap_range = HistogramRange(overlaps), occlusion_range = HistogramRange(occlusions);
  write("overlap_hist.dat", histogram(overlaps, overlap_range));
  write("occlusion_hist.dat", histogram(occlusions, occlusion_range));
  auto range_text = [](std::pair<double, double> r) {
    return "[" + Num(r.first, 2) + ":" + Num(r.second, 2) + "]";
  };
  auto range_title = [](std::pair<double, double> r) {
    return "[" + Num(r.first, 2) + ", " + Num(r.second, 2) + "]";
  };

  std::vector<double> occ;
  for (const auto& p : split.pairs) occ.push_back(p.occlusion);
  std::sort(occ.begin(), occ.end());
  // Over the range of the data as the histograms (demo ratios lie in [0, 0.06]: over [0, 1]
  // the curve is a vertical line at the left).
  std::string cumulative = Num(occlusion_range.first, 8) + " 0\n";
  for (size_t i = 0; i < occ.size(); ++i)
    cumulative += Num(occ[i], 8) + " " + std::to_string(i + 1) + "\n";
  cumulative += Num(occlusion_range.second, 8) + " " + std::to_string(occ.size()) + "\n";
  write("cumulative.dat", cumulative);

  std::string scatter;
  for (const auto& p : split.pairs) scatter += Num(p.overlap, 8) + " " + Num(p.occlusion, 8) + "\n";
  if (scatter.empty()) scatter = "NaN NaN\n";
  write("scatter.dat", scatter);

  std::map<std::string, int64_t> per_scene;
  for (const auto& p : split.pairs) ++per_scene[p.scene];
  // The scenes that gave no pair, from summary.json's pairs_per_scene (a bar of 0).
  if (split.summary.is_object() && split.summary.contains("pairs_per_scene") &&
      split.summary["pairs_per_scene"].is_object()) {
    for (const auto& entry : split.summary["pairs_per_scene"].items()) {
      per_scene.emplace(entry.key(), 0);
    }
  }
  std::vector<std::pair<std::string, int64_t>> scenes(per_scene.begin(), per_scene.end());
  const size_t kMaxScenes = 60;
  const size_t total_scenes = scenes.size();
  if (scenes.size() > kMaxScenes) {
    std::stable_sort(scenes.begin(), scenes.end(),
                     [](const auto& a, const auto& b) { return a.second > b.second; });
    scenes.resize(kMaxScenes);
    std::sort(scenes.begin(), scenes.end());
  }
  std::string scene_text;
  for (size_t i = 0; i < scenes.size(); ++i) {
    scene_text += std::to_string(i) + " " + std::to_string(scenes[i].second) + " " +
                  GnuplotString(scenes[i].first) + "\n";
  }
  if (scene_text.empty()) scene_text = "0 0 \"(none)\"\n";
  write("scenes.dat", scene_text);

  const std::string agg = AggregateName(options.aggregate);
  const std::string occ_name = options.occlusion_metric == OcclusionMetric::kImage
                                   ? "occlusion ratio (OCCLUDED / W*H)"
                                   : "occlusion ratio (OCCLUDED / (VISIBLE+OCCLUDED))";
  const std::string count = std::to_string(n) + " pairs";
  std::ostringstream gp;
  gp << "set terminal pngcairo size " << options.plot_width_px << "," << options.plot_height_px
     << " font \"DejaVu Sans,11\" noenhanced\n"
     << "set encoding utf8\nset grid ytics lc rgb '#dddddd'\nset border 3\n"
     << "set xtics nomirror\nset ytics nomirror\nset style fill solid 0.85 border -1\n"
     << "set boxwidth " << Num(0.9 * (overlap_range.second - overlap_range.first) / bins, 8)
     << "\n";
  gp << "set output 'overlap_hist.png'\nset title "
     << GnuplotString("Overlap (" + agg + " of both directions), " + count + ", " +
                      std::to_string(bins) + " bins over " + range_title(overlap_range))
     << "\nset xlabel 'overlap'\nset ylabel 'pairs'\nset xrange " << range_text(overlap_range)
     << "\nset yrange [0:*]\n"
     << "plot 'overlap_hist.dat' using 1:2 with boxes lc rgb '#3b7dd8' notitle\n";
  gp << "set output 'occlusion_hist.png'\nset title "
     << GnuplotString("Occlusion ratio (" + agg + " of both directions), " + count + ", " +
                      std::to_string(bins) + " bins over " + range_title(occlusion_range))
     << "\nset xlabel " << GnuplotString(occ_name) << "\nset xrange " << range_text(occlusion_range)
     << "\nset boxwidth " << Num(0.9 * (occlusion_range.second - occlusion_range.first) / bins, 8)
     << "\nplot 'occlusion_hist.dat' using 1:2 with boxes lc rgb '#d8503b' notitle\n";
  gp << "set output 'occlusion_cumulative.png'\nset xrange " << range_text(occlusion_range)
     << "\nset title "
     << GnuplotString("Pairs with occlusion ratio <= x, " + count + ", over " +
                      range_title(occlusion_range))
     << "\nset xlabel " << GnuplotString(occ_name) << "\nset ylabel 'cumulative number of pairs'\n"
     << "set yrange [0:" << std::max<size_t>(n, 1) << "]\n"
     << "plot 'cumulative.dat' using 1:2 with steps lw 2 lc rgb '#d8503b' notitle\n";
  gp << "set output 'overlap_vs_occlusion.png'\nset title "
     << GnuplotString("Overlap vs occlusion ratio, " + count)
     << "\nset xlabel 'overlap'\nset ylabel " << GnuplotString(occ_name)
     << "\nset xrange [0:1]\nset yrange [0:" << (n == 0 ? "1" : "*") << "]\nset grid xtics ytics\n"
     << "plot 'scatter.dat' using 1:2 with points pt 7 ps 0.6 lc rgb '#3b7dd8' notitle\n";
  gp << "set output 'pairs_per_scene.png'\nunset grid\nset grid ytics lc rgb '#dddddd'\n"
     << "set title "
     << GnuplotString("Pairs per scene (" + std::to_string(scenes.size()) + " of " +
                      std::to_string(total_scenes) + " scenes)")
     << "\nset xlabel ''\nset ylabel 'pairs'\nset boxwidth 0.8\nset xrange [-0.6:"
     << Num(std::max<size_t>(scenes.size(), 1) - 0.4, 8) << "]\nset yrange [0:*]\n"
     << "set xtics rotate by 60 right\n"
     << "plot 'scenes.dat' using 1:2:xtic(3) with boxes lc rgb '#5a9e4b' notitle\n";
  write("plots.gp", gp.str());

  return RunGnuplot(options.gnuplot, scratch_dir, "plots.gp",
                    {"overlap_hist.png", "occlusion_hist.png", "occlusion_cumulative.png",
                     "overlap_vs_occlusion.png", "pairs_per_scene.png"});
}

GalleryOrder ParseGalleryOrder(const std::string& text, const std::string& field) {
  if (text == "random") return GalleryOrder::kRandom;
  if (text == "most-occluded") return GalleryOrder::kMostOccluded;
  throw InputError(field, "expected one of random, most-occluded; got '" + text + "'");
}

const char* GalleryOrderName(GalleryOrder order) {
  return order == GalleryOrder::kRandom ? "random" : "most-occluded";
}

std::vector<size_t> PickGalleryPairs(const SplitData& split, const SplitReportOptions& options) {
  // Sort keys: (hash, index) for a seeded random choice; (-occlusion as ordered bits, index)
  // for the most occluded first.
  std::vector<std::pair<uint64_t, size_t>> keyed;
  const uint64_t seed_hash = Mix64(options.seed);
  for (size_t i = 0; i < split.pairs.size(); ++i) {
    const SplitPair& p = split.pairs[i];
    if (p.shard.empty() || p.key.empty()) continue;
    if (options.gallery_order == GalleryOrder::kRandom) {
      keyed.emplace_back(Mix64(seed_hash ^ Fnv1a64(p.key)), i);
    } else {
      // Occlusion ratios are in [0, 1]: larger ratio -> smaller key.
      const double occ = std::clamp(std::isfinite(p.occlusion) ? p.occlusion : 0.0, 0.0, 1.0);
      keyed.emplace_back(static_cast<uint64_t>((1.0 - occ) * 9.0e15), i);
    }
  }
  const size_t take = std::min(keyed.size(), static_cast<size_t>(options.gallery_pairs));
  std::partial_sort(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(take), keyed.end());
  std::vector<size_t> out;
  for (size_t k = 0; k < take; ++k) out.push_back(keyed[k].second);
  if (options.gallery_order == GalleryOrder::kRandom) std::sort(out.begin(), out.end());
  return out;
}

nlohmann::ordered_json SplitDepthSharesJson(const SplitDepthShares& shares) {
  nlohmann::ordered_json j;
  j["source"] = render::DepthSourceModeName(shares.source);
  j["tolerance"] = {{"abs_tol_m", shares.tolerance.abs_tol_m},
                    {"rel_tol", shares.tolerance.rel_tol}};
  j["resolution"] = {shares.width, shares.height};
  j["frames"] = shares.frames;
  j["total"] = truth::DepthAgreementJson(shares.total);
  j["scenes"] = nlohmann::ordered_json::array();
  for (const auto& s : shares.scenes) {
    nlohmann::ordered_json e = truth::DepthAgreementJson(s.counts);
    e["name"] = s.name;
    e["frames"] = s.frames;
    j["scenes"].push_back(e);
  }
  return j;
}

namespace {

// The "Depth sources" section: the split's shares and the largest scenes'.
std::string DepthSharesSection(const SplitDepthShares& d) {
  std::ostringstream h;
  char line[512];
  std::snprintf(line, sizeof(line),
                "<h2>Depth sources</h2>\n<p class=\"muted\">Depth source <b>%s</b>: every pixel "
                "of the %lld frames of this split's pairs at %dx%d, sensor against the mesh "
                "rendered, agreeing within %g m + %g of the depth (depth_sources.json): pixel "
                "counts and, in brackets, their share of the pixels.</p>\n",
                render::DepthSourceModeName(d.source), static_cast<long long>(d.frames), d.width,
                d.height, d.tolerance.abs_tol_m, d.tolerance.rel_tol);
  h << line;
  // Every category of depth_sources.json (its names), pixel count and share of the pixels.
  h << "<table class=\"depth-sources\"><tr><th>scene</th><th>frames</th><th>pixels</th>";
  for (const char* name : {"sensor_only", "mesh_only", "agree", "disagree", "neither"}) {
    h << "<th>" << name << "</th>";
  }
  h << "</tr>\n";
  auto row = [&](const std::string& name, int64_t frames, const render::DepthAgreement& a) {
    const double n = static_cast<double>(std::max<int64_t>(1, a.Total()));
    h << "<tr><td>" << HtmlEscape(name) << "</td><td class=\"n\">" << frames
      << "</td><td class=\"n\">" << a.Total() << "</td>";
    for (const int64_t count : {a.sensor_only, a.mesh_only, a.agree, a.disagree, a.neither}) {
      std::snprintf(line, sizeof(line), "<td class=\"n\">%lld (%.4f)</td>",
                    static_cast<long long>(count), count / n);
      h << line;
    }
    h << "</tr>\n";
  };
  row("all (split)", d.frames, d.total);
  constexpr size_t kMaxScenes = 60;
  for (size_t i = 0; i < d.scenes.size() && i < kMaxScenes; ++i) {
    row(d.scenes[i].name, d.scenes[i].frames, d.scenes[i].counts);
  }
  h << "</table>\n";
  if (d.scenes.size() > kMaxScenes) {
    h << "<p class=\"muted\">" << d.scenes.size() - kMaxScenes
      << " more scenes in depth_sources.json.</p>\n";
  }
  return h.str();
}

}  // namespace

std::string RenderHtmlReport(const SplitData& split, const SplitReportOptions& options,
                             const std::vector<NamedImage>& plots,
                             const std::vector<GalleryItem>& gallery,
                             const std::string& eval_section, const std::string& tuples_section,
                             const SplitDepthShares* depth_shares) {
  const std::string name = split.summary.is_object() && split.summary.contains("split") &&
                                   split.summary["split"].is_string()
                               ? split.summary["split"].get<std::string>()
                               : fs::path(split.dir).filename().string();
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
    << "<title>occgt split report: " << HtmlEscape(name) << "</title>\n<style>\n"
    << "body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;margin:0 auto;"
       "max-width:1320px;padding:16px 24px;color:#222;line-height:1.4}\n"
    << "h1{font-size:1.6em;margin:0.2em 0}h2{font-size:1.25em;border-bottom:1px solid #ccc;"
       "padding-bottom:4px;margin-top:1.6em}\n"
    << "table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;"
       "padding:3px 10px;text-align:left;font-size:0.92em}th{background:#f2f2f2}\n"
    << "td.n{text-align:right;font-variant-numeric:tabular-nums}\n"
    << ".plots{display:flex;flex-wrap:wrap;gap:12px}.plots figure{margin:0;flex:1 1 600px;"
       "max-width:640px}\n"
    << "img{max-width:100%;height:auto;border:1px solid #ddd}\n"
    << "figure{margin:0 0 16px 0}figcaption{font-size:0.88em;color:#555}\n"
    << ".pair{margin-bottom:28px;page-break-inside:avoid}.muted{color:#777}\n"
    << ".warn{border:2px solid #c77700;background:#fff4e0;padding:6px 14px;margin:12px 0}"
       ".warn ul{margin:4px 0}\n"
    << "pre.recipe{background:#f7f7f7;border:1px solid #ddd;padding:8px;font-size:0.85em;"
       "overflow-x:auto}\n"
    << ".tables{display:flex;flex-wrap:wrap;gap:32px;align-items:flex-start}\n"
    << ".views{display:flex;flex-wrap:wrap;gap:8px}.views figure{margin:0}\n"
    << "@media print{body{max-width:none;padding:0;font-size:10pt}"
       ".plots figure{flex:none;width:100%;max-width:100%}img{max-width:100%;"
       "page-break-inside:avoid}h2{page-break-after:avoid}figure{page-break-inside:avoid}}\n"
    << "</style>\n</head>\n<body data-images-decoded=\"pending\">\n";
  h << "<h1>Split report: " << HtmlEscape(name) << "</h1>\n<p class=\"muted\">"
    << HtmlEscape(split.dir) << " &middot; ";
  if (split.has_pairs) {
    h << split.pairs.size() << " pairs &middot; "
      << "pair values are the " << AggregateName(options.aggregate)
      << " of both directions; occlusion ratio = "
      << (options.occlusion_metric == OcclusionMetric::kImage ? "OCCLUDED / (W&middot;H)"
                                                              : "OCCLUDED / (VISIBLE + OCCLUDED)");
  } else {
    h << "no pairs.jsonl";
  }
  if (split.tuples) h << " &middot; " << split.tuples->tuples.size() << " N-view tuples";
  h << "</p>\n";
  const std::vector<std::string> warnings = SplitWarnings(split);
  if (!warnings.empty()) {
    h << "<div class=\"warn\" role=\"alert\"><strong>Warnings</strong><ul>\n";
    for (const auto& w : warnings) h << "<li>" << HtmlEscape(w) << "</li>\n";
    h << "</ul></div>\n";
  }

  // Summary tables.
  h << "<h2>Summary</h2>\n<div class=\"tables\">\n";
  std::vector<double> ov, oc, vis;
  for (const auto& p : split.pairs) {
    ov.push_back(p.overlap);
    oc.push_back(p.occlusion);
    vis.push_back(p.visible_min);
  }
  std::vector<double> score_ov, score_oc;
  for (const auto& p : split.pairs) {
    score_ov.push_back(p.score_overlap);
    score_oc.push_back(p.score_occlusion);
  }
  std::vector<double> inconsistent, unknown;
  for (const auto& p : split.pairs) {
    inconsistent.push_back(p.inconsistent_share);
    unknown.push_back(p.unknown_share);
  }
  using Described = std::optional<Stats>;
  const Described so = Describe(ov), sc = Describe(oc), sv = Describe(vis);
  const Described si = Describe(inconsistent), su = Describe(unknown);
  const Described sso = Describe(score_ov), ssc = Describe(score_oc);
  // summary.json's selected_overlap / selected_occlusion are these with the recipe's
  // aggregate and occlusion metric: the row says which ones it used.
  const std::string grid =
      " (score grid, " +
      (split.score_stride > 0 ? "score_stride " + std::to_string(split.score_stride) + "; "
                              : std::string()) +
      AggregateName(options.aggregate) + ", occlusion " +
      OcclusionMetricName(options.occlusion_metric) + ")";
  const std::string overlap_score = "overlap" + grid, occlusion_score = "occlusion ratio" + grid;
  if (split.has_pairs) {
    h << "<table><tr><th>selected pairs (every pixel unless said)</th><th>min</th><th>median</th>"
         "<th>mean</th><th>max</th></tr>\n";
    for (const auto& [label, s] :
         {std::pair<const char*, Described>{"overlap", so},
          {"consistent_overlap_min (visible overlap, weaker direction)", sv},
          {"occlusion ratio", sc},
          {overlap_score.c_str(), sso},
          {occlusion_score.c_str(), ssc},
          {"INCONSISTENT share of valid-depth pixels (both directions)", si},
          {"UNKNOWN share of valid-depth pixels (both directions)", su}}) {
      h << "<tr><td>" << label << "</td>";
      for (const double Stats::*field : {&Stats::min, &Stats::median, &Stats::mean, &Stats::max}) {
        h << "<td class=\"n\">" << (s ? Num((*s).*field) : kNoValue) << "</td>";
      }
      h << "</tr>\n";
    }
    h << "</table>\n";
  }
  if (split.summary.is_object()) {
    h << "<table><tr><th>summary.json</th><th>value</th></tr>\n";
    // Byte counts also in decimal units: "79.2 MB (79234567)".
    auto shown = [](const std::string& key, const json& v) {
      if (v.is_null()) return std::string(kNoValue);  // e.g. selected_overlap without pairs
      std::string value = JsonScalar(v);
      if (v.is_number() && key.find("bytes") != std::string::npos) {
        value = gt::HumanBytes(v.get<double>()) + " (" + value + ")";
      }
      return value;
    };
    for (auto it = split.summary.begin(); it != split.summary.end(); ++it) {
      if (it.value().is_primitive()) {
        h << "<tr><td>" << HtmlEscape(it.key()) << "</td><td class=\"n\">"
          << HtmlEscape(shown(it.key(), it.value())) << "</td></tr>\n";
      }
    }
    for (const char* group : {"counts", "timings"}) {
      if (!split.summary.contains(group) || !split.summary[group].is_object()) continue;
      for (auto it = split.summary[group].begin(); it != split.summary[group].end(); ++it) {
        if (!it.value().is_primitive()) continue;
        h << "<tr><td>" << group << "." << HtmlEscape(it.key()) << "</td><td class=\"n\">"
          << HtmlEscape(shown(it.key(), it.value())) << "</td></tr>\n";
      }
    }
    h << "</table>\n";
    h << "<table><tr><th>dropped, by reason"
      << (split.summary.contains("drops") ? "" : " (summed over selection/*.json)")
      << "</th><th>pairs or frames</th></tr>\n";
    const json& drops = split.drops;
    if (!drops.is_object() || drops.empty()) {
      h << "<tr><td colspan=\"2\" class=\"muted\">none recorded</td></tr>\n";
    } else {
      for (auto it = drops.begin(); it != drops.end(); ++it) {
        h << "<tr><td>" << HtmlEscape(it.key()) << "</td><td class=\"n\">"
          << HtmlEscape(JsonScalar(it.value())) << "</td></tr>\n";
      }
    }
    h << "</table>\n";
  } else {
    h << "<p class=\"muted\">No summary.json in this folder.</p>\n";
  }
  h << "</div>\n";

  if (split.has_pairs) h << "<h2>Plots</h2>\n<div class=\"plots\">\n";
  for (const auto& p : plots) {
    h << "<figure>" << ImgTag(p, PlotAlt(p.name)) << "<figcaption>" << HtmlEscape(p.name)
      << "</figcaption></figure>\n";
  }
  if (split.has_pairs) h << "</div>\n";
  if (depth_shares) h << DepthSharesSection(*depth_shares);
  h << eval_section;

  if (split.has_pairs) {
    h << "<h2>Gallery</h2>\n<p class=\"muted\">" << gallery.size() << " pairs: ";
    if (options.gallery_order == GalleryOrder::kRandom) {
      h << "picked with seed " << options.seed;
    } else {
      h << "the most occluded (largest occlusion ratio first)";
    }
    h << ". Matches: vv green, vo yellow, ov red. Labels: NO_DEPTH near black, OUT_OF_VIEW "
         "blue, VISIBLE green, OCCLUDED red, INCONSISTENT magenta, UNKNOWN orange.</p>\n";
    for (const auto& g : gallery) {
      h << "<div class=\"pair\"><h3>" << HtmlEscape(g.caption) << "</h3>\n";
      for (const auto& im : g.images) {
        h << "<figure>" << ImgTag(im, g.caption + ": " + im.name) << "<figcaption>"
          << HtmlEscape(im.name) << "</figcaption></figure>\n";
      }
      h << "</div>\n";
    }
  } else {
    h << "<p class=\"muted\">No pairs.jsonl in this folder: the tuples of occgt tuples "
         "only.</p>\n";
  }
  h << tuples_section;
  if (split.recipe.is_object()) {
    h << "<h2>Recipe</h2>\n<p class=\"muted\">recipe.json: the resolved recipe this split was "
         "built with (every default filled in).</p>\n<pre class=\"recipe\">"
      << HtmlEscape(split.recipe.dump(2)) << "</pre>\n";
  }

  // Records how many images decoded (the page needs no script to be read).
  h << "<script>window.addEventListener('load',function(){var a=document.images,k=0;"
       "for(var i=0;i<a.length;i++){if(a[i].complete&&a[i].naturalWidth>0)k++;}"
       "document.body.setAttribute('data-images-decoded',k+'/'+a.length);});</script>\n";
  h << "</body>\n</html>\n";
  return h.str();
}

json ReportJson(const SplitData& split, const SplitReportOptions& options,
                const json& tuples_summary, const std::vector<size_t>& gallery_tuples) {
  // version 2 since occgt 0.2 (consistent_overlap_min); 0.1 wrote no version
  // (visible_overlap_min).
  json out = {{"kind", "occgt-split-report"},
              {"version", 2},
              {"dir", split.dir},
              {"seed", options.seed},
              {"histogram_bins", options.histogram_bins},
              {"pairs", nullptr},
              {"tuples", nullptr}};
  if (split.has_pairs) {
    std::vector<double> ov, oc, vis;
    for (const auto& p : split.pairs) {
      ov.push_back(p.overlap);
      oc.push_back(p.occlusion);
      vis.push_back(p.visible_min);
    }
    auto stats = [](const std::vector<double>& v) {
      const std::optional<Stats> s = Describe(v);
      if (!s) {  // no pair, no statistic (as the tuples' distributions at count 0)
        return json{{"min", nullptr}, {"median", nullptr}, {"mean", nullptr}, {"max", nullptr}};
      }
      return json{{"min", s->min}, {"median", s->median}, {"mean", s->mean}, {"max", s->max}};
    };
    out["pairs"] = {{"count", static_cast<int64_t>(split.pairs.size())},
                    {"aggregate", AggregateName(options.aggregate)},
                    // The recipe's and --occlusion-metric's word, and the metrics field it reads.
                    {"occlusion_metric", OcclusionMetricName(options.occlusion_metric)},
                    {"occlusion_field", OcclusionMetricField(options.occlusion_metric)},
                    {"overlap", stats(ov)},
                    {"occlusion", stats(oc)},
                    {"consistent_overlap_min", stats(vis)}};
  }
  if (split.tuples) {
    json t = tuples_summary;
    t["has_shards"] = split.tuples->has_shards;
    json gallery = json::array();
    for (size_t k : gallery_tuples) {
      const SplitTuple& tuple = split.tuples->tuples[k];
      gallery.push_back({{"index", static_cast<int64_t>(k)},
                         {"scene", tuple.scene},
                         {"frame_ids", tuple.frame_ids}});
    }
    t["gallery"] = gallery;
    out["tuples"] = t;
  }
  return out;
}

const std::vector<std::string>& SplitReportFileNames() {
  static const std::vector<std::string> names = {"overlap_hist.png",
                                                 "occlusion_hist.png",
                                                 "occlusion_cumulative.png",
                                                 "overlap_vs_occlusion.png",
                                                 "pairs_per_scene.png",
                                                 "eval_cumulative.png",
                                                 "eval_auc_by_occlusion.png",
                                                 "eval_auc_by_overlap.png",
                                                 "eval_estimator_disagreement.png",
                                                 "tuple_sizes.png",
                                                 "tuple_covisibility_hist.png",
                                                 "tuple_occlusion_hist.png",
                                                 "depth_sources.json",
                                                 "report.html",
                                                 "report.json"};
  return names;
}

SplitReportFiles WriteSplitReport(const std::string& split_dir, const std::string& out_dir,
                                  const SplitReportOptions& options,
                                  const SplitDepthShares* depth_shares) {
  SplitReportFiles files;
  const SplitData split = LoadSplit(split_dir, options);
  EvalReportData eval;
  if (!options.eval_paths.empty()) eval = LoadEvalReport(options.eval_paths, split);
  std::error_code ec;
  const bool out_existed = fs::exists(out_dir, ec);
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "cannot create the report folder: " + ec.message());
  const std::string scratch = (fs::path(out_dir) / kSplitReportScratch).string();
  fs::remove_all(scratch);
  std::vector<NamedImage> plots, eval_plots, tuple_plots;
  try {
    if (split.has_pairs) plots = MakeSplitPlots(split, options, scratch);
    if (!eval.sets.empty()) eval_plots = MakeEvalPlots(eval, options, scratch);
    if (split.tuples) {
      tuple_plots = MakeTuplePlots(*split.tuples, options.histogram_bins, options.gnuplot,
                                   options.plot_width_px, options.plot_height_px, scratch);
    }
  } catch (...) {
    // Nothing published: no scratch files, and no empty report folder this run created.
    fs::remove_all(scratch, ec);
    if (!out_existed) fs::remove(out_dir, ec);  // only when empty
    throw;
  }
  fs::remove_all(scratch);
  std::string eval_section;
  if (!eval.sets.empty()) {
    const std::vector<EvalGallery> galleries = MakeEvalGalleries(eval, split, options);
    // A gallery that could not be drawn is said on the page and to the caller (stderr).
    for (const EvalGallery& g : galleries) {
      for (const std::string& w : g.warnings) {
        if (w.rfind("No gallery:", 0) == 0) files.warnings.push_back(g.set_label + ": " + w);
      }
    }
    eval_section = RenderEvalSection(eval, eval_plots, galleries);
  }

  std::vector<GalleryItem> gallery;
  for (size_t i : PickGalleryPairs(split, options)) {
    const SplitPair& p = split.pairs[i];
    GalleryItem item;
    char caption[256];
    std::snprintf(caption, sizeof(caption), "%s  (overlap %.3f, occlusion %.3f)", p.key.c_str(),
                  p.overlap, p.occlusion);
    item.caption = caption;
    try {
      const PairData pair = LoadPairFromShard((fs::path(split_dir) / p.shard).string(), p.key);
      // Titles and legends drawn larger by the downscale that follows, so that they read
      // at the size they are shown.
      PairPictureOptions pictures = options.pictures;
      const double text_scale = std::min(4.0, 1.0 / options.gallery_scale);
      pictures.matches.text_scale = pictures.labels.text_scale = pictures.occupancy.text_scale =
          text_scale;
      const PairPictures pics = RenderPair(pair, pictures);
      for (const auto& [mat, label] :
           {std::pair<const cv::Mat*, const char*>{&pics.matches, "matches"},
            {&pics.labels, "labels"},
            {&pics.occupancy, "occupancy"}}) {
        if (mat->empty()) continue;
        cv::Mat small;
        cv::resize(*mat, small, cv::Size(), options.gallery_scale, options.gallery_scale,
                   cv::INTER_AREA);
        item.images.push_back(
            {label, "image/jpeg",
             gt::io::EncodeJpegBytes(small, gt::io::ChannelOrder::kBgr, 85, label)});
      }
    } catch (const InputError& e) {
      item.caption += " — could not be read: " + std::string(e.what());
      files.unreadable.push_back(p.key + ": " + e.what());
    }
    gallery.push_back(std::move(item));
  }

  json tuples_summary;
  std::vector<size_t> gallery_tuples;
  std::string tuples_section;
  if (split.tuples) {
    tuples_summary = SummarizeTuples(*split.tuples, options.histogram_bins);
    gallery_tuples = PickGalleryTuples(*split.tuples, options.gallery_tuples, options.seed);
    const std::vector<TupleGalleryItem> thumbs =
        MakeTupleGallery(*split.tuples, gallery_tuples, options.tuple_thumb_width_px);
    for (const TupleGalleryItem& t : thumbs) {
      if (t.unreadable) {
        files.unreadable.push_back("tuple " + std::to_string(t.index) + ": " + t.note);
      }
    }
    tuples_section =
        RenderTuplesSection(*split.tuples, tuples_summary, tuple_plots, thumbs, options.seed);
  }

  std::vector<std::string>& written = files.written;
  for (const std::vector<NamedImage>* group : {&plots, &eval_plots, &tuple_plots}) {
    for (const auto& p : *group) {
      const std::string path = (fs::path(out_dir) / p.name).string();
      gt::io::WriteFileAtomic(path, p.bytes);
      written.push_back(path);
    }
  }
  if (depth_shares) {
    const std::string path = (fs::path(out_dir) / "depth_sources.json").string();
    gt::io::WriteFileAtomic(path, SplitDepthSharesJson(*depth_shares).dump(2) + "\n");
    written.push_back(path);
  }
  const std::string html_path = (fs::path(out_dir) / "report.html").string();
  gt::io::WriteFileAtomic(html_path, RenderHtmlReport(split, options, plots, gallery, eval_section,
                                                      tuples_section, depth_shares));
  written.push_back(html_path);
  const std::string json_path = (fs::path(out_dir) / "report.json").string();
  gt::io::WriteFileAtomic(
      json_path, ReportJson(split, options, tuples_summary, gallery_tuples).dump(1) + "\n");
  written.push_back(json_path);
  // An earlier run's files that this one does not write (fewer sections: no tuples.jsonl
  // any more, no --eval) would pass for this run's: the report's own names only.
  std::set<std::string> written_names;
  for (const std::string& path : written) {
    written_names.insert(fs::path(path).filename().string());
    GT_ASSERT_MSG(std::count(SplitReportFileNames().begin(), SplitReportFileNames().end(),
                             fs::path(path).filename().string()) == 1,
                  "SplitReportFileNames: a written file is not listed");
  }
  for (const std::string& name : SplitReportFileNames()) {
    if (written_names.count(name) > 0) continue;
    const fs::path path = fs::path(out_dir) / name;
    std::error_code ec;
    if (!fs::is_regular_file(fs::symlink_status(path, ec))) continue;
    if (fs::remove(path, ec)) files.removed.push_back(path.string());
  }
  return files;
}

}  // namespace gt::report

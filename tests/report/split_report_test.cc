// The split report's choices that the pictures do not show directly: the histogram range
// fitted to the data, the gallery's order, the eval section's worst pairs and the warning
// sentences.
#include "libgt/report/split_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/core/interrupted.h"
#include "libgt/io/file_read.h"
#include "libgt/report/eval_report.h"
#include "libgt/report/page.h"
#include "tests/support/test_support.h"

namespace gt::report {
namespace {

TEST(HistogramRange, WidensToMultiplesOfTheStepAroundTheData) {
  EXPECT_EQ(HistogramRange({}), std::make_pair(0.0, 1.0));
  EXPECT_EQ(HistogramRange({NAN, INFINITY}), std::make_pair(0.0, 1.0));
  auto [lo, hi] = HistogramRange({0.012, 0.2046, 0.031});
  EXPECT_DOUBLE_EQ(lo, 0.0);
  EXPECT_DOUBLE_EQ(hi, 0.25);
  std::tie(lo, hi) = HistogramRange({0.41, 0.88});
  EXPECT_DOUBLE_EQ(lo, 0.40);
  EXPECT_DOUBLE_EQ(hi, 0.90);
  // Exactly on a multiple: kept, not widened by a step, and the very double written 0.35
  // (7 * 0.05 is 0.35000000000000003).
  std::tie(lo, hi) = HistogramRange({0.35, 0.6});
  EXPECT_EQ(lo, 0.35);
  EXPECT_EQ(hi, 0.6);
  for (int k = 0; k <= 20; ++k) {
    const double x = k / 20.0;  // the double nearest k·0.05
    EXPECT_EQ(HistogramRange({x}).first, std::min(x, 0.95)) << k;
  }
  // One value (or equal values): one step wide, inside [0, 1].
  std::tie(lo, hi) = HistogramRange({1.0, 1.0});
  EXPECT_DOUBLE_EQ(lo, 0.95);
  EXPECT_DOUBLE_EQ(hi, 1.0);
  std::tie(lo, hi) = HistogramRange({0.0});
  EXPECT_DOUBLE_EQ(lo, 0.0);
  EXPECT_DOUBLE_EQ(hi, 0.05);
  // Out-of-range values are clamped to [0, 1].
  EXPECT_EQ(HistogramRange({-0.5, 1.5}), std::make_pair(0.0, 1.0));
}

TEST(HistogramRange, AlwaysHoldsEveryValue) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int t = 0; t < 2000; ++t) {
    std::vector<double> v(1 + t % 5);
    for (double& x : v) x = u(rng) * u(rng);
    const auto [lo, hi] = HistogramRange(v);
    ASSERT_GE(lo, 0.0);
    ASSERT_LE(hi, 1.0);
    ASSERT_GE(hi - lo, 0.05 - 1e-12);
    for (double x : v) {
      ASSERT_GE(x, lo);
      ASSERT_LE(x, hi);
    }
    // Tight: the range is not a step wider than the data on either side.
    const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
    if (hi - lo > 0.05 + 1e-12) {
      ASSERT_LT(*mn - lo, 0.05);
      ASSERT_LT(hi - *mx, 0.05);
    }
  }
}

TEST(HistogramBin, ValuesOnEdgesLandInTheBinWhoseLeftEdgeTheyAre) {
  // [0.35, 0.6] in 5 bins of 0.05: every edge is the double written as that decimal.
  const std::vector<double> edges = HistogramEdges(HistogramRange({0.35, 0.6}), 5);
  EXPECT_EQ(edges, (std::vector<double>{0.35, 0.4, 0.45, 0.5, 0.55, 0.6}));
  EXPECT_EQ(HistogramBin(0.35, edges), 0);
  EXPECT_EQ(HistogramBin(0.4, edges), 1);  // was bin 0: (0.4 - 0.35) / 0.25 * 5 < 1
  EXPECT_EQ(HistogramBin(0.45, edges), 2);
  EXPECT_EQ(HistogramBin(0.5, edges), 3);
  EXPECT_EQ(HistogramBin(0.55, edges), 4);
  EXPECT_EQ(HistogramBin(0.6, edges), 4);  // the last bin is closed
  EXPECT_EQ(HistogramBin(std::nextafter(0.4, 0.0), edges), 0);
  EXPECT_EQ(HistogramBin(0.42, edges), 1);
  EXPECT_EQ(HistogramBin(0.1, edges), 0);  // outside: the first or last bin
  EXPECT_EQ(HistogramBin(0.9, edges), 4);
  EXPECT_EQ(HistogramBin(NAN, edges), 0);
  // Every multiple of 0.05 in [0, 1] with 20 bins: bin k for k·0.05 (the last one 19).
  const std::vector<double> unit = HistogramEdges({0.0, 1.0}, 20);
  for (int k = 0; k <= 20; ++k) {
    EXPECT_EQ(unit[k], k / 20.0);
    EXPECT_EQ(HistogramBin(k / 20.0, unit), std::min(k, 19)) << k;
    // Written as a decimal literal of that multiple ("0.35"), parsed as a reader would.
    const double parsed = std::stod(std::to_string(k * 5 / 100) + "." +
                                    (k * 5 % 100 < 10 ? "0" : "") + std::to_string(k * 5 % 100));
    EXPECT_EQ(HistogramBin(parsed, unit), std::min(k, 19)) << parsed;
  }
  // 40 bins over [0, 1]: inner edges on 0.025 multiples too.
  const std::vector<double> fine = HistogramEdges({0.0, 1.0}, 40);
  EXPECT_EQ(HistogramBin(0.075, fine), 3);
  EXPECT_EQ(HistogramBin(0.7, fine), 28);
}

SplitPair Pair(const std::string& key, double occlusion) {
  SplitPair p;
  p.scene = "s";
  p.key = key;
  p.shard = "x.tar";
  p.occlusion = occlusion;
  return p;
}

TEST(PickGalleryPairs, MostOccludedFirstTiesInFileOrder) {
  SplitData split;
  split.pairs = {Pair("a", 0.1), Pair("b", 0.5), Pair("c", 0.3), Pair("d", 0.5), Pair("e", 0.0)};
  SplitReportOptions o;
  o.gallery_order = GalleryOrder::kMostOccluded;
  o.gallery_pairs = 3;
  EXPECT_EQ(PickGalleryPairs(split, o), (std::vector<size_t>{1, 3, 2}));
  o.gallery_pairs = 10;
  EXPECT_EQ(PickGalleryPairs(split, o), (std::vector<size_t>{1, 3, 2, 0, 4}));
  // Random: a subset in file order, the same for the same seed.
  o.gallery_order = GalleryOrder::kRandom;
  o.gallery_pairs = 3;
  const auto a = PickGalleryPairs(split, o);
  EXPECT_EQ(a.size(), 3u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(a, PickGalleryPairs(split, o));
  EXPECT_EQ(ParseGalleryOrder("most-occluded", "--gallery-order"), GalleryOrder::kMostOccluded);
  EXPECT_THROW(ParseGalleryOrder("worst", "--gallery-order"), std::exception);
}

TEST(SplitWarnings, SaysWhatMustBeKnown) {
  SplitData split;
  EXPECT_EQ(SplitWarnings(split).size(), 1u);  // no pairs
  split.pairs = {Pair("a", 0.1)};
  EXPECT_TRUE(SplitWarnings(split).empty());
  split.recipe = {{"dataset", {{"format", "tartanair"}}}, {"sample", {{"image", "png"}}}};
  EXPECT_TRUE(SplitWarnings(split).empty());
  split.recipe["dataset"]["format"] = "sevenscenes";
  split.summary = {{"drops", {{"scan.no_color", 4}, {"filter.overlap", 9}}}};
  split.drops = split.summary["drops"];  // as LoadSplit takes them from summary.json
  const auto w = SplitWarnings(split);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("unregistered"), std::string::npos);
  EXPECT_EQ(w[1].rfind("4 frames were skipped", 0), 0u) << w[1];
  split.drops = {{"scan.no_color", 1}, {"import.no_color", 1}};
  const auto one = SplitWarnings(split);
  ASSERT_EQ(one.size(), 3u);
  EXPECT_EQ(one[1].rfind("1 frame was skipped for lack", 0), 0u) << one[1];
  EXPECT_EQ(one[2].rfind("1 imported pair was skipped for lack", 0), 0u) << one[2];
}

// The tuples' words: one tuple of one scene in the singular, and a covisibility range whose
// end is not 1 does not read as 1.
TEST(TuplesSection, SingularAndRangeEndsThatDoNotRoundToTheBound) {
  TupleSet set;
  SplitTuple t;
  t.scene = "s";
  t.frame_ids = {"a", "b"};
  t.covisibility = {1, 0.0704, 0.99958, 1};
  set.tuples = {t};
  const std::vector<TupleGalleryItem> gallery = MakeTupleGallery(set, {0}, 240);
  ASSERT_EQ(gallery.size(), 1u);
  EXPECT_NE(gallery[0].caption.find("(covisibility 0.0704..0.9996)"), std::string::npos)
      << gallery[0].caption;
  const std::string html =
      RenderTuplesSection(set, SummarizeTuples(set, 20), {}, gallery, /*seed=*/0);
  EXPECT_NE(html.find(">1 N-view tuple of 1 scene ("), std::string::npos) << html;
  set.tuples[0].covisibility = {1, 0.5, 1.0, 1};
  EXPECT_NE(MakeTupleGallery(set, {0}, 240)[0].caption.find("(covisibility 0.5..1)"),
            std::string::npos);
}

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// The pairs' table rows of the page: "<tr><td>label</td><td class="n">..</td>...</tr>".
std::vector<std::string> TableRowsAfter(const std::string& html, const std::string& heading) {
  std::vector<std::string> rows;
  size_t at = html.find(heading);
  const size_t end = html.find("</table>", at);
  while (at != std::string::npos && (at = html.find("<tr><td>", at)) < end) {
    const size_t stop = html.find("</tr>", at);
    rows.push_back(html.substr(at, stop - at));
    at = stop;
  }
  return rows;
}

// A build whose selection kept no pair (occgt build writes an empty pairs.jsonl, its
// summary.json and recipe.json): no statistic is shown as a number, the score grid's stride
// is the recipe's, summary.json's nulls read as such and the scenes without pairs count.
TEST(EmptySplit, ShowsNoValueWhereReportJsonHasNullAndTheRecipesCounts) {
  const std::string dir = test::ScratchDir("report_empty_split");
  WriteText(dir + "/pairs.jsonl", "");
  WriteText(dir + "/summary.json",
            R"({"split": "e", "scenes": 2, "pairs_per_scene": {"s0": 0, "s1": 0},)"
            R"( "selected_overlap": null, "selected_occlusion": null, "drops": {}})");
  WriteText(dir + "/recipe.json", R"({"selection": {"score_stride": 4}})");
  SplitReportOptions o;
  const SplitData split = LoadSplit(dir, o);
  EXPECT_TRUE(split.pairs.empty());
  EXPECT_EQ(split.score_stride, 4);
  const std::string html = RenderHtmlReport(split, o, {}, {});
  const std::vector<std::string> rows = TableRowsAfter(html, "<th>selected pairs");
  ASSERT_EQ(rows.size(), 7u);
  const nlohmann::json report = ReportJson(split, o, nullptr, {});
  for (const char* field : {"overlap", "occlusion", "consistent_overlap_min"}) {
    for (const char* stat : {"min", "median", "mean", "max"}) {
      EXPECT_TRUE(report["pairs"][field][stat].is_null()) << field << "." << stat;
    }
  }
  for (const std::string& row : rows) {
    EXPECT_EQ(row.find("<td class=\"n\">0</td>"), std::string::npos) << row;
    size_t dashes = 0;
    for (size_t at = 0; (at = row.find("<td class=\"n\">—</td>", at)) != std::string::npos; ++at) {
      ++dashes;
    }
    EXPECT_EQ(dashes, 4u) << row;
  }
  EXPECT_NE(rows[3].find("score_stride 4;"), std::string::npos) << rows[3];
  for (const char* key : {"selected_overlap", "selected_occlusion"}) {
    EXPECT_NE(html.find(std::string("<tr><td>") + key + "</td><td class=\"n\">—</td>"),
              std::string::npos)
        << key;
  }
  EXPECT_EQ(html.find(">null<"), std::string::npos);
  // The plots: every scene of summary.json's pairs_per_scene, with its 0 pairs.
  const std::string scratch = dir + "/plots";
  MakeSplitPlots(split, o, scratch);
  const std::string script = io::ReadFileBytes(scratch + "/plots.gp");
  EXPECT_NE(script.find("Pairs per scene (2 of 2 scenes)"), std::string::npos);
  EXPECT_EQ(io::ReadFileBytes(scratch + "/scenes.dat"), "0 0 \"s0\"\n1 0 \"s1\"\n");
  // A recipe whose stride is not a positive integer: named.
  WriteText(dir + "/recipe.json", R"({"selection": {"score_stride": "4"}})");
  try {
    LoadSplit(dir, o);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("recipe.json: selection.score_stride: expected a "
                                         "positive integer"),
              std::string::npos)
        << e.what();
  }
}

// A re-run with fewer sections (tuples.jsonl gone, no --eval) removes the report's own files
// it does not write, and no other file of the folder.
TEST(WriteSplitReport, RemovesItsOwnFilesThatThisRunDoesNotWrite) {
  const std::string dir = test::ScratchDir("report_stale_files");
  const std::string out = dir + "/report";
  WriteText(dir + "/pairs.jsonl", "");
  WriteText(dir + "/tuples.jsonl",
            R"({"scene": "s", "frame_ids": ["a", "b"], "covisibility": [[1, 0.5], [0.4, 1]],)"
            R"( "occlusion": 0.2})"
            "\n");
  SplitReportOptions o;
  const SplitReportFiles first = WriteSplitReport(dir, out, o);
  for (const char* name :
       {"tuple_sizes.png", "tuple_covisibility_hist.png", "tuple_occlusion_hist.png"}) {
    ASSERT_TRUE(io::FileExists(out + "/" + name)) << name;
  }
  EXPECT_TRUE(first.removed.empty());
  // An earlier run's eval plot and depth shares, and the user's own files.
  for (const char* name : {"eval_cumulative.png", "depth_sources.json", "notes.txt", "mine.png"}) {
    WriteText(out + "/" + name, "x");
  }
  std::filesystem::remove(dir + "/tuples.jsonl");
  const SplitReportFiles second = WriteSplitReport(dir, out, o);
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(out)) {
    left.push_back(e.path().filename().string());
  }
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"mine.png", "notes.txt", "occlusion_cumulative.png",
                                            "occlusion_hist.png", "overlap_hist.png",
                                            "overlap_vs_occlusion.png", "pairs_per_scene.png",
                                            "report.html", "report.json"}));
  EXPECT_EQ(second.removed.size(), 5u);
  // Every file written is one of the report's names.
  for (const std::string& path : second.written) {
    const std::string name = std::filesystem::path(path).filename().string();
    EXPECT_EQ(std::count(SplitReportFileNames().begin(), SplitReportFileNames().end(), name), 1)
        << name;
  }
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// Occlusion ratios of a few percent (the demo's lie in [0, 0.06]): the cumulative curve and
// the tuples' occlusion histogram span the data's range (HistogramRange), not [0, 1].
TEST(Charts, OcclusionChartsSpanTheRangeOfTheData) {
  const std::string dir = test::ScratchDir("report_chart_ranges");
  SplitData split;
  split.dir = dir;
  split.pairs = {Pair("a", 0.01), Pair("b", 0.057)};
  SplitReportOptions o;
  MakeSplitPlots(split, o, dir + "/pairs");
  const std::string script = io::ReadFileBytes(dir + "/pairs/plots.gp");
  EXPECT_NE(script.find("set output 'occlusion_cumulative.png'\nset xrange [0:0.1]\n"),
            std::string::npos)
      << script;
  const std::vector<std::string> curve = Lines(io::ReadFileBytes(dir + "/pairs/cumulative.dat"));
  EXPECT_EQ(curve, (std::vector<std::string>{"0 0", "0.01 1", "0.057 2", "0.1 2"}));
  // The scatter's x is the overlap: [0, 1] again.
  EXPECT_NE(script.find("set xlabel 'overlap'\nset ylabel \"occlusion ratio (OCCLUDED / W*H)\"\n"
                        "set xrange [0:1]"),
            std::string::npos);

  TupleSet tuples;
  tuples.dir = dir;
  for (double occ : {0.02, 0.07}) {
    SplitTuple t;
    t.scene = "s";
    t.frame_ids = {"a", "b"};
    t.covisibility = {1, 0.5, 0.4, 1};
    t.graph_estimate = occ;
    tuples.tuples.push_back(t);
  }
  MakeTuplePlots(tuples, 20, "gnuplot", 800, 480, dir + "/tuples");
  const std::string tscript = io::ReadFileBytes(dir + "/tuples/tuples.gp");
  EXPECT_NE(tscript.find("set xlabel 'occlusion_ratio_visible'"), std::string::npos) << tscript;
  EXPECT_NE(tscript.find("20 bins over [0, 0.1]"), std::string::npos) << tscript;
  EXPECT_NE(tscript.find("set xrange [0:0.1]"), std::string::npos) << tscript;
  // 20 bins of 0.005 over [0, 0.1]: 0.02 starts bin 4, 0.07 bin 14.
  const std::vector<std::string> hist =
      Lines(io::ReadFileBytes(dir + "/tuples/tuple_occlusion_graph_estimate.dat"));
  ASSERT_EQ(hist.size(), 20u);
  for (size_t b = 0; b < hist.size(); ++b) {
    const std::string count = hist[b].substr(hist[b].find(' ') + 1);
    EXPECT_EQ(count, b == 4 || b == 14 ? "1" : "0") << hist[b];
  }
}

// The eval's cumulative curve sampled at a --curve-step not below the largest ratio is one
// point: the plot says so, with the step that would show the data, and spans the points.
TEST(Charts, EvalCurveOfOnePointSaysWhy) {
  const std::string dir = test::ScratchDir("report_eval_curve");
  EvalReportData data;
  data.auc_thresholds_deg = {5, 10, 20};
  data.occlusion_definition = "image";
  data.occlusion_bins = {0, 0.5, 1};
  data.consistent_overlap_bins = {0, 1};
  data.estimator_names = {"opencv-ransac"};
  EvalSetView v;
  v.label = "m";
  v.eval_path = dir + "/eval.json";
  const nlohmann::json bin = {{"pairs", 2}, {"pose", {{{"auc_percent", {1.0, 2.0, 3.0}}}}}};
  v.set = {{"cumulative",
            {{"image", {{{"max_occlusion", 0.05}, {"mean_error_deg", {2.5}}, {"pairs", 2}}}}}},
           {"by_occlusion", {{"image", {bin, bin}}}},
           {"by_consistent_overlap", {bin}}};
  v.options = {{"curve_step", 0.05}, {"estimators", {{{"name", "opencv-ransac"}}}}};
  v.occlusion = {0.01, 0.04};
  data.sets = {v};
  SplitReportOptions o;
  MakeEvalPlots(data, o, dir);
  const std::string script = io::ReadFileBytes(dir + "/eval.gp");
  EXPECT_NE(script.find("1 point: occgt eval --curve-step 0.05, largest ratio 0.04; "
                        "--curve-step 0.004 gives about 10"),
            std::string::npos)
      << script;
  EXPECT_NE(script.find("set xrange [0:0.05]"), std::string::npos) << script;
}

// The depth sources table shows every category of depth_sources.json (neither too: the
// shares add up to 1) with its pixel count.
TEST(DepthSources, TableShowsEveryCategoryWithItsCountAndShare) {
  SplitDepthShares d;
  d.frames = 2;
  d.width = 4;
  d.height = 5;
  d.total.sensor_only = 3;
  d.total.mesh_only = 5;
  d.total.agree = 20;
  d.total.disagree = 4;
  d.total.neither = 8;  // 40 pixels
  d.scenes = {{"s", 2, d.total}};
  SplitData split;
  split.pairs = {Pair("a", 0.1)};
  const std::string html = RenderHtmlReport(split, SplitReportOptions(), {}, {}, "", "", &d);
  const nlohmann::ordered_json j = SplitDepthSharesJson(d);
  std::string header = "<tr><th>scene</th><th>frames</th><th>pixels</th>";
  std::string row = "<tr><td>all (split)</td><td class=\"n\">2</td><td class=\"n\">" +
                    std::to_string(j["total"]["pixels"].get<int64_t>()) + "</td>";
  double shares = 0;
  for (const char* name : {"sensor_only", "mesh_only", "agree", "disagree", "neither"}) {
    ASSERT_TRUE(j["total"].contains(name)) << name;
    header += std::string("<th>") + name + "</th>";
    const int64_t count = j["total"][name].get<int64_t>();
    const double share = static_cast<double>(count) / j["total"]["pixels"].get<int64_t>();
    char cell[64];
    std::snprintf(cell, sizeof(cell), "<td class=\"n\">%lld (%.4f)</td>",
                  static_cast<long long>(count), share);
    row += cell;
    shares += share;
  }
  EXPECT_NEAR(shares, 1.0, 1e-12);
  EXPECT_NE(html.find(header + "</tr>"), std::string::npos) << html;
  EXPECT_NE(html.find(row + "</tr>"), std::string::npos) << row;
  EXPECT_NE(html.find("<tr><td>s</td>"), std::string::npos);
}

// gnuplot missing or failing: an InputError that names no deleted file, and no empty report
// folder left behind (an existing one stays, without the scratch folder).
TEST(WriteSplitReport, GnuplotFailureLeavesNoNewFolderAndNamesNoDeletedScript) {
  const std::string dir = test::ScratchDir("report_gnuplot_fails");
  WriteText(dir + "/pairs.jsonl", "");
  for (const char* gnuplot : {"/bin/false", "no-such-gnuplot-for-occgt-tests"}) {
    SplitReportOptions o;
    o.gnuplot = gnuplot;
    const std::string out = dir + "/report";
    try {
      WriteSplitReport(dir, out, o);
      ADD_FAILURE() << "expected an InputError with " << gnuplot;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).find(".plots.tmp"), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("gnuplot: ", 0), 0u) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out)) << gnuplot;
    std::filesystem::create_directories(out);
    EXPECT_THROW(WriteSplitReport(dir, out, o), InputError);
    EXPECT_TRUE(std::filesystem::is_directory(out));
    EXPECT_TRUE(std::filesystem::is_empty(out));
    std::filesystem::remove(out);
  }
}

// gnuplot ended by a signal: Ctrl-C (SIGINT to the process group, which std::system ignores
// in occgt meanwhile) or SIGTERM is gt::Interrupted, not a broken script (it was "failed on
// the generated plots.gp script", exit 1); another signal (a crash) names the signal. No
// report folder is left either way.
TEST(WriteSplitReport, GnuplotEndedByASignalIsInterruptedNotAScriptFailure) {
  const std::string dir = test::ScratchDir("report_gnuplot_signal");
  WriteText(dir + "/pairs.jsonl", "");
  for (const int signal_number : {SIGINT, SIGTERM, SIGSEGV}) {
    const std::string gnuplot = dir + "/gnuplot-" + std::to_string(signal_number);
    WriteText(gnuplot, "#!/bin/sh\nkill -" + std::to_string(signal_number) + " $$\n");
    std::filesystem::permissions(gnuplot, std::filesystem::perms::owner_all);
    SplitReportOptions o;
    o.gnuplot = gnuplot;
    const std::string out = dir + "/report";
    try {
      WriteSplitReport(dir, out, o);
      ADD_FAILURE() << "expected an exception with signal " << signal_number;
    } catch (const Interrupted& e) {
      EXPECT_NE(signal_number, SIGSEGV) << e.what();
      EXPECT_EQ(e.signal_number(), signal_number);
      EXPECT_EQ(std::string(e.what()),
                "gnuplot ended by " + std::string(signal_number == SIGINT ? "SIGINT" : "SIGTERM"));
    } catch (const InputError& e) {
      EXPECT_EQ(signal_number, SIGSEGV) << e.what();
      EXPECT_NE(std::string(e.what()).find("was killed by signal 11"), std::string::npos)
          << e.what();
      EXPECT_EQ(std::string(e.what()).find("script"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out)) << signal_number;
  }
}

// Every plot the report can write has an alt text saying what it shows (the file name was
// the alt text).
TEST(SplitReportFileNames, EveryPlotHasADescription) {
  int plots = 0;
  for (const std::string& name : SplitReportFileNames()) {
    if (name.size() < 4 || name.compare(name.size() - 4, 4, ".png") != 0) continue;
    EXPECT_NE(PlotAlt(name), name) << name;
    ++plots;
  }
  EXPECT_EQ(plots, 12);
  EXPECT_EQ(PlotAlt("other.png"), "other.png");
}

TEST(PickWorstPairs, FailuresFirstThenLargestErrorThenLowestEpipolarPrecision) {
  EvalSetView v;
  const double inf = INFINITY;
  v.error_deg = {3.0, inf, 10.0, 10.0, inf, 50.0};
  v.epipolar = {0.9, 0.5, 0.8, 0.2, 0.1, 0.7};
  v.predicted = {true, true, true, true, false, true};  // pair 4 has no prediction
  EXPECT_EQ(PickWorstPairs(v, 10), (std::vector<size_t>{1, 5, 3, 2, 0}));
  EXPECT_EQ(PickWorstPairs(v, 2), (std::vector<size_t>{1, 5}));
  EXPECT_TRUE(PickWorstPairs(v, 0).empty());
}

}  // namespace
}  // namespace gt::report

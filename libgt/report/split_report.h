// A report of one split written by `occgt build` (`occgt inspect split DIR`): plots made
// with gnuplot and a self-contained HTML page.
//
// Input (SHARDS.md, libgt/shards/split.h): DIR/pairs.jsonl, one JSON object per pair with
// "scene", "frame0"/"frame1" ({id, number}), "metrics": {"01": {...}, "10": {...}}
// (DirectionMetrics on every pixel: "overlap", "occlusion_ratio", "occlusion_ratio_visible",
// ...), "score_stride" and "score_metrics" (the same on the selection's grid), "shard" (file name
// relative to DIR) and "key"; DIR/summary.json (counts per stage, "drops" by reason,
// "pairs_per_scene", ...), optional.
// Pair values: overlap and occlusion ratio of both directions, combined with
// `aggregate` (min, mean or max; GROUND_TRUTH.md §3); occlusion is "image" (OCCLUDED /
// W·H, the paper's) or "visible" (OCCLUDED / (VISIBLE + OCCLUDED), the released code's).
//
// Plots (PNG, gnuplot's pngcairo terminal driven through a generated script, data in
// temporary files next to the outputs): overlap_hist.png, occlusion_hist.png,
// occlusion_cumulative.png (number of pairs with occlusion ratio <= x, the curve of the
// Occ²Net paper), overlap_vs_occlusion.png (scatter), pairs_per_scene.png (bars; the 60
// scenes with most pairs when there are more).
// report.html: inline CSS (screen and print), every image embedded as a base64 data URI,
// no network; a one-line inline script only records in <body data-images-decoded="k/n">
// how many images decoded (used by the tests). Gallery: `gallery_pairs` pairs picked with
// a seeded hash of their keys (same split and seed → same pairs), rendered from the shards
// with pair_source.h / pictures.h.
// Tuples (tuples_report.h): when DIR holds the tuples.jsonl of `occgt tuples`, a section with
// their sizes, covisibility and occlusion and a gallery of `gallery_tuples` tuples; such a
// folder needs no pairs.jsonl (a folder of `occgt covis` + `occgt tuples` only).
// report.json: the numbers of the page (schemas/report.schema.json): the pairs' statistics
// (null without pairs.jsonl) and the tuples' (SummarizeTuples and the gallery; null without
// tuples.jsonl).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "libgt/geometry/aggregate.h"
#include "libgt/render/frame_depth.h"
#include "libgt/report/page.h"
#include "libgt/report/pair_source.h"
#include "libgt/report/tuples_report.h"

namespace gt::report {

struct SplitPair {
  std::string scene, frame0, frame1, shard, key;
  double overlap01 = 0, overlap10 = 0;      // DirectionMetrics::overlap
  double occlusion01 = 0, occlusion10 = 0;  // occlusion_ratio or occlusion_ratio_visible
  double overlap = 0, occlusion = 0;        // combined with the aggregate
  // The same from score_metrics (the selection's grid, every score_stride-th pixel).
  double score_overlap = 0, score_occlusion = 0;
  // DirectionMetrics::consistent_overlap (VISIBLE / sampled) of each direction, and of the
  // weaker direction (min: the default of selection.visible_aggregate).
  double visible01 = 0, visible10 = 0, visible_min = 0;
  // INCONSISTENT and UNKNOWN pixels of both directions over their valid-depth pixels (the
  // depth errors of MVS data such as MegaDepth; 0 when no pixel has depth).
  double inconsistent_share = 0, unknown_share = 0;
};

struct SplitData {
  std::string dir;
  std::vector<SplitPair> pairs;  // pairs.jsonl order
  // Of every line's score_metrics; without a line, recipe.json's selection.score_stride
  // (0: neither).
  int score_stride = 0;
  nlohmann::json summary;  // summary.json, null when absent
  // Drops by reason: summary.json's, else (the summary `occgt merge` writes has none) summed
  // over selection/<scene>.json; an empty object when neither has them.
  nlohmann::json drops;
  nlohmann::json recipe;           // recipe.json (the resolved recipe), null when absent
  bool has_pairs = true;           // false: no pairs.jsonl (a folder of tuples only)
  std::optional<TupleSet> tuples;  // tuples.jsonl (+ views/pairs.jsonl), when present
};

// What a reader of the report must know before trusting the split, one sentence each: no
// pairs, no images stored, frames skipped for lack of colour, and the dataset's caveats
// (gt::datasets::DatasetCaveats of recipe.json's dataset.format). Empty when none applies.
std::vector<std::string> SplitWarnings(const SplitData& split);

// Which pairs the gallery shows: a seeded random choice, or the most occluded ones (largest
// pair occlusion ratio first, ties by pairs.jsonl order).
enum class GalleryOrder { kRandom, kMostOccluded };
GalleryOrder ParseGalleryOrder(const std::string& text, const std::string& field);
const char* GalleryOrderName(GalleryOrder order);

struct SplitReportOptions {
  Aggregate aggregate = Aggregate::kMean;
  OcclusionMetric occlusion_metric = OcclusionMetric::kImage;
  int histogram_bins = 20;  // bins over the data's range (multiples of 0.05), 1..200
  int gallery_pairs = 6;    // pairs rendered in the gallery, 0..100
  uint64_t seed = 0;        // gallery choice (kRandom)
  GalleryOrder gallery_order = GalleryOrder::kRandom;
  double gallery_scale = 0.5;       // gallery pictures resized by this (0, 1]
  std::string gnuplot = "gnuplot";  // executable (PATH lookup)
  int plot_width_px = 800, plot_height_px = 480;
  PairPictureOptions pictures;
  // The evaluation section (eval_report.h): eval.json files of `occgt eval` on this split,
  // and the worst pairs shown per prediction set (0..50).
  std::vector<std::string> eval_paths;
  int eval_gallery_pairs = 4;
  // The tuples section: tuples shown in its gallery (0..50) and the thumbnails' width.
  int gallery_tuples = 4;
  int tuple_thumb_width_px = 240;  // 32..1024
  bool Check(std::string* error) const;
};

// Reads DIR/pairs.jsonl (required unless DIR/tuples.jsonl exists), DIR/summary.json
// (optional) and the tuples (LoadTupleSet). Throws InputError
// naming "<file>:<line>" and the field on malformed content.
SplitData LoadSplit(const std::string& dir, const SplitReportOptions& options);

// The x range of a histogram that fits the data: [min, max] of the finite values widened
// to multiples of 0.05 inside [0, 1], at least 0.05 wide; [0, 1] when there is no value.
std::pair<double, double> HistogramRange(const std::vector<double>& values);
// The bins + 1 edges of `bins` equal bins over a HistogramRange, each the double nearest its
// exact value (over [0.35, 0.6] with 5 bins: 0.35, 0.4, 0.45, 0.5, 0.55, 0.6 as written).
std::vector<double> HistogramEdges(std::pair<double, double> range, int bins);
// The bin of v among those edges: bins are left-closed, [e_k, e_k+1), the last one closed,
// so that a value on an inner edge lands in the bin whose left edge it is; values outside
// the range (and NaN) go to the first or last bin.
int HistogramBin(double v, const std::vector<double>& edges);

// Runs gnuplot once; returns the plots in the order listed above. Throws
// InputError("gnuplot", ...) when gnuplot is missing or fails (its first error line).
std::vector<NamedImage> MakeSplitPlots(const SplitData& split, const SplitReportOptions& options,
                                       const std::string& scratch_dir);

// Indices into split.pairs of the gallery, at most options.gallery_pairs: increasing for
// kRandom, most occluded first for kMostOccluded.
std::vector<size_t> PickGalleryPairs(const SplitData& split, const SplitReportOptions& options);

// Where the depth of a split came from, when its build rendered it (recipe.json
// dataset.depth_source mesh or fused; docs/GROUND_TRUTH.md "Depth sources"): the
// sensor-vs-mesh counts of every frame used by the split's pairs at the working resolution
// (truth::CompareWorkingDepthWithMesh, the counts of `occgt scan --mesh`), summed per scene
// and over the split. pipeline::ComputeSplitDepthShares fills it.
struct SplitDepthShares {
  render::DepthSourceMode source = render::DepthSourceMode::kFused;
  render::FusedDepthOptions tolerance;
  int width = 0, height = 0;  // working resolution of the counts
  struct Scene {
    std::string name;
    int64_t frames = 0;  // distinct frames of the split's pairs in this scene
    render::DepthAgreement counts;
  };
  std::vector<Scene> scenes;  // sorted by name
  int64_t frames = 0;
  render::DepthAgreement total;
};

// depth_sources.json (schemas/split_depth_sources.schema.json): {source, tolerance, resolution,
// frames, total, scenes}, counts and shares as truth::DepthAgreementJson writes them.
nlohmann::ordered_json SplitDepthSharesJson(const SplitDepthShares& shares);

struct GalleryItem {
  std::string caption;             // key and metrics
  std::vector<NamedImage> images;  // matches, labels, occupancy (when present)
};

// The HTML page (deterministic for the same inputs); eval_section (RenderEvalSection) is
// placed after the plots when not empty, tuples_section (RenderTuplesSection) after the
// pairs' gallery.
std::string RenderHtmlReport(const SplitData& split, const SplitReportOptions& options,
                             const std::vector<NamedImage>& plots,
                             const std::vector<GalleryItem>& gallery,
                             const std::string& eval_section = "",
                             const std::string& tuples_section = "",
                             const SplitDepthShares* depth_shares = nullptr);

// report.json (the layout above).
nlohmann::json ReportJson(const SplitData& split, const SplitReportOptions& options,
                          const nlohmann::json& tuples_summary,
                          const std::vector<size_t>& gallery_tuples);

// Everything: plots as PNG files (with options.eval_paths, the eval plots too; with tuples,
// theirs), report.html and report.json, into out_dir (atomic writes), and with depth_shares
// depth_sources.json and a "Depth sources" section. The eval files are checked before any
// work. A gallery pair or tuple that cannot be read is shown with its error on the page and
// listed in `unreadable` (the report is still written).
struct SplitReportFiles {
  std::vector<std::string> written;     // paths written
  std::vector<std::string> removed;     // an earlier run's files this run does not write
  std::vector<std::string> unreadable;  // "<pair key>: <error>", "tuple <k>: <error>"
  std::vector<std::string> warnings;    // "<eval set>: No gallery: ..." (also on the page)
};
// Every file name WriteSplitReport may write into out_dir (plots of the pairs, of the eval
// section and of the tuples, depth_sources.json, report.html, report.json). A run removes
// those of this list it did not write (an earlier run's tuple or eval plots would pass for
// this run's); no other file of out_dir is touched.
const std::vector<std::string>& SplitReportFileNames();
// The folder of out_dir that holds gnuplot's data, script and plots while they are made
// (removed, with its files, before the report's files are written, and when a run fails).
// Besides it a run writes only the files above, each through "<name>.tmp".
inline constexpr char kSplitReportScratch[] = ".plots.tmp";
SplitReportFiles WriteSplitReport(const std::string& split_dir, const std::string& out_dir,
                                  const SplitReportOptions& options,
                                  const SplitDepthShares* depth_shares = nullptr);

}  // namespace gt::report

// The tuples section of the split report (`occgt inspect split DIR`, docs/INSPECT.md): the
// N-view tuples of `occgt tuples` in DIR, their sizes, the covisibility inside them, their
// occlusion and a gallery of a few of them.
//
// Inputs (docs/MULTIVIEW.md, docs/FORMATS.md):
//   DIR/tuples.jsonl        one tuple per line (schemas/tuples_line.schema.json): scene,
//                           frame_ids [N], covisibility N×N, "occlusion" with
//                           selection.tuples.balance_occlusion (the graph's estimate)
//   DIR/views/pairs.jsonl   optional, with `occgt tuples --shards`: one line per sample,
//                           "tuple_index" (the line of tuples.jsonl, 0-based), "frame_ids",
//                           "occlusion_ratio_visible" (the N-view ground truth: OCCLUDED bits
//                           over VISIBLE + OCCLUDED bits of the ordered pairs i != j; named
//                           "occluded_fraction" before 0.2, still read), "shard", "key"
// Values:
//   sizes                   tuples per N
//   covisibility            every off-diagonal entry [a][b], a != b, of every tuple: the
//                           visible overlap of view a in view b (directed; N·(N−1) per tuple)
//   occlusion               per tuple, from each source present: "ground_truth"
//                           (views/pairs.jsonl occlusion_ratio_visible) and "graph_estimate"
//                           (tuples.jsonl occlusion)
// Histograms: `bins` equal bins over [0, 1]; value v falls in bin min(floor(v · bins), bins − 1).
// Gallery: the `count` tuples with the smallest SplitMix64(SplitMix64(seed) ^ FNV-1a-64(id))
// where id = "<scene>:<frame id>,<frame id>,..." (same tuples and seed → same choice, whether
// or not the shards exist), shown in tuples.jsonl order; each view's thumbnail comes from the
// N-view shard sample (its image, else its depth in grey), the pixels occluded in at least one
// other view of the tuple tinted red.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libgt/report/page.h"

namespace gt::report {

struct SplitTuple {
  std::string scene;
  std::vector<std::string> frame_ids;    // N
  std::vector<double> covisibility;      // [N, N] row-major
  std::optional<double> graph_estimate;  // tuples.jsonl "occlusion"
  // From views/pairs.jsonl (N-view shards), when present.
  std::optional<double> ground_truth;  // occlusion_ratio_visible
  std::string shard, key;              // shard file relative to DIR/views, sample key
};

struct TupleSet {
  std::string dir;                 // DIR
  std::vector<SplitTuple> tuples;  // tuples.jsonl order
  bool has_shards = false;         // views/pairs.jsonl was read
};

// DIR/tuples.jsonl and, when present, DIR/views/pairs.jsonl; nullopt when there is no
// tuples.jsonl. Throws InputError naming "<file>:<line>" and the field on malformed content,
// and when a views line names another tuple than tuples.jsonl's line of its tuple_index.
std::optional<TupleSet> LoadTupleSet(const std::string& dir);

// The numbers of the section (report.json's "tuples", schemas/report.schema.json):
// {"count", "scenes", "sizes": {"<N>": count}, "covisibility": {"count", "min", "median",
//  "mean", "max", "histogram": [bins]}, "occlusion": {"<source>": {same}}}.
nlohmann::json SummarizeTuples(const TupleSet& set, int bins);

// Indices into set.tuples of the gallery (rule above), increasing.
std::vector<size_t> PickGalleryTuples(const TupleSet& set, int count, uint64_t seed);

// Plots (one gnuplot run in scratch_dir): tuple_sizes.png, tuple_covisibility_hist.png and,
// when a source of occlusion exists, tuple_occlusion_hist.png.
std::vector<NamedImage> MakeTuplePlots(const TupleSet& set, int bins, const std::string& gnuplot,
                                       int width_px, int height_px, const std::string& scratch_dir);

struct TupleGalleryItem {
  size_t index = 0;               // into set.tuples
  std::string caption;            // scene, frames, covisibility and occlusion
  std::vector<NamedImage> views;  // one thumbnail per view (empty without shards)
  std::string note;               // why there are no thumbnails, when there are none
  bool unreadable = false;        // the note is a read error (the shard or sample is bad)
};

// Thumbnails of `indices` at most thumb_width_px wide (JPEG).
std::vector<TupleGalleryItem> MakeTupleGallery(const TupleSet& set,
                                               const std::vector<size_t>& indices,
                                               int thumb_width_px);

// The HTML section (<h2>Tuples</h2> ...), deterministic for the same inputs.
std::string RenderTuplesSection(const TupleSet& set, const nlohmann::json& summary,
                                const std::vector<NamedImage>& plots,
                                const std::vector<TupleGalleryItem>& gallery, uint64_t seed);

}  // namespace gt::report

// JSON records and output folders of one pair's ground truth: the metrics object used by
// every output (sample .json, pairs.jsonl, selection lines, meta.json), and the folders
// that `occgt pair` and `occgt occupancy` write (docs/GROUND_TRUTH.md, docs/OCCUPANCY.md).
//
// `occgt pair` folder: label01.npy, label10.npy (uint8 [H, W]), matches.npy (int32 [M, 2]),
// match_type.npy (uint8 [M]), match_xy.npy (float32 [M, 2]), cells0.npy, cells1.npy (uint8
// [H/s, W/s]) and meta.json (schemas/pair_meta.schema.json).
// `occgt occupancy` folder: occ0.npy, known0.npy, occ1.npy, known1.npy (uint64 [H/2, W/2]),
// with `dense` also occ0_dense.npy, occ1_dense.npy (uint8 [D, H/2, W/2]: 0 free, 1 occupied,
// 255 unknown; a shard's member names, occupancy0/1.npy before) and occupancy.json
// (schemas/occupancy.schema.json; the bin edges "bins"."edges_m", as a sample's
// "occupancy"."bins"."edges_m").
// Every file is published atomically (io/atomic_file.h).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libgt/geometry/labels.h"
#include "libgt/truth/pair_truth.h"

namespace gt::truth {

// {sampled, valid, counts: {NO_DEPTH: n, ...}, overlap, consistent_overlap, occlusion_ratio,
//  occlusion_ratio_visible} (GROUND_TRUTH.md §3).
template <typename Json = nlohmann::json>
Json MetricsJson(const DirectionMetrics& m) {
  Json counts = Json::object();
  for (int k = 0; k < kNumPixelLabels; ++k) {
    counts[PixelLabelName(static_cast<PixelLabel>(k))] = m.counts[k];
  }
  return Json{{"sampled", m.sampled},
              {"valid", m.valid},
              {"counts", counts},
              {"overlap", m.overlap},
              {"consistent_overlap", m.consistent_overlap},
              {"occlusion_ratio", m.occlusion_ratio},
              {"occlusion_ratio_visible", m.occlusion_ratio_visible}};
}
// Inverse of MetricsJson (the ratios recomputed from the counts); throws
// nlohmann::json::exception on a missing field.
DirectionMetrics MetricsFromJson(const nlohmann::json& j);

// Rows of a matrix as nested arrays.
nlohmann::json MatrixJson(const Eigen::MatrixXd& m);

// The label and patch options as every output records them ("label_options",
// "patch_options": {stride, anchor, mutual}).
nlohmann::ordered_json LabelOptionsJson(const LabelOptions& lo);
nlohmann::ordered_json PatchOptionsJson(const PatchOptions& po);
// The occupancy options ("occupancy_options"): {mode, bins: {num_bins, near_m, far_m,
// spacing, traversal}, fusion: {scope, voxel_m, max_range_m, downsample,
// remove_outliers[, outlier_k, outlier_stddev when remove_outliers]}}; occupancy.json's "mode",
// "bins" and "fusion" use the same names.
nlohmann::ordered_json OccupancyOptionsJson(const PairTruthOptions& o);
// What happened to the points of a fusion (occupancy::FusionStats, summed over its frames):
// {frames, pixels, invalid_pixels, out_of_key_range, after_downsample, downsample_fallbacks,
// outliers_removed, inserted_points}; occupancy.json's "fusion"."stats", a sample's
// "occupancy"."fusion_stats" and Python's "fusion_stats" use these names.
nlohmann::ordered_json FusionStatsJson(const occupancy::FusionStats& s);

// A sensor-vs-mesh comparison (render::DepthAgreement) as render.json, `occgt scan --mesh` and
// the split report's depth_sources.json record it: {pixels, sensor_only, mesh_only, agree,
// disagree, neither} pixel counts (pixels = their sum) and "shares" {sensor_only, mesh_only,
// agree, disagree}, those counts as fractions of pixels.
nlohmann::ordered_json DepthAgreementJson(const render::DepthAgreement& a);

// Where a pair came from, for the records.
struct PairSource {
  DatasetFormat format = DatasetFormat::kGeneric;
  std::string scene;                 // scene name
  std::string id0, id1;              // frame ids
  int64_t number0 = 0, number1 = 0;  // the frames' numbers (Frame::number)
  std::string preset;                // label preset name the options started from
  Resolution resolution;             // working resolution
  // ScanNet++: the camera whose frames were read ("dslr" or "iphone", recorded as "device"
  // so that a command re-reading the folder opens the same frames); "" for other formats.
  std::string device;
  // The frames' depth source (render/frame_depth.h), recorded as "depth_source" when not the
  // sensor's (files of sensor-depth runs unchanged).
  render::DepthSourceMode depth_source = render::DepthSourceMode::kSensor;
  // TUM: the tolerance that associated the frames' poses and colour images, recorded as
  // "tum_max_dt_s" so that a command re-reading the folder opens the same colour images;
  // negative for other formats.
  double tum_max_dt_s = -1;
};

// Writes the `occgt pair` folder. meta.json's "metrics" are the labels' own (every pixel of
// the working resolution); its "score_metrics" count every score_stride-th pixel of each
// row and column (the grid pair selection scores on; 1 = the same as "metrics").
void WritePairFolder(const std::string& dir, const PairSource& source, const WorkingFrame& frame0,
                     const WorkingFrame& frame1, const PairTruthOptions& options,
                     const PairTruth& truth, int score_stride);

// Writes the `occgt occupancy` folder. scope: the fused map and its frames for mode octomap
// (null for two_point). occupancy.json's "fusion"."stats" are volumes.fusion_stats (null for
// two_point), with the map's "leaf_nodes" when scope is given.
void WriteOccupancyFolder(const std::string& dir, const PairSource& source,
                          const PairTruthOptions& options, const occupancy::PairOccupancy& volumes,
                          const ScopeMap* scope, bool dense);

}  // namespace gt::truth

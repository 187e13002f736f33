// N-view shards of `occgt tuples --shards` (docs/MULTIVIEW.md "N-view shards"): one
// WebDataset sample per line of tuples.jsonl, written with the shard writer of `occgt build`
// (shards/split.h: plan, temporary tar then rename, part record, merge) into DIR/views/.
//
// Sample members, in this order (key "<scene>/tuple_<k:06d>", k = the tuple's line in
// tuples.jsonl; W×H = working resolution, N views, Q tracks; ".npy" members are gzipped to
// ".npy.gz" under sample.compression: deflate, as pair samples):
//   json               schemas/views_sample.schema.json (scene, frames, K, world_from_cam,
//                      covisibility, label options, track options, metrics {counts
//                      {VISIBLE, OCCLUDED bits}, valid, occlusion_ratio_visible}, image
//                      {format, colour K per view} or null, digest)
//   image<i>.png       colour of view i at W×H, bilinear (sample.image; absent with none)
//   depth<i>.npy       float32 [H, W] metres, 0 = invalid (the labels' depth map)
//   intrinsics.npy     float64 [N, 3, 3] K at W×H
//   world_from_cam.npy float64 [N, 4, 4]
//   visible_in.npy, occluded_in.npy  uint32 [N, H, W]; valid.npy uint8 [N, H, W]
//   queries.npy int32 [Q, 2]; track_xy.npy float32 [N, Q, 2]; track_depth.npy float32 [N, Q];
//   track_state.npy uint8 [N, Q]
// The ground truth is truth::ComputeViewsTruth of the frames with the recipe's label options
// of the scene (RecipePairTruthOptions, as pair samples), the tracks of
// selection.tuples.num_tracks / query_view (recipe.tuple_tracks; defaults those of
// truth::ViewsTruthOptions), seed recipe.seed + k.
// Shards: shards.samples_per_shard samples each, or with shards.target_mb > 0 filled in
// order while the sum of the samples' EstimatedViewsSampleBytes(recipe, N of the tuple) stays
// within target_mb · 10⁶ (at least one sample a shard).
//
// Work: shards in order, each computed in chunks of samples in parallel (TBB) and added in
// order, so the files are byte-identical for any thread count. A complete shard (part record
// and tar of the recorded size) is skipped on a re-run when its record's lines name the same
// tuples and options digest (else an InputError); a plan of other sizes is refused.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libgt/datasets/reader.h"
#include "libgt/pipeline/recipe.h"

namespace gt::pipeline {

// One line of tuples.jsonl.
struct TupleLine {
  std::string scene;
  std::vector<std::string> frame_ids;
  std::vector<float> covisibility;  // [N, N] row-major
};

// Estimated bytes of one N-view sample of `views` views, so that shards.target_mb bounds a
// shard: per view its image (PNG 2 bytes/pixel, JPG 0.3),
// depth (4 bytes/pixel, × DeflatedDepthShare deflated: build.h), visible_in + occluded_in (8) and
// valid (1) (×0.06 deflated, long runs), its tracks (13 bytes per track, ×0.9 deflated); plus 8
// bytes per track (queries) and 4096 (json). Zero tracks when selection.tuples is unset.
int64_t EstimatedViewsSampleBytes(const Recipe& recipe, int views);

// Samples per N-view shard for the tuples `lines` (the rule above), in order.
std::vector<int64_t> PlanViewsShards(const Recipe& recipe, const std::vector<TupleLine>& lines);

// The folder of the N-view shards under an `occgt tuples` output: DIR/views.
std::string ViewsShardDir(const std::string& out_dir);

// Refuses (InputError naming the file) N-view shards already in ViewsShardDir(out_dir) that
// hold other tuples or options than `lines` under `recipe`: `occgt tuples` calls it before it
// replaces tuples.jsonl, so that the two never go out of step. Nothing there: no check.
void CheckViewsShards(const Recipe& recipe, const std::string& out_dir,
                      const std::vector<TupleLine>& lines);

// Refuses (InputError naming the sample key) tuples whose sample keys' longest member,
// world_from_cam.npy (.gz under sample.compression: deflate), would not fit a tar member path
// (shards::kMaxMemberPathBytes): `occgt tuples --shards` calls it before it writes anything.
void CheckViewsKeys(const Recipe& recipe, const std::vector<TupleLine>& lines);

// Writes the N-view shards of `lines` (recipe.split) into ViewsShardDir(out_dir) and publishes
// index.json / pairs.jsonl there. `recipe` reads the frames (its dataset root resolved).
// Returns {"dir", "shards", "shards_written", "shards_skipped", "samples"}.
nlohmann::json WriteViewsShards(const Recipe& recipe, const datasets::DatasetReader& reader,
                                const std::string& out_dir, const std::vector<TupleLine>& lines);

}  // namespace gt::pipeline

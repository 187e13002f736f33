// The values of one stored N-view sample (`occgt tuples --shards`, DIR/views) checked against
// its json and against each other, so that `occgt validate` and occgt.torch.TupleShardDataset
// refuse a damaged or hand-edited tuple by its values, not only by its bytes (docs/CLI.md
// "validate"). The rules are the writer's contract (libgt/pipeline/views_write.cc,
// docs/MULTIVIEW.md, docs/FORMATS.md "N-view shards"):
// - json: num_views N (1..32) with N frames of distinct ids, N K's proper at the resolution
//   (Camera::Check), N rigid world_from_cam's (PoseProblem), covisibility N x N,
//   tracks.query_view < N;
// - depth<i>: float32 [H, W], finite and >= 0 (0 = invalid);
// - intrinsics / world_from_cam: float64 [N, 3, 3] / [N, 4, 4], the json's K / world_from_cam;
// - valid: uint8 [N, H, W], 1 exactly where depth<i> is valid under label_options' range
//   (IsValidDepth), else 0;
// - visible_in / occluded_in uint32 [N, H, W], track_xy float32 [N, Q, 2], track_state uint8
//   [N, Q]: truth::CheckStoredViewsTruth (bits, diagonal, states, positions);
// - metrics: counts.VISIBLE / OCCLUDED the bits of visible_in / occluded_in off the diagonal,
//   valid the sum of `valid`, occlusion_ratio_visible = OCCLUDED / (VISIBLE + OCCLUDED) (0
//   when both are 0), exactly;
// - queries: int32 [Q, 2] with Q = tracks.count, the pixels truth::SampleQueries draws from
//   view query_view's valid pixels with tracks.num_tracks and tracks.seed;
// - the tracks against the bits: in view j, a track is VISIBLE (OCCLUDED) exactly where bit j
//   of visible_in (occluded_in) is set at its query pixel of view query_view; there it is at
//   its query pixel with that pixel's depth; track_depth float32 [N, Q] is NaN exactly where
//   track_xy is;
// - image<i>: as a pair sample's (the json's image.format, complete, W x H).
// Only the members present are checked (CheckViewsSampleMembers says which must be).
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/io/npy.h"
#include "libgt/shards/sample_check.h"

namespace gt::shards {

// The problems of one N-view sample, each "<field>: <problem>" ("valid.npy", "json"), the
// first of each kind only; empty = consistent. `arrays` and `images` as CheckPairSampleValues'.
// `seen_by`, when given and visible_in and valid pass their checks: the count of other views
// seeing each pixel, uint8 [N, H, W] (truth::CountSeenBy), else left empty. Never throws.
std::vector<std::string> CheckViewsSampleValues(
    const nlohmann::json& meta, const std::map<std::string, StoredArray>& arrays,
    const std::map<std::string, std::string_view>& images, std::vector<uint8_t>* seen_by = nullptr);
// The same over .npy members parsed by io::ParseNpy (validate), viewed, not copied.
std::vector<std::string> CheckViewsSampleValues(
    const nlohmann::json& meta, const std::map<std::string, io::NpyArray>& arrays,
    const std::map<std::string, std::string_view>& images = {},
    std::vector<uint8_t>* seen_by = nullptr);

// The member set of an N-view sample against its json's num_views N: json, depth0..depth<N-1>,
// intrinsics, world_from_cam, visible_in, occluded_in, valid, queries, track_xy, track_depth,
// track_state (.npy), image0..image<N-1> of the json's image.format (none when it is null);
// nothing else. `fields`: the plain field names (a .npy.gz member as .npy).
std::vector<std::string> CheckViewsSampleMembers(const nlohmann::json& meta,
                                                 const std::set<std::string>& fields);

}  // namespace gt::shards

// The values of one stored pair sample (`occgt build`'s shards) checked against its json and
// against each other, so that `occgt validate` and occgt.torch.ShardDataset find a damaged or
// foreign sample by its values, not only by its bytes (docs/CLI.md "validate"). The rules
// are the writer's contract (libgt/pipeline/sample.cc, docs/FORMATS.md, GROUND_TRUTH.md §3–4):
// - json: resolution, K0/K1 proper for it (Camera::Check), world_from_cam0/1 and T_0to1 rigid
//   (PoseProblem), T_0to1 = cam1_from_cam0 of the two poses (1e-6), patch_options, matches
//   totals;
// - label01/label10: uint8 [H, W] of PixelLabel codes whose counts and ratios are the json's
//   `metrics` (every pixel) and `score_metrics` (every score_stride-th), exactly;
// - depth0/depth1: float32 [H, W], finite and >= 0 (0 = invalid); NO_DEPTH exactly where the
//   depth is invalid under label_options' range (IsValidDepth);
// - cells0/cells1: uint8 [H/s, W/s], the label at each cell's anchor pixel;
// - matches/match_type/match_xy: [M, 2] int32, [M] uint8, [M, 2] float32 with M the json's
//   total; cells inside the grids; types 0..2 counted as the json's vv/vo/ov, in the writer's
//   order (vv, vo by cell of image 0, ov by cell of image 1); each match by its rule
//   (geometry/patches.h): its anchor's label and TargetCell(match_xy) = its other cell;
// - occ/known (uint64 words) and occ*_dense (uint8 [bins, h, w]): the json's grid and bins,
//   occ within known, no bit past the bins, the json's counts0/counts1, dense values 0, 1 or
//   255 and equal to the words when both are stored;
// - image0/image1: the json's format, complete (PngDamage/JpegDamage), W x H (header only).
// Only the members present are checked (CheckPairSampleMembers says which must be).
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/io/npy.h"

namespace gt::shards {

// One .npy member as stored: its descr ("<f4", "|u1"), C-order shape and data (not owned;
// product(shape) items of the descr's size).
struct StoredArray {
  std::string descr;
  std::vector<int64_t> shape;
  const void* data = nullptr;
};

// The problems of one pair sample, each "<field>: <problem>" with the member's field name
// ("label01.npy", "json"), the first of each kind only; empty = consistent. `arrays`: the
// .npy members present, by field name; `images`: the image members' bytes by field name
// ("image0.png"). A json without the fields a check needs gives a "json: ..." problem; never
// throws.
std::vector<std::string> CheckPairSampleValues(
    const nlohmann::json& meta, const std::map<std::string, StoredArray>& arrays,
    const std::map<std::string, std::string_view>& images);
// The same over .npy members parsed by io::ParseNpy (validate, eval), viewed, not copied.
std::vector<std::string> CheckPairSampleValues(
    const nlohmann::json& meta, const std::map<std::string, io::NpyArray>& arrays,
    const std::map<std::string, std::string_view>& images = {});

// The member set of a pair sample against its json: json, matches.npy, match_type.npy,
// match_xy.npy; label01/label10/cells0/cells1 all or none; depth0/depth1 both or none;
// image0/image1 both or none, of the json's image.format (none when it is null); occupancy
// members iff the json's occupancy is not null, by its encoding (packed: occ0, known0, occ1,
// known1; dense: occ0_dense, occ1_dense; both: all six); nothing else. `fields`: the plain
// field names (a .npy.gz member as .npy). Problems as CheckPairSampleValues.
std::vector<std::string> CheckPairSampleMembers(const nlohmann::json& meta,
                                                const std::set<std::string>& fields);

}  // namespace gt::shards

// The arrays of one pair for the pictures of pictures.h, from the three places a pair can
// come from, and the pictures of a pair written as PNG files (`occgt inspect pair`).
//
// Sources:
//  - a WebDataset shard sample (SHARDS.md; fields written by `occgt build`): "json" (the
//    sample metadata), "label01.npy", "label10.npy" (uint8 [H, W]), "matches.npy" (int32
//    [M, 2]), "match_type.npy" (uint8 [M]), "match_xy.npy" (float32 [M, 2]), "cells0.npy",
//    "cells1.npy" (uint8 [H/s, W/s]), optional "image0.png"/"image1.png" (or .jpg) and
//    optional occupancy "occ0.npy"/"known0.npy"/"occ1.npy"/"known1.npy" (uint64 [H/2, W/2])
//    or dense "occ0_dense.npy"/"occ1_dense.npy" (uint8 [D, H/2, W/2]);
//  - an `occgt pair` and/or `occgt occupancy` output folder: the same arrays as files,
//    "meta.json" instead of the sample json (its "occupancy" entry: the folder's
//    occupancy.json, whose "bins.edges_m" are the bin edges), dense volumes as
//    occ0_dense.npy/occ1_dense.npy (occupancy0/1.npy in folders written before they took
//    the shard's names), colour images as image0.png/image1.png in the folder or through the
//    "color_path" entries of meta.json (or given explicitly). A folder of `occgt occupancy`
//    alone has no labels or matches: only its occupancy is rendered;
//  - a scene and two frame ids: computed here with libgt/geometry (labels, matches) and,
//    when asked, libgt/occupancy (pair fusion, 64 bins).
// Metadata lookups: the patch stride is W / (columns of cells0); the anchor rule is the
// first "anchor" string found in the json ("center" when absent); occupancy bin edges are
// the first numeric array of D + 1 entries under a key "edges_m" (occupancy.json's
// "bins"."edges_m", a sample's "occupancy"."bins"."edges_m") or one ending in "edges_m"
// (a sample written before: "occupancy"."bin_edges_m"). A missing or malformed array is an
// InputError naming the source and the field.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libgt/datasets/reader.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/render/frame_depth.h"
#include "libgt/report/pictures.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/working_frame.h"

namespace gt::report {

struct PairData {
  std::string name;           // "<shard>:<key>", a folder, or "<scene> <id0>,<id1>"
  int width = 0, height = 0;  // working resolution (size of label01)
  cv::Mat image0, image1;     // BGR CV_8UC3 at the working resolution (grey when absent)
  bool has_images = false;    // false when grey placeholders stand in for the colour
  bool has_labels = true;     // false for an `occgt occupancy` folder alone
  LabelMap labels01, labels10;
  gt::PatchMatches matches;  // cells_w*/cells_h* filled
  int stride = 8;
  gt::Anchor anchor = gt::Anchor::kCenter;
  bool has_occupancy = false;
  gt::occupancy::FrustumVolume occ0, occ1;
  nlohmann::json meta;  // the sample json / meta.json (null when computed here)
  // The depth source of the labels ("sensor", "mesh", "fused"; docs/GROUND_TRUTH.md "Depth
  // sources"): computed here, meta.json's "depth_source", a shard's recipe.json
  // dataset.depth_source (absent: sensor); "" when unknown.
  std::string depth_source;
  // Computed in a scene with a mesh: each frame's depth at the working resolution, one row
  // per frame, [sensor | rendered | fused | agreement classes] (BGR; DepthSourcesPicture).
  cv::Mat depth_sources;
};

// Fields by name ("label01.npy" → bytes). `source` names the origin in error messages.
// image0/image1 override colour from the fields when non-empty.
PairData PairFromFields(const std::map<std::string, std::string>& fields, const std::string& source,
                        const cv::Mat& image0 = cv::Mat(), const cv::Mat& image1 = cv::Mat());

// Sample `key` of a shard (gt::shards::ReadShardSample).
PairData LoadPairFromShard(const std::string& tar_path, const std::string& key);

// An `occgt pair` output folder. Colour: image0_path/image1_path when given, else
// image*.png in the folder, else meta.json's "color_path" entries, else, when dataset_root
// is given, the colour files of meta.json's "format", "scene" and "frame0"/"frame1" ids read
// with that dataset's reader; grey placeholders otherwise.
PairData LoadPairFromDir(const std::string& dir, const std::string& image0_path = "",
                         const std::string& image1_path = "", const std::string& dataset_root = "");

// Frames id0, id1 of `scene` (read by the caller, its mesh path applied) labelled at
// `resolution` with the resolved options `o` (truth::ResolvePairTruthOptions), their depth
// from `depth` (the labels' source and the fusion tolerance). When the scene has a mesh,
// PairData::depth_sources shows the frames' sensor, rendered and fused depth whatever source
// the labels used. `occgt inspect pair` reads the scene and resolves the options as
// `occgt pair` does (apps/pair_recipe.h), so both label a pair alike.
PairData ComputePairFromScene(const Scene& scene, const std::string& id0, const std::string& id1,
                              const truth::PairTruthOptions& o, const truth::Resolution& resolution,
                              const render::FrameDepthOptions& depth);

// One row per frame: [sensor | rendered | fused | agreement] at the working resolution, each
// panel titled ("<id> sensor", ...), the ramps sharing one scale (0 m white-ish to the largest
// depth shown dark grey, black = none), agreement in render/depth_picture.h's colours with a
// legend. BGR CV_8UC3. The scene must have a mesh.
cv::Mat DepthSourcesPicture(const Scene& scene, const std::vector<const Frame*>& frames,
                            const truth::Resolution& resolution,
                            const render::FrameDepthOptions& depth);

struct PairPictureOptions {
  MatchPictureOptions matches;  // stride/anchor are taken from the PairData
  LabelPictureOptions labels;
  OccupancyPictureOptions occupancy;
  bool Check(std::string* error) const;
};

struct PairPictures {
  cv::Mat matches;    // RenderMatches; empty when the pair has no labels
  cv::Mat labels;     // RenderLabels; empty when the pair has no labels
  cv::Mat occupancy;  // RenderOccupancy; empty when the pair has none
  cv::Mat depth;      // PairData::depth_sources; empty when the pair has none
};
PairPictures RenderPair(const PairData& pair, const PairPictureOptions& options);

// Writes matches.png, labels.png and (when present) occupancy.png and depth.png into out_dir
// atomically, and removes those of them an earlier run left there that this pair has not
// (they would pass for this pair's); returns the paths written.
std::vector<std::string> WritePairPictures(const PairPictures& pictures,
                                           const std::string& out_dir);

}  // namespace gt::report

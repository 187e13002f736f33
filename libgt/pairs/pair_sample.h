// One training sample of a selected pair: everything `occgt build` stores for it, encoded
// as named member files (WebDataset fields) plus its pairs.jsonl line. Layouts (docs/
// USER_GUIDE.md and schemas/sample.schema.json; W×H = working resolution, s = patch stride):
//   json            sample metadata (scene, frame ids, K0/K1 at W×H, world_from_cam0/1 4×4,
//                   T_0to1 = cam1_from_cam0 4×4, metrics of both directions at stride 1 and
//                   at score_stride, label counts, match counts, options digest, occupancy
//                   bin edges)
//   label01.npy     uint8 [H, W]  PixelLabel codes of image 0 towards 1 (label10: 1 → 0)
//   matches.npy     int32 [M, 2]  (cell in image 0, cell in image 1)
//   match_type.npy  uint8 [M]     0 vv, 1 vo, 2 ov
//   match_xy.npy    float32 [M, 2] warped anchor (geometry/patches.h)
//   cells0.npy      uint8 [H/s, W/s] anchor labels of image 0 (cells1: image 1)
//   occ0.npy, known0.npy   uint64 [H/2, W/2] bit k = bin k occupied / known (encoding
//                   packed or both); occ0_dense.npy uint8 [D, H/2, W/2] 0 free, 1 occupied,
//                   255 unknown (encoding dense or both); same for camera 1
//   image0.png      colour at W×H, bilinear (or image0.jpg)
//   depth0.npy      float32 [H, W] metres, 0 = invalid (when sample.depth)
// Field order is fixed (the list above), so the bytes of a sample are deterministic.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "libgt/core/frame.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/pairs/recipe.h"
#include "libgt/pairs/selection.h"

namespace gt::pairs {

// The algorithm options a recipe selects, converted once.
struct SampleSpec {
  int width = 640, height = 480;
  LabelOptions labels;
  PatchOptions patches;
  bool occupancy = true;  // occupancy.enabled && sample.occupancy
  occupancy::FusionOptions fusion;
  occupancy::BinOptions bins;
  occupancy::OccupancyMode mode = occupancy::OccupancyMode::kOctomap;
  std::string encoding = "packed";
  std::string image = "png";
  bool depth = false;
  bool label_maps = true;
  std::string digest;  // Recipe::Digest()
  std::string recipe_name, split;
};
// Label options of a recipe for a scene: preset, then dataset depth range (recipe's
// dataset.min/max_depth_m, else the scene's), then labels.overrides.
LabelOptions RecipeLabelOptions(const Recipe& recipe, const Scene& scene);
SampleSpec RecipeSampleOptions(const Recipe& recipe);

struct EncodedSample {
  std::string key;
  std::vector<std::pair<std::string, std::string>> fields;  // (field name, bytes)
  nlohmann::json pair_line;                                 // pairs.jsonl object (no shard/key)
  int64_t bytes = 0;                                        // sum of field sizes
};

// The selected pair as recorded by the select stage.
struct SelectedPair {
  std::string scene;
  std::string frame0, frame1;  // frame ids
  int64_t number0 = 0, number1 = 0;
  DirectionMetrics score01, score10;  // at score_stride ({} for imported pairs: computed here)
};
nlohmann::json MetricsJson(const DirectionMetrics& m);
DirectionMetrics MetricsFromJson(const nlohmann::json& j);

// The colour of a frame at W×H, bilinear, encoded as options.image ("png" or "jpg").
// Throws InputError naming the file when it cannot be read.
std::string EncodeFrameImage(const Frame& frame, const SampleSpec& options);

// Encoded colour image of a scene's frame (EncodeFrameImage of frame_index), from the
// caller's cache: a frame appears in many pairs.
using ImageSource = std::function<std::shared_ptr<const std::string>(size_t frame_index)>;

// Computes labels, matches, occupancy and encodes the sample. depth0/1 at W×H. images: where
// the two frames' encoded images come from (called from the sample's parallel tasks, so it
// must be thread-safe); empty: they are encoded here. Throws InputError (naming the file)
// when an input cannot be read.
EncodedSample ComputeSample(const Scene& scene, size_t i0, size_t i1, const SelectedPair& pair,
                            const std::string& key, const DepthImage& depth0,
                            const DepthImage& depth1, const SampleSpec& options,
                            const occupancy::OccupancyMap* shared_map,
                            const ImageSource& images = {});

// K (row-major 3×3) of a frame's depth camera at the working resolution.
Camera WorkingCamera(const Frame& frame, int width, int height);

}  // namespace gt::pairs

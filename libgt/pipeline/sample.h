// One training sample of a selected pair: everything `occgt build` stores for it, as a
// shards::Sample (named member files, WebDataset fields) plus its pairs.jsonl line. Layouts
// (docs/USER_GUIDE.md and schemas/sample.schema.json; W×H = working resolution, s = patch
// stride):
//   json            sample metadata (scene, frame ids, K0/K1 at W×H, world_from_cam0/1 4×4,
//                   T_0to1 = cam1_from_cam0 4×4, metrics of both directions at stride 1 and
//                   at score_stride, label counts, match counts, options digest, occupancy
//                   bin edges "occupancy"."bins"."edges_m" beside "occupancy_options")
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
// The ground truth itself is truth::ComputePairTruth; this file encodes it.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "libgt/core/frame.h"
#include "libgt/geometry/labels.h"
#include "libgt/shards/sample.h"
#include "libgt/truth/pair_truth.h"

namespace gt::pipeline {

enum class ImageFormat { kNone, kPng, kJpg };  // "none" | "png" | "jpg"
ImageFormat ParseImageFormat(const std::string& text, const std::string& field);
const char* ImageFormatName(ImageFormat format);

// How array members are stored (recipe sample.compression; docs/RECIPES.md "Sample
// compression"): "<field>.npy.gz", the gzip (libdeflate level 1) of "<field>.npy" (io/gzip.h;
// the default), or "<field>.npy" as is.
enum class SampleCompression { kNone, kDeflate };  // "none" | "deflate"
SampleCompression ParseSampleCompression(const std::string& text, const std::string& field);
const char* SampleCompressionName(SampleCompression compression);

// How the occupancy volumes are stored: occ/known words, the dense uint8 volume, or both.
enum class VolumeEncoding { kPacked, kDense, kBoth };  // "packed" | "dense" | "both"
VolumeEncoding ParseVolumeEncoding(const std::string& text, const std::string& field);
const char* VolumeEncodingName(VolumeEncoding encoding);

// The options of one sample (recipe.h RecipeSampleOptions; truth.labels per scene).
struct SampleOptions {
  truth::Resolution resolution;
  truth::PairTruthOptions truth;  // labels, patches, occupancy
  VolumeEncoding encoding = VolumeEncoding::kPacked;
  ImageFormat image = ImageFormat::kPng;
  bool depth = false;      // depth0/1.npy
  bool label_maps = true;  // label01/10.npy, cells0/1.npy
  SampleCompression compression = SampleCompression::kDeflate;
  int score_stride = 1;  // the grid of the selection's score_metrics (recorded)
  std::string digest;    // Recipe::Digest()
  std::string recipe_name, split;
};

// The selected pair as recorded by the select stage.
struct SelectedPair {
  std::string scene;
  std::string frame0, frame1;  // frame ids
  int64_t number0 = 0, number1 = 0;
  DirectionMetrics score01, score10;  // at score_stride ({} for imported pairs)
};

struct EncodedSample {
  shards::Sample sample;  // key and fields
  std::string pair_line;  // pairs.jsonl object (no shard/key), compact JSON
};

// The member name of field `name`: "<name>.gz" for a ".npy" name under kDeflate, else `name`.
std::string StoredFieldName(const std::string& name, SampleCompression compression);

// The longest member name of a pair sample: match_type.npy, always stored (occ0_dense.npy is
// as long, the other fields shorter), under `compression`. A key whose member of this name
// fits shards::kMaxMemberPathBytes fits with every field.
std::string LongestPairField(SampleCompression compression);

// Appends a member: "<name>.gz" (the gzip of `bytes`, level 1) for a ".npy" name under
// kDeflate, else `name` as is (pair samples and N-view samples alike).
void AddSampleField(shards::Sample* sample, const std::string& name, std::string bytes,
                    SampleCompression compression);

// The colour of a frame at W×H, bilinear, encoded as options.image ("png" or "jpg").
// Throws InputError naming the file when it cannot be read.
std::string EncodeFrameImage(const Frame& frame, const SampleOptions& options);

// Encoded colour image of a scene's frame, from the caller's cache (a frame appears in many
// pairs); called from the sample's parallel tasks, so it must be thread-safe.
using ImageSource = std::function<std::shared_ptr<const std::string>(size_t frame_index)>;

// Computes the pair's ground truth and encodes the sample. frame0/1: the frames i0, i1 of
// `scene` at the working resolution. scope_map: see truth::ComputePairTruth. Throws
// InputError (naming the file) when an input cannot be read.
EncodedSample ComputeSample(const Scene& scene, size_t i0, size_t i1, const SelectedPair& pair,
                            const std::string& key, const truth::WorkingFrame& frame0,
                            const truth::WorkingFrame& frame1, const SampleOptions& options,
                            const occupancy::OccupancyMap* scope_map, const ImageSource& images);

}  // namespace gt::pipeline

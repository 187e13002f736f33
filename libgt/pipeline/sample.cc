#include "libgt/pipeline/sample.h"

#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include <exception>
#include <opencv2/core.hpp>

#include "libgt/core/error.h"
#include "libgt/io/codec.h"
#include "libgt/io/gzip.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"
#include "libgt/shards/sample.h"
#include "libgt/truth/pair_files.h"

namespace gt::pipeline {
namespace {

using nlohmann::json;

std::string EncodeImage(const io::ColorImage& image, ImageFormat format, const std::string& what) {
  GT_ASSERT(format == ImageFormat::kJpg || format == ImageFormat::kPng);
  return shards::EncodeSampleColor(
      image.rgb.data(), image.width, image.height,
      format == ImageFormat::kJpg ? shards::ColorMember::kJpg : shards::ColorMember::kPng, what);
}

}  // namespace

ImageFormat ParseImageFormat(const std::string& text, const std::string& field) {
  if (text == "png") return ImageFormat::kPng;
  if (text == "jpg") return ImageFormat::kJpg;
  if (text == "none") return ImageFormat::kNone;
  throw InputError(field, "expected png, jpg or none; got '" + text + "'");
}

SampleCompression ParseSampleCompression(const std::string& text, const std::string& field) {
  if (text == "none") return SampleCompression::kNone;
  if (text == "deflate") return SampleCompression::kDeflate;
  throw InputError(field, "expected none or deflate; got '" + text + "'");
}

const char* SampleCompressionName(SampleCompression compression) {
  return compression == SampleCompression::kDeflate ? "deflate" : "none";
}

const char* ImageFormatName(ImageFormat format) {
  switch (format) {
    case ImageFormat::kPng:
      return "png";
    case ImageFormat::kJpg:
      return "jpg";
    case ImageFormat::kNone:
      break;
  }
  return "none";
}

VolumeEncoding ParseVolumeEncoding(const std::string& text, const std::string& field) {
  if (text == "packed") return VolumeEncoding::kPacked;
  if (text == "dense") return VolumeEncoding::kDense;
  if (text == "both") return VolumeEncoding::kBoth;
  throw InputError(field, "expected packed, dense or both; got '" + text + "'");
}

const char* VolumeEncodingName(VolumeEncoding encoding) {
  switch (encoding) {
    case VolumeEncoding::kDense:
      return "dense";
    case VolumeEncoding::kBoth:
      return "both";
    case VolumeEncoding::kPacked:
      break;
  }
  return "packed";
}

namespace {

bool DeflatedField(const std::string& name, SampleCompression compression) {
  const bool array = name.size() > 4 && name.compare(name.size() - 4, 4, ".npy") == 0;
  return array && compression == SampleCompression::kDeflate;
}

}  // namespace

std::string StoredFieldName(const std::string& name, SampleCompression compression) {
  return DeflatedField(name, compression) ? name + ".gz" : name;
}

std::string LongestPairField(SampleCompression compression) {
  return StoredFieldName("match_type.npy", compression);
}

void AddSampleField(shards::Sample* sample, const std::string& name, std::string bytes,
                    SampleCompression compression) {
  if (DeflatedField(name, compression)) {
    sample->fields.push_back({name + ".gz", io::GzipBytes(bytes, 1)});
  } else {
    sample->fields.push_back({name, std::move(bytes)});
  }
}

std::string EncodeFrameImage(const Frame& frame, const SampleOptions& options) {
  const io::ColorImage c =
      io::ReadFrameColorResized(frame, options.resolution.width, options.resolution.height);
  return EncodeImage(c, options.image, frame.color_path);
}

EncodedSample ComputeSample(const Scene& scene, size_t i0, size_t i1, const SelectedPair& pair,
                            const std::string& key, const truth::WorkingFrame& frame0,
                            const truth::WorkingFrame& frame1, const SampleOptions& options,
                            const occupancy::OccupancyMap* scope_map, const ImageSource& images) {
  const Frame& f0 = scene.frames[i0];
  const Frame& f1 = scene.frames[i1];
  // The two images and the ground truth are independent: computed as parallel TBB tasks
  // (one thread under --threads 1), so that a sample computed alone, e.g. the last one of a
  // run, uses every core. Errors are rethrown in a fixed order (ground truth, then the
  // images), so the one reported does not depend on timing.
  truth::PairTruth truth;
  std::string encoded_image[2];
  const bool with_images =
      options.image != ImageFormat::kNone && !f0.color_path.empty() && !f1.color_path.empty();
  std::exception_ptr error[3];
  auto guarded = [](std::exception_ptr* e, auto&& f) {
    try {
      f();
    } catch (...) {
      *e = std::current_exception();
    }
  };
  // Its own context: a cancellation of the caller's work (another sample of the pipeline
  // failing) must not silently skip these tasks and leave the results empty.
  tbb::task_group_context own(tbb::task_group_context::isolated);
  auto image = [&](size_t i, const Frame& f) {
    return images ? *images(i) : EncodeFrameImage(f, options);
  };
  tbb::parallel_invoke(
      [&] {
        guarded(&error[1], [&] {
          if (with_images) encoded_image[0] = image(i0, f0);
        });
      },
      [&] {
        guarded(&error[2], [&] {
          if (with_images) encoded_image[1] = image(i1, f1);
        });
      },
      [&] {
        guarded(&error[0],
                [&] { truth = truth::ComputePairTruth(frame0, frame1, options.truth, scope_map); });
      },
      own);
  for (const std::exception_ptr& e : error) {
    if (e) std::rethrow_exception(e);
  }
  const PairLabels& labels = truth.labels;
  const DepthImage& depth0 = *frame0.depth;
  const DepthImage& depth1 = *frame1.depth;
  EncodedSample out;
  shards::Sample& sample = out.sample;
  sample.key = key;
  const int64_t W = options.resolution.width, H = options.resolution.height;
  auto add = [&](const std::string& name, std::string bytes) {
    AddSampleField(&sample, name, std::move(bytes), options.compression);
  };

  // Metadata first (the json member), filled below; its slot is reserved now.
  add("json", "");
  if (options.label_maps) {
    add("label01.npy", io::EncodeNpy<uint8_t>({H, W}, labels.l01.labels));
    add("label10.npy", io::EncodeNpy<uint8_t>({H, W}, labels.l10.labels));
  }
  const PatchMatches& pm = labels.patches;
  const int64_t M = static_cast<int64_t>(pm.size());
  add("matches.npy", io::EncodeNpy<int32_t>({M, 2}, pm.matches));
  add("match_type.npy", io::EncodeNpy<uint8_t>({M}, pm.match_type));
  add("match_xy.npy", io::EncodeNpy<float>({M, 2}, pm.match_xy));
  if (options.label_maps) {
    add("cells0.npy", io::EncodeNpy<uint8_t>({pm.cells_h0, pm.cells_w0}, pm.cells0));
    add("cells1.npy", io::EncodeNpy<uint8_t>({pm.cells_h1, pm.cells_w1}, pm.cells1));
  }
  json occupancy_json = nullptr;
  if (truth.occupancy) {
    const occupancy::PairOccupancy& occ = *truth.occupancy;
    const bool packed = options.encoding != VolumeEncoding::kDense;
    const bool dense = options.encoding != VolumeEncoding::kPacked;
    int cam_index = 0;
    for (const occupancy::FrustumVolume* v : {&occ.cam0, &occ.cam1}) {
      const std::string c = std::to_string(cam_index++);
      const int64_t h = v->height, w = v->width;
      if (packed) {
        add("occ" + c + ".npy", io::EncodeNpy<uint64_t>({h, w}, v->occ));
        add("known" + c + ".npy", io::EncodeNpy<uint64_t>({h, w}, v->known));
      }
      if (dense) {
        add("occ" + c + "_dense.npy",
            io::EncodeNpy<uint8_t>({v->num_bins(), h, w}, occupancy::DenseVolume(*v)));
      }
    }
    const occupancy::VolumeCounts c0 = occupancy::CountBins(occ.cam0);
    const occupancy::VolumeCounts c1 = occupancy::CountBins(occ.cam1);
    // The bin edges and the fusion statistics under occupancy.json's names ("bins"."edges_m",
    // "fusion"."stats"); the voxel size and the other options are occupancy_options' (one
    // key for one number).
    occupancy_json = {
        {"bins", {{"edges_m", occ.cam0.edges_m}}},
        {"mode", occupancy::OccupancyModeName(options.truth.mode)},
        {"encoding", VolumeEncodingName(options.encoding)},
        {"grid", {occ.cam0.width, occ.cam0.height}},
        {"counts0", {{"occupied", c0.occupied}, {"free", c0.free}, {"unknown", c0.unknown}}},
        {"counts1", {{"occupied", c1.occupied}, {"free", c1.free}, {"unknown", c1.unknown}}},
        {"fusion",
         {{"stats",
           occ.fusion_stats ? json(truth::FusionStatsJson(*occ.fusion_stats)) : json(nullptr)}}}};
  }
  json image_json = nullptr;
  if (with_images) {
    const std::string ext = ImageFormatName(options.image);
    add("image0." + ext, std::move(encoded_image[0]));
    add("image1." + ext, std::move(encoded_image[1]));
    const Camera k0 = f0.color_camera.Resized(W, H);
    const Camera k1 = f1.color_camera.Resized(W, H);
    image_json = {
        {"format", ext}, {"K0", truth::MatrixJson(k0.K())}, {"K1", truth::MatrixJson(k1.K())}};
  }
  if (options.depth) {
    add("depth0.npy", io::EncodeNpy<float>({H, W}, depth0.values_m));
    add("depth1.npy", io::EncodeNpy<float>({H, W}, depth1.values_m));
  }

  const MatchTypeCounts types = CountMatchTypes(pm);
  const Rigid3d cam1_from_cam0 = labels.cam1_from_cam0;
  using truth::MatrixJson;
  using truth::MetricsJson;
  const json metrics = {{"01", MetricsJson(labels.m01)}, {"10", MetricsJson(labels.m10)}};
  const json score_metrics = {{"01", MetricsJson(pair.score01)}, {"10", MetricsJson(pair.score10)}};
  json meta = {
      {"key", key},
      {"scene", scene.name},
      {"frame0", {{"id", f0.id}, {"number", f0.number}}},
      {"frame1", {{"id", f1.id}, {"number", f1.number}}},
      {"resolution", {W, H}},
      {"K0", MatrixJson(frame0.camera.K())},
      {"K1", MatrixJson(frame1.camera.K())},
      {"world_from_cam0", MatrixJson(f0.world_from_cam.matrix())},
      {"world_from_cam1", MatrixJson(f1.world_from_cam.matrix())},
      {"T_0to1", MatrixJson(cam1_from_cam0.matrix())},
      {"metrics", metrics},
      {"score_metrics", score_metrics},
      {"matches", {{"total", M}, {"vv", types.vv}, {"vo", types.vo}, {"ov", types.ov}}},
      {"score_stride", options.score_stride},
      {"label_options", truth::LabelOptionsJson(options.truth.labels)},
      {"patch_options", truth::PatchOptionsJson(options.truth.patches)},
      {"occupancy", occupancy_json},
      {"occupancy_options",
       options.truth.occupancy ? json(truth::OccupancyOptionsJson(options.truth)) : json(nullptr)},
      {"image", image_json},
      {"options_digest", options.digest},
      {"recipe", options.recipe_name},
      {"split", options.split}};
  sample.fields[0].bytes = meta.dump(1) + "\n";

  out.pair_line =
      json{{"scene", scene.name},
           {"frame0", {{"id", f0.id}, {"number", f0.number}}},
           {"frame1", {{"id", f1.id}, {"number", f1.number}}},
           {"metrics", metrics},
           {"score_stride", options.score_stride},
           {"score_metrics", score_metrics},
           {"matches", {{"total", M}, {"vv", types.vv}, {"vo", types.vo}, {"ov", types.ov}}},
           {"T_0to1", MatrixJson(cam1_from_cam0.matrix())}}
          .dump();
  return out;
}

}  // namespace gt::pipeline

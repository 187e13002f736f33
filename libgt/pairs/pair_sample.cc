#include "libgt/pairs/pair_sample.h"

#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include <exception>
#include <opencv2/core.hpp>

#include "libgt/core/error.h"
#include "libgt/geometry/pair.h"
#include "libgt/io/codec.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"

namespace gt::pairs {
namespace {

using nlohmann::json;

json MatrixJson(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (int r = 0; r < m.rows(); ++r) {
    json row = json::array();
    for (int c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

json CountsJson(const std::array<int64_t, kNumPixelLabels>& counts) {
  json j = json::object();
  for (int k = 0; k < kNumPixelLabels; ++k) {
    j[PixelLabelName(static_cast<PixelLabel>(k))] = counts[k];
  }
  return j;
}

std::string EncodeImage(const io::ColorImage& image, const std::string& format,
                        const std::string& what) {
  const cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.rgb.data()));
  if (format == "jpg") return io::EncodeJpegBytes(rgb, io::ChannelOrder::kRgb, 95, what);
  if (format == "png") return io::EncodePngBytes(rgb, io::ChannelOrder::kRgb, 1, what);
  throw InputError(what, "cannot encode " + format + " (expected png or jpg)");
}

}  // namespace

Camera WorkingCamera(const Frame& frame, int width, int height) {
  return frame.depth_camera.Resized(width, height);
}

LabelOptions RecipeLabelOptions(const Recipe& recipe, const Scene& scene) {
  LabelOptions o = LabelPreset(recipe.labels.preset);
  o.min_depth_m = recipe.dataset.min_depth_m.value_or(scene.min_depth_m);
  o.max_depth_m = recipe.dataset.max_depth_m.value_or(scene.max_depth_m);
  if (recipe.labels.abs_tol_m) o.abs_tol_m = *recipe.labels.abs_tol_m;
  if (recipe.labels.rel_tol) o.rel_tol = *recipe.labels.rel_tol;
  if (recipe.labels.min_depth_m) o.min_depth_m = *recipe.labels.min_depth_m;
  if (recipe.labels.max_depth_m) o.max_depth_m = *recipe.labels.max_depth_m;
  std::string error;
  if (!o.Check(&error)) throw InputError(recipe.file, "labels: " + error);
  return o;
}

SampleSpec RecipeSampleOptions(const Recipe& recipe) {
  SampleSpec s;
  s.width = recipe.width;
  s.height = recipe.height;
  s.patches.stride = recipe.patches.stride;
  s.patches.anchor = ParseAnchor(recipe.patches.anchor, "patches.anchor");
  s.patches.mutual = recipe.patches.mutual;
  s.occupancy = recipe.occupancy.enabled && recipe.sample.occupancy;
  s.fusion.voxel_size_m = recipe.occupancy.voxel_m;
  s.fusion.max_range_m = recipe.occupancy.far_m;
  s.bins.num_bins = recipe.occupancy.bins;
  s.bins.near_m = recipe.occupancy.near_m;
  s.bins.far_m = recipe.occupancy.far_m;
  s.bins.spacing = occupancy::ParseBinSpacing(recipe.occupancy.spacing);
  s.bins.traversal = occupancy::ParseTraversal(recipe.occupancy.traversal);
  s.mode = occupancy::ParseOccupancyMode(recipe.occupancy.mode);
  s.encoding = recipe.occupancy.encoding;
  s.image = recipe.sample.image;
  s.depth = recipe.sample.depth;
  s.label_maps = recipe.sample.labels;
  s.digest = recipe.Digest();
  s.recipe_name = recipe.name;
  s.split = recipe.split;
  std::string error;
  if (!s.patches.Check(&error)) throw InputError(recipe.file, "patches: " + error);
  if (s.occupancy && !s.bins.Check(&error)) throw InputError(recipe.file, "occupancy: " + error);
  return s;
}

json MetricsJson(const DirectionMetrics& m) {
  return {{"sampled", m.sampled},
          {"valid", m.valid},
          {"counts", CountsJson(m.counts)},
          {"overlap", m.overlap},
          {"consistent_overlap", m.consistent_overlap},
          {"occlusion_ratio", m.occlusion_ratio},
          {"occlusion_ratio_visible", m.occlusion_ratio_visible}};
}

DirectionMetrics MetricsFromJson(const json& j) {
  DirectionMetrics m;
  m.sampled = j.at("sampled").get<int64_t>();
  m.valid = j.at("valid").get<int64_t>();
  for (int k = 0; k < kNumPixelLabels; ++k) {
    m.counts[k] = j.at("counts").at(PixelLabelName(static_cast<PixelLabel>(k))).get<int64_t>();
  }
  FinishMetrics(&m);
  return m;
}

std::string EncodeFrameImage(const Frame& frame, const SampleSpec& options) {
  const io::ColorImage c =
      io::ReadColorResized(frame.color_path, frame.color_camera, options.width, options.height);
  return EncodeImage(c, options.image, frame.color_path);
}

EncodedSample ComputeSample(const Scene& scene, size_t i0, size_t i1, const SelectedPair& pair,
                            const std::string& key, const DepthImage& depth0,
                            const DepthImage& depth1, const SampleSpec& options,
                            const occupancy::OccupancyMap* shared_map, const ImageSource& images) {
  const Frame& f0 = scene.frames[i0];
  const Frame& f1 = scene.frames[i1];
  const Camera cam0 = WorkingCamera(f0, options.width, options.height);
  const Camera cam1 = WorkingCamera(f1, options.width, options.height);
  // The two images, the occupancy volumes and the labels are independent: computed as
  // parallel TBB tasks (one thread under --threads 1), so that a sample computed alone, e.g.
  // the last one of a run, uses every core; the images (decoding, resizing and encoding,
  // ~25 ms each at 640x480 PNG) are the longest and come first. Errors are rethrown in a
  // fixed order (labels, occupancy, images), so the one reported does not depend on timing.
  PairLabels labels;
  occupancy::PairOccupancy occ;
  std::string encoded_image[2];
  const bool with_images =
      options.image != "none" && !f0.color_path.empty() && !f1.color_path.empty();
  std::exception_ptr error[4];
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
        guarded(&error[2], [&] {
          if (with_images) encoded_image[0] = image(i0, f0);
        });
      },
      [&] {
        guarded(&error[3], [&] {
          if (with_images) encoded_image[1] = image(i1, f1);
        });
      },
      [&] {
        guarded(&error[1], [&] {
          if (!options.occupancy) return;
          occupancy::FusionInput in0{&depth0, cam0, f0.world_from_cam, options.labels.min_depth_m,
                                     options.labels.max_depth_m};
          occupancy::FusionInput in1{&depth1, cam1, f1.world_from_cam, options.labels.min_depth_m,
                                     options.labels.max_depth_m};
          occ = occupancy::ComputePairOccupancy(in0, in1, options.fusion, options.bins,
                                                options.mode, shared_map);
        });
      },
      [&] {
        guarded(&error[0], [&] {
          labels = LabelPair(depth0, cam0, f0.world_from_cam, depth1, cam1, f1.world_from_cam,
                             options.labels, options.patches);
        });
      },
      own);
  for (const std::exception_ptr& e : error) {
    if (e) std::rethrow_exception(e);
  }
  EncodedSample out;
  out.key = key;
  const int64_t W = options.width, H = options.height;
  auto add = [&](const std::string& name, std::string bytes) {
    out.bytes += static_cast<int64_t>(bytes.size());
    out.fields.emplace_back(name, std::move(bytes));
  };

  // Metadata first (the json member), filled below; its slot is reserved now.
  out.fields.emplace_back("json", "");
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
  if (options.occupancy) {
    int cam_index = 0;
    for (const occupancy::FrustumVolume* v : {&occ.cam0, &occ.cam1}) {
      const std::string c = std::to_string(cam_index++);
      const int64_t h = v->height, w = v->width;
      if (options.encoding == "packed" || options.encoding == "both") {
        add("occ" + c + ".npy", io::EncodeNpy<uint64_t>({h, w}, v->occ));
        add("known" + c + ".npy", io::EncodeNpy<uint64_t>({h, w}, v->known));
      }
      if (options.encoding == "dense" || options.encoding == "both") {
        add("occ" + c + "_dense.npy",
            io::EncodeNpy<uint8_t>({v->num_bins(), h, w}, occupancy::DenseVolume(*v)));
      }
    }
    const occupancy::VolumeCounts c0 = occupancy::CountBins(occ.cam0);
    const occupancy::VolumeCounts c1 = occupancy::CountBins(occ.cam1);
    occupancy_json = {
        {"bin_edges_m", occ.cam0.edges_m},
        {"mode", occupancy::OccupancyModeName(options.mode)},
        {"encoding", options.encoding},
        {"voxel_m", options.fusion.voxel_size_m},
        {"grid", {occ.cam0.height, occ.cam0.width}},
        {"counts0", {{"occupied", c0.occupied}, {"free", c0.free}, {"unknown", c0.unknown}}},
        {"counts1", {{"occupied", c1.occupied}, {"free", c1.free}, {"unknown", c1.unknown}}}};
  }
  json image_json = nullptr;
  if (with_images) {
    add("image0." + options.image, std::move(encoded_image[0]));
    add("image1." + options.image, std::move(encoded_image[1]));
    const Camera k0 = f0.color_camera.Resized(options.width, options.height);
    const Camera k1 = f1.color_camera.Resized(options.width, options.height);
    image_json = {
        {"format", options.image}, {"K0", MatrixJson(k0.K())}, {"K1", MatrixJson(k1.K())}};
  }
  if (options.depth) {
    add("depth0.npy", io::EncodeNpy<float>({H, W}, depth0.values_m));
    add("depth1.npy", io::EncodeNpy<float>({H, W}, depth1.values_m));
  }

  int64_t type_counts[3] = {0, 0, 0};
  for (uint8_t t : pm.match_type) ++type_counts[t];
  const Rigid3d cam1_from_cam0 = labels.cam1_from_cam0;
  json metrics = {{"01", MetricsJson(labels.m01)}, {"10", MetricsJson(labels.m10)}};
  json score_metrics = {{"01", MetricsJson(pair.score01)}, {"10", MetricsJson(pair.score10)}};
  json meta = {
      {"key", key},
      {"scene", scene.name},
      {"frame0", {{"id", f0.id}, {"number", f0.number}}},
      {"frame1", {{"id", f1.id}, {"number", f1.number}}},
      {"resolution", {options.width, options.height}},
      {"K0", MatrixJson(cam0.K())},
      {"K1", MatrixJson(cam1.K())},
      {"world_from_cam0", MatrixJson(f0.world_from_cam.matrix())},
      {"world_from_cam1", MatrixJson(f1.world_from_cam.matrix())},
      {"T_0to1", MatrixJson(cam1_from_cam0.matrix())},
      {"metrics", metrics},
      {"score_metrics", score_metrics},
      {"matches",
       {{"total", M}, {"vv", type_counts[0]}, {"vo", type_counts[1]}, {"ov", type_counts[2]}}},
      {"patch_stride", options.patches.stride},
      {"anchor", AnchorName(options.patches.anchor)},
      {"label_preset_options",
       {{"abs_tol_m", options.labels.abs_tol_m},
        {"rel_tol", options.labels.rel_tol},
        {"min_depth_m", options.labels.min_depth_m},
        {"max_depth_m", options.labels.max_depth_m},
        {"relative_to", RelativeToName(options.labels.relative_to)},
        {"bounds", BoundsName(options.labels.bounds)},
        {"target_lookup", TargetLookupName(options.labels.target_lookup)},
        {"missing_target", MissingTargetName(options.labels.missing_target)}}},
      {"occupancy", occupancy_json},
      {"image", image_json},
      {"options_digest", options.digest},
      {"recipe", options.recipe_name},
      {"split", options.split}};
  std::string meta_text = meta.dump(1) + "\n";
  out.bytes += static_cast<int64_t>(meta_text.size());
  out.fields[0].second = std::move(meta_text);

  out.pair_line = {{"scene", scene.name},
                   {"frame0", f0.id},
                   {"frame1", f1.id},
                   {"number0", f0.number},
                   {"number1", f1.number},
                   {"metrics", metrics},
                   {"score_metrics", score_metrics},
                   {"matches", M},
                   {"T_0to1", MatrixJson(cam1_from_cam0.matrix())}};
  return out;
}

}  // namespace gt::pairs

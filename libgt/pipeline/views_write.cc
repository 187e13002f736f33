#include "libgt/pipeline/views_write.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "libgt/pairs/selection.h"
#include "libgt/pipeline/build.h"
#include "libgt/pipeline/image_cache.h"
#include "libgt/pipeline/sample.h"
#include "libgt/pipeline/write.h"
#include "libgt/shards/split.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/views_truth.h"
#include "libgt/truth/working_frame.h"

namespace gt::pipeline {
namespace {

using nlohmann::json;

// The frames, depth maps and encoded images of one scene.
struct ViewsScene {
  Scene scene;
  SampleOptions options;  // with the scene's label options
  std::unique_ptr<pairs::DepthCache> depths;
  std::unique_ptr<ImageCache> images;
  std::map<std::string, size_t> index_of_id;
};

std::shared_ptr<ViewsScene> LoadViewsScene(const Recipe& recipe,
                                           const datasets::DatasetReader& reader,
                                           const std::string& name) {
  auto d = std::make_shared<ViewsScene>();
  d->scene = ReadRecipeScene(recipe, reader, name);
  d->options = RecipeSampleOptions(recipe);
  d->options.truth = RecipePairTruthOptions(recipe, d->scene);
  d->depths = std::make_unique<pairs::DepthCache>(d->scene, recipe.width, recipe.height,
                                                  pairs::kDefaultDepthCacheMb << 20,
                                                  RecipeFrameDepthOptions(recipe));
  d->images = std::make_unique<ImageCache>(
      128, [s = d.get()](size_t i) { return EncodeFrameImage(s->scene.frames[i], s->options); });
  for (size_t i = 0; i < d->scene.frames.size(); ++i) d->index_of_id[d->scene.frames[i].id] = i;
  return d;
}

std::string SampleKey(const std::string& scene, int64_t line) {
  char tail[32];
  std::snprintf(tail, sizeof(tail), "/tuple_%06lld", static_cast<long long>(line));
  return shards::SanitizeScenePath(scene) + tail;
}

json Rows(const std::vector<float>& m, size_t n) {
  json out = json::array();
  for (size_t a = 0; a < n; ++a) {
    out.push_back(std::vector<float>(m.begin() + a * n, m.begin() + (a + 1) * n));
  }
  return out;
}

EncodedSample ComputeViewsSample(const ViewsScene& d, const TupleLine& line, int64_t index,
                                 const Recipe& recipe, const std::string& out_dir) {
  const SampleOptions& options = d.options;
  const std::string where = out_dir + "/tuples.jsonl line " + std::to_string(index + 1);
  const size_t n = line.frame_ids.size();
  std::vector<size_t> frames;
  std::vector<truth::WorkingFrame> views;
  for (const std::string& id : line.frame_ids) {
    auto it = d.index_of_id.find(id);
    if (it == d.index_of_id.end()) {
      throw InputError(where, "frame " + id + " is not in scene " + line.scene);
    }
    const Frame& f = d.scene.frames[it->second];
    frames.push_back(it->second);
    views.push_back(
        {d.depths->Get(it->second), truth::WorkingCamera(f, options.resolution), f.world_from_cam});
  }
  truth::ViewsTruthOptions vo;
  vo.labels = options.truth.labels;
  vo.num_tracks = recipe.tuple_tracks.num_tracks;
  vo.query_view = recipe.tuple_tracks.query_view;
  vo.seed = recipe.seed + static_cast<uint64_t>(index);
  const truth::ViewsTruth t = truth::ComputeViewsTruth(views, vo);
  // Every view is a frame the graph kept: occgt covis's scan (ScanRecipeFrames) needs colour
  // when images are stored and this much valid depth. A frame that fails now was changed
  // since the graph was made; its sample would come without images or without ground truth.
  const size_t hw = static_cast<size_t>(t.width) * t.height;
  const std::string rerun =
      " (changed since occgt covis made the graph?); re-run occgt covis "
      "for scene " +
      line.scene + " after deleting its graph";
  for (size_t a = 0; a < n; ++a) {
    const Frame& f = d.scene.frames[frames[a]];
    if (options.image != ImageFormat::kNone && f.color_path.empty()) {
      throw InputError(where, "frame " + f.id + " has no colour image, which sample.image (" +
                                  ImageFormatName(options.image) + ") needs" + rerun);
    }
    // Row a of the histogram counts view a's valid pixels by how many views see them.
    const auto row = t.seen_by_histogram.begin() + static_cast<std::ptrdiff_t>(a * n);
    const auto valid = static_cast<size_t>(std::accumulate(row, row + n, int64_t{0}));
    const double fraction = static_cast<double>(valid) / static_cast<double>(hw);
    if (valid == 0 || fraction < recipe.dataset.min_valid_depth_fraction) {
      throw InputError(where, "frame " + f.id + " has " + std::to_string(valid) +
                                  " valid depth pixels of " + std::to_string(hw) +
                                  ", below dataset.min_valid_depth_fraction " +
                                  std::to_string(recipe.dataset.min_valid_depth_fraction) + rerun);
    }
  }

  EncodedSample out;
  shards::Sample& sample = out.sample;
  sample.key = SampleKey(line.scene, index);
  const int64_t W = options.resolution.width, H = options.resolution.height;
  const int64_t N = static_cast<int64_t>(n), Q = static_cast<int64_t>(t.num_queries());
  auto add = [&](const std::string& name, std::string bytes) {
    AddSampleField(&sample, name, std::move(bytes), options.compression);
  };
  add("json", "");                                               // filled last
  const bool with_images = options.image != ImageFormat::kNone;  // each view has colour (above)
  std::vector<double> K, world_from_cam;
  json frames_json = json::array(), K_json = json::array(), pose_json = json::array();
  json color_K_json = json::array();
  for (size_t a = 0; a < n; ++a) {
    const Frame& f = d.scene.frames[frames[a]];
    if (with_images)
      add("image" + std::to_string(a) + "." + ImageFormatName(options.image),
          *d.images->Get(frames[a]));
    add("depth" + std::to_string(a) + ".npy",
        io::EncodeNpy<float>({H, W}, views[a].depth->values_m));
    const Eigen::Matrix3d k = views[a].camera.K();
    const Eigen::Matrix4d T = f.world_from_cam.matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K.push_back(k(r, c));
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) world_from_cam.push_back(T(r, c));
    frames_json.push_back({{"id", f.id}, {"number", f.number}});
    K_json.push_back(truth::MatrixJson(k));
    pose_json.push_back(truth::MatrixJson(T));
    if (with_images) color_K_json.push_back(truth::MatrixJson(f.color_camera.Resized(W, H).K()));
  }
  add("intrinsics.npy", io::EncodeNpy<double>({N, 3, 3}, K));
  add("world_from_cam.npy", io::EncodeNpy<double>({N, 4, 4}, world_from_cam));
  add("visible_in.npy", io::EncodeNpy<uint32_t>({N, H, W}, t.visible_in));
  add("occluded_in.npy", io::EncodeNpy<uint32_t>({N, H, W}, t.occluded_in));
  add("valid.npy", io::EncodeNpy<uint8_t>({N, H, W}, t.valid));
  add("queries.npy", io::EncodeNpy<int32_t>({Q, 2}, t.queries));
  add("track_xy.npy", io::EncodeNpy<float>({N, Q, 2}, t.track_xy));
  add("track_depth.npy", io::EncodeNpy<float>({N, Q}, t.track_depth));
  add("track_state.npy", io::EncodeNpy<uint8_t>({N, Q}, t.track_state));

  // Bit counts over the ordered pairs i != j (the tuple's occlusion).
  int64_t valid = 0, visible = 0, occluded = 0;
  const size_t plane = static_cast<size_t>(W * H);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t others = ~(uint32_t{1} << i);
    for (size_t p = i * plane; p < (i + 1) * plane; ++p) {
      valid += t.valid[p];
      visible += static_cast<int64_t>(std::bitset<32>(t.visible_in[p] & others).count());
      occluded += static_cast<int64_t>(std::bitset<32>(t.occluded_in[p] & others).count());
    }
  }
  // OCCLUDED / (VISIBLE + OCCLUDED): the pair metric occlusion_ratio_visible over the tuple.
  const double occlusion_ratio_visible =
      visible + occluded > 0 ? static_cast<double>(occluded) / (visible + occluded) : 0.0;
  const json meta = {
      {"kind", "occgt-views-sample"},
      {"key", sample.key},
      {"scene", line.scene},
      {"tuple_index", index},
      {"num_views", N},
      {"frames", frames_json},
      {"resolution", {W, H}},
      {"K", K_json},
      {"world_from_cam", pose_json},
      {"covisibility", Rows(line.covisibility, n)},
      {"label_options", truth::LabelOptionsJson(options.truth.labels)},
      {"tracks",
       {{"num_tracks", vo.num_tracks},
        {"query_view", vo.query_view},
        {"seed", vo.seed},
        {"count", Q}}},
      {"metrics",
       {{"counts", {{"VISIBLE", visible}, {"OCCLUDED", occluded}}},
        {"valid", valid},
        {"occlusion_ratio_visible", occlusion_ratio_visible}}},
      {"image", with_images ? json{{"format", ImageFormatName(options.image)}, {"K", color_K_json}}
                            : json(nullptr)},
      {"compression", SampleCompressionName(options.compression)},
      {"options_digest", options.digest},
      {"recipe", options.recipe_name},
      {"split", options.split}};
  sample.fields[0].bytes = meta.dump(1) + "\n";
  json ids = json::array();
  for (const std::string& id : line.frame_ids) ids.push_back(id);
  out.pair_line = json{{"scene", line.scene},
                       {"tuple_index", index},
                       {"frame_ids", ids},
                       {"options_digest", options.digest},
                       {"occlusion_ratio_visible", occlusion_ratio_visible}}
                      .dump();
  return out;
}

// A complete shard is kept only when it holds these tuples under these options: its part
// record's lines name the same scene, frames and options digest, sample by sample.
void CheckCompleteShard(const std::string& dir, const Recipe& recipe, int64_t shard, int64_t start,
                        const std::vector<TupleLine>& lines) {
  const shards::PartRecord r = shards::ReadPartRecord(dir, recipe.split, shard);
  const std::string digest = RecipeSampleOptions(recipe).digest;
  for (size_t k = 0; k < r.pair_lines.size(); ++k) {
    const json line = json::parse(r.pair_lines[k]);
    const TupleLine& want = lines.at(static_cast<size_t>(start) + k);
    if (line.value("scene", "") != want.scene || line.value("options_digest", "") != digest ||
        line.value("frame_ids", std::vector<std::string>{}) != want.frame_ids) {
      throw InputError(
          shards::PartRecordPath(dir, recipe.split, shard),
          "written for other tuples or options (sample " + r.keys[k] + "); use a fresh --out");
    }
  }
}

}  // namespace

std::string ViewsShardDir(const std::string& out_dir) { return out_dir + "/views"; }

void CheckViewsShards(const Recipe& recipe, const std::string& out_dir,
                      const std::vector<TupleLine>& lines) {
  const std::string dir = ViewsShardDir(out_dir);
  const std::string plan = shards::PlanPath(dir, recipe.split);
  if (!io::FileExists(plan)) return;  // no N-view shards yet
  const std::vector<int64_t> sizes = PlanViewsShards(recipe, lines);
  if (shards::ReadPlan(dir, recipe.split).shard_nsamples != sizes) {
    throw InputError(plan,
                     "holds the N-view shard plan of other tuples than this run's; use a "
                     "fresh --out (or remove " +
                         dir + ")");
  }
  for (int64_t s = 0, start = 0; s < static_cast<int64_t>(sizes.size()); start += sizes[s], ++s) {
    if (shards::IsShardComplete(dir, recipe.split, s)) {
      CheckCompleteShard(dir, recipe, s, start, lines);
    }
  }
}

void CheckViewsKeys(const Recipe& recipe, const std::vector<TupleLine>& lines) {
  // world_from_cam.npy is the longest field of an N-view sample (the list in views_write.h).
  const std::string longest = StoredFieldName("world_from_cam.npy", recipe.sample.compression);
  for (size_t k = 0; k < lines.size(); ++k) {
    const std::string key = SampleKey(lines[k].scene, static_cast<int64_t>(k));
    std::string e = shards::CheckSampleKey(key);
    if (e.empty()) e = shards::CheckMemberPath(key, longest);
    if (!e.empty()) {
      throw InputError("sample key " + key,
                       e + " (scene " + lines[k].scene + "): shorten the scene name");
    }
  }
}

int64_t EstimatedViewsSampleBytes(const Recipe& r, int views) {
  const bool deflate = r.sample.compression == SampleCompression::kDeflate;
  const double sparse = deflate ? 0.06 : 1.0;
  const double px = static_cast<double>(r.width) * r.height;
  const double tracks = r.tuples ? r.tuple_tracks.num_tracks : 0;
  double per_view = (deflate ? DeflatedDepthShare(r) : 1.0) * 4 * px + sparse * 9 * px +
                    (deflate ? 0.9 : 1.0) * 13 * tracks;
  if (r.sample.image == ImageFormat::kPng) per_view += 2 * px;
  if (r.sample.image == ImageFormat::kJpg) per_view += px * 3 / 10;
  return static_cast<int64_t>(std::ceil(4096 + 8 * tracks + views * per_view));
}

std::vector<int64_t> PlanViewsShards(const Recipe& recipe, const std::vector<TupleLine>& lines) {
  const int64_t total = static_cast<int64_t>(lines.size());
  std::vector<int64_t> sizes;
  if (recipe.shards.target_mb <= 0) {
    const int64_t per_shard = recipe.shards.samples_per_shard;
    for (int64_t start = 0; start < total; start += per_shard) {
      sizes.push_back(std::min(per_shard, total - start));
    }
    return sizes;
  }
  // Integers, so that the plan cannot depend on a rounding order; at most 1e18 bytes, so that
  // the conversion cannot overflow (a target of 1e300 MB gave every sample its own shard).
  const auto target = static_cast<int64_t>(std::min(recipe.shards.target_mb * 1e6, 1e18));
  int64_t bytes = 0;
  for (const TupleLine& line : lines) {
    const int64_t sample =
        EstimatedViewsSampleBytes(recipe, static_cast<int>(line.frame_ids.size()));
    if (sizes.empty() || bytes + sample > target) {
      sizes.push_back(0);
      bytes = 0;
    }
    ++sizes.back();
    bytes += sample;
  }
  return sizes;
}

json WriteViewsShards(const Recipe& recipe, const datasets::DatasetReader& reader,
                      const std::string& out_dir, const std::vector<TupleLine>& lines) {
  BuildOptions options;
  options.out_dir = ViewsShardDir(out_dir);
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) throw InputError(options.out_dir, "cannot create the output folder: " + ec.message());
  const int64_t total = static_cast<int64_t>(lines.size());
  const std::vector<int64_t> sizes = PlanViewsShards(recipe, lines);
  WritePlan(options, recipe.split, sizes);
  const size_t threads = std::max<size_t>(
      1, tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const int64_t chunk = static_cast<int64_t>(2 * threads);
  std::map<std::string, std::shared_ptr<ViewsScene>> scenes;
  int64_t written = 0, skipped = 0;
  for (int64_t s = 0, start = 0; s < static_cast<int64_t>(sizes.size()); start += sizes[s], ++s) {
    if (shards::IsShardComplete(options.out_dir, recipe.split, s)) {
      CheckCompleteShard(options.out_dir, recipe, s, start, lines);
      ++skipped;
      continue;
    }
    shards::SplitShardWriter writer(options.out_dir, recipe.split, s,
                                    RecipeSampleOptions(recipe).digest);
    for (int64_t c = start; c < start + sizes[s]; c += chunk) {
      const int64_t end = std::min(c + chunk, start + sizes[s]);
      std::vector<std::shared_ptr<ViewsScene>> data(end - c);
      for (int64_t k = c; k < end; ++k) {  // serial: scenes are read in order, once
        auto it = scenes.find(lines[k].scene);
        if (it == scenes.end()) {
          scenes.clear();  // lines are in scene order: the previous scene is done
          it = scenes.emplace(lines[k].scene, LoadViewsScene(recipe, reader, lines[k].scene)).first;
        }
        data[k - c] = it->second;
      }
      std::vector<EncodedSample> samples(end - c);
      // A bad sample's error is the first in line order, whatever the thread count.
      std::vector<std::exception_ptr> failed(end - c);
      tbb::parallel_for(int64_t{0}, end - c, [&](int64_t k) {
        try {
          samples[k] = ComputeViewsSample(*data[k], lines[c + k], c + k, recipe, out_dir);
        } catch (...) {
          failed[k] = std::current_exception();
        }
      });
      for (const std::exception_ptr& e : failed) {
        if (!e) continue;
        try {
          std::rethrow_exception(e);
        } catch (const InputError& error) {
          // tuples.jsonl is this run's and shards before this one may be complete: a run on
          // other graphs (other tuples) would find them and refuse its plan.
          throw InputError(error.what(), "remove " + options.out_dir +
                                             " too before a run on other graphs (it holds "
                                             "shards of these tuples)");
        }
      }
      for (EncodedSample& e : samples) writer.Add(std::move(e.sample), e.pair_line);
    }
    writer.Finish();
    ++written;
  }
  // A re-run that wrote no shard leaves the published indices alone (no new inodes or
  // mtimes), as `occgt build` does; one deleted since is written again.
  // summary.json as `occgt merge` writes it (the split's counts, tuples per scene), so that
  // the folder is the same whichever made it.
  if (written > 0 || !io::FileExists(options.out_dir + "/index.json") ||
      !io::FileExists(options.out_dir + "/pairs.jsonl") ||
      !io::FileExists(options.out_dir + "/summary.json")) {
    shards::MergeOptions merge;
    merge.split = recipe.split;
    shards::WriteMergeSummary(options.out_dir, shards::MergeSplit(options.out_dir, merge));
  }
  return {{"dir", options.out_dir},
          {"shards", static_cast<int64_t>(sizes.size())},
          {"shards_written", written},
          {"shards_skipped", skipped},
          {"samples", total}};
}

}  // namespace gt::pipeline

#include "libgt/pipeline/write.h"

#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/folder_lock.h"
#include "libgt/pairs/selection.h"
#include "libgt/pipeline/image_cache.h"
#include "libgt/pipeline/select.h"
#include "libgt/shards/loftr_export.h"
#include "libgt/shards/loftr_tree.h"
#include "libgt/shards/megadepth_export.h"
#include "libgt/shards/posed_export.h"
#include "libgt/shards/split.h"
#include "libgt/truth/working_frame.h"

namespace gt::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Everything the write stage needs about one scene.
struct SceneData {
  Scene scene;
  SampleOptions options;  // with the scene's label options
  std::unique_ptr<pairs::DepthCache> depths;
  std::unique_ptr<ImageCache> images;  // encoded colour images (128 frames)
  std::map<std::string, size_t> index_of_id;
  std::once_flag map_once;  // scope scene: one map for every pair
  std::unique_ptr<truth::ScopeMap> scene_map;
};

std::shared_ptr<SceneData> LoadSceneData(const Recipe& recipe,
                                         const datasets::DatasetReader& reader,
                                         const std::string& name, const BuildOptions& options) {
  auto d = std::make_shared<SceneData>();
  d->scene = ReadRecipeScene(recipe, reader, name);
  d->options = RecipeSampleOptions(recipe);
  d->options.truth = RecipePairTruthOptions(recipe, d->scene);
  d->depths = std::make_unique<pairs::DepthCache>(d->scene, recipe.width, recipe.height,
                                                  options.depth_cache_mb << 20,
                                                  RecipeFrameDepthOptions(recipe));
  d->images = std::make_unique<ImageCache>(
      128, [s = d.get()](size_t i) { return EncodeFrameImage(s->scene.frames[i], s->options); });
  for (size_t i = 0; i < d->scene.frames.size(); ++i) d->index_of_id[d->scene.frames[i].id] = i;
  return d;
}

truth::WorkingFrame FrameOf(SceneData* d, size_t i) {
  const Frame& f = d->scene.frames[i];
  return {d->depths->Get(i), truth::WorkingCamera(f, d->options.resolution), f.world_from_cam};
}

// The fused map of a window or scene scope; a frame of the scope that cannot be read fails
// the sample (as a pair frame would); its unusable frames are left out, counted by the scan
// (scan.*).
std::unique_ptr<truth::ScopeMap> FuseScopeOf(SceneData* d, size_t i0, size_t i1) {
  auto map = std::make_unique<truth::ScopeMap>(truth::FuseScope(
      d->scene, i0, i1, d->options.truth, [d](size_t i) { return FrameOf(d, i); }));
  for (const truth::ScopeMap::Skipped& s : map->skipped) {
    if (!s.unusable) throw InputError("scene " + d->scene.name + " frame " + s.frame_id, s.reason);
  }
  return map;
}

// Runs a shard's Finish (close, fsync, rename, part record) on a thread of its own while
// the build goes on. Get() returns its size (rethrows its error) once Finish has returned;
// the writer, with the buffers it still holds, is destroyed on that thread. The thread is
// joined by the next Start() and by the destructor.
class ShardFinisher {
 public:
  ShardFinisher() = default;
  ShardFinisher(const ShardFinisher&) = delete;
  ShardFinisher& operator=(const ShardFinisher&) = delete;
  ~ShardFinisher() { Join(); }

  void Start(std::unique_ptr<shards::SplitShardWriter> writer) {
    Join();
    std::promise<int64_t> promise;
    result_ = promise.get_future();
    thread_ = std::thread([w = std::move(writer), promise = std::move(promise)]() mutable {
      try {
        promise.set_value(w->Finish().info.filesize);
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
      w.reset();
    });
  }
  bool pending() const { return result_.valid(); }
  int64_t Get() { return result_.get(); }

 private:
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  std::future<int64_t> result_;
  std::thread thread_;
};

}  // namespace

std::vector<int64_t> PlanShards(const Recipe& recipe, int64_t total) {
  int64_t per_shard = recipe.shards.samples_per_shard;
  if (recipe.shards.target_mb > 0) {
    // In doubles until it is known to fit: a target of 1e300 MB overflowed the int64
    // conversion, and every sample got a shard of its own. No shard holds more than all.
    const double fit = recipe.shards.target_mb * 1e6 / EstimatedSampleBytes(recipe);
    per_shard = fit >= static_cast<double>(std::max<int64_t>(total, 1))
                    ? std::max<int64_t>(total, 1)
                    : std::max<int64_t>(1, static_cast<int64_t>(fit));
  }
  std::vector<int64_t> sizes;
  for (int64_t start = 0; start < total; start += per_shard) {
    sizes.push_back(std::min(per_shard, total - start));
  }
  return sizes;
}

std::vector<std::string> SampleKeys(const std::vector<const SelectedPair*>& all,
                                    SampleCompression compression) {
  std::vector<std::string> keys(all.size());
  std::map<std::string, size_t> seen;
  const std::string longest = LongestPairField(compression);
  for (size_t k = 0; k < all.size(); ++k) {
    keys[k] = shards::MakeSampleKey(all[k]->scene, all[k]->frame0, all[k]->frame1);
    if (std::string e = shards::CheckMemberPath(keys[k], longest); !e.empty()) {
      throw InputError("sample key " + keys[k], e + " (scene " + all[k]->scene + ", frames " +
                                                    all[k]->frame0 + " and " + all[k]->frame1 +
                                                    "): shorten the scene name or the frame ids");
    }
    auto [it, inserted] = seen.emplace(keys[k], k);
    if (!inserted) {
      // Named by scene and frames: frame ids joined by '_' collide as well as sanitised
      // scene names ("0_1" and "2", "0" and "1_2").
      auto pair = [](const SelectedPair& p) {
        return "scene " + p.scene + ", frames " + p.frame0 + " and " + p.frame1;
      };
      throw InputError("sample key " + keys[k], "two pairs map to the same key after sanitising (" +
                                                    pair(*all[it->second]) + "; " + pair(*all[k]) +
                                                    ")");
    }
  }
  return keys;
}

void WritePlan(const BuildOptions& options, const std::string& split,
               const std::vector<int64_t>& shard_sizes) {
  io::FolderLock lock(options.out_dir);
  const std::string path = shards::PlanPath(options.out_dir, split);
  if (io::FileExists(path)) {
    if (shards::ReadPlan(options.out_dir, split).shard_nsamples != shard_sizes) {
      throw InputError(path, "holds another shard plan than this recipe's; use a fresh --out");
    }
    return;
  }
  shards::SplitPlan plan;
  plan.split = split;
  plan.shard_nsamples = shard_sizes;
  shards::WritePlan(options.out_dir, plan);
}

bool AllShardsComplete(const BuildOptions& options, const std::string& split, int64_t nshards) {
  for (int64_t s = 0; s < nshards; ++s) {
    if (!shards::IsShardComplete(options.out_dir, split, s)) return false;
  }
  return true;
}

WriteResult WriteShards(const Recipe& recipe, const datasets::DatasetReader& reader,
                        const BuildOptions& options, const std::vector<const SelectedPair*>& all,
                        const std::vector<std::string>& keys,
                        const std::vector<int64_t>& shard_sizes, const ProgressFn& progress) {
  const auto t_write = Clock::now();
  WriteResult result;
  // This task's work: the samples of its incomplete shards, in order (shard s is this
  // task's when s % tasks == task). Complete shards are skipped (resume).
  struct Job {
    int64_t shard;   // shard index
    int64_t sample;  // index into `all` (and `keys`)
  };
  std::vector<Job> jobs;
  int64_t my_samples = 0, done_samples = 0;  // progress unit of the write stage: samples
  int64_t resumed_samples = 0;               // of those, in shards found complete
  const int64_t nshards = static_cast<int64_t>(shard_sizes.size());
  // Byte s of DIR/.shards.lock while this task may write shard s: the task lock keeps out a
  // second run of task K, this one a task of another --tasks count that owns the same shard
  // (task 1 of 2 and task 3 of 4 both own shard 3), which would write the same temporary
  // file. Taken before the shards are found complete, so a shard another task finished in
  // between is skipped.
  std::vector<int64_t> mine;
  for (int64_t s = options.task; s < nshards; s += options.tasks) mine.push_back(s);
  int64_t busy = 0;
  const std::unique_ptr<io::FileLock> shard_locks =
      io::FileLock::TryAcquire(options.out_dir + "/.shards.lock", mine, &busy);
  if (!shard_locks) {
    throw InputError(options.out_dir,
                     "another occgt build is writing shard " + std::to_string(busy) + " of split " +
                         recipe.split +
                         " now (a task of another --tasks count?); wait for it to finish, or "
                         "give every task of the split the same --tasks");
  }
  for (int64_t s = 0, start = 0; s < nshards; start += shard_sizes[s], ++s) {
    if (s % options.tasks != options.task) continue;
    my_samples += shard_sizes[s];
    if (shards::IsShardComplete(options.out_dir, recipe.split, s)) {
      ++result.shards_skipped;
      resumed_samples += shard_sizes[s];
    } else {
      for (int64_t k = start; k < start + shard_sizes[s]; ++k) jobs.push_back({s, k});
    }
  }
  done_samples = resumed_samples;
  if (progress && resumed_samples > 0) {
    progress({Stage::kWrite, done_samples, my_samples, Seconds(t_write), resumed_samples});
  }
  if (jobs.empty()) return result;

  // A scene's data is dropped from `scene_data` when its last sample of this task enters
  // the pipeline; the samples in flight hold it (shared_ptr) until they are computed, so a
  // task over many scenes holds only the current ones in memory.
  std::map<std::string, std::shared_ptr<SceneData>> scene_data;
  std::map<std::string, size_t> last_job_of_scene;
  for (size_t j = 0; j < jobs.size(); ++j) last_job_of_scene[all[jobs[j].sample]->scene] = j;
  struct Item {
    std::shared_ptr<SceneData> data;
    EncodedSample sample;
  };
  // The items in flight are owned here, and only their job numbers travel through the
  // pipeline: a cancelled tbb::parallel_pipeline does not destroy the values still in its
  // buffers.
  std::vector<std::unique_ptr<Item>> items(jobs.size());
  size_t next_job = 0;
  std::unique_ptr<shards::SplitShardWriter> writer;  // the shard being filled
  int64_t in_writer = 0;                             // its samples so far
  const std::string digest = recipe.Digest();        // recorded with each shard
  ShardFinisher finisher;
  int64_t finishing_samples = 0;
  auto collect_finished = [&] {
    if (!finisher.pending()) return;
    result.bytes_written += finisher.Get();
    ++result.shards_written;
    result.samples_written += finishing_samples;
  };

  auto input = [&](tbb::flow_control& fc) -> size_t {
    if (next_job == jobs.size()) {
      fc.stop();
      return 0;
    }
    const size_t j = next_job++;
    items[j] = std::make_unique<Item>();
    const std::string& scene = all[jobs[j].sample]->scene;
    std::shared_ptr<SceneData>& d = scene_data[scene];
    if (!d) d = LoadSceneData(recipe, reader, scene, options);
    items[j]->data = d;
    if (last_job_of_scene.at(scene) == j) scene_data.erase(scene);
    return j;
  };
  auto compute = [&](size_t j) -> size_t {
    Item* item = items[j].get();
    const int64_t k = jobs[j].sample;
    const SelectedPair& p = *all[k];
    SceneData& d = *item->data;
    auto i0 = d.index_of_id.find(p.frame0), i1 = d.index_of_id.find(p.frame1);
    if (i0 == d.index_of_id.end() || i1 == d.index_of_id.end()) {
      throw InputError(SelectionDir(options.out_dir) + "/" + SceneFileName(p.scene) + ".jsonl",
                       "frame " + p.frame0 + " or " + p.frame1 + " no longer in the dataset");
    }
    const occupancy::OccupancyMap* scope_map = nullptr;
    std::unique_ptr<truth::ScopeMap> window_map;
    const truth::PairTruthOptions& t = d.options.truth;
    if (t.occupancy && t.mode == occupancy::OccupancyMode::kOctomap) {
      if (t.fusion.scope == occupancy::FusionScope::kScene) {
        std::call_once(d.map_once, [&] { d.scene_map = FuseScopeOf(&d, i0->second, i1->second); });
        scope_map = &d.scene_map->map;
      } else if (t.fusion.scope == occupancy::FusionScope::kWindow) {
        window_map = FuseScopeOf(&d, i0->second, i1->second);
        scope_map = &window_map->map;
      }
    }
    const ImageSource images = [&d](size_t i) { return d.images->Get(i); };
    item->sample =
        ComputeSample(d.scene, i0->second, i1->second, p, keys[k], FrameOf(&d, i0->second),
                      FrameOf(&d, i1->second), d.options, scope_map, images);
    item->data.reset();  // the last sample of a scene releases its data here
    return j;
  };
  auto collect = [&](size_t j) {
    const int64_t s = jobs[j].shard;
    if (!writer) {
      writer = std::make_unique<shards::SplitShardWriter>(options.out_dir, recipe.split, s, digest);
    }
    EncodedSample& e = items[j]->sample;
    writer->Add(std::move(e.sample), e.pair_line);
    items[j].reset();
    const int64_t n = shard_sizes[s];
    if (++in_writer < n) return;
    collect_finished();
    finishing_samples = n;
    finisher.Start(std::move(writer));
    in_writer = 0;
    done_samples += n;
    if (progress) {
      progress({Stage::kWrite, done_samples, my_samples, Seconds(t_write), resumed_samples});
    }
  };
  const size_t threads = std::max<size_t>(
      1, tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  tbb::parallel_pipeline(
      2 * threads, tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order, input) &
                       tbb::make_filter<size_t, size_t>(tbb::filter_mode::parallel, compute) &
                       tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order, collect));
  collect_finished();
  return result;
}

namespace {

// The depth the exports write (shards/frame_files.h): the build's own when it is not the
// sensor's file (dataset.depth_source mesh or fused: the working depth, rendered directly at
// the export's size in the frame's working camera, exactly as the shards' depth at that
// size); empty for `sensor`, where the exports read (or link) the depth files.
shards::FrameDepthLoader ExportDepthLoader(const Recipe& recipe) {
  if (recipe.dataset.depth_source == render::DepthSourceMode::kSensor) return {};
  const render::FrameDepthOptions depth = RecipeFrameDepthOptions(recipe);
  return [depth](const Scene& scene, const Frame& frame, int width, int height) {
    return truth::LoadWorkingDepth(scene, frame, truth::Resolution{width, height}, depth);
  };
}

// DIR/gluefactory/ and DIR/dust3r/ (libgt/shards/posed_export.h): the pairs with their
// selection score and both overlaps, the frames at the working resolution.
void PublishPosedExports(const Recipe& recipe, const BuildOptions& options,
                         const std::vector<const SelectedPair*>& all,
                         const std::map<std::string, Scene>& scenes) {
  std::vector<shards::PosedPair> pairs;
  for (const SelectedPair* p : all) {
    shards::PosedPair row;
    row.scene = p->scene;
    row.frame0 = p->number0;
    row.frame1 = p->number1;
    row.score = Combine(p->score01.overlap, p->score10.overlap, recipe.selection.aggregate);
    row.overlap01 = p->score01.overlap;
    row.overlap10 = p->score10.overlap;
    pairs.push_back(row);
  }
  std::map<std::string, const Scene*> scene_ptrs;
  for (const auto& [name, scene] : scenes) scene_ptrs[name] = &scene;
  shards::PosedExportOptions posed;
  posed.width = recipe.width;
  posed.height = recipe.height;
  posed.load_depth = ExportDepthLoader(recipe);
  if (recipe.gluefactory_export) {
    shards::ExportGlueFactory(options.out_dir + "/gluefactory", scene_ptrs, pairs, posed);
  }
  if (recipe.dust3r_export) {
    shards::ExportDust3r(options.out_dir + "/dust3r", scene_ptrs, pairs, posed);
  }
}

// The pair's score in a LoFTR index (recipe loftr_export.score).
double LoftrScoreOf(const Recipe& recipe, const SelectedPair& p) {
  return recipe.loftr_score == LoftrScore::kCovisible
             ? Combine(p.score01.consistent_overlap, p.score10.consistent_overlap,
                       recipe.selection.aggregate)
             : Combine(p.score01.overlap, p.score10.overlap, recipe.selection.aggregate);
}

// LoFTR's root_dir for a MegaDepth file: the folder holding phoenix/ when the path has
// one (the download folder, where LoFTR's indices point), else the recipe's dataset root.
std::string MegaDepthRootDir(const std::string& path, const std::string& dataset_root) {
  const size_t at = path.rfind("/phoenix/S6/zl548/MegaDepth_v1/");
  if (at != std::string::npos) return path.substr(0, at);
  return dataset_root;
}

std::string RelativeTo(const std::string& path, const std::string& root) {
  return std::filesystem::path(path).lexically_relative(root).generic_string();
}

// DIR/loftr/scene_info/<scene>.npz and {split}_list.txt (shards/megadepth_export.h): every
// frame of each scene with a selected pair, the pairs by frame index.
void PublishMegaDepthIndex(const Recipe& recipe, const BuildOptions& options,
                           const std::vector<const SelectedPair*>& all,
                           const std::map<std::string, Scene>& scenes) {
  std::map<std::string, shards::MegaDepthIndexScene> index;
  for (const auto& [name, scene] : scenes) {
    shards::MegaDepthIndexScene& out = index[name];
    out.scene = name;
    for (const Frame& f : scene.frames) {
      const std::string root = MegaDepthRootDir(f.depth.path, recipe.dataset.root);
      shards::MegaDepthIndexFrame x;
      x.image_path = RelativeTo(f.color_path, root);
      if (f.usable) {
        x.depth_path = RelativeTo(f.depth.path, root);
        // COLMAP's convention: the top-left pixel's centre at (0.5, 0.5) (core/camera.h has
        // it at (0, 0)).
        const Camera& c = f.depth_camera;
        x.K = std::array<double, 9>{c.fx, 0, c.cx + 0.5, 0, c.fy, c.cy + 0.5, 0, 0, 1};
        const Eigen::Matrix4d T = f.world_from_cam.inverse().matrix();
        std::array<double, 16> t16;
        for (int r = 0; r < 4; ++r) {
          for (int c4 = 0; c4 < 4; ++c4) t16[r * 4 + c4] = T(r, c4);
        }
        x.cam_from_world = t16;
      }
      out.frames.push_back(std::move(x));
    }
  }
  for (const SelectedPair* p : all) {
    const Scene& scene = scenes.at(p->scene);
    shards::MegaDepthIndexPair pair;
    pair.i = static_cast<int64_t>(truth::FindFrame(scene, p->frame0, "selection"));
    pair.j = static_cast<int64_t>(truth::FindFrame(scene, p->frame1, "selection"));
    pair.score = LoftrScoreOf(recipe, *p);
    index.at(p->scene).pairs.push_back(pair);
  }
  std::vector<shards::MegaDepthIndexScene> list;
  for (auto& [name, s] : index) list.push_back(std::move(s));
  shards::LoftrExportOptions export_options;
  export_options.split = recipe.split;
  shards::ExportLoftrMegaDepth(options.out_dir + "/loftr", std::move(list), export_options);
}

}  // namespace

void CheckExportFolders(const Recipe& recipe, const std::vector<const SelectedPair*>& all) {
  std::set<std::string> names;
  for (const SelectedPair* p : all) names.insert(p->scene);
  if (recipe.loftr_export == LoftrExportKind::kTrain ||
      recipe.loftr_export == LoftrExportKind::kTest) {
    shards::LoftrSceneFolders(names);
  }
  if (recipe.gluefactory_export || recipe.dust3r_export) shards::PosedSceneFolders(names);
}

void PublishIndices(const Recipe& recipe, const datasets::DatasetReader& reader,
                    const BuildOptions& options, const std::vector<const SelectedPair*>& all) {
  shards::MergeOptions merge;
  merge.split = recipe.split;
  shards::MergeSplit(options.out_dir, merge);
  if (recipe.loftr_export == LoftrExportKind::kNone && !recipe.gluefactory_export &&
      !recipe.dust3r_export) {
    return;
  }
  std::map<std::string, Scene> scenes;
  for (const SelectedPair* p : all) {
    if (!scenes.count(p->scene)) {
      scenes.emplace(p->scene, ReadRecipeScene(recipe, reader, p->scene));
    }
  }
  if (recipe.gluefactory_export || recipe.dust3r_export) {
    PublishPosedExports(recipe, options, all, scenes);
  }
  if (recipe.loftr_export == LoftrExportKind::kNone) return;
  if (recipe.loftr_export == LoftrExportKind::kMegaDepth) {
    PublishMegaDepthIndex(recipe, options, all, scenes);
    return;
  }
  std::vector<shards::LoftrPair> rows;
  shards::SceneIntrinsics intrinsics;
  for (const SelectedPair* p : all) {
    const Scene& scene = scenes.at(p->scene);
    const Frame& f0 = scene.frames.at(truth::FindFrame(scene, p->frame0, "selection"));
    const Frame& f1 = scene.frames.at(truth::FindFrame(scene, p->frame1, "selection"));
    shards::LoftrPair row;
    row.scene = p->scene;
    row.frame0 = p->number0;
    row.frame1 = p->number1;
    row.score = LoftrScoreOf(recipe, *p);
    const Rigid3d t = RelativePose(f0.world_from_cam, f1.world_from_cam);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) row.cam1_from_cam0[r * 4 + c] = t.matrix()(r, c);
    }
    rows.push_back(row);
    if (!intrinsics.count(p->scene)) {
      // At the consumer's resolution (LoFTR resizes to 640x480), not the working one.
      const Eigen::Matrix3d K =
          truth::WorkingCamera(f0, {shards::kLoftrWidth, shards::kLoftrHeight}).K();
      std::array<double, 9> k9;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) k9[r * 3 + c] = K(r, c);
      }
      intrinsics[p->scene] = k9;
    }
  }
  shards::LoftrExportOptions export_options;
  export_options.split = recipe.split;
  if (recipe.loftr_export == LoftrExportKind::kTest) {
    shards::ExportLoftrTest(options.out_dir + "/loftr", rows, intrinsics, export_options);
  } else {
    shards::ExportLoftrTrain(options.out_dir + "/loftr", rows, intrinsics, export_options);
  }
  if (!recipe.loftr_tree) return;
  // The frames the index names, in ScanNet's exported layout (DIR/loftr/data/).
  std::set<std::string> names;
  for (const auto& [name, scene] : scenes) names.insert(name);
  const auto folders = shards::LoftrSceneFolders(names);
  std::vector<shards::LoftrTreeScene> tree;
  for (const auto& [name, scene] : scenes) {
    shards::LoftrTreeScene t;
    t.scene = &scene;
    t.folder = folders.at(name);
    for (const shards::LoftrPair& row : rows) {
      if (row.scene != name) continue;
      t.numbers.push_back(row.frame0);
      t.numbers.push_back(row.frame1);
    }
    tree.push_back(std::move(t));
  }
  shards::LoftrTreeOptions tree_options;
  tree_options.load_depth = ExportDepthLoader(recipe);
  const shards::LoftrTreeStats stats =
      shards::ExportLoftrTree(options.out_dir + "/loftr/data", tree, tree_options);
  const nlohmann::json doc = {{"frames", stats.frames},
                              {"linked", stats.linked},
                              {"converted", stats.converted},
                              {"depth_zeroed_px", stats.depth_zeroed_px}};
  io::WriteFileAtomic(options.out_dir + "/loftr/tree.json", doc.dump(2) + "\n");
}

}  // namespace gt::pipeline

#include "libgt/pairs/pipeline.h"

#include <fcntl.h>
#include <malloc.h>
#include <sys/file.h>
#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/io/files.h"
#include "libgt/io/npy.h"
#include "libgt/io/reader.h"
#include "libgt/pairs/image_cache.h"
#include "libgt/pairs/synthetic.h"

namespace gt::pairs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Exclusive advisory lock (flock) on DIR/.lock, held while a task writes one of the files
// that every task of a split may write at the same moment (recipe.json, the synthetic
// dataset, the shard plan, the indices and summary): WriteFileAtomic's fixed `X.tmp` name
// is safe for one writer only. The lock file is empty and never removed.
class FolderLock {
 public:
  explicit FolderLock(const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw InputError(dir, "cannot create the output folder: " + ec.message());
    const std::string path = dir + "/.lock";
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
    while (::flock(fd_, LOCK_EX) != 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      ::close(fd_);
      throw InputError(path, std::string("cannot lock: ") + std::strerror(e));
    }
  }
  ~FolderLock() { ::close(fd_); }  // releases the lock
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Publishes the small files of a build (recipe.json, each scene's selection, the shard
// plan) on a background thread, one after the other in the order posted, while the caller
// goes on computing: their fsyncs (several ms each, the first one in a new folder the
// longest) are then off the build's critical path. Wait() returns when every posted file
// is published and rethrows the first error (a failed job skips the jobs after it); the
// build calls it before anything that must come after these files (a shard's
// publication, the indices, a return). The destructor waits without rethrowing (a build
// that failed elsewhere).
class OrderedPublisher {
 public:
  OrderedPublisher() = default;
  OrderedPublisher(const OrderedPublisher&) = delete;
  OrderedPublisher& operator=(const OrderedPublisher&) = delete;
  ~OrderedPublisher() {
    if (last_.valid()) last_.wait();
  }

  void Post(std::function<void()> job) {
    last_ = std::async(std::launch::async,
                       [previous = std::move(last_), job = std::move(job)]() mutable {
                         if (previous.valid()) previous.get();  // its error skips this job
                         job();
                       });
  }
  void Wait() {  // a no-op when nothing was posted since the last call
    if (last_.valid()) last_.get();
  }

 private:
  std::future<void> last_;
};

// Runs a shard's Finish (close, fsync, rename, part record) on a thread of its own while
// the build goes on. Get() returns its result (rethrows its error) as soon as Finish has
// returned; the stream, with the buffers it still holds, is destroyed afterwards on that
// thread, so freeing them (munmap, slow with several threads) is not on the way to the
// next publication or to the indices. The thread is joined by the next Start() and by the
// destructor.
class ShardFinisher {
 public:
  ShardFinisher() = default;
  ShardFinisher(const ShardFinisher&) = delete;
  ShardFinisher& operator=(const ShardFinisher&) = delete;
  ~ShardFinisher() { Join(); }

  void Start(std::unique_ptr<ShardStream> stream) {
    Join();
    std::promise<int64_t> promise;
    result_ = promise.get_future();
    thread_ = std::thread([st = std::move(stream), promise = std::move(promise)]() mutable {
      try {
        promise.set_value(st->Finish());
      } catch (...) {
        promise.set_exception(std::current_exception());
      }
      st.reset();
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

// Returns the free pages of the allocator's heaps to the kernel (glibc malloc_trim).
void ReleaseFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

// Imported pairs (LoFTR test.npz): scene → (frame number 0, frame number 1) in file order.
using ImportList = std::map<std::string, std::vector<std::pair<int64_t, int64_t>>>;

std::vector<int64_t> IntegerValues(const io::NpyArray& a, const std::string& what) {
  std::vector<int64_t> out(static_cast<size_t>(a.NumElements()));
  auto copy = [&](auto tag) {
    using T = decltype(tag);
    const T* p = a.As<T>(what);
    for (size_t i = 0; i < out.size(); ++i) out[i] = static_cast<int64_t>(p[i]);
  };
  if (a.descr == "<u2")
    copy(uint16_t{});
  else if (a.descr == "<i4")
    copy(int32_t{});
  else if (a.descr == "<i8")
    copy(int64_t{});
  else if (a.descr == "<u4")
    copy(uint32_t{});
  else if (a.descr == "<u8")
    copy(uint64_t{});
  else
    throw InputError(what, "dtype '" + a.descr + "', expected an integer array");
  return out;
}

ImportList ReadImportList(const std::string& path) {
  const auto members = io::ReadNpz(path);
  auto it = members.find("name");
  if (it == members.end())
    throw InputError(path, "no member 'name' (expected LoFTR's [N, 4] pair names)");
  const io::NpyArray& name = it->second;
  if (name.shape.size() != 2 || name.shape[1] != 4) {
    throw InputError(path + ":name", "expected shape [N, 4] (scene, sub-scene, frame0, frame1)");
  }
  const std::vector<int64_t> v = IntegerValues(name, path + ":name");
  ImportList list;
  for (int64_t r = 0; r < name.shape[0]; ++r) {
    char scene[64];
    std::snprintf(scene, sizeof(scene), "scene%04lld_%02lld", static_cast<long long>(v[r * 4]),
                  static_cast<long long>(v[r * 4 + 1]));
    list[scene].emplace_back(v[r * 4 + 2], v[r * 4 + 3]);
  }
  return list;
}

std::vector<std::string> ResolveScenes(const Recipe& r, const io::DatasetReader& reader,
                                       const ImportList* imports) {
  std::vector<std::string> scenes;
  if (!r.dataset.scenes.empty()) {
    scenes = r.dataset.scenes;
  } else if (!r.dataset.split_file.empty()) {
    for (std::string line : io::ReadLines(r.dataset.split_file)) {
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())))
        line.pop_back();
      if (line.empty() || line[0] == '#') continue;
      scenes.push_back(line);
    }
    if (scenes.empty())
      throw InputError(r.file, "dataset.split_file: expected at least one scene name");
  } else if (imports) {
    for (const auto& [scene, pairs] : *imports) scenes.push_back(scene);
  }
  const std::vector<std::string> available = reader.ListScenes(r.dataset.root);
  if (scenes.empty()) scenes = available;
  std::sort(scenes.begin(), scenes.end());
  scenes.erase(std::unique(scenes.begin(), scenes.end()), scenes.end());
  const std::set<std::string> have(available.begin(), available.end());
  for (const auto& s : scenes) {
    if (!have.count(s)) {
      throw InputError(r.file, "dataset: scene '" + s + "' not found under " + r.dataset.root);
    }
  }
  if (scenes.empty())
    throw InputError(r.file, "dataset.root: no scenes found under " + r.dataset.root);
  std::map<std::string, std::string> files;
  for (const auto& s : scenes) {
    auto [it, inserted] = files.emplace(SceneFileName(s), s);
    if (!inserted) {
      throw InputError(r.file, "dataset: scenes '" + it->second + "' and '" + s +
                                   "' have the same file name after sanitising");
    }
  }
  return scenes;
}

struct SceneSelection {
  std::string scene;
  std::vector<SelectedPair> pairs;
  json stats;
};

json PairJson(const SelectedPair& p) {
  return {{"scene", p.scene},
          {"frame0", p.frame0},
          {"frame1", p.frame1},
          {"number0", p.number0},
          {"number1", p.number1},
          {"score_metrics", {{"01", MetricsJson(p.score01)}, {"10", MetricsJson(p.score10)}}}};
}

SelectedPair PairFromJson(const json& j) {
  SelectedPair p;
  p.scene = j.at("scene").get<std::string>();
  p.frame0 = j.at("frame0").get<std::string>();
  p.frame1 = j.at("frame1").get<std::string>();
  p.number0 = j.at("number0").get<int64_t>();
  p.number1 = j.at("number1").get<int64_t>();
  p.score01 = MetricsFromJson(j.at("score_metrics").at("01"));
  p.score10 = MetricsFromJson(j.at("score_metrics").at("10"));
  return p;
}

std::vector<Camera> WorkingCameras(const Scene& scene, int w, int h) {
  std::vector<Camera> cams;
  cams.reserve(scene.frames.size());
  for (const auto& f : scene.frames) cams.push_back(WorkingCamera(f, w, h));
  return cams;
}

// Everything the write stage needs about one scene.
struct SceneData {
  std::string name;                    // as listed by the reader (the selection's scene name)
  std::unique_ptr<ImageCache> images;  // encoded colour images (128 frames)
  Scene scene;
  std::unique_ptr<DepthCache> cache;
  std::map<std::string, size_t> index_of_id;
  SampleSpec spec;
  std::once_flag map_once;
  std::unique_ptr<occupancy::OccupancyMap> scene_map;  // scope scene
  std::vector<bool> prefetched;  // frames whose input files were read ahead (write stage)
};

// Reads a scene and sets up its depth cache and per-scene sample options.
std::shared_ptr<SceneData> LoadSceneData(const Recipe& recipe, const io::DatasetReader& reader,
                                         const std::string& name, const BuildOptions& options) {
  auto d = std::make_shared<SceneData>();
  d->name = name;
  d->scene = reader.ReadScene(recipe.dataset.root, name);
  d->cache = std::make_unique<DepthCache>(d->scene, recipe.width, recipe.height,
                                          options.depth_cache_mb << 20);
  for (size_t i = 0; i < d->scene.frames.size(); ++i) d->index_of_id[d->scene.frames[i].id] = i;
  d->prefetched.assign(d->scene.frames.size(), false);
  d->images = std::make_unique<ImageCache>(
      128, [s = d.get()](size_t i) { return EncodeFrameImage(s->scene.frames[i], s->spec); });
  d->spec = RecipeSampleOptions(recipe);
  d->spec.labels = RecipeLabelOptions(recipe, d->scene);
  if (recipe.occupancy.scope == "window") {
    d->spec.fusion.scope = occupancy::FusionScope::kWindow;
    d->spec.fusion.window = recipe.occupancy.window;
  } else if (recipe.occupancy.scope == "scene") {
    d->spec.fusion.scope = occupancy::FusionScope::kScene;
    d->spec.fusion.scene_stride = recipe.occupancy.scene_stride;
  }
  return d;
}

// The scene's data (scene, depth cache with the maps the selection decoded) is left in
// *data, for the write stage when it starts with this scene.
SceneSelection SelectScene(const Recipe& r, const io::DatasetReader& reader,
                           const std::string& scene_name, const BuildOptions& options,
                           const ImportList* imports, std::shared_ptr<SceneData>* data) {
  data->reset();  // one scene's data at a time
  *data = LoadSceneData(r, reader, scene_name, options);
  const Scene& scene = (*data)->scene;
  DepthCache& cache = *(*data)->cache;
  const std::vector<Camera> cams = WorkingCameras(scene, r.width, r.height);
  const LabelOptions& labels = (*data)->spec.labels;
  SceneSelection out;
  out.scene = scene_name;
  DropCounts drops;
  std::vector<CandidatePair> candidates, pruned;
  int64_t frames_kept = 0;
  if (imports) {
    std::map<int64_t, size_t> by_number;
    for (size_t i = 0; i < scene.frames.size(); ++i) by_number[scene.frames[i].number] = i;
    auto it = imports->find(scene_name);
    if (it != imports->end()) {
      for (const auto& [n0, n1] : it->second) {
        auto a = by_number.find(n0), b = by_number.find(n1);
        if (a == by_number.end() || b == by_number.end()) {
          ++drops["import.missing_frame"];
        } else if (!scene.frames[a->second].usable || !scene.frames[b->second].usable) {
          ++drops["import.unusable_frame"];
        } else {
          candidates.push_back({a->second, b->second});
        }
      }
    }
    pruned = candidates;
    frames_kept = static_cast<int64_t>(scene.NumUsable());
  } else {
    ScanOptions scan;
    scan.frame_stride = r.dataset.frame_stride;
    scan.min_valid_depth_fraction = r.dataset.min_valid_depth_fraction;
    scan.min_depth_m = labels.min_depth_m;
    scan.max_depth_m = labels.max_depth_m;
    const ScanResult scanned = ScanFrames(scene, scan, &cache);
    AddCounts(scanned.drops, &drops);
    frames_kept = static_cast<int64_t>(scanned.kept.size());
    candidates = GenerateCandidates(scanned.kept, r.selection.max_frame_gap);
    pruned = PruneCandidates(scene, cams, candidates, scanned.median_depth_m, r.selection.pruning,
                             &drops);
  }
  // Imported pairs may list (i0 > i1); scoring and labels keep the file's order.
  const std::vector<ScoredPair> scored =
      ScorePairs(scene, cams, pruned, labels, r.selection.score_stride, &cache, &drops);
  std::vector<size_t> chosen;
  if (imports) {
    for (size_t k = 0; k < scored.size(); ++k) chosen.push_back(k);
  } else {
    chosen = FilterAndSample(scored, r.selection, SceneSeed(r.seed, scene_name), &drops);
  }
  for (size_t k : chosen) {
    const ScoredPair& s = scored[k];
    SelectedPair p;
    p.scene = scene_name;
    p.frame0 = scene.frames[s.pair.i0].id;
    p.frame1 = scene.frames[s.pair.i1].id;
    p.number0 = scene.frames[s.pair.i0].number;
    p.number1 = scene.frames[s.pair.i1].number;
    p.score01 = s.m01;
    p.score10 = s.m10;
    out.pairs.push_back(p);
  }
  out.stats = {{"scene", scene_name},
               {"frames_total", static_cast<int64_t>(scene.frames.size())},
               {"frames_kept", frames_kept},
               {"candidates", static_cast<int64_t>(candidates.size())},
               {"after_pruning", static_cast<int64_t>(pruned.size())},
               {"scored", static_cast<int64_t>(scored.size())},
               {"selected", static_cast<int64_t>(out.pairs.size())},
               {"drops", drops},
               {"options_digest", r.Digest()}};
  return out;
}

std::string SelectionDir(const BuildOptions& o) { return o.out_dir + "/selection"; }
std::string SelectionLinesPath(const BuildOptions& o, const std::string& scene) {
  return SelectionDir(o) + "/" + SceneFileName(scene) + ".jsonl";
}
std::string SelectionStatsPath(const BuildOptions& o, const std::string& scene) {
  return SelectionDir(o) + "/" + SceneFileName(scene) + ".json";
}

int64_t WriteSelection(const BuildOptions& o, const SceneSelection& s) {
  std::string lines;
  for (const auto& p : s.pairs) lines += PairJson(p).dump() + "\n";
  const std::string stats = s.stats.dump(2) + "\n";
  // Written at once; the stats, the scene's completion marker, are published second.
  io::WriteFilesAtomic(
      {{SelectionLinesPath(o, s.scene), lines}, {SelectionStatsPath(o, s.scene), stats}});
  return static_cast<int64_t>(lines.size() + stats.size());
}

// Reads a completed selection; nullopt when the scene is not complete.
std::optional<SceneSelection> ReadSelection(const BuildOptions& o, const std::string& scene,
                                            const std::string& digest) {
  const std::string stats_path = SelectionStatsPath(o, scene);
  if (!io::FileExists(stats_path)) return std::nullopt;
  SceneSelection s;
  s.scene = scene;
  try {
    s.stats = json::parse(io::ReadFileBytes(stats_path));
  } catch (const json::exception& e) {
    throw InputError(stats_path, std::string("not valid JSON: ") + e.what());
  }
  if (s.stats.value("options_digest", "") != digest) {
    throw InputError(stats_path, "was selected with other options (digest " +
                                     s.stats.value("options_digest", "?") + ", recipe " + digest +
                                     "); use a fresh --out folder");
  }
  const std::string lines_path = SelectionLinesPath(o, scene);
  for (const std::string& line : io::ReadLines(lines_path)) {
    if (line.empty()) continue;
    try {
      s.pairs.push_back(PairFromJson(json::parse(line)));
    } catch (const json::exception& e) {
      throw InputError(lines_path, std::string("bad selection line: ") + e.what());
    }
  }
  if (static_cast<int64_t>(s.pairs.size()) != s.stats.value("selected", int64_t{-1})) {
    throw InputError(lines_path, "line count differs from " + stats_path);
  }
  return s;
}

occupancy::OccupancyMap FuseFrames(SceneData* d, const std::vector<size_t>& frames,
                                   const SampleSpec& spec) {
  std::vector<std::shared_ptr<const DepthImage>> depths;
  std::vector<occupancy::FusionInput> inputs;
  for (size_t i : frames) {
    depths.push_back(d->cache->Get(i));
    inputs.push_back(
        {depths.back().get(), WorkingCamera(d->scene.frames[i], spec.width, spec.height),
         d->scene.frames[i].world_from_cam, spec.labels.min_depth_m, spec.labels.max_depth_m});
  }
  return occupancy::FuseOccupancy(inputs, spec.fusion);
}

// ShardOutput::OpenShard's default: the samples in memory, one WriteShard at Finish.
class BufferedShard : public ShardStream {
 public:
  BufferedShard(ShardOutput* output, int64_t shard) : output_(output), shard_(shard) {}
  void Add(EncodedSample sample, bool /*last*/) override { samples_.push_back(std::move(sample)); }
  int64_t Finish() override { return output_->WriteShard(shard_, samples_); }

 private:
  ShardOutput* output_;
  int64_t shard_;
  std::vector<EncodedSample> samples_;
};

}  // namespace

std::unique_ptr<ShardStream> ShardOutput::OpenShard(int64_t shard) {
  return std::make_unique<BufferedShard>(this, shard);
}

bool BuildOptions::Check(std::string* error) const {
  if (out_dir.empty()) return *error = "--out: expected an output folder", false;
  if (tasks < 1) return *error = "--tasks: expected an integer >= 1", false;
  if (task < 0 || task >= tasks) return *error = "--task: expected 0 <= task < tasks", false;
  if (stage != "select" && stage != "write" && stage != "all") {
    return *error = "--stage: expected select, write or all", false;
  }
  if (depth_cache_mb < 1) return *error = "depth cache: expected >= 1 MB", false;
  return true;
}

std::string SceneFileName(const std::string& scene) {
  std::string out;
  for (unsigned char c : scene) {
    if (c == '/') {
      out += "__";
    } else if (std::isalnum(c) || c == '-' || c == '_') {
      out += static_cast<char>(c);
    } else {
      out += '_';
    }
  }
  return out.empty() ? "_" : out;
}

int64_t EstimatedSampleBytes(const Recipe& r) {
  const int64_t px = static_cast<int64_t>(r.width) * r.height;
  int64_t bytes = 4096 + 64 * 1024;  // json + matches
  if (r.sample.labels) bytes += 2 * px + 2 * px / (r.patches.stride * r.patches.stride);
  if (r.occupancy.enabled && r.sample.occupancy) {
    const int64_t rays = px / 4;
    if (r.occupancy.encoding != "dense") bytes += 2 * 2 * 8 * rays;
    if (r.occupancy.encoding != "packed") bytes += 2 * r.occupancy.bins * rays;
  }
  if (r.sample.image == "png") bytes += 2 * 2 * px;
  if (r.sample.image == "jpg") bytes += 2 * px * 3 / 10;
  if (r.sample.depth) bytes += 2 * 4 * px;
  return bytes;
}

json RunBuild(const Recipe& recipe_in, const BuildOptions& options, ShardOutput* output,
              const ProgressFn& progress) {
  std::string error;
  if (!options.Check(&error)) throw InputError("occgt build", error);
  const auto t_start = Clock::now();
  Recipe recipe = recipe_in;
  json summary;
  summary["recipe"] = recipe.name;
  summary["split"] = recipe.split;
  summary["options_digest"] = recipe.Digest();
  summary["task"] = options.task;
  summary["tasks"] = options.tasks;
  summary["stage"] = options.stage;
  summary["dry_run"] = options.dry_run;
  json timings = json::object();
  int64_t bytes_written = 0;

  // Output folder identity: one recipe (options digest) per folder.
  const std::string recipe_path = options.out_dir + "/recipe.json";
  json normalised = recipe.ToJson();
  normalised["options_digest"] = recipe.Digest();
  if (io::FileExists(recipe_path)) {
    json existing;
    try {
      existing = json::parse(io::ReadFileBytes(recipe_path));
    } catch (const json::exception&) {
      throw InputError(recipe_path, "not valid JSON");
    }
    if (existing.value("options_digest", "") != recipe.Digest()) {
      throw InputError("--out " + options.out_dir,
                       "holds outputs of another recipe (options digest " +
                           existing.value("options_digest", "?") + "); use a fresh folder");
    }
  }

  // Synthetic datasets are generated into DIR/data when missing.
  if (recipe.dataset.format == "synthetic") {
    if (recipe.dataset.root.empty()) recipe.dataset.root = options.out_dir + "/data";
    if (!options.dry_run || !fs::exists(recipe.dataset.root)) {
      FolderLock lock(options.out_dir);
      EnsureSyntheticDataset(recipe.dataset.root, recipe.dataset.synthetic);
    }
    recipe.dataset.format = "generic";
  }
  std::unique_ptr<io::DatasetReader> reader = io::MakeReader(recipe.dataset.format);
  std::unique_ptr<ImportList> imports;
  if (!recipe.selection.import_pairs.path.empty()) {
    imports = std::make_unique<ImportList>(ReadImportList(recipe.selection.import_pairs.path));
  }
  const std::vector<std::string> scenes = ResolveScenes(recipe, *reader, imports.get());
  summary["scenes"] = static_cast<int64_t>(scenes.size());
  // recipe.json, the selections and the plan are published in the background, in this
  // order, and before any shard (publisher.Wait() below).
  // (Declared before the publisher, whose destructor waits for the jobs that use them.)
  std::map<std::string, SceneSelection> selections;
  int64_t selection_bytes = 0;  // written by the publisher's jobs; read after Wait()
  OrderedPublisher publisher;
  if (!options.dry_run && !io::FileExists(recipe_path)) {
    publisher.Post([&options, recipe_path, text = normalised.dump(2) + "\n"] {
      FolderLock lock(options.out_dir);
      if (!io::FileExists(recipe_path)) io::WriteFileAtomic(recipe_path, text);
    });
  }

  // ---- phase 1: select ----
  const auto t_select = Clock::now();
  int64_t scenes_selected = 0, scenes_reused = 0;
  std::shared_ptr<SceneData> last_selected;  // the data of the scene selected last
  if (options.stage != "write") {
    std::vector<std::string> mine;
    for (size_t i = 0; i < scenes.size(); ++i) {
      if (static_cast<int>(i % options.tasks) == options.task) mine.push_back(scenes[i]);
    }
    int64_t done = 0;
    for (const std::string& scene : mine) {
      if (auto s = ReadSelection(options, scene, recipe.Digest())) {
        selections[scene] = std::move(*s);
        ++scenes_reused;
      } else {
        SceneSelection& sel = selections[scene];
        sel = SelectScene(recipe, *reader, scene, options, imports.get(), &last_selected);
        // `sel` stays in place (std::map), and is only read from here on.
        if (!options.dry_run) {
          publisher.Post([&options, &sel, &selection_bytes] {
            selection_bytes += WriteSelection(options, sel);
          });
        }
        ++scenes_selected;
      }
      if (progress)
        progress({"select", ++done, static_cast<int64_t>(mine.size()), Seconds(t_select)});
    }
  }
  timings["select_s"] = Seconds(t_select);
  summary["scenes_selected_this_run"] = scenes_selected;
  summary["scenes_reused"] = scenes_reused;

  // Global statistics over every completed scene.
  bool all_selected = true;
  for (const std::string& scene : scenes) {
    if (selections.count(scene)) continue;
    if (auto s = ReadSelection(options, scene, recipe.Digest())) {
      selections[scene] = std::move(*s);
    } else {
      all_selected = false;
    }
  }
  json counts = {{"frames_total", 0},  {"frames_kept", 0}, {"candidates", 0},
                 {"after_pruning", 0}, {"scored", 0},      {"selected", 0}};
  DropCounts drops;
  json per_scene = json::object();
  for (const auto& [scene, sel] : selections) {
    for (auto& [k, v] : counts.items()) v = v.get<int64_t>() + sel.stats.value(k, int64_t{0});
    for (const auto& [k, v] : sel.stats.at("drops").items()) drops[k] += v.get<int64_t>();
    per_scene[scene] = sel.stats.at("selected");
  }
  summary["counts"] = counts;
  summary["drops"] = drops;
  summary["pairs_per_scene"] = per_scene;
  summary["scenes_complete"] = static_cast<int64_t>(selections.size());

  // The global sample list.
  std::vector<const SelectedPair*> all;
  for (const std::string& scene : scenes) {
    auto it = selections.find(scene);
    if (it == selections.end()) continue;
    for (const auto& p : it->second.pairs) all.push_back(&p);
  }
  {
    json ov = json::array(), oc = json::array();
    std::vector<double> overlaps, occlusions;
    for (const SelectedPair* p : all) {
      ScoredPair s;
      s.m01 = p->score01;
      s.m10 = p->score10;
      overlaps.push_back(PairOverlap(s, recipe.selection.aggregate));
      occlusions.push_back(
          PairOcclusion(s, recipe.selection.aggregate, recipe.selection.occlusion_metric));
    }
    auto stats = [](std::vector<double> v) {
      if (v.empty()) return json(nullptr);
      std::sort(v.begin(), v.end());
      double sum = 0;
      for (double x : v) sum += x;
      return json{{"min", v.front()},
                  {"median", v[v.size() / 2]},
                  {"mean", sum / v.size()},
                  {"max", v.back()}};
    };
    summary["selected_overlap"] = stats(overlaps);
    summary["selected_occlusion"] = stats(occlusions);
  }
  int64_t samples_per_shard = recipe.shards.samples_per_shard;
  if (recipe.shards.target_mb > 0) {
    samples_per_shard = std::max<int64_t>(
        1, static_cast<int64_t>(recipe.shards.target_mb * 1e6 / EstimatedSampleBytes(recipe)));
  }
  const int64_t total = static_cast<int64_t>(all.size());
  std::vector<int64_t> shard_sizes;
  for (int64_t start = 0; start < total; start += samples_per_shard) {
    shard_sizes.push_back(std::min(samples_per_shard, total - start));
  }
  summary["samples"] = total;
  summary["samples_per_shard"] = samples_per_shard;
  summary["shards_planned"] = static_cast<int64_t>(shard_sizes.size());
  summary["estimated_bytes"] = total * EstimatedSampleBytes(recipe);

  if (options.dry_run || options.stage == "select") {
    publisher.Wait();
    bytes_written += std::exchange(selection_bytes, 0);
    timings["total_s"] = Seconds(t_start);
    summary["timings"] = timings;
    summary["bytes_written"] = bytes_written;
    summary["complete"] = false;
    return summary;
  }
  if (!all_selected) {
    publisher.Wait();  // a failed publication is the error to report
    throw InputError("--stage write", "the selection of some scenes is not complete in " +
                                          SelectionDir(options) +
                                          " (run every task with --stage select first)");
  }

  // ---- phase 2: write ----
  const auto t_write = Clock::now();
  std::vector<std::string> keys(all.size());
  {
    std::map<std::string, size_t> seen;
    for (size_t k = 0; k < all.size(); ++k) {
      keys[k] = output->SampleKey(all[k]->scene, all[k]->frame0, all[k]->frame1);
      auto [it, inserted] = seen.emplace(keys[k], k);
      if (!inserted) {
        throw InputError("sample key " + keys[k],
                         "two pairs map to the same key after sanitising (" +
                             all[it->second]->scene + " and " + all[k]->scene + ")");
      }
    }
  }
  publisher.Post([&options, output, shard_sizes] {
    FolderLock lock(options.out_dir);
    output->WritePlan(shard_sizes);
  });
  // Every file posted above is published before the first shard and before the indices
  // (a second call returns at once).
  auto wait_published = [&] {
    publisher.Wait();
    bytes_written += std::exchange(selection_bytes, 0);
  };
  std::map<std::string, std::shared_ptr<SceneData>> scene_data;
  auto scene_of = [&](const std::string& name) -> std::shared_ptr<SceneData> {
    auto& d = scene_data[name];
    if (!d) d = LoadSceneData(recipe, *reader, name, options);
    return d;
  };
  // This task's work: the samples of its incomplete shards, in order (shard s is this
  // task's when s % tasks == task). Complete shards are skipped (resume).
  int64_t shards_written = 0, shards_skipped = 0, samples_written = 0;
  const int64_t nshards = static_cast<int64_t>(shard_sizes.size());
  int64_t my_samples = 0;  // progress unit of the write stage: pairs (samples)
  int64_t done_samples = 0;
  struct Job {
    int64_t shard;   // shard index
    int64_t sample;  // index into `all` (and `keys`)
  };
  std::vector<Job> jobs;
  std::vector<int64_t> skipped_sizes;
  for (int64_t s = 0, start = 0; s < nshards; start += shard_sizes[s], ++s) {
    if (s % options.tasks != options.task) continue;
    my_samples += shard_sizes[s];
    if (output->IsShardComplete(s)) {
      ++shards_skipped;
      skipped_sizes.push_back(shard_sizes[s]);
    } else {
      for (int64_t k = start; k < start + shard_sizes[s]; ++k) jobs.push_back({s, k});
    }
  }
  for (int64_t n : skipped_sizes) {
    done_samples += n;
    if (progress) progress({"write", done_samples, my_samples, Seconds(t_write)});
  }
  // A scene's data (and its depth cache) is dropped from `scene_data` when its last sample
  // of this task enters the pipeline; the samples in flight hold it (shared_ptr) until
  // they are computed, so a task over many scenes holds only the current ones in memory.
  std::map<std::string, size_t> last_job_of_scene;
  for (size_t j = 0; j < jobs.size(); ++j) last_job_of_scene[all[jobs[j].sample]->scene] = j;
  // The scene selected last is reused (not read and decoded again) when the writing starts
  // with it, as it does for a task of one scene; else it is dropped now.
  if (last_selected && !jobs.empty() && all[jobs[0].sample]->scene == last_selected->name) {
    scene_data[last_selected->name] = std::move(last_selected);
  }
  last_selected.reset();

  // The samples of this task flow through one pipeline without a barrier at shard ends:
  //   1. serial, in order: the next job; reads its scene when first needed;
  //   2. parallel: ComputeSample (labels, occupancy, encoding);
  //   3. serial, in order: adds the sample to its shard's stream (OpenShard: the tar
  //      member data is written and digested now); when the shard is complete, its
  //      Finish (close, fsync, rename, part record) is handed to a writer thread while
  //      the pipeline goes on computing. At most one Finish is in flight (stage 3 waits
  //      for the previous one before handing over the next), so shards are published in
  //      order and byte for byte as with any thread count.
  // At most `tokens` samples are in flight between stages 1 and 3; memory stays bounded.
  // An exception in any stage (InputError of a sample, a write error) cancels the
  // pipeline and propagates from here: the stream being filled is dropped (its temporary
  // file removed, nothing published), and a Finish in flight completes (ShardFinisher's
  // destructor joins its thread) before RunBuild returns.
  ShardFinisher pending_write;
  int64_t pending_samples = 0;
  auto finish_write = [&] {
    if (!pending_write.pending()) return;
    bytes_written += pending_write.Get();
    ++shards_written;
    samples_written += pending_samples;
  };
  struct Item {
    std::shared_ptr<SceneData> data;
    EncodedSample sample;
  };
  const size_t threads = std::max<size_t>(
      1, tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const size_t tokens = 2 * threads;
  // The items in flight are owned here, and only their job numbers travel through the
  // pipeline: a cancelled tbb::parallel_pipeline does not destroy the values still in its
  // buffers (LeakSanitizer found shared_ptr items leaked on the disk-full path).
  std::vector<std::unique_ptr<Item>> items(jobs.size());
  size_t next_job = 0;
  std::unique_ptr<ShardStream> stream;  // the shard being collected
  int64_t in_stream = 0;                // its samples so far
  // The input files of the jobs ahead (the colour images to encode, depth maps no longer
  // in the depth cache) are read into the page cache in the background
  // (io::PrefetchFile), up to `lookahead` jobs of the same scene beyond the one entering,
  // each frame once per scene: a file that is not cached is then read from disk while the
  // threads compute, instead of stalling a thread (and a thread waiting for that image).
  const size_t lookahead = 2 * tokens;
  size_t prefetched_to = 0;  // jobs below this index were prefetched
  auto prefetch_ahead = [&](size_t j, SceneData* d) {
    const std::string& scene = all[jobs[j].sample]->scene;
    for (size_t k = std::max(prefetched_to, j); k < std::min(jobs.size(), j + 1 + lookahead);
         ++k, prefetched_to = k) {
      const SelectedPair& p = *all[jobs[k].sample];
      if (p.scene != scene) break;  // the next scene's files: when it starts
      for (const std::string* id : {&p.frame0, &p.frame1}) {
        auto it = d->index_of_id.find(*id);
        if (it == d->index_of_id.end() || d->prefetched[it->second]) continue;
        d->prefetched[it->second] = true;
        const Frame& f = d->scene.frames[it->second];
        if (d->spec.image != "none" && !f.color_path.empty()) {
          io::PrefetchFile(f.color_path);
          d->images->Expect(it->second);  // a thread waiting for an image may encode it
        }
        if (!d->cache->Contains(it->second)) io::PrefetchFile(f.depth.path);
      }
    }
  };
  auto input = [&](tbb::flow_control& fc) -> size_t {
    if (next_job == jobs.size()) {
      fc.stop();
      return 0;
    }
    const size_t j = next_job++;
    items[j] = std::make_unique<Item>();
    Item* item = items[j].get();
    const std::string& scene = all[jobs[j].sample]->scene;
    item->data = scene_of(scene);
    prefetch_ahead(j, item->data.get());
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
      throw InputError(SelectionLinesPath(options, p.scene),
                       "frame " + p.frame0 + " or " + p.frame1 + " no longer in the dataset");
    }
    const auto depth0 = d.cache->Get(i0->second);
    const auto depth1 = d.cache->Get(i1->second);
    const occupancy::OccupancyMap* shared = nullptr;
    std::unique_ptr<occupancy::OccupancyMap> window_map;
    if (d.spec.occupancy && d.spec.mode == occupancy::OccupancyMode::kOctomap) {
      if (d.spec.fusion.scope == occupancy::FusionScope::kScene) {
        std::call_once(d.map_once, [&] {
          d.scene_map = std::make_unique<occupancy::OccupancyMap>(FuseFrames(
              &d, occupancy::ScopeFrameIndices(d.scene, i0->second, i1->second, d.spec.fusion),
              d.spec));
        });
        shared = d.scene_map.get();
      } else if (d.spec.fusion.scope == occupancy::FusionScope::kWindow) {
        window_map = std::make_unique<occupancy::OccupancyMap>(FuseFrames(
            &d, occupancy::ScopeFrameIndices(d.scene, i0->second, i1->second, d.spec.fusion),
            d.spec));
        shared = window_map.get();
      }
    }
    const ImageSource images = [&d](size_t i) { return d.images->Get(i); };
    item->sample = ComputeSample(d.scene, i0->second, i1->second, p, keys[k], *depth0, *depth1,
                                 d.spec, shared, images);
    item->data.reset();  // the last sample of a scene releases its data here
    return j;
  };
  auto collect = [&](size_t j) {
    const int64_t s = jobs[j].shard;
    if (!stream) stream = output->OpenShard(s);
    const int64_t n = shard_sizes[s];
    const bool last = ++in_stream == n;
    stream->Add(std::move(items[j]->sample), last);
    items[j].reset();
    if (!last) return;
    finish_write();
    wait_published();
    pending_samples = n;
    pending_write.Start(std::move(stream));
    stream.reset();
    in_stream = 0;
    done_samples += n;
    if (progress) progress({"write", done_samples, my_samples, Seconds(t_write)});
  };
  if (!jobs.empty()) {
    tbb::parallel_pipeline(
        tokens, tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order, input) &
                    tbb::make_filter<size_t, size_t>(tbb::filter_mode::parallel, compute) &
                    tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order, collect));
  }
  // The scenes' data is released while the last shard's Finish (digest, fsync) runs, and
  // so are the pages of every freed block (they are kept during the run: apps/main.cc):
  // else the kernel frees them when the process exits, after the last output, with the
  // other core idle (~10 ms for the ~70 MB of a sample recipe).
  scene_data.clear();
  if (pending_write.pending()) ReleaseFreedMemory();
  finish_write();
  wait_published();
  timings["write_s"] = Seconds(t_write);
  summary["shards_written_this_run"] = shards_written;
  summary["shards_skipped_complete"] = shards_skipped;
  summary["samples_written_this_run"] = samples_written;

  // ---- indices ----
  // This task's shards are complete now (found complete above, or just published); only
  // the other tasks' shards are looked up.
  bool complete = true;
  for (int64_t s = 0; s < nshards && complete; ++s) {
    if (s % options.tasks != options.task) complete = output->IsShardComplete(s);
  }
  summary["complete"] = complete;
  // A re-run that wrote nothing leaves published indices alone (no new inodes or mtimes).
  // Tasks finishing together publish one after the other (the lock is held to the end).
  std::optional<FolderLock> publish_lock;
  if (complete) publish_lock.emplace(options.out_dir);
  const bool indices_current = shards_written == 0 &&
                               io::FileExists(options.out_dir + "/index.json") &&
                               io::FileExists(options.out_dir + "/summary.json");
  if (complete && !indices_current) {
    const auto t_index = Clock::now();
    // The split's indices and the LoFTR export are independent files: written at once.
    auto loftr = [&] {
      if (recipe.loftr_export.empty()) return;
      std::vector<LoftrRow> rows;
      std::map<std::string, std::array<double, 9>> intrinsics;
      for (const SelectedPair* p : all) {
        SceneData& d = *scene_of(p->scene);
        const size_t i0 = d.index_of_id.at(p->frame0), i1 = d.index_of_id.at(p->frame1);
        LoftrRow row;
        row.scene = p->scene;
        row.frame0 = p->number0;
        row.frame1 = p->number1;
        ScoredPair s;
        s.m01 = p->score01;
        s.m10 = p->score10;
        row.score = PairOverlap(s, recipe.selection.aggregate);
        const Rigid3d t =
            RelativePose(d.scene.frames[i0].world_from_cam, d.scene.frames[i1].world_from_cam);
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 4; ++c) row.cam1_from_cam0[r * 4 + c] = t.matrix()(r, c);
        }
        rows.push_back(row);
        if (!intrinsics.count(p->scene)) {
          const Eigen::Matrix3d K =
              WorkingCamera(d.scene.frames[i0], recipe.width, recipe.height).K();
          std::array<double, 9> k9;
          for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) k9[r * 3 + c] = K(r, c);
          }
          intrinsics[p->scene] = k9;
        }
      }
      output->ExportLoftr(recipe.loftr_export, rows, intrinsics);
    };
    io::RunConcurrently({[&] { output->Finish(); }, loftr});
    timings["index_s"] = Seconds(t_index);
  }
  timings["total_s"] = Seconds(t_start);
  summary["timings"] = timings;
  summary["bytes_written"] = bytes_written;
  if (complete && !indices_current) {
    json on_disk = summary;
    io::WriteFileAtomic(options.out_dir + "/summary.json", on_disk.dump(2) + "\n");
  }
  return summary;
}

}  // namespace gt::pairs

#include "libgt/pipeline/covisibility.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/folder_lock.h"
#include "libgt/io/image.h"
#include "libgt/io/md5.h"
#include "libgt/io/npy.h"
#include "libgt/io/npz_members.h"
#include "libgt/pipeline/build.h"
#include "libgt/pipeline/sample.h"
#include "libgt/pipeline/select.h"
#include "libgt/pipeline/synthetic.h"
#include "libgt/truth/working_frame.h"

namespace gt::pipeline {
namespace {

namespace fs = std::filesystem;

// The digest stored in a graph (the recipe's md5, 32 hex characters), or "" when none.
std::string StoredDigest(const std::string& path) {
  const std::map<std::string, std::string> npz = io::ReadNpzBytes(path);  // frame_ids: '<U'
  auto it = npz.find("options_digest");
  if (it == npz.end()) return "";
  return io::ParseNpy(it->second, path + ":options_digest.npy").data;
}

// Graphs of scenes this recipe does not have, written into the folder under another recipe
// (another dataset, or the same one with other options): one recipe per folder, as a build's,
// so that the graphs of two recipes never mix. A graph of one of `scenes` is checked where it
// is read (the loop of RunCovisibility).
void RequireOneRecipe(const std::string& out_dir, const std::vector<std::string>& scenes,
                      const std::string& digest) {
  std::set<std::string> ours;
  for (const std::string& name : scenes) {
    ours.insert(fs::path(CovisibilityPath(out_dir, name)).filename().string());
  }
  const fs::path dir = fs::path(out_dir) / "covisibility";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  std::vector<std::string> others;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const fs::path& p = entry.path();
    if (p.extension() == ".npz" && entry.is_regular_file(ec) &&
        !ours.count(p.filename().string())) {
      others.push_back(p.string());
    }
  }
  std::sort(others.begin(), others.end());
  for (const std::string& path : others) {
    const std::string stored = StoredDigest(path);
    if (stored != digest) {
      throw InputError(path, "written under another recipe (options digest " + stored +
                                 ", this one " + digest + ", which has no scene of this name; " +
                                 std::to_string(others.size()) +
                                 " such graph(s)): one recipe per --out, so that their graphs "
                                 "do not mix; write into another --out");
    }
  }
}

}  // namespace

std::string CovisibilityDigest(const Recipe& recipe) {
  const nlohmann::json r = recipe.ToJson();
  nlohmann::json j = {{"resolution", r["resolution"]},
                      {"dataset", r["dataset"]},
                      {"labels", r["labels"]},
                      {"pruning", r["selection"]["pruning"]},
                      {"score_stride", r["selection"]["score_stride"]},
                      // The kept frames leave out those without colour when images are stored.
                      {"needs_color", recipe.sample.image != ImageFormat::kNone}};
  j["dataset"].erase("root");
  j["dataset"].erase("split_file");
  j["dataset"].erase("scenes");
  j["dataset"].erase("mesh_path");  // a path, as root (Recipe::Digest)
  return io::Md5Hex(j.dump());
}

SceneCovisibility ComputeSceneCovisibility(const Recipe& r, const Scene& scene,
                                           pairs::DepthCache* cache) {
  using namespace pairs;  // NOLINT(google-build-using-namespace): the stage's vocabulary
  std::vector<Camera> cams;
  cams.reserve(scene.frames.size());
  for (const Frame& f : scene.frames) cams.push_back(truth::WorkingCamera(f, {r.width, r.height}));
  const LabelOptions labels = RecipePairTruthOptions(r, scene).labels;
  SceneCovisibility out;
  out.scene = scene.name;
  out.score_stride = r.selection.score_stride;
  // The frames the build keeps (without colour when the recipe stores images: the N-view
  // samples of occgt tuples --shards carry every view's image).
  const ScanResult scanned = ScanRecipeFrames(r, scene, labels, cache);
  AddCounts(scanned.drops, &out.drops);
  const std::vector<CandidatePair> candidates = GenerateCandidates(scanned.kept, 0);
  out.candidates = static_cast<int64_t>(candidates.size());
  const std::vector<CandidatePair> pruned = PruneCandidates(
      scene, cams, candidates, scanned.median_depth_m, r.selection.pruning, &out.drops);
  const std::vector<ScoredPair> scored =
      ScorePairs(scene, cams, pruned, labels, r.selection.score_stride, cache, &out.drops);
  // Kept frames → their position in frame_ids.
  std::map<size_t, int32_t> position;
  for (size_t k = 0; k < scanned.kept.size(); ++k) {
    position[scanned.kept[k]] = static_cast<int32_t>(k);
    out.frame_ids.push_back(scene.frames[scanned.kept[k]].id);
    const size_t f = scanned.kept[k];
    const std::shared_ptr<const DepthImage> d = cache->Get(f);
    out.self.push_back(
        static_cast<float>(ScoreDirection(*d, cams[f], *d, cams[f], Rigid3d::Identity(), labels,
                                          r.selection.score_stride)
                               .consistent_overlap));
  }
  for (const ScoredPair& s : scored) {  // candidate order: increasing (i0, i1)
    out.i.push_back(position.at(s.pair.i0));
    out.j.push_back(position.at(s.pair.i1));
    out.c_ij.push_back(static_cast<float>(s.m01.consistent_overlap));
    out.c_ji.push_back(static_cast<float>(s.m10.consistent_overlap));
    out.o_ij.push_back(static_cast<float>(s.m01.overlap));
    out.o_ji.push_back(static_cast<float>(s.m10.overlap));
  }
  return out;
}

namespace {

// Member `key`, of `ndim` dimensions (0: a scalar, 1: [n]).
template <typename T>
std::vector<T> Member(const std::map<std::string, std::string>& m, const std::string& key,
                      const std::string& path, int ndim) {
  auto it = m.find(key);
  if (it == m.end()) throw InputError(path, "expected a member '" + key + "'");
  const std::string where = path + ":" + key + ".npy";
  const io::NpyArray a = io::ParseNpy(it->second, where);
  if (static_cast<int>(a.shape.size()) != ndim) {
    throw InputError(where, "expected " +
                                std::string(ndim == 0 ? "a scalar (shape [])" : "shape [n]") +
                                ", got " + std::to_string(a.shape.size()) + " dimensions");
  }
  const T* p = a.As<T>(path + ":" + key);
  return std::vector<T>(p, p + a.NumElements());
}

// '<U<n>' [F]: the frame ids (io::DecodeStringsNpy).
std::vector<std::string> Strings(const std::map<std::string, std::string>& m,
                                 const std::string& key, const std::string& path) {
  auto it = m.find(key);
  if (it == m.end()) throw InputError(path, "expected a member '" + key + "'");
  return io::DecodeStringsNpy(it->second, path + ":" + key + ".npy");
}

}  // namespace

SceneCovisibility ReadSceneCovisibility(const std::string& path, const std::string& digest,
                                        int score_stride) {
  if (!io::FileExists(path)) {
    throw InputError(path, "missing: run `occgt covis` with this recipe and --out first");
  }
  const std::map<std::string, std::string> m = io::ReadNpzBytes(path);
  const std::vector<uint8_t> d = Member<uint8_t>(m, "options_digest", path, 1);
  if (std::string(d.begin(), d.end()) != digest) {
    throw InputError(path, "written under other covisibility options (digest " +
                               std::string(d.begin(), d.end()) + ", this recipe's " + digest +
                               "); re-run occgt covis into another --out");
  }
  SceneCovisibility g;
  g.frame_ids = Strings(m, "frame_ids", path);
  g.i = Member<int32_t>(m, "i", path, 1);
  g.j = Member<int32_t>(m, "j", path, 1);
  g.c_ij = Member<float>(m, "c_ij", path, 1);
  g.c_ji = Member<float>(m, "c_ji", path, 1);
  g.o_ij = Member<float>(m, "o_ij", path, 1);
  g.o_ji = Member<float>(m, "o_ji", path, 1);
  g.self = Member<float>(m, "self", path, 1);
  g.score_stride = Member<int32_t>(m, "score_stride", path, 0).at(0);
  if (g.score_stride != score_stride) {  // the digest holds the recipe's: a damaged member
    throw InputError(path + ":score_stride.npy",
                     std::to_string(g.score_stride) + ", expected the recipe's " +
                         std::to_string(score_stride) + " (which its options digest holds)");
  }
  const size_t p = g.i.size();
  const auto f = static_cast<int32_t>(g.frame_ids.size());
  bool ok = g.j.size() == p && g.c_ij.size() == p && g.c_ji.size() == p && g.o_ij.size() == p &&
            g.o_ji.size() == p && g.self.size() == g.frame_ids.size();
  for (size_t k = 0; ok && k < p; ++k) ok = g.i[k] >= 0 && g.i[k] < g.j[k] && g.j[k] < f;
  if (!ok) throw InputError(path, "expected i < j < F and arrays of matching sizes");
  // What occgt covis writes, checked so that a damaged or hand-made graph cannot turn into
  // tuples of missing, repeated or NaN-scored frames.
  for (size_t k = 1; k < p; ++k) {
    if (g.i[k] < g.i[k - 1] || (g.i[k] == g.i[k - 1] && g.j[k] <= g.j[k - 1])) {
      throw InputError(path, "pair " + std::to_string(k) + " (" + std::to_string(g.i[k]) + ", " +
                                 std::to_string(g.j[k]) +
                                 "): expected distinct pairs in increasing (i, j)");
    }
  }
  std::set<std::string> ids;
  for (size_t k = 0; k < g.frame_ids.size(); ++k) {
    const std::string& id = g.frame_ids[k];
    if (id.empty() || !ids.insert(id).second) {
      throw InputError(path + ":frame_ids.npy",
                       "entry " + std::to_string(k) + ": expected distinct non-empty frame ids, " +
                           (id.empty() ? "got an empty one" : "'" + id + "' repeats"));
    }
  }
  for (const auto& [name, values] :
       {std::pair<const char*, const std::vector<float>*>{"c_ij", &g.c_ij},
        {"c_ji", &g.c_ji},
        {"o_ij", &g.o_ij},
        {"o_ji", &g.o_ji},
        {"self", &g.self}}) {
    for (size_t k = 0; k < values->size(); ++k) {
      const float v = (*values)[k];
      if (!(v >= 0.0f && v <= 1.0f)) {
        throw InputError(path + ":" + name + ".npy", "entry " + std::to_string(k) + " is " +
                                                         std::to_string(v) +
                                                         ", expected a score in [0, 1]");
      }
    }
  }
  return g;
}

void CheckGraphFrames(const Recipe& recipe, const Scene& scene, const SceneCovisibility& g,
                      const std::string& path, size_t depth_cache_mb) {
  const std::string rerun = "; re-run occgt covis for it (delete " + path + " first)";
  std::map<std::string, size_t> scene_index;
  for (size_t k = 0; k < scene.frames.size(); ++k) scene_index.emplace(scene.frames[k].id, k);
  const bool needs_color = NeedsColor(recipe, scene);
  const auto stride = static_cast<size_t>(recipe.dataset.frame_stride);
  std::vector<size_t> held;  // scene index of each frame_ids entry
  for (size_t k = 0; k < g.frame_ids.size(); ++k) {
    const std::string& id = g.frame_ids[k];
    const std::string field = "frame_ids[" + std::to_string(k) + "] '" + id + "'";
    const auto it = scene_index.find(id);
    if (it == scene_index.end()) {
      throw InputError(path, field + " is not a frame of scene " + scene.name + " under " +
                                 recipe.dataset.root + " (a graph of other data?)" + rerun);
    }
    const Frame& frame = scene.frames[it->second];
    if (!frame.usable) {
      throw InputError(path, field + " is a frame the dataset now marks unusable (" +
                                 frame.unusable_reason + "): the data changed since occgt covis" +
                                 rerun);
    }
    if (k > 0 && it->second <= held.back()) {
      throw InputError(path, field + " comes before frame_ids[" + std::to_string(k - 1) +
                                 "] in the scene: expected the scene's order" + rerun);
    }
    if (it->second % stride != 0) {
      throw InputError(path, field + " is frame " + std::to_string(it->second) + " of scene " +
                                 scene.name + ", which dataset.frame_stride " +
                                 std::to_string(stride) +
                                 " skips: the data changed since occgt covis" + rerun);
    }
    if (needs_color && frame.color_path.empty()) {
      throw InputError(path, field + " has no colour image, which sample.image (" +
                                 ImageFormatName(recipe.sample.image) +
                                 ") needs: the data changed since occgt covis" + rerun);
    }
    held.push_back(it->second);
  }
  // The frames the graph lacks, scanned as covis scans (the held ones marked unusable, so
  // that only the others' depth is decoded): one kept now is a frame the graph should hold.
  Scene rest = scene;
  for (size_t f : held) rest.frames[f].usable = false;
  pairs::DepthCache cache(rest, recipe.width, recipe.height, depth_cache_mb << 20,
                          RecipeFrameDepthOptions(recipe));
  const pairs::ScanResult scanned =
      ScanRecipeFrames(recipe, rest, RecipePairTruthOptions(recipe, rest).labels, &cache);
  if (scanned.kept.empty()) return;
  const size_t missing = scanned.kept.front();
  const size_t k =
      static_cast<size_t>(std::upper_bound(held.begin(), held.end(), missing) - held.begin());
  const std::string where =
      k < held.size() ? "before frame_ids[" + std::to_string(k) + "] '" + g.frame_ids[k] + "'"
      : k > 0 ? "after frame_ids[" + std::to_string(k - 1) + "] '" + g.frame_ids[k - 1] + "'"
              : "frame_ids is empty";
  throw InputError(path, "frame_ids lacks frame '" + scene.frames[missing].id + "' of scene " +
                             scene.name + " (" + where +
                             "), which the recipe's scan keeps now: the data changed since "
                             "occgt covis" +
                             rerun);
}

void CheckGraphFramesDepth(const Recipe& recipe, const Scene& scene, const SceneCovisibility& g,
                           const std::vector<int32_t>& frames, const std::string& path,
                           size_t depth_cache_mb) {
  std::map<std::string, size_t> scene_index;
  for (size_t k = 0; k < scene.frames.size(); ++k) scene_index.emplace(scene.frames[k].id, k);
  // Only the asked frames are scanned (the others marked unusable); `frames` are graph indices.
  Scene only = scene;
  std::vector<char> wanted(scene.frames.size(), 0);
  for (int32_t k : frames) wanted[scene_index.at(g.frame_ids.at(static_cast<size_t>(k)))] = 1;
  for (size_t f = 0; f < only.frames.size(); ++f) {
    if (!wanted[f]) only.frames[f].usable = false;
  }
  pairs::DepthCache cache(only, recipe.width, recipe.height, depth_cache_mb << 20,
                          RecipeFrameDepthOptions(recipe));
  const LabelOptions labels = RecipePairTruthOptions(recipe, only).labels;
  const pairs::ScanResult scanned = ScanRecipeFrames(recipe, only, labels, &cache);
  const std::set<size_t> kept(scanned.kept.begin(), scanned.kept.end());
  for (size_t k = 0; k < g.frame_ids.size(); ++k) {  // graph order = scene order
    const size_t f = scene_index.at(g.frame_ids[k]);
    if (!wanted[f] || kept.count(f)) continue;
    // Why the scan drops it: its depth (unreadable, too few valid pixels), else its colour
    // image (ScanRecipeFrames' header check).
    std::string why;
    try {
      const std::shared_ptr<const DepthImage> d = cache.Get(f);
      int64_t valid = 0;
      for (float z : d->values_m) valid += IsValidDepth(z, labels.min_depth_m, labels.max_depth_m);
      why = "has " + std::to_string(valid) + " valid depth pixels of " +
            std::to_string(d->values_m.size()) + ", below dataset.min_valid_depth_fraction " +
            std::to_string(recipe.dataset.min_valid_depth_fraction);
      // ScanFrames' rule: no valid pixel, or a fraction below the recipe's.
      if (valid > 0 && static_cast<double>(valid) / static_cast<double>(d->values_m.size()) >=
                           recipe.dataset.min_valid_depth_fraction) {
        io::CheckFrameColorHeader(scene.frames[f]);
        why = "is no longer kept by the recipe's scan";
      }
    } catch (const InputError& e) {
      why = "has a file that cannot be used (" + std::string(e.what()) + ")";
    }
    throw InputError(path, "frame_ids[" + std::to_string(k) + "] '" + g.frame_ids[k] + "' " + why +
                               ": the data changed since occgt covis; re-run occgt covis for it "
                               "(delete " +
                               path + " first)");
  }
}

std::vector<float> DenseCovisibility(const SceneCovisibility& g) {
  const size_t f = g.frame_ids.size();
  std::vector<float> c(f * f, 0.0f);
  for (size_t k = 0; k < f; ++k) c[k * f + k] = g.self[k];
  for (size_t p = 0; p < g.i.size(); ++p) {
    const size_t i = static_cast<size_t>(g.i[p]), j = static_cast<size_t>(g.j[p]);
    c[i * f + j] = g.c_ij[p];
    c[j * f + i] = g.c_ji[p];
  }
  return c;
}

bool CovisibilityOptions::Check(std::string* error) const {
  if (out_dir.empty()) return *error = "--out: expected a folder", false;
  if (std::string e = TaskRangeError(task, tasks); !e.empty()) return *error = e, false;
  if (depth_cache_mb < 1)
    return *error = "--depth-cache-mb: expected an integer >= 1, got 0", false;
  return true;
}

std::string CovisibilityPath(const std::string& out_dir, const std::string& scene) {
  return out_dir + "/covisibility/" + SceneFileName(scene) + ".npz";
}

void WriteSceneCovisibility(const std::string& path, const SceneCovisibility& g,
                            const std::string& options_digest) {
  const int64_t p = static_cast<int64_t>(g.i.size());
  const int64_t f = static_cast<int64_t>(g.frame_ids.size());
  std::map<std::string, std::string> m;
  m["frame_ids"] = io::EncodeStringsNpy(g.frame_ids, "frame_ids");
  m["i"] = io::EncodeNpy<int32_t>({p}, g.i);
  m["j"] = io::EncodeNpy<int32_t>({p}, g.j);
  m["c_ij"] = io::EncodeNpy<float>({p}, g.c_ij);
  m["c_ji"] = io::EncodeNpy<float>({p}, g.c_ji);
  m["o_ij"] = io::EncodeNpy<float>({p}, g.o_ij);
  m["o_ji"] = io::EncodeNpy<float>({p}, g.o_ji);
  m["self"] = io::EncodeNpy<float>({f}, g.self);
  m["score_stride"] = io::EncodeNpy<int32_t>({}, std::vector<int32_t>{g.score_stride});
  m["options_digest"] = io::EncodeNpy("|u1", {static_cast<int64_t>(options_digest.size())},
                                      options_digest.data(), options_digest.size());
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  if (ec) throw InputError(path, "cannot create the parent folder: " + ec.message());
  io::WriteNpz(path, m);
}

SceneLoop StartSceneLoop(const Recipe& recipe_in, const std::string& out_dir, bool generate) {
  SceneLoop loop;
  loop.recipe = recipe_in;
  Recipe& recipe = loop.recipe;
  if (recipe.dataset.is_synthetic) {  // as the build: generated once under DIR/data
    if (recipe.dataset.root.empty()) recipe.dataset.root = out_dir + "/data";
    if (generate) {
      io::FolderLock lock(out_dir);
      EnsureSyntheticDataset(recipe.dataset.root, recipe.dataset.synthetic);
    }
    recipe.dataset.format = DatasetFormat::kGeneric;  // is_synthetic stays (the digest)
  }
  loop.digest = CovisibilityDigest(recipe_in);
  loop.reader = MakeRecipeReader(recipe);
  loop.scenes = ResolveScenes(recipe, *loop.reader, nullptr);
  return loop;
}

nlohmann::json RunCovisibility(const Recipe& recipe_in, const CovisibilityOptions& options,
                               const std::function<void(int64_t, int64_t)>& progress) {
  std::string error;
  if (!options.Check(&error)) throw InputError("options", error);
  // One run per task and folder (a second one would rename the first's temporary graphs).
  const std::unique_ptr<io::FileLock> task_lock =
      AcquireTaskLock(options.out_dir, ".covis.lock", "covis", options.task, options.tasks,
                      "write into another --out");
  const auto t0 = std::chrono::steady_clock::now();
  const SceneLoop loop = StartSceneLoop(recipe_in, options.out_dir, /*generate=*/true);
  const Recipe& recipe = loop.recipe;
  const std::string& digest = loop.digest;
  const datasets::DatasetReader* reader = loop.reader.get();
  const std::vector<std::string>& scenes = loop.scenes;
  std::vector<std::string> mine;
  for (size_t s = 0; s < scenes.size(); ++s) {
    if (static_cast<int>(s % options.tasks) == options.task) mine.push_back(scenes[s]);
  }
  RequireOneRecipe(options.out_dir, scenes, digest);
  int64_t written = 0, skipped = 0, scored = 0, candidates = 0, done = 0;
  pairs::DropCounts drops;
  // --dense: the F×F matrix of a scene's graph, DIR/covisibility/<scene>/...--FxF.npy.
  const auto dense_path = [&](const std::string& name, const SceneCovisibility& g) {
    const std::string f = std::to_string(g.frame_ids.size());
    return fs::path(options.out_dir) / "covisibility" / SceneFileName(name) /
           ("pairwise_covisibility--" + f + "x" + f + ".npy");
  };
  const auto write_dense = [&](const std::string& name, const SceneCovisibility& g) {
    const fs::path path = dense_path(name, g);
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (ec) throw InputError(path.string(), "cannot create the parent folder: " + ec.message());
    const auto f = static_cast<int64_t>(g.frame_ids.size());
    io::WriteNpy<float>(path.string(), {f, f}, DenseCovisibility(g));
  };
  for (const std::string& name : mine) {
    const std::string path = CovisibilityPath(options.out_dir, name);
    if (io::FileExists(path)) {
      const std::string stored = StoredDigest(path);
      if (stored != digest) {
        throw InputError(path, "written under another recipe (options digest " + stored +
                                   ", this one " + digest +
                                   "); remove it or write into another --out");
      }
      ++skipped;
      // A complete scene's graph is read through (a damaged or stale one is not counted
      // complete); it gets its dense matrix when asked for and missing (a first run without
      // --dense): from the stored graph, not scored again.
      SceneCovisibility g;
      try {
        g = ReadSceneCovisibility(path, digest, recipe.selection.score_stride);
      } catch (const InputError& e) {
        throw InputError(e.what(), "remove the file to compute the scene again");
      }
      // ... and checked against the data as occgt tuples checks it (the same frames kept now).
      CheckGraphFrames(recipe, ReadRecipeScene(recipe, *reader, name), g, path,
                       options.depth_cache_mb);
      // A dense matrix that is missing, or not the graph's (cut, edited), is written again.
      if (options.dense) {
        const std::string dense = dense_path(name, g).string();
        const auto f = static_cast<int64_t>(g.frame_ids.size());
        if (!io::FileExists(dense) ||
            io::ReadFileBytes(dense) != io::EncodeNpy({f, f}, DenseCovisibility(g))) {
          write_dense(name, g);
        }
      }
    } else {
      const Scene scene = ReadRecipeScene(recipe, *reader, name);
      RequireSceneMesh(recipe, scene);
      pairs::DepthCache cache(scene, recipe.width, recipe.height, options.depth_cache_mb << 20,
                              RecipeFrameDepthOptions(recipe));
      const SceneCovisibility g = ComputeSceneCovisibility(recipe, scene, &cache);
      if (options.dense) write_dense(name, g);
      WriteSceneCovisibility(path, g, digest);  // last: completes the scene
      ++written;
      scored += static_cast<int64_t>(g.i.size());
      candidates += g.candidates;
      pairs::AddCounts(g.drops, &drops);
    }
    if (progress) progress(++done, static_cast<int64_t>(mine.size()));
  }
  nlohmann::json out = {{"scenes", static_cast<int64_t>(scenes.size())},
                        {"scenes_this_task", static_cast<int64_t>(mine.size())},
                        {"written", written},
                        {"skipped_complete", skipped},
                        {"candidates", candidates},
                        {"pairs_scored", scored},
                        {"drops", drops}};
  out["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace gt::pipeline

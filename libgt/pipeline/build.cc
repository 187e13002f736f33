#include "libgt/pipeline/build.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/core/stats.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/folder_lock.h"
#include "libgt/pipeline/select.h"
#include "libgt/pipeline/synthetic.h"
#include "libgt/pipeline/write.h"

namespace gt::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// One recipe (options digest) per output folder: recipe.json is written once and a recipe
// of another digest is refused. Returns false for the folder of another recipe, which only
// a dry run may look at (its selections are then not read).
bool ClaimOutputFolder(const Recipe& recipe, const BuildOptions& options) {
  const std::string path = options.out_dir + "/recipe.json";
  if (io::FileExists(path)) {
    json existing;
    try {
      existing = json::parse(io::ReadFileBytes(path));
    } catch (const json::exception&) {
      throw InputError(path, "not valid JSON");
    }
    // A dry run writes nothing: it may preview another recipe against the folder (its
    // selections, of the other digest, are not reused).
    if (existing.value("options_digest", "") != recipe.Digest() && !options.dry_run) {
      throw InputError("--out " + options.out_dir,
                       "holds outputs of another recipe (options digest " +
                           existing.value("options_digest", "?") + ", this recipe's " +
                           recipe.Digest() + "); use a fresh folder (--dry-run previews it here)");
    }
    return existing.value("options_digest", "") == recipe.Digest();
  }
  if (options.dry_run) return true;
  json normalised = recipe.ToJson();
  normalised["options_digest"] = recipe.Digest();
  io::FolderLock lock(options.out_dir);
  if (!io::FileExists(path)) io::WriteFileAtomic(path, normalised.dump(2) + "\n");
  return true;
}

// Synthetic datasets are generated into DIR/data when missing; the recipe then reads them
// as the generic format.
Recipe ResolveDataset(const Recipe& in, const BuildOptions& options) {
  Recipe recipe = in;
  if (!recipe.dataset.is_synthetic) return recipe;
  if (recipe.dataset.root.empty()) recipe.dataset.root = options.out_dir + "/data";
  if (!options.dry_run || !fs::exists(recipe.dataset.root)) {
    io::FolderLock lock(options.out_dir);
    EnsureSyntheticDataset(recipe.dataset.root, recipe.dataset.synthetic);
  }
  // Read as generic manifests; is_synthetic stays, so that the digest the samples and
  // selections record is recipe.json's (the recipe as written, its root aside).
  recipe.dataset.format = DatasetFormat::kGeneric;
  return recipe;
}

// The select stage of this task (its scenes not selected yet), then every completed scene's
// selection. `complete`: every scene of the recipe is selected.
std::map<std::string, SceneSelection> SelectStage(
    const Recipe& recipe, const datasets::DatasetReader& reader,
    const std::vector<std::string>& scenes, const ImportList* imports, const BuildOptions& options,
    const ProgressFn& progress, bool own_folder, json* summary, bool* complete) {
  const auto t_select = Clock::now();
  std::map<std::string, SceneSelection> selections;
  int64_t selected = 0, reused = 0, bytes = 0;
  if (options.stage != Stage::kWrite) {
    std::vector<std::string> mine;
    for (size_t i = 0; i < scenes.size(); ++i) {
      if (static_cast<int>(i % options.tasks) == options.task) mine.push_back(scenes[i]);
    }
    int64_t done = 0;
    for (const std::string& name : mine) {
      std::optional<SceneSelection> stored;
      if (own_folder) stored = ReadSelection(options.out_dir, name, recipe.Digest());
      if (auto& s = stored) {
        selections[name] = std::move(*s);
        ++reused;
      } else {
        const Scene scene = ReadRecipeScene(recipe, reader, name);
        RequireSceneMesh(recipe, scene);
        pairs::DepthCache cache(scene, recipe.width, recipe.height, options.depth_cache_mb << 20,
                                RecipeFrameDepthOptions(recipe));
        SceneSelection& sel = selections[name];
        sel = SelectScene(recipe, scene, &cache, imports);  // scene.name == name
        if (!options.dry_run) bytes += WriteSelection(options.out_dir, sel);
        ++selected;
      }
      if (progress) {
        progress(
            {Stage::kSelect, ++done, static_cast<int64_t>(mine.size()), Seconds(t_select), reused});
      }
    }
  }
  (*summary)["timings"]["select_s"] = Seconds(t_select);
  (*summary)["scenes_selected_this_run"] = selected;
  (*summary)["scenes_reused"] = reused;
  (*summary)["bytes_written"] = bytes;  // the selection files
  *complete = true;
  for (const std::string& scene : scenes) {
    if (selections.count(scene)) continue;
    if (!own_folder) {
      *complete = false;
      continue;
    }
    if (auto s = ReadSelection(options.out_dir, scene, recipe.Digest())) {
      selections[scene] = std::move(*s);
    } else {
      *complete = false;
    }
  }
  return selections;
}

// Whether every export the recipe asks for is in out_dir, by its top files: gluefactory/
// and dust3r/ by their export.json, loftr/ by intrinsics.npz, scenes.txt and its list file
// (kinds train and test; `{split}_list.txt`, `test_list.txt`), test.npz (kind test) and
// tree.json (loftr_export.tree), or as a folder that is not empty (kind megadepth). A file
// deeper in an export is restored by deleting the export's folder.
bool RequestedExportsPresent(const Recipe& recipe, const std::string& out_dir) {
  if (recipe.gluefactory_export && !io::FileExists(out_dir + "/gluefactory/export.json")) {
    return false;
  }
  if (recipe.dust3r_export && !io::FileExists(out_dir + "/dust3r/export.json")) return false;
  if (recipe.loftr_export == LoftrExportKind::kMegaDepth) {
    std::error_code ec;
    return std::filesystem::is_directory(out_dir + "/loftr", ec) &&
           !std::filesystem::is_empty(out_dir + "/loftr", ec);
  }
  if (recipe.loftr_export != LoftrExportKind::kNone) {
    const bool test = recipe.loftr_export == LoftrExportKind::kTest;
    for (const char* file : {"/loftr/intrinsics.npz", "/loftr/scenes.txt"}) {
      if (!io::FileExists(out_dir + file)) return false;
    }
    // The list file as shards::WriteLoftr*Export names it (LoftrExportOptions::list_name "").
    if (!io::FileExists(out_dir + "/loftr/" + (test ? "test" : recipe.split) + "_list.txt")) {
      return false;
    }
    if (test && !io::FileExists(out_dir + "/loftr/test.npz")) return false;
    if (recipe.loftr_tree && !io::FileExists(out_dir + "/loftr/tree.json")) return false;
  }
  return true;
}

// Counts, drops and the distribution of the selected pairs' scores, over every completed
// scene.
void AddSelectionStatistics(const Recipe& recipe,
                            const std::map<std::string, SceneSelection>& selections,
                            const std::vector<const SelectedPair*>& all, json* summary) {
  json counts = {{"frames_total", 0},  {"frames_kept", 0}, {"candidates", 0},
                 {"after_pruning", 0}, {"scored", 0},      {"selected", 0}};
  pairs::DropCounts drops;
  json examples = json::object();  // per reason, the first scene's example (scene order)
  json per_scene = json::object();
  for (const auto& [scene, sel] : selections) {
    for (auto& [k, v] : counts.items()) v = v.get<int64_t>() + sel.stats.value(k, int64_t{0});
    for (const auto& [k, v] : sel.stats.at("drops").items()) drops[k] += v.get<int64_t>();
    const json scene_examples = sel.stats.value("drop_examples", json::object());
    for (const auto& [k, v] : scene_examples.items()) {
      if (!examples.contains(k)) examples[k] = v;
    }
    per_scene[scene] = sel.stats.at("selected");
  }
  (*summary)["counts"] = counts;
  (*summary)["drops"] = drops;
  (*summary)["drop_examples"] = examples;
  (*summary)["pairs_per_scene"] = per_scene;
  (*summary)["scenes_complete"] = static_cast<int64_t>(selections.size());
  std::vector<double> overlaps, occlusions;
  const pairs::SelectionOptions& s = recipe.selection;
  for (const SelectedPair* p : all) {
    overlaps.push_back(Combine(p->score01.overlap, p->score10.overlap, s.aggregate));
    occlusions.push_back(Combine(OcclusionOf(p->score01, s.occlusion_metric),
                                 OcclusionOf(p->score10, s.occlusion_metric), s.aggregate));
  }
  // Of the pairs' score_metrics: the grid of every score_stride-th pixel the selection
  // scored on (the same numbers as pairs.jsonl's score_metrics and the report's).
  auto stats = [&s](std::vector<double> v) {
    if (v.empty()) return json(nullptr);
    std::sort(v.begin(), v.end());
    double sum = 0;
    for (double x : v) sum += x;
    return json{{"min", v.front()},
                {"median", SortedMedian(v)},
                {"mean", sum / v.size()},
                {"max", v.back()},
                {"score_stride", s.score_stride}};
  };
  (*summary)["selected_overlap"] = stats(overlaps);
  (*summary)["selected_occlusion"] = stats(occlusions);
}

}  // namespace

Stage ParseStage(const std::string& text, const std::string& field) {
  if (text == "select") return Stage::kSelect;
  if (text == "write") return Stage::kWrite;
  if (text == "all") return Stage::kAll;
  throw InputError(field, "expected select, write or all; got '" + text + "'");
}

const char* StageName(Stage stage) {
  switch (stage) {
    case Stage::kSelect:
      return "select";
    case Stage::kWrite:
      return "write";
    case Stage::kAll:
      break;
  }
  return "all";
}

bool BuildOptions::Check(std::string* error) const {
  if (out_dir.empty()) return *error = "--out: expected an output folder", false;
  if (std::string e = TaskRangeError(task, tasks); !e.empty()) return *error = e, false;
  if (depth_cache_mb < 1)
    return *error = "--depth-cache-mb: expected an integer >= 1, got 0", false;
  return true;
}

std::string TaskRangeError(int task, int tasks) {
  if (tasks < 1) return "--tasks: expected an integer >= 1";
  if (task >= 0 && task < tasks) return "";
  return "--task: expected 0 <= task < tasks, got task " + std::to_string(task) + " of " +
         std::to_string(tasks) + (tasks == 1 ? " (--tasks N gives the number of tasks)" : "");
}

std::unique_ptr<io::FileLock> AcquireTaskLock(const std::string& out_dir,
                                              const std::string& lock_file,
                                              const std::string& command, int task, int tasks,
                                              const std::string& advice) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "cannot create the output folder: " + ec.message());
  const std::string lock_path = out_dir + "/" + lock_file;  // byte K: task K
  std::unique_ptr<io::FileLock> lock = io::FileLock::TryAcquire(lock_path, task);
  if (!lock) {
    // "of task K" only for a command split into tasks (occgt tuples has none); not "of N":
    // the holder may have been started with another --tasks.
    const std::string of_task = tasks > 1 ? " of task " + std::to_string(task) : "";
    throw InputError(out_dir, "another occgt " + command + of_task +
                                  " is writing this folder now (it holds byte " +
                                  std::to_string(task) + " of " + lock_path +
                                  "); wait for it to finish, or " + advice);
  }
  return lock;
}

double DeflatedDepthShare(const Recipe& recipe) { return recipe.dataset.is_synthetic ? 0.8 : 0.2; }

int64_t EstimatedSampleBytes(const Recipe& r) {
  const bool deflate = r.sample.compression == SampleCompression::kDeflate;
  const double sparse = deflate ? 0.06 : 1.0;  // labels, cells, occupancy: long runs
  const double px = static_cast<double>(r.width) * r.height;
  double bytes = 4096 + 64 * 1024 * (deflate ? 0.9 : 1.0);  // json + matches
  if (r.sample.labels) {
    bytes += sparse * (2 * px + 2 * px / (r.patches.stride * r.patches.stride));
  }
  const truth::PairTruthOptions t = truth::ResolvePairTruthOptions(RecipePairSettings(r));
  if (t.occupancy) {
    const double rays = px / 4;
    if (r.occupancy.encoding != VolumeEncoding::kDense) bytes += sparse * 2 * 2 * 8 * rays;
    if (r.occupancy.encoding != VolumeEncoding::kPacked) {
      bytes += sparse * 2 * t.bins.num_bins * rays;
    }
  }
  if (r.sample.image == ImageFormat::kPng) bytes += 2 * 2 * px;
  if (r.sample.image == ImageFormat::kJpg) bytes += 2 * px * 3 / 10;
  if (r.sample.depth) bytes += (deflate ? DeflatedDepthShare(r) : 1.0) * 2 * 4 * px;
  return static_cast<int64_t>(std::ceil(bytes));
}

json RunBuild(const Recipe& recipe_in, const BuildOptions& options, const ProgressFn& progress) {
  std::string error;
  if (!options.Check(&error)) throw InputError("occgt build", error);
  const auto t_start = Clock::now();
  json summary = {{"recipe", recipe_in.name},
                  {"split", recipe_in.split},
                  {"options_digest", recipe_in.Digest()},
                  {"task", options.task},
                  {"tasks", options.tasks},
                  {"stage", StageName(options.stage)},
                  {"dry_run", options.dry_run},
                  {"timings", json::object()}};
  // The write stage writes the shards of a selection made before: a folder where nothing
  // was selected (no recipe.json, which the select stage writes first) is refused before
  // anything is written (recipe.json, a synthetic recipe's data/).
  if (options.stage == Stage::kWrite && !options.dry_run &&
      !io::FileExists(options.out_dir + "/recipe.json")) {
    throw InputError(SelectionDir(options.out_dir),
                     "no scene is selected in this folder (the write stage selects nothing: run "
                     "--stage select for every task, or a build without --stage, first); "
                     "nothing written");
  }
  const bool own_folder = ClaimOutputFolder(recipe_in, options);
  // One process per task and folder: a second `occgt build` of the same task into the same
  // --out (a re-run started while the first still runs) would rename the first's temporary
  // files. Tasks of one array job hold different locks and run together.
  std::unique_ptr<io::FileLock> task_lock;
  if (!options.dry_run) {
    task_lock = AcquireTaskLock(options.out_dir, ".tasks.lock", "build", options.task,
                                options.tasks, "build into another --out");
  }
  const Recipe recipe = ResolveDataset(recipe_in, options);
  const std::unique_ptr<datasets::DatasetReader> reader = MakeRecipeReader(recipe);
  // An imported pair list names the scenes (unless dataset.scenes or split_file does): each
  // must be under the root, as a listed scene (its pairs were dropped without a count).
  std::unique_ptr<ImportList> imports;
  if (!recipe.selection.import_pairs.path.empty()) {
    imports = std::make_unique<ImportList>(
        ReadImportList(recipe.selection.import_pairs.path, recipe.selection.import_pairs.format));
  }
  const std::vector<std::string> scenes = ResolveScenes(recipe, *reader, imports.get());
  summary["scenes"] = static_cast<int64_t>(scenes.size());

  bool all_selected = false;
  const std::map<std::string, SceneSelection> selections =
      SelectStage(recipe, *reader, scenes, imports.get(), options, progress, own_folder, &summary,
                  &all_selected);
  std::vector<const SelectedPair*> all;  // the global sample order
  for (const std::string& scene : scenes) {
    auto it = selections.find(scene);
    if (it == selections.end()) continue;
    for (const SelectedPair& p : it->second.pairs) all.push_back(&p);
  }
  AddSelectionStatistics(recipe, selections, all, &summary);
  const std::vector<int64_t> shard_sizes = PlanShards(recipe, static_cast<int64_t>(all.size()));
  summary["samples"] = static_cast<int64_t>(all.size());
  summary["samples_per_shard"] =
      shard_sizes.empty() ? recipe.shards.samples_per_shard : shard_sizes.front();
  summary["shards_planned"] = static_cast<int64_t>(shard_sizes.size());
  summary["estimated_bytes"] = static_cast<int64_t>(all.size()) * EstimatedSampleBytes(recipe);
  summary["complete"] = false;
  // Every key must fit the tar's member paths: checked before the dry run's plan is shown and
  // before any sample is computed.
  const std::vector<std::string> keys = SampleKeys(all, recipe.sample.compression);
  if (options.dry_run || options.stage == Stage::kSelect) {
    summary["timings"]["total_s"] = Seconds(t_start);
    return summary;
  }
  if (!all_selected) {
    std::vector<std::string> missing;
    for (const std::string& scene : scenes) {
      if (!selections.count(scene)) missing.push_back(scene);
    }
    std::string names;
    for (size_t i = 0; i < missing.size() && i < 5; ++i) names += (i ? ", " : "") + missing[i];
    if (missing.size() > 5) names += ", ...";
    throw InputError(
        SelectionDir(options.out_dir),
        std::to_string(missing.size()) + " of " +
            Counted(static_cast<long long>(scenes.size()), "scene") +
            (missing.size() == 1 ? " has" : " have") + " no selection yet (" + names + "): " +
            (options.stage == Stage::kWrite
                 ? "the write stage selects nothing: run --stage select for every task, or a "
                   "build without --stage, first"
                 : "run every task with --stage select first, then --stage write; this task's "
                   "selection is kept"));
  }

  const auto t_write = Clock::now();
  CheckExportFolders(recipe, all);
  WritePlan(options, recipe.split, shard_sizes);
  const WriteResult written =
      WriteShards(recipe, *reader, options, all, keys, shard_sizes, progress);
  summary["timings"]["write_s"] = Seconds(t_write);
  summary["shards_written_this_run"] = written.shards_written;
  summary["shards_skipped_complete"] = written.shards_skipped;
  summary["samples_written_this_run"] = written.samples_written;

  // Tasks finishing together publish one after the other (the lock is held to the end); a
  // re-run that wrote nothing leaves published indices alone (no new inodes or mtimes).
  const int64_t nshards = static_cast<int64_t>(shard_sizes.size());
  const bool complete = AllShardsComplete(options, recipe.split, nshards);
  summary["complete"] = complete;
  std::optional<io::FolderLock> lock;
  if (complete) lock.emplace(options.out_dir);
  // An index or export deleted since is written again.
  const bool current = written.shards_written == 0 &&
                       io::FileExists(options.out_dir + "/index.json") &&
                       io::FileExists(options.out_dir + "/pairs.jsonl") &&
                       io::FileExists(options.out_dir + "/summary.json") &&
                       RequestedExportsPresent(recipe, options.out_dir);
  if (complete && !current) {
    const auto t_index = Clock::now();
    PublishIndices(recipe, *reader, options, all);
    summary["timings"]["index_s"] = Seconds(t_index);
  }
  summary["timings"]["total_s"] = Seconds(t_start);
  summary["bytes_written"] = summary["bytes_written"].get<int64_t>() + written.bytes_written;
  if (complete && !current) {
    io::WriteFileAtomic(options.out_dir + "/summary.json", summary.dump(2) + "\n");
  }
  return summary;
}

}  // namespace gt::pipeline

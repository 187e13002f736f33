// occgt build RECIPE --out DIR [--dry-run] [--threads N] [--task K --tasks N]
//                   [--stage select|write|all] [--root PATH] [--depth-cache-mb MB]
// Turns a dataset and a YAML recipe into a filtered pair index and WebDataset shards
// (docs/USER_GUIDE.md, docs/RECIPES.md, docs/CLI.md). The job is libgt/pairs/pipeline.h;
// this file parses flags, connects the pipeline's ShardOutput to libgt/shards, prints
// progress on stderr and the summary on stdout. Without --task/--tasks, a Slurm array
// task takes its place from SLURM_ARRAY_TASK_{ID,MIN,MAX,COUNT} (docs/SCALE.md).
#include <tbb/global_control.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "libgt/core/error.h"
#include "libgt/io/files.h"
#include "libgt/pairs/pipeline.h"
#include "libgt/pairs/recipe.h"
#include "libgt/shards/loftr_export.h"
#include "libgt/shards/sample.h"
#include "libgt/shards/split.h"

namespace occgt {
namespace {

struct BuildArgs {
  std::string recipe;
  std::string root;
  int threads = 0;
  bool task_given = false;  // --task or --tasks on the command line (then Slurm's env is ignored)
  gt::pairs::BuildOptions build;
};

// The value of environment variable `name` as an integer >= 0, nullopt when unset or empty;
// anything else throws InputError naming the variable.
std::optional<int> EnvIndex(const char* name) {
  const char* text = std::getenv(name);
  if (text == nullptr || *text == '\0') return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (*end != '\0' || errno != 0 || v < 0 || v > 1000000000 ||
      !std::isdigit(static_cast<unsigned char>(*text))) {
    throw gt::InputError(name, std::string("expected an integer >= 0, got '") + text + "'");
  }
  return static_cast<int>(v);
}

// Task layout of a Slurm array task: task = SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN,
// tasks = SLURM_ARRAY_TASK_COUNT. The array must be contiguous with step 1 (0-7, or 1-8),
// so that the tasks cover 0..tasks-1 exactly once. False when not in an array job.
bool TaskFromSlurm(gt::pairs::BuildOptions* build) {
  const std::optional<int> id = EnvIndex("SLURM_ARRAY_TASK_ID");
  if (!id) return false;
  const int min = EnvIndex("SLURM_ARRAY_TASK_MIN").value_or(0);
  const std::optional<int> max = EnvIndex("SLURM_ARRAY_TASK_MAX");
  std::optional<int> count = EnvIndex("SLURM_ARRAY_TASK_COUNT");
  if (!count && max) count = *max - min + 1;
  if (!count) {
    throw gt::InputError("SLURM_ARRAY_TASK_COUNT",
                         "unset (and no SLURM_ARRAY_TASK_MAX): pass --task K --tasks N");
  }
  if (*id < min || (max && *id > *max)) {
    throw gt::InputError("SLURM_ARRAY_TASK_ID", std::to_string(*id) + " outside the array " +
                                                    std::to_string(min) + "-" +
                                                    (max ? std::to_string(*max) : "?"));
  }
  if (max && *max - min + 1 != *count) {
    throw gt::InputError("SLURM_ARRAY_TASK_COUNT",
                         std::to_string(*count) + " tasks do not fill the array " +
                             std::to_string(min) + "-" + std::to_string(*max) +
                             " (use a contiguous --array=0-N-1 without a step, or pass --task "
                             "K --tasks N)");
  }
  if (*count < 1 || *id - min >= *count) {
    throw gt::InputError("SLURM_ARRAY_TASK_COUNT",
                         std::to_string(*count) + " does not cover SLURM_ARRAY_TASK_ID " +
                             std::to_string(*id) + " (SLURM_ARRAY_TASK_MIN " + std::to_string(min) +
                             ")");
  }
  build->task = *id - min;
  build->tasks = *count;
  return true;
}

// ShardOutput over libgt/shards: tar shards + part records, plan, merge, LoFTR export.
class ShardsOutput : public gt::pairs::ShardOutput {
 public:
  ShardsOutput(std::string dir, std::string split)
      : dir_(std::move(dir)), split_(std::move(split)) {}

  std::string SampleKey(const std::string& scene, const std::string& frame0,
                        const std::string& frame1) const override {
    return gt::shards::MakeSampleKey(scene, frame0, frame1);
  }
  void WritePlan(const std::vector<int64_t>& shard_nsamples) override {
    const std::string path = gt::shards::PlanPath(dir_, split_);
    if (gt::io::FileExists(path)) {
      const gt::shards::SplitPlan existing = gt::shards::ReadPlan(dir_, split_);
      if (existing.shard_nsamples != shard_nsamples) {
        throw gt::InputError(path,
                             "holds another shard plan than this recipe's; use a fresh --out");
      }
      return;
    }
    gt::shards::SplitPlan plan;
    plan.split = split_;
    plan.shard_nsamples = shard_nsamples;
    gt::shards::WritePlan(dir_, plan);
  }
  bool IsShardComplete(int64_t shard) const override {
    return gt::shards::IsShardComplete(dir_, split_, shard);
  }
  int64_t WriteShard(int64_t shard, const std::vector<gt::pairs::EncodedSample>& samples) override {
    auto stream = OpenShard(shard);
    for (size_t i = 0; i < samples.size(); ++i) stream->Add(samples[i], i + 1 == samples.size());
    return stream->Finish();
  }
  std::unique_ptr<gt::pairs::ShardStream> OpenShard(int64_t shard) override {
    class Stream : public gt::pairs::ShardStream {
     public:
      Stream(const std::string& dir, const std::string& split, int64_t shard)
          : writer_(dir, split, shard) {}
      // The shard's last sample is digested in Finish, beside the fsync's wait, and freed
      // with this stream (on the thread that runs Finish).
      void Add(gt::pairs::EncodedSample s, bool last) override {
        gt::shards::Sample sample;
        sample.key = std::move(s.key);
        for (auto& [name, bytes] : s.fields) sample.fields.push_back({name, std::move(bytes)});
        writer_.Add(std::move(sample), s.pair_line.dump(),
                    last ? gt::shards::TarShardWriter::Digest::kDeferred
                         : gt::shards::TarShardWriter::Digest::kNow);
      }
      int64_t Finish() override { return writer_.Finish().info.filesize; }

     private:
      gt::shards::SplitShardWriter writer_;
    };
    return std::make_unique<Stream>(dir_, split_, shard);
  }
  void Finish() override {
    gt::shards::MergeOptions options;
    options.split = split_;
    options.verify_md5 = false;  // just written (or verified by size) by this command
    options.read_tars = false;
    gt::shards::MergeSplit(dir_, options);
  }
  void ExportLoftr(const std::string& kind, const std::vector<gt::pairs::LoftrRow>& rows,
                   const std::map<std::string, std::array<double, 9>>& intrinsics) override {
    std::vector<gt::shards::LoftrPair> pairs;
    for (const auto& r : rows) {
      gt::shards::LoftrPair p;
      p.scene = r.scene;
      p.frame0 = r.frame0;
      p.frame1 = r.frame1;
      p.score = r.score;
      p.cam1_from_cam0 = r.cam1_from_cam0;
      pairs.push_back(p);
    }
    gt::shards::LoftrExportOptions options;
    options.split = split_;
    if (kind == "test") {
      gt::shards::ExportLoftrTest(dir_ + "/loftr", pairs, intrinsics, options);
    } else {
      gt::shards::ExportLoftrTrain(dir_ + "/loftr", pairs, intrinsics, options);
    }
  }

 private:
  std::string dir_, split_;
};

void PrintProgress(const gt::pairs::Progress& p) {
  static const bool tty = ::isatty(STDERR_FILENO);
  const double rate = p.elapsed_s > 0 ? p.done / p.elapsed_s : 0.0;
  const double eta = rate > 0 ? (p.total - p.done) / rate : 0.0;
  const char* unit = p.stage == "select" ? "scenes" : "pairs";
  if (tty) {
    std::fprintf(stderr, "\r[%s] %lld/%lld %s  %.2f/s  ETA %.0fs   ", p.stage.c_str(),
                 static_cast<long long>(p.done), static_cast<long long>(p.total), unit, rate, eta);
    if (p.done == p.total) std::fprintf(stderr, "\n");
  } else {
    std::fprintf(stderr, "[%s] %lld/%lld %s %.2f/s ETA %.0fs\n", p.stage.c_str(),
                 static_cast<long long>(p.done), static_cast<long long>(p.total), unit, rate, eta);
  }
  std::fflush(stderr);
}

void Run(const BuildArgs& args_in) {
  BuildArgs args = args_in;
  const bool from_slurm = !args.task_given && TaskFromSlurm(&args.build);
  gt::pairs::RecipeOverrides overrides;
  overrides.root = args.root;
  const gt::pairs::Recipe recipe = gt::pairs::LoadRecipe(args.recipe, overrides);
  if (args.threads < 0)
    throw gt::InputError("--threads", "expected an integer >= 0 (0 = all cores)");
  std::unique_ptr<tbb::global_control> limit;
  if (args.threads > 0) {
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  args.threads);
  }
  std::string error;
  if (!args.build.Check(&error)) throw gt::InputError("occgt build", error);
  if (std::string e = gt::shards::CheckSplitName(recipe.split); !e.empty()) {
    throw gt::InputError(args.recipe, "split: " + e);
  }
  if (from_slurm) {
    std::fprintf(stderr, "[build] task %d of %d (from SLURM_ARRAY_TASK_ID %s)\n", args.build.task,
                 args.build.tasks, std::getenv("SLURM_ARRAY_TASK_ID"));
  }
  ShardsOutput output(args.build.out_dir, recipe.split);
  const nlohmann::json summary = gt::pairs::RunBuild(recipe, args.build, &output, PrintProgress);
  std::cout << summary.dump(2) << std::endl;
}

}  // namespace

void AddBuildCommand(CLI::App& app) {
  auto args = std::make_shared<BuildArgs>();
  auto* cmd = app.add_subcommand(
      "build", "Build a pair index and WebDataset shards from a recipe (docs/USER_GUIDE.md)");
  cmd->add_option("recipe", args->recipe, "Recipe YAML file (docs/RECIPES.md)")->required();
  cmd->add_option("--out", args->build.out_dir, "Output folder")->required();
  cmd->add_flag("--dry-run", args->build.dry_run,
                "Select in memory, print the plan and statistics, write nothing");
  cmd->add_option("--threads", args->threads, "Worker threads (0 = all cores)");
  auto* task = cmd->add_option(
      "--task", args->build.task,
      "This task's index (0-based) when split in --tasks (default: from SLURM_ARRAY_TASK_ID)");
  auto* tasks = cmd->add_option(
      "--tasks", args->build.tasks,
      "Number of tasks the run is split into (default: SLURM_ARRAY_TASK_COUNT, else 1)");
  cmd->add_option("--stage", args->build.stage, "select | write | all (default all)");
  cmd->add_option("--depth-cache-mb", args->build.depth_cache_mb,
                  "Budget of decoded depth maps held per scene (LRU, default 512)");
  cmd->add_option(
      "--root", args->root,
      "Dataset root overriding the recipe's dataset.root (relative to the working folder)");
  cmd->callback([args, task, tasks] {
    args->task_given = task->count() > 0 || tasks->count() > 0;
    Run(*args);
  });
}

}  // namespace occgt

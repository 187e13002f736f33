// occgt build RECIPE --out DIR [--dry-run] [--threads N] [--task K --tasks N]
//                   [--stage select|write|all] [--root PATH] [--depth-cache-mb MB]
// Turns a dataset and a YAML recipe into a filtered pair index and WebDataset shards
// (docs/USER_GUIDE.md, docs/RECIPES.md, docs/CLI.md). The job is libgt/pipeline/build.h;
// this file parses flags, prints progress on stderr and a short human summary on stdout
// (--json: this run's summary JSON, with the fields of DIR/summary.json, instead). Without
// --task/--tasks, a Slurm array task takes its place from SLURM_ARRAY_TASK_{ID,MIN,MAX,COUNT}
// (docs/SCALE.md).
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
#include "apps/interrupt.h"
#include "apps/job_flags.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/pipeline/build.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/shards/split.h"

namespace occgt {
namespace {

struct BuildArgs {
  std::string depth_source;  // --depth-source: overrides dataset.depth_source
  std::string recipe;
  std::string root;
  int threads = 0;
  std::string stage = "all";
  bool json = false;        // print the summary JSON instead of the human summary
  bool task_given = false;  // --task or --tasks on the command line (then Slurm's env is ignored)
  gt::pipeline::BuildOptions build;
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

}  // namespace

// Task layout of a Slurm array task: task = SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN,
// tasks = SLURM_ARRAY_TASK_COUNT. The array must be contiguous with step 1 (0-7, or 1-8),
// so that the tasks cover 0..tasks-1 exactly once. False when not in an array job.
bool TaskFromSlurm(int* task, int* tasks) {
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
  // A stepped array (--array=0-6:2) skips indices: its tasks would not cover 0..N-1.
  if (const std::optional<int> step = EnvIndex("SLURM_ARRAY_TASK_STEP"); step && *step != 1) {
    throw gt::InputError("SLURM_ARRAY_TASK_STEP",
                         std::to_string(*step) +
                             ": expected 1 (use a contiguous --array=0-N-1 without a step, or "
                             "pass --task K --tasks N)");
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
  *task = *id - min;
  *tasks = *count;
  return true;
}

std::string DropsText(const nlohmann::json& s) {
  if (!s.contains("drops") || !s["drops"].is_object() || s["drops"].empty()) return "";
  std::string text = "  dropped:";
  bool first = true;
  for (const auto& [reason, n] : s["drops"].items()) {
    text += (first ? " " : ", ") + reason + " " + n.dump();
    first = false;
  }
  text += "\n";
  // The first error behind a reason, so that a missing mesh or file is named.
  if (s.contains("drop_examples") && s["drop_examples"].is_object()) {
    for (const auto& [reason, example] : s["drop_examples"].items()) {
      if (example.is_string())
        text += "  first " + reason + ": " + example.get<std::string>() + "\n";
    }
  }
  return text;
}

namespace {

void PrintProgress(const gt::pipeline::Progress& p) {
  static const bool tty = ::isatty(STDERR_FILENO);
  // Units found complete (resume) took no time: the rate is of this run's work only.
  const int64_t computed = p.done - p.resumed;
  const double rate = p.elapsed_s > 0 && computed > 0 ? computed / p.elapsed_s : 0.0;
  const double eta = rate > 0 ? (p.total - p.done) / rate : 0.0;
  const char* unit = p.stage == gt::pipeline::Stage::kSelect ? "scenes" : "pairs";
  const char* stage = gt::pipeline::StageName(p.stage);
  const std::string resumed =
      p.resumed > 0 ? " (" + std::to_string(p.resumed) + " resumed)" : std::string();
  if (tty) {
    std::fprintf(stderr, "\r[%s] %lld/%lld %s%s  %.2f/s  ETA %.0fs   ", stage,
                 static_cast<long long>(p.done), static_cast<long long>(p.total), unit,
                 resumed.c_str(), rate, eta);
    if (p.done == p.total) std::fprintf(stderr, "\n");
  } else {
    std::fprintf(stderr, "[%s] %lld/%lld %s%s %.2f/s ETA %.0fs\n", stage,
                 static_cast<long long>(p.done), static_cast<long long>(p.total), unit,
                 resumed.c_str(), rate, eta);
  }
  std::fflush(stderr);
}

using gt::HumanBytes;

// A few lines for a person: what was selected and written, what was dropped and why, where
// it went and what to run next. Every figure is a field of the summary JSON (--json).
std::string HumanSummary(const nlohmann::json& s, const std::string& out_dir) {
  using nlohmann::json;
  const auto num = [&](const char* key) { return s.value(key, json(0)).get<int64_t>(); };
  std::string text;
  char line[512];
  const std::string name = s.value("recipe", "") + " / " + s.value("split", "");
  const double seconds = s.contains("timings") ? s["timings"].value("total_s", 0.0) : 0.0;
  std::snprintf(line, sizeof(line), " (%.1f s)\n", seconds);
  const std::string took = line;
  const std::string pairs = gt::Counted(num("samples"), "pair");
  const std::string scenes = gt::Counted(num("scenes"), "scene");
  if (s.value("dry_run", false)) {
    text += name + ": dry run: " + pairs + " in " + scenes + " would be written as " +
            gt::Counted(num("shards_planned"), "shard") + ", about " +
            HumanBytes(static_cast<double>(num("estimated_bytes"))) +
            "; no selection, shard or index written" + took;
  } else if (s.value("stage", "all") == "select") {
    // The pairs of the scenes selected so far (a task of several selects its own).
    const int64_t complete = num("scenes_complete");
    const std::string in =
        complete < num("scenes") ? std::to_string(complete) + " of " + scenes + " so far" : scenes;
    // A task of more tasks than scenes may own none.
    const bool owns_none =
        num("scenes_selected_this_run") == 0 && num("scenes_reused") == 0 && num("tasks") > 1;
    text += name + ": selected " + pairs + " in " + in + " (" +
            (owns_none ? "task " + std::to_string(num("task")) + " of " +
                             std::to_string(num("tasks")) + " owns none of the scenes"
                       : gt::Counted(num("scenes_selected_this_run"), "scene") + " this run") +
            "); the select stage writes no shard: run --stage write" +
            (complete < num("scenes") ? " once every task has selected" : "") + took;
  } else {
    const int64_t written = num("samples_written_this_run");
    text +=
        name + ": " + pairs + " in " + scenes + ", " + gt::Counted(num("shards_planned"), "shard");
    if (num("samples") == 0) {
      text += "; no pair passed the selection (the drops below say why)";
    } else if (written == 0 && num("shards_skipped_complete") == 0) {
      text += "; nothing to write: task " + std::to_string(num("task")) + " of " +
              std::to_string(num("tasks")) + " owns none of the shards";
    } else if (written == 0) {
      text += "; nothing to write: every shard of this task was complete already";
    } else {
      text += "; wrote " + gt::Counted(written, "pair") + ", " +
              gt::Counted(num("shards_written_this_run"), "shard") + ", " +
              HumanBytes(static_cast<double>(num("bytes_written")));
    }
    text += took;
  }
  text += DropsText(s);
  if (!s.value("complete", false) && !s.value("dry_run", false) &&
      s.value("stage", "all") != "select") {
    text += "  this task's part is done; the split is published once every task has run\n";
  } else if (s.value("complete", false)) {
    text += "  out: " + out_dir +
            " (index.json, pairs.jsonl, summary.json); see it with: occgt "
            "inspect split " +
            ShellWord(out_dir) + "\n";
  }
  return text;
}

void Run(const BuildArgs& args_in) {
  BuildArgs args = args_in;
  args.build.stage = gt::pipeline::ParseStage(args.stage, "--stage");
  const bool from_slurm = !args.task_given && TaskFromSlurm(&args.build.task, &args.build.tasks);
  gt::pipeline::RecipeOverrides overrides;
  overrides.root = args.root;
  if (!args.depth_source.empty()) {
    overrides.depth_source = gt::render::ParseDepthSourceMode(args.depth_source, "--depth-source");
  }
  const gt::pipeline::Recipe recipe = gt::pipeline::LoadRecipe(args.recipe, overrides);
  const std::unique_ptr<tbb::global_control> limit = LimitThreads(args.threads);
  std::string error;
  if (!args.build.Check(&error)) {  // "--flag: expected ...": a usage error naming the flag
    const size_t colon = error.find(": ");
    throw gt::InputError(error.substr(0, colon), error.substr(colon + 2));
  }
  if (std::string e = gt::shards::CheckSplitName(recipe.split); !e.empty()) {
    throw gt::InputError(args.recipe, "split: " + e);
  }
  if (from_slurm) {
    std::fprintf(stderr, "[build] task %d of %d (from SLURM_ARRAY_TASK_ID %s)\n", args.build.task,
                 args.build.tasks, std::getenv("SLURM_ARRAY_TASK_ID"));
  }
  // Finished shards and selections are complete files (temporary name, then rename), so a
  // re-run resumes (apps/interrupt.h: one line, then the end by the signal).
  ExitOnInterrupt("re-run the same command to resume (finished shards are kept)");
  const nlohmann::json summary = gt::pipeline::RunBuild(recipe, args.build, PrintProgress);
  if (args.json) {
    std::cout << summary.dump(2) << std::endl;
  } else {
    std::cout << HumanSummary(summary, args.build.out_dir) << std::flush;
  }
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
  AddThreadsFlag(cmd, &args->threads, "Worker threads");
  cmd->add_flag("--json", args->json,
                "Print this run's summary as JSON (the fields of DIR/summary.json, which the run "
                "that published the split wrote) instead of a short human summary");
  const TaskFlags task_flags = AddTaskFlags(cmd, &args->build.task, &args->build.tasks);
  cmd->add_option("--stage", args->stage, "select | write | all (default all)");
  AddDepthCacheFlag(cmd, &args->build.depth_cache_mb);
  cmd->add_option("--depth-source", args->depth_source,
                  "sensor|mesh|fused: overrides the recipe's dataset.depth_source");
  AddRootFlag(cmd, &args->root);
  cmd->callback([args, task_flags] {
    args->task_given = task_flags.Given();
    task_flags.Check(args->build.tasks);
    Run(*args);
  });
}

}  // namespace occgt

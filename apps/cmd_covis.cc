// occgt covis RECIPE --out DIR [--dense] [--threads N] [--task K --tasks N] [--root PATH]
//                   [--depth-cache-mb MB] [--json]
// The covisibility graph of every scene of a recipe's dataset (libgt/pipeline/covisibility.h,
// docs/MULTIVIEW.md): DIR/covisibility/<scene>.npz, and with --dense MapAnything's
// DIR/covisibility/<scene>/pairwise_covisibility--FxF.npy. A re-run skips finished scenes;
// without --task/--tasks a Slurm array task takes its place from SLURM_ARRAY_TASK_* (as
// `occgt build`). This file parses flags and prints; the job is pipeline::RunCovisibility.
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/job_flags.h"
#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/pipeline/covisibility.h"
#include "libgt/pipeline/recipe.h"

namespace occgt {
namespace {

struct CovisArgs {
  std::string recipe, root;
  int threads = 0;
  bool json = false;
  bool task_given = false;
  gt::pipeline::CovisibilityOptions options;
};

void Run(const CovisArgs& args_in) {
  ExitOnInterrupt("re-run the same command to resume (finished scenes are kept)");
  CovisArgs args = args_in;
  const bool from_slurm =
      !args.task_given && TaskFromSlurm(&args.options.task, &args.options.tasks);
  const std::unique_ptr<tbb::global_control> limit = LimitThreads(args.threads);
  std::string error;
  if (!args.options.Check(&error)) {  // "--flag: expected ...": a usage error naming the flag
    const size_t colon = error.find(": ");
    throw gt::InputError(error.substr(0, colon), error.substr(colon + 2));
  }
  gt::pipeline::RecipeOverrides overrides;
  overrides.root = args.root;
  const gt::pipeline::Recipe recipe = gt::pipeline::LoadRecipe(args.recipe, overrides);
  if (from_slurm) {
    std::fprintf(stderr, "[covis] task %d of %d (from SLURM_ARRAY_TASK_ID %s)\n", args.options.task,
                 args.options.tasks, std::getenv("SLURM_ARRAY_TASK_ID"));
  }
  const nlohmann::json s =
      gt::pipeline::RunCovisibility(recipe, args.options, [](int64_t done, int64_t total) {
        std::fprintf(stderr, "[covis] %lld/%lld scenes\n", static_cast<long long>(done),
                     static_cast<long long>(total));
      });
  if (args.json) {
    std::cout << s.dump(2) << std::endl;
  } else {
    // A task of several writes its share of the scenes only: say so where the counts are.
    if (args.options.tasks > 1) {
      std::printf("task %d of %d (%s): its share of the scenes only; ", args.options.task,
                  args.options.tasks, from_slurm ? "from the Slurm array" : "--task/--tasks");
    }
    std::printf(
        "%s written, %lld already complete; %lld of %s scored (%.1f s); graphs in "
        "%s/covisibility/\n",
        gt::Counted(s["written"].get<int64_t>(), "scene").c_str(),
        static_cast<long long>(s["skipped_complete"].get<int64_t>()),
        static_cast<long long>(s["pairs_scored"].get<int64_t>()),
        gt::Counted(s["candidates"].get<int64_t>(), "candidate pair").c_str(),
        s["seconds"].get<double>(), args.options.out_dir.c_str());
    std::fputs(DropsText(s).c_str(), stdout);
  }
}

}  // namespace

void AddCovisCommand(CLI::App& app) {
  auto args = std::make_shared<CovisArgs>();
  auto* cmd = app.add_subcommand(
      "covis", "Covisibility graph of every scene of a recipe (docs/MULTIVIEW.md)");
  cmd->add_option("recipe", args->recipe,
                  "Recipe YAML file: dataset, resolution, labels, selection.pruning and "
                  "selection.score_stride are used (docs/RECIPES.md)")
      ->required();
  cmd->add_option("--out", args->options.out_dir, "Output folder")->required();
  cmd->add_flag("--dense", args->options.dense,
                "Also write MapAnything's pairwise_covisibility--FxF.npy per scene");
  AddThreadsFlag(cmd, &args->threads, "Worker threads");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  const TaskFlags task_flags = AddTaskFlags(cmd, &args->options.task, &args->options.tasks);
  AddDepthCacheFlag(cmd, &args->options.depth_cache_mb);
  AddRootFlag(cmd, &args->root);
  cmd->callback([args, task_flags] {
    args->task_given = task_flags.Given();
    task_flags.Check(args->options.tasks);
    Run(*args);
  });
}

}  // namespace occgt

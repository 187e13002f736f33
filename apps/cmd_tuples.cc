// occgt tuples RECIPE --out DIR [--shards] [--threads N] [--root PATH] [--json]
// Seeded N-view tuples of every scene (recipe selection.views / selection.tuples) on the
// covisibility graphs `occgt covis` wrote into DIR: DIR/tuples.jsonl (docs/MULTIVIEW.md), and
// with --shards the N-view shards of those tuples in DIR/views/ (views_write.h). The
// job is pipeline::RunTuples (libgt/pipeline/tuple_stage.h); this file parses flags and prints.
#include <tbb/global_control.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/job_flags.h"
#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/tuple_stage.h"

namespace occgt {
namespace {

struct TuplesArgs {
  std::string recipe, root, out_dir;
  bool json = false, shards = false;
  int threads = 0;
};

void Run(const TuplesArgs& args) {
  ExitOnInterrupt(
      "re-run the same command to resume (tuples.jsonl comes last; finished shards are kept)");
  const std::unique_ptr<tbb::global_control> limit = LimitThreads(args.threads);
  gt::pipeline::RecipeOverrides overrides;
  overrides.root = args.root;
  const gt::pipeline::Recipe recipe = gt::pipeline::LoadRecipe(args.recipe, overrides);
  const nlohmann::json s = gt::pipeline::RunTuples(recipe, args.out_dir, args.shards);
  if (args.json) {
    std::cout << s.dump(2) << std::endl;
  } else {
    std::printf("%s from %s written to %s/tuples.jsonl\n",
                gt::Counted(s["tuples"].get<int64_t>(), "tuple").c_str(),
                gt::Counted(s["scenes"].get<int64_t>(), "scene").c_str(), args.out_dir.c_str());
    const nlohmann::json& empty = s["scenes_without_tuples"];
    if (!empty.empty()) {
      std::string names;
      for (size_t k = 0; k < empty.size() && k < 5; ++k) {
        names += (k ? ", " : "") + empty[k].get<std::string>();
      }
      std::printf("  %zu scene(s) gave no tuple: %s%s\n", empty.size(), names.c_str(),
                  empty.size() > 5 ? ", ..." : "");
    }
    std::fputs(DropsText(s).c_str(), stdout);
    if (s.contains("shards")) {
      std::printf("%s in %s in %s (%lld written, %lld complete)\n",
                  gt::Counted(s["shards"]["samples"].get<int64_t>(), "N-view sample").c_str(),
                  gt::Counted(s["shards"]["shards"].get<int64_t>(), "shard").c_str(),
                  s["shards"]["dir"].get<std::string>().c_str(),
                  static_cast<long long>(s["shards"]["shards_written"].get<int64_t>()),
                  static_cast<long long>(s["shards"]["shards_skipped"].get<int64_t>()));
    }
  }
}

}  // namespace

void AddTuplesCommand(CLI::App& app) {
  auto args = std::make_shared<TuplesArgs>();
  auto* cmd = app.add_subcommand(
      "tuples",
      "Seeded N-view tuples on the covisibility graphs of occgt covis (docs/MULTIVIEW.md)");
  cmd->add_option("recipe", args->recipe, "Recipe YAML file with selection.views (docs/RECIPES.md)")
      ->required();
  cmd->add_option("--out", args->out_dir, "The folder of occgt covis (writes tuples.jsonl there)")
      ->required();
  AddRootFlag(cmd, &args->root);
  cmd->add_flag("--shards", args->shards,
                "Also write one N-view sample per tuple into DIR/views/ (docs/MULTIVIEW.md)");
  AddThreadsFlag(cmd, &args->threads, "Worker threads of --shards");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args] { Run(*args); });
}

}  // namespace occgt

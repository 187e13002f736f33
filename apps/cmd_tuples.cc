// occgt tuples RECIPE --out DIR [--root PATH] [--json]
// Seeded N-view tuples of every scene (recipe selection.views / selection.tuples) on the
// covisibility graphs `occgt covis` wrote into DIR: DIR/tuples.jsonl (docs/MULTIVIEW.md). The
// job is pipeline::RunTuples (libgt/pipeline/tuple_stage.h); this file parses flags and prints.
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/tuple_stage.h"

namespace occgt {
namespace {

struct TuplesArgs {
  std::string recipe, root, out_dir;
  bool json = false;
};

void Run(const TuplesArgs& args) {
  gt::pipeline::RecipeOverrides overrides;
  overrides.root = args.root;
  const gt::pipeline::Recipe recipe = gt::pipeline::LoadRecipe(args.recipe, overrides);
  const nlohmann::json s = gt::pipeline::RunTuples(recipe, args.out_dir);
  if (args.json) {
    std::cout << s.dump(2) << std::endl;
  } else {
    std::printf("%lld tuples from %lld scenes written to %s/tuples.jsonl\n",
                static_cast<long long>(s["tuples"].get<int64_t>()),
                static_cast<long long>(s["scenes"].get<int64_t>()), args.out_dir.c_str());
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
  cmd->add_option(
      "--root", args->root,
      "Dataset root overriding the recipe's dataset.root (relative to the working folder)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->callback([args] { Run(*args); });
}

}  // namespace occgt

#include "apps/pair_recipe.h"

#include "libgt/build/sample.h"
#include "libgt/core/error.h"

namespace occgt {

PairSetup StartPairSetup(const PairDatasetArgs& args) {
  PairSetup s;
  // A recipe without keys is the defaults: one mapping for both cases keeps them equal.
  gt::build::Recipe defaults;
  if (!args.recipe.empty()) {
    gt::build::RecipeOverrides overrides;
    overrides.root = args.root;
    s.recipe = gt::build::LoadRecipe(args.recipe, overrides);
  }
  const gt::build::Recipe& r = s.recipe ? *s.recipe : defaults;
  const gt::build::SampleOptions sample = gt::build::RecipeSampleOptions(r);
  s.options = sample.truth;
  s.resolution = sample.resolution;
  if (args.resolution) s.resolution = gt::truth::ParseResolution(*args.resolution, "--resolution");

  s.format = args.format;
  s.root = args.root;
  if (s.recipe) {
    if (s.format.empty()) s.format = r.dataset.format == "synthetic" ? "generic" : r.dataset.format;
    if (s.root.empty()) s.root = r.dataset.root;
    if (s.root.empty()) {  // synthetic: generated into the build's folder
      throw gt::InputError("--root", "required with a synthetic recipe (the build's DIR/data)");
    }
  }
  if (s.root.empty()) throw gt::InputError("--root", "required (or --recipe)");
  if (s.format.empty()) throw gt::InputError("--format", "required (or --recipe)");
  return s;
}

gt::LabelOptions LabelsFor(const PairSetup& setup, const gt::Scene& scene,
                           const std::optional<std::string>& preset, const PairDatasetArgs& args) {
  gt::build::Recipe r = setup.recipe ? *setup.recipe : gt::build::Recipe();
  if (preset) r.labels.preset = *preset;
  gt::LabelOptions o = gt::build::RecipeLabelOptions(r, scene);  // checked; the flags next
  if (args.min_depth_m) o.min_depth_m = *args.min_depth_m;
  if (args.max_depth_m) o.max_depth_m = *args.max_depth_m;
  return o;
}

}  // namespace occgt

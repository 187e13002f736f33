// `occgt pair` and `occgt occupancy` with `--recipe R.yaml`: the options of one pair of a
// build, so that the single-pair tools reproduce a built shard's arrays byte for byte
// (docs/CLI.md). The recipe is read by the build's own loader (build::LoadRecipe) and
// mapped by the build's own functions (build::RecipeSampleOptions for the resolution,
// patches, fusion and bins; build::RecipeLabelOptions for the labels of a scene); flags
// given on the command line then override single fields. Without a recipe the tools start
// from the same defaults as a recipe without those keys.
#pragma once

#include <optional>
#include <string>

#include "libgt/build/recipe.h"
#include "libgt/core/frame.h"
#include "libgt/geometry/labels.h"
#include "libgt/truth/pair_truth.h"

namespace occgt {

// The dataset flags shared by both tools. root/format: from the recipe's dataset when not
// given (a `synthetic` recipe reads its generated data as `generic`, found with --root).
struct PairDatasetArgs {
  std::string recipe, root, format, scene, frames, out;
  std::optional<std::string> resolution;           // WxH; default the recipe's or 640x480
  std::optional<double> min_depth_m, max_depth_m;  // default the recipe's or the dataset's
};

struct PairSetup {
  std::optional<gt::build::Recipe> recipe;
  std::string root, format;             // resolved as above
  gt::truth::Resolution resolution;     // working resolution
  gt::truth::PairTruthOptions options;  // the recipe's (labels filled by LabelsFor)
};

// Loads the recipe (when given) and resolves root, format and resolution; throws InputError
// naming the recipe file or the flag.
PairSetup StartPairSetup(const PairDatasetArgs& args);

// Label options for `scene` (build::RecipeLabelOptions: the preset, `preset` when given,
// else the recipe's, else `default`; the depth range of the recipe's dataset/labels, else
// the scene's; the recipe's tolerances), then the --min/max-depth-m flags (unchecked).
gt::LabelOptions LabelsFor(const PairSetup& setup, const gt::Scene& scene,
                           const std::optional<std::string>& preset, const PairDatasetArgs& args);

}  // namespace occgt

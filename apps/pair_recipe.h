// `occgt pair` and `occgt occupancy`: the settings of one pair, from a recipe (`--recipe
// R.yaml`, so that the single-pair tools reproduce a built shard's arrays byte for byte;
// docs/CLI.md) or the defaults, then the flags. The recipe is read by the build's loader
// (pipeline::LoadRecipe) and its settings taken as the build takes them
// (pipeline::RecipePairSettings, RecipeDepthRange); the options are resolved by
// truth::ResolvePairTruthOptions, as everywhere.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "apps/usage.h"
#include "libgt/core/frame.h"
#include "libgt/datasets/reader.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/pair_truth.h"
#include "libgt/truth/working_frame.h"

namespace occgt {

// The dataset flags shared by both tools. root/format: from the recipe's dataset when not
// given (a `synthetic` recipe reads its generated data as `generic`, found with --root).
struct PairDatasetArgs {
  std::string recipe, root, format, scene, frames, out;
  std::optional<std::string> resolution;           // WxH; default the recipe's or 640x480
  std::optional<double> min_depth_m, max_depth_m;  // default the recipe's or the dataset's
  std::optional<std::string> depth_source;         // sensor|mesh|fused; default the recipe's
  std::string mesh;                                // the scene's mesh; default the recipe's
  std::optional<std::string> device;               // scannetpp: dslr|iphone; default the recipe's
  std::optional<double> tum_max_dt_s;              // tum: association tolerance; the recipe's
};

struct PairSetup {
  std::optional<gt::pipeline::Recipe> recipe;
  std::string root;  // resolved as above
  gt::DatasetFormat format = gt::DatasetFormat::kGeneric;
  gt::truth::Resolution resolution;     // working resolution
  gt::truth::PairSettings settings;     // the recipe's (or the defaults), then the depth flags
  gt::render::FrameDepthOptions depth;  // the recipe's depth source, then --depth-source
  std::string mesh_path;                // --mesh, else the recipe's dataset.mesh_path
  // The recipe's reader options (pipeline::RecipeReaderOptions), then the flags.
  // ScanNet++ (scannetpp_device): --device, else the recipe's dataset.device, else from the
  // frame ids (datasets::ScanNetPPDeviceOfFrameId); frame ids of the other device are refused.
  // TUM (tum_max_dt_s): --tum-max-dt, else the recipe's dataset.tum_max_dt_s.
  gt::datasets::ReaderOptions reader;
};

// The scene of the setup (its mesh path applied) and its frames at the working resolution
// with the setup's depth source.
gt::Scene ReadSetupScene(const PairSetup& setup, const std::string& scene_name);
gt::truth::WorkingFrame LoadSetupFrame(const PairSetup& setup, const gt::Scene& scene,
                                       const gt::Frame& frame);

// Whether the pair is the command's only input (`occgt pair`, `occgt occupancy`: --scene,
// --frames and --out required) or one of several sources (`occgt inspect pair`, which also
// reads a shard sample or a pair folder: only --out required, the rest checked when used).
enum class PairFlags { kOnlySource, kOneOfSources };

// Adds the flags of PairDatasetArgs to a subcommand; `recipe_gives` says what the recipe
// contributes (help text).
void AddPairDatasetFlags(CLI::App* cmd, PairDatasetArgs* args, const std::string& recipe_gives,
                         PairFlags use = PairFlags::kOnlySource);

// Loads the recipe (when given) and resolves root, format, resolution and settings; throws
// InputError naming the recipe file or the flag.
PairSetup StartPairSetup(const PairDatasetArgs& args);

// The depth range of `scene` under the setup (the recipe's dataset.min/max_depth_m apply).
gt::truth::DatasetDepthRange DepthRangeFor(const PairSetup& setup, const gt::Scene& scene);

// What a command computes of a pair: labels, metrics and matches (and the occupancy when the
// settings enable it), or the occupancy volumes only (`occgt occupancy`, whose patch settings
// are not used and so not checked).
enum class PairOutputs { kAll, kOccupancyOnly };

// The settings of the setup resolved (truth::ResolvePairTruthOptions) and checked: a field
// set by --min-depth-m, --max-depth-m or one of the command's `flags` is a usage error
// naming that flag, any other an error under `what` (ThrowOptionsError).
// ResolveSettings: without a scene (the preset's depth range), so that bad flags fail before
// any file is read; ResolveForScene: with the depth range of `scene` (DepthRangeFor), the
// options the command runs with.
gt::truth::PairTruthOptions ResolveSettings(const PairSetup& setup, const PairDatasetArgs& args,
                                            PairOutputs outputs, const std::string& what,
                                            const std::vector<FieldFlag>& flags = {});
gt::truth::PairTruthOptions ResolveForScene(const PairSetup& setup, const PairDatasetArgs& args,
                                            const gt::Scene& scene, PairOutputs outputs,
                                            const std::string& what,
                                            const std::vector<FieldFlag>& flags = {});

}  // namespace occgt

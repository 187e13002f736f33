// What a user sets for one pair's ground truth, and the one function that turns it into
// PairTruthOptions. Every entry point fills a PairSettings and calls
// ResolvePairTruthOptions: a recipe (pipeline::RecipePairSettings), the flags of `occgt
// pair` / `occgt occupancy` (on top of a recipe's settings), `occgt inspect pair`, and the
// keyword arguments of the Python binding. Nothing else maps user settings onto the Options
// structs, so a setting means the same everywhere.
//
// Defaults live in the Options structs only (LabelOptions through its preset, PatchOptions,
// occupancy::FusionOptions and BinOptions, PairTruthOptions): a setting left unset (nullopt)
// keeps the default of the field it maps onto.
//
// Resolution order of the labels (later wins; GROUND_TRUTH.md §2):
//   1. the preset (geometry/labels.h LabelPreset);
//   2. the dataset's valid depth range (the reader's Scene range), unless the preset ignores
//      it (occ2net-compat: LabelOptions::dataset_depth_range = false);
//   3. the range set for the whole dataset (a recipe's dataset.min/max_depth_m), whatever the
//      preset;
//   4. the label overrides (a recipe's labels.*, flags, keyword arguments).
// Occupancy: the fusion's ray range is max_range_m when set, else the last bin edge far_m,
// and the fusion's depth validity range is the labels' (truth::FusionInputOf).
#pragma once

#include <optional>
#include <string>

#include "libgt/core/depth.h"
#include "libgt/core/frame.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/truth/pair_truth.h"

namespace gt::truth {

// A recipe's `labels:` keys, `occgt pair`'s label flags, the Python label arguments.
struct LabelSettings {
  std::string preset = "default";  // LabelPreset name
  std::optional<double> abs_tol_m, rel_tol;
  std::optional<double> min_depth_m, max_depth_m;  // replace every range below (step 4)
  std::optional<RelativeTo> relative_to;
  std::optional<Bounds> bounds;
  std::optional<TargetLookup> target_lookup;
  std::optional<MissingTarget> missing_target;
};

// A recipe's `occupancy:` keys (but `encoding`, a storage choice), `occgt occupancy`'s flags,
// the Python occupancy arguments. Unset: the Options structs' defaults.
struct OccupancySettings {
  bool enabled = true;                  // compute the two volumes
  std::optional<double> voxel_m;        // FusionOptions::voxel_m
  std::optional<double> max_range_m;    // FusionOptions::max_range_m; unset: the bins' far_m
  std::optional<int> bins;              // BinOptions::num_bins
  std::optional<double> near_m, far_m;  // BinOptions
  std::optional<occupancy::BinSpacing> spacing;
  std::optional<occupancy::Traversal> traversal;
  std::optional<occupancy::FusionScope> scope;  // FusionOptions::scope
  std::optional<int> window, scene_stride;      // FusionOptions (used by their scope only)
  std::optional<occupancy::OccupancyMode> mode;
  std::optional<bool> downsample, remove_outliers;  // FusionOptions
  std::optional<int> outlier_k;                     // FusionOptions (remove_outliers only)
  std::optional<double> outlier_stddev;             // FusionOptions (remove_outliers only)
};

// A setting given that its own switch leaves unused ("outlier_k: ..." when remove_outliers
// is not on), else "". Every entry point refuses such settings (they were recorded and not
// applied); the values themselves are checked on the resolved options.
std::string OccupancySettingsProblem(const OccupancySettings& settings);

struct PairSettings {
  LabelSettings labels;
  PatchOptions patches;  // used as they are (stride 8, centre anchors, mutual vv)
  OccupancySettings occupancy;
};

// The dataset's valid depth range for one scene: the reader's (Scene::min/max_depth_m), and a
// range set for the whole dataset (a recipe's dataset.min/max_depth_m), which applies to
// every preset. Without a dataset (plain arrays): the defaults of core/depth.h.
struct DatasetDepthRange {
  double min_depth_m = kDefaultMinDepthM;
  double max_depth_m = kDefaultMaxDepthM;
  std::optional<double> set_min_depth_m, set_max_depth_m;
};
// The reader's range of `scene`.
DatasetDepthRange DepthRangeOf(const Scene& scene);

// The options of the settings for a scene of that depth range (order above). Not checked:
// PairTruthOptions::Check (called by ComputePairTruth) names the field of a bad value as
// "<section>: <field> ..." (labels, patches, occupancy).
PairTruthOptions ResolvePairTruthOptions(const PairSettings& settings,
                                         const DatasetDepthRange& range = {});

}  // namespace gt::truth

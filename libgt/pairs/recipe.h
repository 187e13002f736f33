// Recipes: the YAML file that `occgt build` turns into a pair index and WebDataset shards
// (docs/RECIPES.md is the reference of every key; schemas/recipe.schema.json the schema).
//
// Loading is all-or-nothing and happens before any work: the YAML is converted to JSON,
// validated against the recipe schema (JSON Schema, embedded in the binary at build
// time; unknown keys and wrong types are errors), mapped 1:1 onto the Options structs
// below, and then checked with Recipe::Check. Every failure throws gt::InputError whose
// one-line message names the recipe file and the dotted field, e.g.
//   "recipes/x.yaml: selection.overlap: expected [lo, hi] with 0 <= lo <= hi <= 1".
//
// Paths (dataset.root, dataset.split_file, selection.import_pairs.path) may contain
// ${VAR} or ${VAR:-default}, expanded from the environment; after expansion a relative
// path is taken relative to the folder of the recipe file. An unset variable without a
// default is an error naming the field.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace gt::pairs {

// dataset.synthetic: the procedural sample generated into <out>/data when missing.
struct SyntheticDatasetOptions {
  int scenes = 2;     // number of synthetic scenes
  int frames = 16;    // frames per scene
  int width = 160;    // pixels of the generated depth/colour
  int height = 120;   // pixels
  uint64_t seed = 0;  // generator seed
};

struct DatasetOptions {
  std::string format;               // scannet | tartanair | sevenscenes | tum | generic | synthetic
  std::string root;                 // absolute after loading ("" = <out>/data for synthetic)
  std::vector<std::string> scenes;  // explicit scene names ({} = every scene under root)
  std::string split_file;           // absolute after loading; one scene name per line
  int frame_stride = 1;             // keep every n-th frame of a scene
  double min_valid_depth_fraction = 0.1;  // frames with less valid depth are skipped
  std::optional<double> min_depth_m;      // overrides the dataset's validity range (metres)
  std::optional<double> max_depth_m;
  SyntheticDatasetOptions synthetic;

  bool Check(std::string* error) const;
};

// labels: a named preset (GROUND_TRUTH.md §2) plus optional overrides of its fields.
struct LabelRecipe {
  std::string preset = "default";
  std::optional<double> abs_tol_m;
  std::optional<double> rel_tol;
  std::optional<double> min_depth_m;
  std::optional<double> max_depth_m;
};

struct PatchRecipe {
  int stride = 8;                 // pixels per cell side at the working resolution
  std::string anchor = "center";  // center | corner
  bool mutual = true;             // vv matches must loop back (LoFTR)
};

struct PruningOptions {
  double max_distance_m = 0.0;        // camera centre distance; 0 = no limit
  double max_view_angle_deg = 180.0;  // angle between optical axes; 180 = no limit
  bool frustum = true;                // drop pairs whose frustums do not intersect

  bool Check(std::string* error) const;
};

enum class Aggregate { kMin, kMean, kMax };
const char* AggregateName(Aggregate a);

struct ImportPairsOptions {
  std::string format = "loftr-npz";
  std::string path;  // absolute after loading; "" = no import
};

struct SelectionOptions {
  int max_frame_gap = 0;  // pairs (i < j) with j - i <= gap in kept-frame order; 0 = all pairs
  PruningOptions pruning;
  int score_stride = 8;                       // score on every n-th pixel in x and y
  double overlap_lo = 0.0, overlap_hi = 1.0;  // aggregated overlap must lie in [lo, hi]
  double occlusion_lo = 0.0, occlusion_hi = 1.0;
  std::string occlusion_metric = "image";  // image: OCCLUDED/(W*H); visible: /(VIS+OCC)
  Aggregate aggregate = Aggregate::kMean;  // how the two directions are combined
  int quota_per_scene = 0;                 // max pairs per scene after filters; 0 = all
  int balance_bins = 0;                    // sample evenly across overlap bins; 0 = off
  ImportPairsOptions import_pairs;

  bool Check(std::string* error) const;
};

struct OccupancyRecipe {
  bool enabled = true;
  double voxel_m = 0.05;            // OctoMap resolution (metres)
  int bins = 64;                    // depth bins per ray
  double near_m = 0.1;              // first bin edge (metres)
  double far_m = 10.0;              // last bin edge (metres)
  std::string spacing = "linear";   // linear | log | inverse
  std::string traversal = "exact";  // exact | center
  std::string scope = "pair";       // pair | window | scene
  int window = 2;                   // scope window: usable neighbours on each side of the pair
  int scene_stride = 10;            // scope scene: fuse every n-th frame (one map per scene)
  std::string mode = "octomap";     // octomap | two_point
  std::string encoding = "packed";  // packed | dense | both

  bool Check(std::string* error) const;
};

struct SampleOptions {
  std::string image = "png";  // png | jpg | none
  bool depth = false;         // depth0/1.npy (float32 metres)
  bool labels = true;         // label01/10.npy and cells0/1.npy
  bool occupancy = true;      // occ/known (or dense) volumes (also needs occupancy.enabled)
};

struct ShardOptions {
  int samples_per_shard = 100;  // samples per tar shard
  double target_mb = 0.0;       // > 0: derive samples_per_shard from an estimated sample size

  bool Check(std::string* error) const;
};

struct Recipe {
  std::string file;      // the recipe path as given (for messages)
  std::string base_dir;  // folder relative paths are resolved against
  std::string name;
  std::string split = "train";
  uint64_t seed = 0;
  int width = 640, height = 480;  // working resolution
  DatasetOptions dataset;
  LabelRecipe labels;
  PatchRecipe patches;
  SelectionOptions selection;
  OccupancyRecipe occupancy;
  SampleOptions sample;
  ShardOptions shards;
  std::string loftr_export;  // "" | train | test

  // Cross-field checks after the schema (ranges lo <= hi, stride divides the resolution,
  // near < far ...). On failure *error is "<field>: expected ...".
  bool Check(std::string* error) const;
  // The normalised recipe (every default filled in, paths absolute) as JSON, and its md5:
  // the options digest stored in every sample.
  nlohmann::json ToJson() const;
  std::string Digest() const;
};

// Overrides applied from the command line after parsing (before Check).
struct RecipeOverrides {
  std::string root;  // --root: replaces dataset.root (relative to the working directory)
};

// Reads, validates and checks a recipe file; throws InputError("<file>: <field>", ...).
Recipe LoadRecipe(const std::string& path, const RecipeOverrides& overrides = {});
// Same from text; `file` names the recipe in messages, `base_dir` resolves relative paths.
Recipe ParseRecipe(const std::string& yaml_text, const std::string& file,
                   const std::string& base_dir, const RecipeOverrides& overrides = {});

// YAML text to JSON (plain scalars typed as null/bool/int/float/string like YAML 1.2's
// core schema; quoted scalars stay strings). Throws InputError(file, ...) on a YAML error.
nlohmann::json YamlToJson(const std::string& yaml_text, const std::string& file);
// Validates against schemas/recipe.schema.json; returns "" or "<field>: expected ...".
std::string ValidateRecipeJson(const nlohmann::json& recipe);
// The embedded schema text.
const std::string& RecipeSchemaText();
// ${VAR} / ${VAR:-default} expansion; throws InputError(field, ...) for an unset VAR.
std::string ExpandEnv(const std::string& text, const std::string& field);

}  // namespace gt::pairs

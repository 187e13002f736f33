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
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libgt/core/frame.h"
#include "libgt/datasets/reader.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/pairs/selection.h"
#include "libgt/pairs/tuples.h"
#include "libgt/pipeline/sample.h"
#include "libgt/render/frame_depth.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/views_truth.h"

namespace gt::pipeline {

// loftr_export.kind: the LoFTR-family index written beside the shards (DIR/loftr/).
enum class LoftrExportKind {
  kNone,
  kTrain,
  kTest,
  kMegaDepth
};  // "" | "train" | "test" | "megadepth"
const char* LoftrExportKindName(LoftrExportKind kind);
// loftr_export.score: what the train index's `score` holds (docs/EXPORTS.md).
enum class LoftrScore {
  kOverlap,    // "overlap": Combine of the two directions' overlap (the selection score)
  kCovisible,  // "covisible": Combine of the two consistent_overlap (VISIBLE / sampled)
};

// dataset.synthetic: the procedural sample generated into <out>/data when missing.
struct SyntheticDatasetOptions {
  int scenes = 2;     // number of synthetic scenes
  int frames = 16;    // frames per scene
  int width = 160;    // pixels of the generated depth/colour
  int height = 120;   // pixels
  uint64_t seed = 0;  // generator seed
};

struct DatasetOptions {
  // dataset.format: a reader's format (core/frame.h), or `synthetic`: occgt's generated sample
  // (is_synthetic = true), written into <out>/data and read as generic.
  DatasetFormat format = DatasetFormat::kGeneric;
  bool is_synthetic = false;
  std::string root;                 // absolute after loading ("" = <out>/data for synthetic)
  std::vector<std::string> scenes;  // explicit scene names ({} = every scene under root)
  std::string split_file;           // absolute after loading; one scene name per line
  int frame_stride = 1;             // keep every n-th frame of a scene
  // scannetpp: the camera whose frames are read (dataset.device: dslr | iphone).
  datasets::ScanNetPPDevice device = datasets::ScanNetPPDevice::kDslr;
  // tum: the association tolerance (dataset.tum_max_dt_s; unset: ReaderOptions' default).
  std::optional<double> tum_max_dt_s;
  double min_valid_depth_fraction = 0.1;  // frames with less valid depth are skipped
  std::optional<double> min_depth_m;      // overrides the dataset's validity range (metres)
  std::optional<double> max_depth_m;
  SyntheticDatasetOptions synthetic;
  // dataset.depth_source: where frames' depth comes from (render/frame_depth.h,
  // docs/GROUND_TRUTH.md "Depth sources"): sensor (default) | mesh | fused.
  render::DepthSourceMode depth_source = render::DepthSourceMode::kSensor;
  // dataset.mesh_path: the scenes' mesh, in the frames' world frame; "{scene}" is replaced by
  // the scene's name. Absolute after loading; "" = the reader's (ScanNet's
  // <scene>_vh_clean_2.ply beside the scene), if any.
  std::string mesh_path;
  render::FusedDepthOptions fused_depth;  // dataset.fused_depth: {abs_tol_m, rel_tol}

  bool Check(std::string* error) const;
};

// occupancy: the keys of truth::OccupancySettings (voxel_m, bins, near_m, far_m,
// max_range_m, spacing, traversal, scope, window, scene_stride, mode; unset keys keep the
// Options structs' defaults) and the storage of the volumes.
struct OccupancyRecipe {
  truth::OccupancySettings settings;
  VolumeEncoding encoding = VolumeEncoding::kPacked;  // packed | dense | both

  bool enabled() const { return settings.enabled; }
};

struct SampleRecipe {
  ImageFormat image = ImageFormat::kPng;  // png | jpg | none
  bool depth = false;                     // depth0/1.npy (float32 metres)
  bool labels = true;                     // label01/10.npy and cells0/1.npy
  bool occupancy = true;  // occ/known (or dense) volumes (also needs occupancy.enabled)
  SampleCompression compression = SampleCompression::kDeflate;  // deflate (.npy.gz) | none
};

struct ShardOptions {
  int samples_per_shard = 100;  // samples per tar shard
  double target_mb = 0.0;       // > 0: derive samples_per_shard from an estimated sample size

  bool Check(std::string* error) const;
};

// selection.tuples.num_tracks / query_view: the tracks of each N-view sample of `occgt tuples
// --shards` (views_write.h), as truth::ViewsTruthOptions's fields of those names (the
// defaults are that struct's).
struct TupleTrackOptions {
  int num_tracks = truth::ViewsTruthOptions().num_tracks;  // query pixels per sample, >= 0
  int query_view = truth::ViewsTruthOptions().query_view;  // their view, < selection.views min

  bool Check(std::string* error) const;  // num_tracks >= 0, query_view >= 0
};

struct Recipe {
  std::string file;      // the recipe path as given (for messages)
  std::string base_dir;  // folder relative paths are resolved against
  std::string name;
  std::string split = "train";
  uint64_t seed = 0;
  int width = 640, height = 480;  // working resolution
  DatasetOptions dataset;
  truth::LabelSettings labels;  // labels: preset and overrides (truth/pair_settings.h)
  PatchOptions patches;         // stride must divide W and H
  pairs::SelectionOptions selection;
  OccupancyRecipe occupancy;
  SampleRecipe sample;
  ShardOptions shards;
  LoftrExportKind loftr_export = LoftrExportKind::kNone;
  bool loftr_tree = false;  // loftr_export.tree: also DIR/loftr/data/, ScanNet's exported layout
  LoftrScore loftr_score = LoftrScore::kOverlap;  // loftr_export.score
  bool gluefactory_export = false;  // DIR/gluefactory/: glue-factory's posed-image layout
  bool dust3r_export = false;       // DIR/dust3r/: DUSt3R's preprocessed ScanNet++ layout
  // selection.views (N or [min, max]) and selection.tuples: the N-view tuples of `occgt
  // tuples` (pairs/tuples.h); unset: the recipe has no tuples (and its digest is unchanged).
  std::optional<pairs::TupleOptions> tuples;
  TupleTrackOptions tuple_tracks;  // with tuples only

  // Cross-field checks after the schema (ranges lo <= hi, stride divides the resolution,
  // near < far ...). On failure *error is "<field>: expected ...".
  bool Check(std::string* error) const;
  // The normalised recipe (every default filled in, paths absolute) as JSON, and its md5:
  // the options digest stored in every sample.
  nlohmann::json ToJson() const;
  std::string Digest() const;
};

// The pair settings of a recipe (labels, patches, occupancy; occupancy is computed when
// occupancy.enabled and sample.occupancy), and the depth range of a scene under it (the
// reader's, and dataset.min/max_depth_m): what truth::ResolvePairTruthOptions turns into the
// options of that scene's pairs (RecipePairTruthOptions).
truth::PairSettings RecipePairSettings(const Recipe& recipe);
truth::DatasetDepthRange RecipeDepthRange(const Recipe& recipe, const Scene& scene);
truth::PairTruthOptions RecipePairTruthOptions(const Recipe& recipe, const Scene& scene);
// The sample options of a recipe (sample.h SampleOptions), its `truth` resolved without a
// scene (the write stage sets it per scene with RecipePairTruthOptions).
SampleOptions RecipeSampleOptions(const Recipe& recipe);

// The recipe's depth source as the frame-depth options of every scene (render range: the
// defaults of render::FrameDepthOptions).
render::FrameDepthOptions RecipeFrameDepthOptions(const Recipe& recipe);
// The reader options a recipe's dataset keys give (dataset.device for ScanNet++,
// dataset.tum_max_dt_s for TUM; the defaults otherwise).
datasets::ReaderOptions RecipeReaderOptions(const Recipe& recipe);
// The reader of the recipe's dataset: its format, with RecipeReaderOptions.
std::unique_ptr<datasets::DatasetReader> MakeRecipeReader(const Recipe& recipe);
// A scene read by `reader` with dataset.mesh_path applied (Scene::mesh_path, "{scene}"
// replaced by its name). With dataset.depth_source mesh or fused, a scene without a mesh
// file is an InputError naming it (not every frame a read error).
Scene ReadRecipeScene(const Recipe& recipe, const datasets::DatasetReader& reader,
                      const std::string& name);
// With dataset.depth_source mesh or fused, the scene's mesh parsed and its ray-casting
// structure built (render::SharedMeshRenderer, kept for the frames' renders that follow): a
// mesh that cannot be parsed is an InputError naming it before a scene's frames are scanned
// (every frame was a scan.read_error, and the empty selection was kept by a re-run after the
// mesh was mended). For the stages that render the scene's frames (select, covis).
void RequireSceneMesh(const Recipe& recipe, const Scene& scene);
// Scene::mesh_path from a dataset.mesh_path / --mesh value ("" keeps the reader's).
void ApplyMeshPath(const std::string& mesh_path, Scene* scene);

// Overrides applied from the command line after parsing (before Check).
struct RecipeOverrides {
  std::string root;  // --root: replaces dataset.root (relative to the working directory)
  std::optional<render::DepthSourceMode> depth_source;  // --depth-source
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

}  // namespace gt::pipeline

// Recipe loading: schema validation (unknown keys, wrong types, missing sections) gives one
// line naming the recipe file and the field; defaults, env expansion, relative paths; every
// shipped recipe loads; docs/RECIPES.md documents exactly the schema's keys.
#include "libgt/pipeline/recipe.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <set>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "tests/support/test_support.h"

namespace gt::pipeline {
namespace {

namespace fs = std::filesystem;

const char kMinimal[] = R"(
name: tiny
dataset:
  format: sevenscenes
  root: data/seq
)";

std::string ErrorOf(const std::string& yaml) {
  try {
    ParseRecipe(yaml, "recipes/x.yaml", "/base");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Recipe, MinimalGetsDefaultsAndResolvesRootAgainstRecipeFolder) {
  Recipe r = ParseRecipe(kMinimal, "recipes/x.yaml", "/base/recipes");
  EXPECT_EQ(r.name, "tiny");
  EXPECT_EQ(r.split, "train");
  EXPECT_EQ(r.width, 640);
  EXPECT_EQ(r.height, 480);
  EXPECT_EQ(r.dataset.root, "/base/recipes/data/seq");
  EXPECT_EQ(r.selection.aggregate, Aggregate::kMean);
  EXPECT_EQ(r.labels.preset, "default");
  EXPECT_EQ(r.patches.stride, 8);
  EXPECT_EQ(r.shards.samples_per_shard, 100);
  EXPECT_EQ(r.loftr_score, LoftrScore::kOverlap);
  EXPECT_FALSE(r.gluefactory_export);
  EXPECT_FALSE(r.dust3r_export);
  EXPECT_EQ(r.Digest().size(), 32u);
}

TEST(Recipe, FullRecipeMapsEveryField) {
  const std::string yaml = R"(
name: full
split: val
seed: 7
resolution: [320, 240]
dataset: {format: tartanair, root: /abs/root, scenes: [a, "b/c"], frame_stride: 2,
          min_valid_depth_fraction: 0.25, max_depth_m: 80}
labels: {preset: loftr, overrides: {abs_tol_m: 0.05, rel_tol: 0.1}}
patches: {stride: 16, anchor: corner, mutual: false}
selection:
  max_frame_gap: 5
  pruning: {max_distance_m: 3.5, max_view_angle_deg: 60, frustum: false}
  score_stride: 4
  overlap: [0.4, 0.8]
  visible_overlap: [0.15, 0.9]
  visible_aggregate: max
  occlusion: [0.3, 1]
  occlusion_metric: visible
  aggregate: min
  quota_per_scene: 50
  balance_bins: 4
occupancy: {enabled: false, voxel_m: 0.1, bins: 32, near_m: 0.5, far_m: 20, spacing: log,
            traversal: center, scope: scene, mode: two_point, encoding: both}
sample: {image: jpg, depth: true, labels: false, occupancy: false}
shards: {samples_per_shard: 10, target_mb: 0}
loftr_export: {kind: train, score: covisible}
gluefactory_export: true
dust3r_export: true
)";
  Recipe r = ParseRecipe(yaml, "f.yaml", "/x");
  EXPECT_EQ(r.split, "val");
  EXPECT_EQ(r.seed, 7u);
  EXPECT_EQ(r.width, 320);
  EXPECT_EQ(r.dataset.root, "/abs/root");
  EXPECT_EQ(r.dataset.scenes, (std::vector<std::string>{"a", "b/c"}));
  EXPECT_EQ(r.dataset.frame_stride, 2);
  EXPECT_DOUBLE_EQ(r.dataset.min_valid_depth_fraction, 0.25);
  EXPECT_DOUBLE_EQ(*r.dataset.max_depth_m, 80);
  EXPECT_FALSE(r.dataset.min_depth_m.has_value());
  EXPECT_EQ(r.labels.preset, "loftr");
  EXPECT_DOUBLE_EQ(*r.labels.abs_tol_m, 0.05);
  EXPECT_EQ(r.patches.anchor, Anchor::kCorner);
  EXPECT_FALSE(r.patches.mutual);
  EXPECT_EQ(r.selection.max_frame_gap, 5);
  EXPECT_DOUBLE_EQ(r.selection.pruning.max_distance_m, 3.5);
  EXPECT_FALSE(r.selection.pruning.frustum);
  EXPECT_DOUBLE_EQ(r.selection.overlap_lo, 0.4);
  EXPECT_DOUBLE_EQ(r.selection.occlusion_lo, 0.3);
  EXPECT_DOUBLE_EQ(r.selection.visible_overlap_lo, 0.15);
  EXPECT_DOUBLE_EQ(r.selection.visible_overlap_hi, 0.9);
  EXPECT_EQ(r.selection.visible_aggregate, Aggregate::kMax);
  EXPECT_EQ(r.selection.aggregate, Aggregate::kMin);
  EXPECT_EQ(r.selection.occlusion_metric, OcclusionMetric::kVisible);
  EXPECT_EQ(r.selection.quota_per_scene, 50);
  EXPECT_EQ(r.occupancy.settings.spacing, occupancy::BinSpacing::kLog);
  EXPECT_EQ(r.occupancy.encoding, VolumeEncoding::kBoth);
  EXPECT_EQ(r.sample.image, ImageFormat::kJpg);
  EXPECT_TRUE(r.sample.depth);
  EXPECT_EQ(r.shards.samples_per_shard, 10);
  EXPECT_EQ(r.loftr_export, LoftrExportKind::kTrain);
  EXPECT_EQ(r.loftr_score, LoftrScore::kCovisible);
  EXPECT_TRUE(r.gluefactory_export);
  EXPECT_TRUE(r.dust3r_export);
}

TEST(Recipe, LabelOptionsTakeTheDatasetRangeExceptForCompat) {
  Scene scene;
  scene.min_depth_m = 0.05;
  scene.max_depth_m = 100.0;
  Recipe r = ParseRecipe(kMinimal, "f.yaml", "/x");
  LabelOptions o = RecipePairTruthOptions(r, scene).labels;
  EXPECT_EQ(o.min_depth_m, 0.05);
  EXPECT_EQ(o.max_depth_m, 100.0);
  r.labels.preset = "occ2net-compat";  // every finite depth > 0, as the release
  o = RecipePairTruthOptions(r, scene).labels;
  EXPECT_EQ(o.min_depth_m, 0.0);
  EXPECT_EQ(o.max_depth_m, std::numeric_limits<float>::max());
  r.dataset.max_depth_m = 80.0;  // asked for explicitly: applies to compat too
  EXPECT_EQ(RecipePairTruthOptions(r, scene).labels.max_depth_m, 80.0);
  r.labels.max_depth_m = 60.0;  // a label override wins over the dataset's
  EXPECT_EQ(RecipePairTruthOptions(r, scene).labels.max_depth_m, 60.0);
}

TEST(Recipe, UnknownKeyNamesFileAndField) {
  const std::string e = ErrorOf(std::string(kMinimal) + "selection: {overlapp: [0.4, 0.8]}\n");
  EXPECT_EQ(e.find("recipes/x.yaml: selection.overlapp: unknown key"), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
  const std::string top = ErrorOf(std::string(kMinimal) + "seeds: 3\n");
  EXPECT_EQ(top.find("recipes/x.yaml: seeds: unknown key"), 0u) << top;
}

TEST(Recipe, WrongTypeNamesFieldAndExpectation) {
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "selection: {overlap: 0.5}\n"),
            "recipes/x.yaml: selection.overlap: expected [lo, hi] with 0 <= lo <= hi <= 1");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "selection: {overlap: [0.4, high]}\n"),
            "recipes/x.yaml: selection.overlap: expected [lo, hi] with 0 <= lo <= hi <= 1");
  // Quoted numbers stay strings.
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "seed: \"3\"\n"),
            "recipes/x.yaml: seed: expected an integer in [0, 9223372036854775807]");
  // Beyond int64 (a uint64 seed such as 2^64 - 1 read as a double): the range is stated, where
  // ">= 0" was said of a value that is >= 0.
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "seed: 18446744073709551615\n"),
            "recipes/x.yaml: seed: expected an integer in [0, 9223372036854775807]");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "seed: 9223372036854775807\n"), "");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "sample: {depth: yes}\n"),
            "recipes/x.yaml: sample.depth: expected true or false");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "dust3r_export: 1\n"),
            "recipes/x.yaml: dust3r_export: expected true or false (true: DIR/dust3r/, the pairs "
            "and their frames in DUSt3R's preprocessed ScanNet++ layout)");
}

TEST(Recipe, SemanticChecksNameTheField) {
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "selection: {overlap: [0.8, 0.4]}\n"),
            "recipes/x.yaml: selection.overlap: expected [lo, hi] with 0 <= lo <= hi <= 1");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "selection: {visible_overlap: [0.5, 0.2]}\n"),
            "recipes/x.yaml: selection.visible_overlap: expected [lo, hi] with 0 <= lo <= hi "
            "<= 1");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "selection: {visible_aggregate: median}\n")
                .find("recipes/x.yaml: selection.visible_aggregate:"),
            0u);
  EXPECT_EQ(ParseRecipe(kMinimal, "f.yaml", "/x").selection.visible_aggregate, Aggregate::kMin);
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "patches: {stride: 7}\n")
                .find("recipes/x.yaml: patches.stride:"),
            0u);
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "occupancy: {near_m: 5, far_m: 2}\n")
                .find("recipes/x.yaml: occupancy.far_m:"),
            0u);
}

TEST(Recipe, RangesThatWouldFailLaterNameTheirKeyAtLoad) {
  // Each used to load and fail at the first scene (after --out was claimed), under the
  // resolved option's name ("labels: max_depth_m ...") or not at all (target_mb: inf).
  const std::string m(kMinimal);
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic, max_depth_m: 0}\n"),
            "recipes/x.yaml: dataset.max_depth_m: expected a number > 0 (metres)");
  EXPECT_EQ(ErrorOf(m + "labels: {overrides: {max_depth_m: 0}}\n"),
            "recipes/x.yaml: labels.overrides.max_depth_m: expected a number > 0 (metres)");
  EXPECT_EQ(ErrorOf(m + "labels: {overrides: {min_depth_m: 2000}}\n"),
            "recipes/x.yaml: labels.overrides.min_depth_m: max_depth_m must be > min_depth_m "
            "(2000), got 1000");
  EXPECT_EQ(ErrorOf(m + "labels: {overrides: {abs_tol_m: .inf}}\n"),
            "recipes/x.yaml: labels.overrides.abs_tol_m: abs_tol_m must be finite and >= 0, "
            "got inf");
  EXPECT_EQ(ErrorOf(m + "shards: {target_mb: .inf}\n"),
            "recipes/x.yaml: shards.target_mb: expected a finite number >= 0");
  EXPECT_EQ(ErrorOf(m + "selection: {quota_per_scene: 3000000000}\n"),
            "recipes/x.yaml: selection.quota_per_scene: expected an integer <= 2147483647, got "
            "3000000000");
  // Past int's range below: the bound on that side (a field with minimum 0 is checked first).
  EXPECT_EQ(ErrorOf(m + "occupancy: {near_m: 0.1, bins: -3000000000}\n"),
            "recipes/x.yaml: occupancy.bins: expected an integer in [1, 64]");
  // TupleOptions::Check's fields under selection.tuples, selection.views under selection.
  EXPECT_EQ(ErrorOf(m + "selection: {views: 3, tuples: {pair_covisibility: [0.8, 0.2]}}\n"),
            "recipes/x.yaml: selection.tuples.pair_covisibility: expected [lo, hi] with 0 <= "
            "lo <= hi <= 1");
  EXPECT_EQ(
      ErrorOf(m + "selection: {views: [5, 3]}\n").rfind("recipes/x.yaml: selection.views:", 0), 0u);
  // 4·quota + 16 draws wrapped around in 32 bits: 536870908 gave 0 tuples, silently.
  for (const char* quota : {"536870908", "1000001", "2147483647"}) {
    EXPECT_EQ(ErrorOf(m + "selection: {views: 3, tuples: {quota_per_scene: " + quota + "}}\n"),
              "recipes/x.yaml: selection.tuples.quota_per_scene: expected an integer in [1, "
              "1000000]: tuples per scene")
        << quota;
  }
  EXPECT_EQ(ErrorOf(m + "selection: {views: 3, tuples: {quota_per_scene: 1000000}}\n"), "");
}

TEST(Recipe, KeysThatWouldBeIgnoredAreRefused) {
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "  device: iphone\n"),
            "recipes/x.yaml: dataset.device: expected only with format scannetpp (ScanNet++'s "
            "camera), not sevenscenes");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "  synthetic: {scenes: 3}\n"),
            "recipes/x.yaml: dataset.synthetic: expected only with format synthetic, not "
            "sevenscenes");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "loftr_export: {kind: test, score: covisible}\n"),
            "recipes/x.yaml: loftr_export.score: expected only with kind train or megadepth "
            "(LoFTR's test index has no score)");
  EXPECT_EQ(ParseRecipe("name: a\ndataset: {format: scannetpp, root: r, device: iphone}\n",
                        "x.yaml", "/b")
                .dataset.device,
            datasets::ScanNetPPDevice::kIphone);
  EXPECT_EQ(
      ParseRecipe(std::string(kMinimal) + "sample: {depth: true}\nloftr_export: {kind: test}\n",
                  "x.yaml", "/b")
          .loftr_export,
      LoftrExportKind::kTest);
}

// dataset.tum_max_dt_s: tum only, a finite number >= 0, in recipe.json and the digest only
// when given (the digest of recipes without it is unchanged).
TEST(Recipe, TumToleranceKey) {
  const Recipe plain = ParseRecipe("name: t\ndataset: {format: tum, root: x}\n", "t.yaml", "/b");
  const Recipe wide =
      ParseRecipe("name: t\ndataset: {format: tum, root: x, tum_max_dt_s: 0.05}\n", "t.yaml", "/b");
  EXPECT_FALSE(plain.dataset.tum_max_dt_s.has_value());
  EXPECT_FALSE(plain.ToJson()["dataset"].contains("tum_max_dt_s"));
  EXPECT_DOUBLE_EQ(*wide.dataset.tum_max_dt_s, 0.05);
  EXPECT_DOUBLE_EQ(wide.ToJson()["dataset"]["tum_max_dt_s"].get<double>(), 0.05);
  EXPECT_NE(plain.Digest(), wide.Digest());
  EXPECT_EQ(ErrorOf("name: t\ndataset: {format: generic, root: x, tum_max_dt_s: 0.05}\n"),
            "recipes/x.yaml: dataset.tum_max_dt_s: expected only with format tum (TUM's time "
            "association), not generic");
  EXPECT_NE(ErrorOf("name: t\ndataset: {format: tum, root: x, tum_max_dt_s: -1}\n"), "");
}

// two_point fuses nothing: a wider scope would be recorded in recipe.json and not applied.
TEST(Recipe, TwoPointWithAWiderScopeIsRefused) {
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: generic, root: x}\n"
                    "occupancy: {enabled: true, mode: two_point, scope: window}\n"),
            "recipes/x.yaml: occupancy: scope window:2 fuses frames for mode octomap only (mode "
            "two_point uses the pair's depth alone): use scope pair");
}

TEST(Recipe, MissingDatasetAndFormat) {
  EXPECT_EQ(ErrorOf("name: a\n"), "recipes/x.yaml: dataset: missing (required)");
  EXPECT_EQ(ErrorOf("name: a\ndataset: {root: x}\n"),
            "recipes/x.yaml: dataset.format: missing (required)");
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: scannet}\n"),
            "recipes/x.yaml: dataset.root: expected a folder path");
  EXPECT_EQ(ErrorOf("- a\n- b\n"),
            "recipes/x.yaml: (top level): expected a mapping of recipe keys");
  EXPECT_NE(ErrorOf("name: [unclosed\n").find("recipes/x.yaml: invalid YAML"), std::string::npos);
}

TEST(Recipe, LoadFailsBeforeWorkWhenDatasetRootIsMissing) {
  const std::string dir = test::ScratchDir("recipe_missing_root");
  const std::string path = dir + "/r.yaml";
  io::WriteFileAtomic(path, "name: r\ndataset: {format: sevenscenes, root: nowhere}\n");
  try {
    LoadRecipe(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find(path + ": dataset.root: expected an existing folder"), 0u)
        << e.what();
  }
  EXPECT_THROW(LoadRecipe(dir + "/absent.yaml"), InputError);
  // The same from --root names the flag (a usage error), not the recipe's dataset.root.
  RecipeOverrides overrides;
  overrides.root = dir + "/elsewhere";
  try {
    LoadRecipe(path, overrides);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--root: expected an existing folder, not found: " + dir + "/elsewhere");
  }
}

TEST(Recipe, LoadFailsBeforeWorkWhenAFixedMeshPathIsMissing) {
  const std::string dir = test::ScratchDir("recipe_missing_mesh");
  fs::create_directories(dir + "/data");
  const std::string path = dir + "/r.yaml";
  io::WriteFileAtomic(path, "name: r\ndataset: {format: generic, root: data, mesh_path: m.ply}\n");
  try {
    LoadRecipe(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(
        std::string(e.what()),
        path + ": dataset.mesh_path: expected an existing file, not found: " + dir + "/m.ply");
  }
  // Once the file is there, the recipe loads; a path with {scene} is checked per scene.
  io::WriteFileAtomic(dir + "/m.ply", "ply\n");
  EXPECT_EQ(LoadRecipe(path).dataset.mesh_path, dir + "/m.ply");
  io::WriteFileAtomic(
      path, "name: r\ndataset: {format: generic, root: data, mesh_path: '{scene}.ply'}\n");
  EXPECT_EQ(LoadRecipe(path).dataset.mesh_path, dir + "/{scene}.ply");
}

TEST(Recipe, EnvironmentExpansionAndRootOverride) {
  ::setenv("OCCGT_TEST_ROOT_VAR", "/from/env", 1);
  EXPECT_EQ(ExpandEnv("${OCCGT_TEST_ROOT_VAR}/x", "f"), "/from/env/x");
  EXPECT_EQ(ExpandEnv("${OCCGT_TEST_UNSET_VAR:-../fallback}/x", "f"), "../fallback/x");
  EXPECT_THROW(ExpandEnv("${OCCGT_TEST_UNSET_VAR}/x", "f"), InputError);
  EXPECT_THROW(ExpandEnv("${OCCGT_TEST_ROOT_VAR", "f"), InputError);
  Recipe r =
      ParseRecipe("name: e\ndataset: {format: generic, root: \"${OCCGT_TEST_ROOT_VAR}/d\"}\n",
                  "e.yaml", "/base");
  EXPECT_EQ(r.dataset.root, "/from/env/d");
  RecipeOverrides o;
  o.root = "/override/root";
  EXPECT_EQ(ParseRecipe(kMinimal, "x.yaml", "/base", o).dataset.root, "/override/root");
  try {
    ParseRecipe("name: e\ndataset: {format: generic, root: \"${OCCGT_TEST_UNSET_VAR}/d\"}\n",
                "e.yaml", "/base");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("e.yaml: dataset.root: environment variable"), 0u)
        << e.what();
  }
}

TEST(Recipe, DigestIgnoresPathsButNotOptions) {
  Recipe a = ParseRecipe(kMinimal, "x.yaml", "/one");
  Recipe b = ParseRecipe(kMinimal, "x.yaml", "/two");
  EXPECT_EQ(a.Digest(), b.Digest());
  Recipe c = ParseRecipe(std::string(kMinimal) + "seed: 1\n", "x.yaml", "/one");
  EXPECT_NE(a.Digest(), c.Digest());
}

TEST(Recipe, YamlScalarsAreTypedLikeYaml12Core) {
  nlohmann::json j =
      YamlToJson("a: 1\nb: 1.5\nc: true\nd: ~\ne: '2'\nf: 1e3\ng: abc\nh: -4\n", "t");
  EXPECT_TRUE(j["a"].is_number_integer());
  EXPECT_TRUE(j["b"].is_number_float());
  EXPECT_TRUE(j["c"].is_boolean());
  EXPECT_TRUE(j["d"].is_null());
  EXPECT_TRUE(j["e"].is_string());
  EXPECT_DOUBLE_EQ(j["f"].get<double>(), 1000.0);
  EXPECT_TRUE(j["g"].is_string());
  EXPECT_EQ(j["h"].get<int>(), -4);
  EXPECT_THROW(YamlToJson("a: 1\na: 2\n", "t"), InputError);
}

// Every recipe shipped in recipes/ passes the schema and Check.
TEST(Recipe, ShippedRecipesParse) {
  const fs::path dir = fs::path(OCCGT_SOURCE_DIR) / "recipes";
  ASSERT_TRUE(fs::is_directory(dir));
  int n = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    ++n;
    SCOPED_TRACE(entry.path().string());
    ::setenv("OCCGT_SHARED_DATA", OCCGT_SHARED_DATA, 1);
    EXPECT_NO_THROW(
        ParseRecipe(io::ReadFileBytes(entry.path().string()), entry.path().string(), dir.string()));
  }
  EXPECT_GE(n, 6);
}

// Dotted key paths of the schema ("selection.pruning.frustum").
void SchemaKeys(const nlohmann::json& node, const nlohmann::json& root, const std::string& prefix,
                std::set<std::string>* out) {
  const nlohmann::json* n = &node;
  if (n->contains("$ref")) {
    n = &root.at(nlohmann::json::json_pointer((*n)["$ref"].get<std::string>().substr(1)));
  }
  if (!n->contains("properties")) return;
  for (const auto& [k, v] : (*n)["properties"].items()) {
    const std::string key = prefix.empty() ? k : prefix + "." + k;
    out->insert(key);
    SchemaKeys(v, root, key, out);
  }
}

TEST(Recipe, DocsListExactlyTheSchemaKeys) {
  const nlohmann::json schema = nlohmann::json::parse(RecipeSchemaText());
  std::set<std::string> keys;
  SchemaKeys(schema, schema, "", &keys);
  // The reference table rows of docs/RECIPES.md start with "| `key.path` |".
  const std::string doc = io::ReadFileBytes(std::string(OCCGT_SOURCE_DIR) + "/docs/RECIPES.md");
  std::set<std::string> documented;
  std::regex row(R"(\n\| `([a-z0-9_.]+)` \|)");
  for (auto it = std::sregex_iterator(doc.begin(), doc.end(), row); it != std::sregex_iterator();
       ++it) {
    documented.insert((*it)[1].str());
  }
  for (const auto& k : keys) EXPECT_TRUE(documented.count(k)) << "undocumented key " << k;
  for (const auto& k : documented)
    EXPECT_TRUE(keys.count(k)) << "documented but not in schema " << k;
  // The file on disk is the schema the binary embeds.
  EXPECT_EQ(io::ReadFileBytes(std::string(OCCGT_SOURCE_DIR) + "/schemas/recipe.schema.json"),
            RecipeSchemaText());
}

// The shipped ScanNet v2 train list: 1201 distinct scene names, none of the test scenes
// (0707-0806) that test-1500 uses.
TEST(Recipe, ScanNetTrainSplitIsTheOfficialList) {
  const auto lines =
      io::ReadLines(std::string(OCCGT_SOURCE_DIR) + "/recipes/splits/scannetv2_train.txt");
  std::set<std::string> names(lines.begin(), lines.end());
  EXPECT_EQ(lines.size(), 1201u);
  EXPECT_EQ(names.size(), 1201u);
  const std::regex pattern(R"(scene(\d{4})_(\d{2}))");
  std::set<int> scans;
  for (const auto& n : names) {
    std::smatch m;
    ASSERT_TRUE(std::regex_match(n, m, pattern)) << n;
    const int scan = std::stoi(m[1].str());
    EXPECT_LT(scan, 707) << n;
    scans.insert(scan);
  }
  EXPECT_GT(scans.size(), 500u);  // every train scan, several with re-scans _01, _02
}

// Regressions found by tests/fuzz/recipe_fuzz.cc (docs/RELIABILITY.md): each used to
// escape as a non-InputError exception, hang, or load a wrong value silently.
TEST(Recipe, FuzzFoundSequenceAsKeyIsInputError) {
  // yaml-cpp's BadConversion from kv.first.as<std::string>() escaped.
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic}\n[1, 2]: 3\n"),
            "recipes/x.yaml: line 3: expected a plain key, found a sequence or mapping");
}

TEST(Recipe, FuzzFoundInvalidUtf8IsInputError) {
  // nlohmann::json::dump() (the options digest) threw type_error 316 on a scene name
  // with a Latin-1 byte.
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic, scenes: [gascola/E\xd2sy]}\n"),
            "recipes/x.yaml: line 2: text is not valid UTF-8");
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic}\n\xff: 1\n"),
            "recipes/x.yaml: line 3: key is not valid UTF-8");
  // Valid multi-byte text is fine (it fails later, on the scene name pattern or not at all).
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic, scenes: [\xc3\xa9t\xc3\xa9]}\n"), "");
}

TEST(Recipe, FuzzFoundAliasExpansionIsBounded) {
  // Ten anchors of ten aliases each stand for 10^7 nodes: the conversion used to run for
  // minutes; now it stops at the node limit.
  std::string yaml =
      "name: a\ndataset: {format: synthetic}\nx:\n  a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 7; ++i) {
    yaml += "  a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 10; ++k) yaml += (k ? ", *a" : "*a") + std::to_string(i - 1);
    yaml += "]\n";
  }
  EXPECT_EQ(ErrorOf(yaml), "recipes/x.yaml: more than 100000 YAML nodes (after expanding aliases)");
  std::string deep = "name: a\ndataset: {format: synthetic}\nx: ";
  for (int i = 0; i < 100; ++i) deep += "[";
  for (int i = 0; i < 100; ++i) deep += "]";
  EXPECT_NE(ErrorOf(deep + "\n").find("nested deeper than 64 levels"), std::string::npos);
}

TEST(Recipe, FuzzFoundIntegersMustFitTheirField) {
  // get<int>() truncated 4294967297 to 1, which then passed every check.
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic, frame_stride: 4294967297}\n"),
            "recipes/x.yaml: dataset.frame_stride: expected an integer <= 2147483647, got "
            "4294967297");
  EXPECT_EQ(ErrorOf("name: a\ndataset: {format: synthetic}\nshards: {samples_per_shard: 3e9}\n")
                .rfind("recipes/x.yaml: ", 0),
            0u);
  const Recipe r = ParseRecipe(
      "name: a\nseed: 9223372036854775807\ndataset: {format: synthetic, frame_stride: 3}\n",
      "x.yaml", "/b");
  EXPECT_EQ(r.seed, 9223372036854775807u);
  EXPECT_EQ(r.dataset.frame_stride, 3);
}

}  // namespace
}  // namespace gt::pipeline

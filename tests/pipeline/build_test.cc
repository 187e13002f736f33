// The build job with the real shard writer: the same bytes (shards, pairs.jsonl) whatever
// the thread count and task split; re-runs reuse selections and skip complete shards; errors
// mid-pipeline publish nothing later; a key collision after sanitising is an error naming
// both scenes; a dry run writes nothing; counts in the summary add up.
#include "libgt/pipeline/build.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "libgt/pipeline/select.h"
#include "libgt/pipeline/synthetic.h"
#include "libgt/pipeline/write.h"
#include "libgt/shards/split.h"
#include "libgt/shards/tar_shard.h"
#include "tests/support/test_support.h"

namespace gt::pipeline {
namespace {

namespace fs = std::filesystem;

// A split as written on disk by RunBuild (the real shard writer).
struct Written {
  std::vector<int64_t> plan;                              // shard sizes (parts/<split>.plan.json)
  std::map<int64_t, std::vector<shards::Sample>> shards;  // complete shards only
  std::string bytes;     // every complete shard's tar bytes in order, then pairs.jsonl
  bool indexed = false;  // index.json published
};

Written Read(const std::string& dir, const std::string& split = "small") {
  Written w;
  if (io::FileExists(shards::PlanPath(dir, split))) {
    w.plan = shards::ReadPlan(dir, split).shard_nsamples;
  }
  for (int64_t s = 0; s < static_cast<int64_t>(w.plan.size()); ++s) {
    if (!shards::IsShardComplete(dir, split, s)) continue;
    const std::string path = shards::ShardPath(dir, split, s);
    w.shards[s] = shards::ReadShardSamples(path);
    w.bytes += io::ReadFileBytes(path);
  }
  w.indexed = io::FileExists(dir + "/index.json");
  if (w.indexed) w.bytes += io::ReadFileBytes(dir + "/pairs.jsonl");
  return w;
}

Recipe SmallRecipe(const std::string& data_root) {
  const std::string yaml = R"(
name: small
split: small
resolution: [64, 48]
dataset:
  format: generic
  root: )" + data_root + R"(
  min_valid_depth_fraction: 0.2
selection:
  max_frame_gap: 3
  score_stride: 2
  overlap: [0.2, 1.0]
  quota_per_scene: 5
occupancy: {voxel_m: 0.1, far_m: 8.0}
sample: {image: png, depth: true}
shards: {samples_per_shard: 3}
)";
  return ParseRecipe(yaml, "small.yaml", "/");
}

// A synthetic dataset shared by the tests of this file (generated once).
std::string Dataset() {
  static const std::string root = [] {
    const std::string dir = test::ScratchDir("pipeline_data");
    SyntheticDatasetOptions o;
    o.scenes = 2;
    o.frames = 10;
    o.width = 64;
    o.height = 48;
    EnsureSyntheticDataset(dir, o);
    return dir;
  }();
  return root;
}

TEST(Pipeline, SameSamplesOnAnyThreadCountAndTaskSplit) {
  const Recipe r = SmallRecipe(Dataset());
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_one");
  nlohmann::json summary;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    summary = RunBuild(r, o, nullptr);
  }
  ASSERT_TRUE(summary["complete"].get<bool>());
  const Written one = Read(o.out_dir);
  EXPECT_TRUE(one.indexed);
  // Quota 5 per scene; the plan is the equal cut of the samples into shards of 3.
  const int64_t n = summary["samples"].get<int64_t>();
  int64_t per_scene_total = 0;
  for (const auto& [scene, k] : summary["pairs_per_scene"].items()) {
    EXPECT_LE(k.get<int64_t>(), 5) << scene;
    EXPECT_GE(k.get<int64_t>(), 1) << scene;
    per_scene_total += k.get<int64_t>();
  }
  EXPECT_EQ(per_scene_total, n);
  ASSERT_GE(n, 4);  // at least two shards, so that the task split below means something
  std::vector<int64_t> plan;
  for (int64_t left = n; left > 0; left -= 3) plan.push_back(std::min<int64_t>(3, left));
  EXPECT_EQ(one.plan, plan);
  int64_t stored = 0;
  for (const auto& [shard, samples] : one.shards) stored += static_cast<int64_t>(samples.size());
  EXPECT_EQ(stored, n);
  const auto& c = summary["counts"];
  int64_t scan = 0, prune = 0, later = 0;
  for (const auto& [k, v] : summary["drops"].items()) {
    if (k.rfind("scan.", 0) == 0) scan += v.get<int64_t>();
    if (k.rfind("prune.", 0) == 0) prune += v.get<int64_t>();
    if (k.rfind("filter.", 0) == 0 || k.rfind("sample.", 0) == 0) later += v.get<int64_t>();
  }
  EXPECT_EQ(c["frames_total"].get<int64_t>(), c["frames_kept"].get<int64_t>() + scan);
  EXPECT_EQ(c["candidates"].get<int64_t>(), c["after_pruning"].get<int64_t>() + prune);
  EXPECT_EQ(c["scored"].get<int64_t>(), c["selected"].get<int64_t>() + later);

  // Two threads, three tasks (select for all, then write for all), into another folder.
  BuildOptions t;
  t.out_dir = test::ScratchDir("pipeline_tasks");
  t.tasks = 3;
  int64_t shards_written = 0;
  for (const Stage stage : {Stage::kSelect, Stage::kWrite}) {
    for (int k = 2; k >= 0; --k) {
      t.task = k;
      t.stage = stage;
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      shards_written += RunBuild(r, t, nullptr).value("shards_written_this_run", int64_t{0});
    }
  }
  const Written split = Read(t.out_dir);
  EXPECT_EQ(one.bytes, split.bytes);
  EXPECT_EQ(shards_written, static_cast<int64_t>(plan.size()));
  EXPECT_TRUE(split.indexed);
}

// One sample per shard: the write pipeline has many shard ends in flight at once (more
// shards than tokens); 1 thread, 2 threads and 2 threads in 3 tasks give the same bytes,
// every shard written once, in plan order.
TEST(Pipeline, OneSampleShardsSameBytesOnOneAndTwoThreads) {
  Recipe r = SmallRecipe(Dataset());
  r.shards.samples_per_shard = 1;
  auto run = [&](int threads, int tasks, const std::string& name, int64_t* writes) {
    BuildOptions o;
    o.out_dir = test::ScratchDir(name);
    o.tasks = tasks;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    for (const Stage stage : tasks > 1 ? std::vector<Stage>{Stage::kSelect, Stage::kWrite}
                                       : std::vector<Stage>{Stage::kAll}) {
      o.stage = stage;
      for (int k = 0; k < tasks; ++k) {
        o.task = k;
        *writes += RunBuild(r, o, nullptr).value("shards_written_this_run", int64_t{0});
      }
    }
    return Read(o.out_dir);
  };
  int64_t w1 = 0, w2 = 0, w3 = 0;
  const Written one = run(1, 1, "pipeline_sps1_t1", &w1);
  const Written two = run(2, 1, "pipeline_sps1_t2", &w2);
  const Written tasks = run(2, 3, "pipeline_sps1_tasks", &w3);
  ASSERT_GE(one.plan.size(), 8u);
  EXPECT_EQ(w1, static_cast<int64_t>(one.plan.size()));
  EXPECT_EQ(w2, static_cast<int64_t>(one.plan.size()));
  EXPECT_EQ(w3, static_cast<int64_t>(one.plan.size()));
  for (const auto& [shard, samples] : two.shards) EXPECT_EQ(samples.size(), 1u) << shard;
  EXPECT_EQ(one.bytes, two.bytes);
  EXPECT_EQ(one.bytes, tasks.bytes);
}

// An InputError in a sample in the middle of the pipeline (a selected frame gone from the
// dataset) propagates from RunBuild; its shard and every later one are not written, and
// a re-run after the fix writes exactly the missing shards, byte for byte as one run.
// A failing shard write propagates the same way.
TEST(Pipeline, ErrorsMidPipelinePropagateAndWriteNoLaterShard) {
  const Recipe r = SmallRecipe(Dataset());
  Written good;
  {
    BuildOptions o;
    o.out_dir = test::ScratchDir("pipeline_err_good");
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    RunBuild(r, o, nullptr);
    good = Read(o.out_dir);
  }
  ASSERT_GE(good.plan.size(), 3u);
  // The selection of the first scene, then one of its pairs in shard 1 made stale.
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_err");
  o.stage = Stage::kSelect;
  RunBuild(r, o, nullptr);
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(o.out_dir + "/selection")) {
    if (e.path().extension() == ".jsonl") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty());
  std::vector<std::string> lines = io::ReadLines(files[0]);
  const size_t bad = 3;  // sample 3 = the first sample of shard 1 (shards of 3)
  ASSERT_GT(lines.size(), bad);
  const std::string original = io::ReadFileBytes(files[0]);
  nlohmann::json j = nlohmann::json::parse(lines[bad]);
  j["frame0"]["id"] = "no-such-frame";
  lines[bad] = j.dump();
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  io::WriteFileAtomic(files[0], text);
  o.stage = Stage::kAll;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    try {
      RunBuild(r, o, nullptr);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("no longer in the dataset"), std::string::npos)
          << e.what();
    }
  }
  Written out = Read(o.out_dir);
  EXPECT_LE(out.shards.size(), 1u);  // shard 0 at most (complete before the error)
  for (const auto& [shard, samples] : out.shards) EXPECT_EQ(shard, 0);
  EXPECT_FALSE(out.indexed);
  // A write error of shard 1 (the selection repaired): also propagates, nothing after. A
  // folder where the shard's temporary file goes makes its writer fail.
  io::WriteFileAtomic(files[0], original);
  const std::string blocker = shards::ShardPath(o.out_dir, "small", 1) + ".tmp";
  fs::create_directories(blocker);
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    try {
      RunBuild(r, o, nullptr);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(shards::ShardPath(o.out_dir, "small", 1)),
                std::string::npos)
          << e.what();
    }
  }
  out = Read(o.out_dir);
  EXPECT_FALSE(out.shards.count(1));
  for (const auto& [shard, samples] : out.shards) EXPECT_LT(shard, 1);
  EXPECT_FALSE(out.indexed);
  // The re-run completes the split: the same bytes as the run without errors.
  fs::remove_all(blocker);
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    const nlohmann::json s = RunBuild(r, o, nullptr);
    EXPECT_TRUE(s["complete"].get<bool>());
  }
  out = Read(o.out_dir);
  EXPECT_TRUE(out.indexed);
  EXPECT_EQ(out.bytes, good.bytes);
}

TEST(Pipeline, ReRunReusesSelectionAndSkipsCompleteShards) {
  const Recipe r = SmallRecipe(Dataset());
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_rerun");
  RunBuild(r, o, nullptr);
  const Written first = Read(o.out_dir);
  fs::remove(shards::PartRecordPath(o.out_dir, "small", 2));  // shard 2 not complete now
  nlohmann::json s = RunBuild(r, o, nullptr);
  EXPECT_EQ(s["shards_written_this_run"], 1);
  EXPECT_EQ(s["shards_skipped_complete"], static_cast<int64_t>(first.plan.size()) - 1);
  EXPECT_EQ(s["scenes_reused"], 2);
  EXPECT_EQ(Read(o.out_dir).bytes, first.bytes);
  // A re-run that has nothing to do writes nothing.
  s = RunBuild(r, o, nullptr);
  EXPECT_EQ(s["shards_written_this_run"], 0);
  EXPECT_EQ(s["bytes_written"], 0);
  // Another recipe (options digest) into the same folder is refused.
  Recipe other = r;
  other.seed = 99;
  EXPECT_THROW(RunBuild(other, o, nullptr), InputError);
}

// recipe.json, the scenes' selections and the plan are published before the first shard;
// an error publishing the plan is the build's error, and no shard is written after it.
TEST(Pipeline, MetadataIsPublishedBeforeTheFirstShardAndItsErrorsPropagate) {
  const Recipe r = SmallRecipe(Dataset());
  for (const int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    BuildOptions o;
    o.out_dir = test::ScratchDir("pipeline_metadata_" + std::to_string(threads));
    // Stop after the first shard: progress of the write stage fires once it is complete.
    bool metadata_before_first_shard = false;
    const nlohmann::json s = RunBuild(r, o, [&](const Progress& p) {
      if (p.stage != Stage::kWrite || metadata_before_first_shard) return;
      int selections = 0;
      for (const auto& e : fs::directory_iterator(o.out_dir + "/selection")) {
        selections += e.path().extension() == ".json";
      }
      metadata_before_first_shard = fs::exists(o.out_dir + "/recipe.json") && selections == 2 &&
                                    fs::exists(shards::PlanPath(o.out_dir, "small"));
    });
    EXPECT_TRUE(s["complete"].get<bool>());
    EXPECT_TRUE(metadata_before_first_shard) << threads << " threads";
    EXPECT_GT(s["bytes_written"].get<int64_t>(), 0);

    BuildOptions o2;
    o2.out_dir = test::ScratchDir("pipeline_plan_refused_" + std::to_string(threads));
    fs::create_directories(shards::PlanPath(o2.out_dir, "small"));  // a folder: not writable
    try {
      RunBuild(r, o2, nullptr);
      ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("plan.json"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(shards::ShardPath(o2.out_dir, "small", 0)));
  }
}

TEST(Pipeline, ShardPlanOfAHugeTargetHoldsEverySampleInOneShard) {
  Recipe r = SmallRecipe(Dataset());
  r.shards.target_mb = 1e300;  // legal (finite, >= 0); overflowed the int64 conversion
  EXPECT_EQ(PlanShards(r, 60), (std::vector<int64_t>{60}));
  EXPECT_EQ(PlanShards(r, 0), (std::vector<int64_t>{}));
  r.shards.target_mb = 1e-300;  // below one sample: one sample a shard
  EXPECT_EQ(PlanShards(r, 3), (std::vector<int64_t>{1, 1, 1}));
}

TEST(Pipeline, KeyCollisionIsAnErrorNamingBothScenes) {
  SelectedPair a, b;
  a.scene = "seq.01";
  b.scene = "seq_01";
  a.frame0 = b.frame0 = "000001";
  a.frame1 = b.frame1 = "000002";
  try {
    SampleKeys({&a, &b}, SampleCompression::kDeflate);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("same key after sanitising"), std::string::npos) << m;
    EXPECT_NE(m.find("seq.01"), std::string::npos) << m;
    EXPECT_NE(m.find("seq_01"), std::string::npos) << m;
  }
  // Frame ids joined by '_' collide too: both pairs are named with their frames.
  SelectedPair c = a, d = a;
  c.frame0 = "0_1";
  c.frame1 = "2";
  d.frame0 = "0";
  d.frame1 = "1_2";
  try {
    SampleKeys({&c, &d}, SampleCompression::kDeflate);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(scene seq.01, frames 0_1 and 2; scene seq.01, frames 0 "
                                         "and 1_2)"),
              std::string::npos)
        << e.what();
  }
  b.frame1 = "000003";
  EXPECT_EQ(SampleKeys({&a, &b}, SampleCompression::kDeflate),
            (std::vector<std::string>{"seq_01/000001_000002", "seq_01/000001_000003"}));
}

TEST(Pipeline, DryRunWritesNothing) {
  const Recipe r = SmallRecipe(Dataset());
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_dry") + "/out";
  o.dry_run = true;
  nlohmann::json s = RunBuild(r, o, nullptr);
  BuildOptions w;
  w.out_dir = test::ScratchDir("pipeline_dry_real");
  const nlohmann::json written = RunBuild(r, w, nullptr);
  EXPECT_EQ(s["samples"], written["samples"]);
  EXPECT_EQ(s["shards_planned"], written["shards_planned"]);
  EXPECT_EQ(s["drops"], written["drops"]);
  EXPECT_EQ(s["selected_overlap"], written["selected_overlap"]);
  EXPECT_FALSE(s["complete"].get<bool>());
  EXPECT_EQ(s["bytes_written"], 0);
  EXPECT_FALSE(fs::exists(o.out_dir));
}

TEST(Pipeline, SceneFileNamesAreSafeAndOptionsChecked) {
  EXPECT_EQ(SceneFileName("hospital/Easy/P036"), "hospital__Easy__P036");
  EXPECT_EQ(SceneFileName("seq.01 x"), "seq_01_x");
  EXPECT_EQ(SceneFileName("scene0707_00"), "scene0707_00");
  BuildOptions o;
  std::string error;
  EXPECT_FALSE(o.Check(&error));  // no --out
  o.out_dir = "x";
  EXPECT_TRUE(o.Check(&error));
  o.tasks = 2;
  o.task = 2;
  EXPECT_FALSE(o.Check(&error));
  o.task = 1;
  EXPECT_TRUE(o.Check(&error));
  o.depth_cache_mb = 0;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_EQ(ParseStage("write", "--stage"), Stage::kWrite);
  EXPECT_THROW(ParseStage("merge", "--stage"), InputError);
}

int64_t KnownBits(const Written& out) {
  int64_t bits = 0;
  for (const auto& [shard, samples] : out.shards) {
    for (const auto& x : samples) {
      for (const auto& [name, bytes] : x.fields) {
        if (name.rfind("known", 0) != 0) continue;
        const io::NpyArray a = io::ParseNpy(bytes, name);
        const uint64_t* w = a.As<uint64_t>(name);
        for (int64_t i = 0; i < a.NumElements(); ++i) bits += __builtin_popcountll(w[i]);
      }
    }
  }
  return bits;
}

// Occupancy scopes: a window around the pair and a scene map (fused once, reused by every
// pair) see more of the room than the pair alone; two_point marks few bins.
TEST(Pipeline, OccupancyScopesAndModes) {
  Recipe r = SmallRecipe(Dataset());
  using occupancy::FusionScope;
  using occupancy::OccupancyMode;
  auto run = [&](FusionScope scope, OccupancyMode mode, const std::string& name) {
    Recipe x = r;
    x.occupancy.settings.scope = scope;
    x.occupancy.settings.mode = mode;
    x.occupancy.settings.window = 2;
    x.occupancy.settings.scene_stride = 2;
    BuildOptions o;
    o.out_dir = test::ScratchDir("pipeline_scope_" + name);
    RunBuild(x, o, nullptr);
    return Read(o.out_dir);
  };
  const Written pair = run(FusionScope::kPair, OccupancyMode::kOctomap, "pair");
  const Written window = run(FusionScope::kWindow, OccupancyMode::kOctomap, "window");
  const Written scene = run(FusionScope::kScene, OccupancyMode::kOctomap, "scene");
  const Written two = run(FusionScope::kPair, OccupancyMode::kTwoPoint, "two");
  const int64_t k_pair = KnownBits(pair);
  EXPECT_GT(k_pair, 0);
  EXPECT_GE(KnownBits(window), k_pair);
  EXPECT_GT(KnownBits(scene), 0);
  EXPECT_NE(scene.bytes, pair.bytes);
  EXPECT_GT(KnownBits(two), 0);
  EXPECT_NE(two.bytes, pair.bytes);
}

// A recipe that stores images skips (and counts) frames without colour, and refuses a
// scene without any: nothing requested is silently dropped.
TEST(Pipeline, FramesWithoutColourAreCountedAndAColourlessSceneIsAnError) {
  const std::string real = test::SharedData("sevenscenes/rgbd-frames");
  ASSERT_FALSE(real.empty());
  auto copy = [&](const std::string& name, bool colour_of_151) {
    const std::string dir = test::ScratchDir(name);
    for (const char* id : {"000150", "000151", "000152"}) {
      const std::string base = std::string("/frame-") + id;
      for (const char* f : {".pose.txt", ".depth.png"}) {
        io::WriteFileAtomic(dir + "/seq-01" + base + f, io::ReadFileBytes(real + base + f));
      }
    }
    if (colour_of_151) {
      io::WriteFileAtomic(dir + "/seq-01/frame-000151.color.png",
                          io::ReadFileBytes(real + "/frame-000151.color.png"));
      io::WriteFileAtomic(dir + "/seq-01/frame-000152.color.png",
                          io::ReadFileBytes(real + "/frame-000152.color.png"));
    }
    return dir;
  };
  auto recipe = [](const std::string& root) {
    return ParseRecipe("name: c\nsplit: c\ndataset: {format: sevenscenes, root: " + root +
                           "}\nselection: {score_stride: 8}\noccupancy: {enabled: false}\n",
                       "c.yaml", "/");
  };
  BuildOptions o;
  o.dry_run = true;
  o.out_dir = test::ScratchDir("pipeline_colour_out") + "/out";
  const nlohmann::json s = RunBuild(recipe(copy("pipeline_colour_some", true)), o, nullptr);
  EXPECT_EQ(s["drops"].value("scan.no_color", 0), 1) << s["drops"].dump();  // frame 150
  EXPECT_EQ(s["counts"]["frames_kept"], 2);
  try {
    RunBuild(recipe(copy("pipeline_colour_none", false)), o, nullptr);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("c.yaml: sample.image"), std::string::npos) << m;
    EXPECT_NE(m.find("set sample.image: none"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace gt::pipeline

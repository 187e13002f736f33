// The build pipeline against an in-memory ShardOutput: the same samples (bytes) whatever
// the thread count and task split; re-runs reuse selections and skip complete shards; a
// key collision after sanitising fails before any shard is written; a dry run writes
// nothing; counts in the summary add up.
#include "libgt/pairs/pipeline.h"

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
#include "libgt/io/files.h"
#include "libgt/io/npy.h"
#include "libgt/pairs/synthetic.h"
#include "tests/support/test_support.h"

namespace gt::pairs {
namespace {

namespace fs = std::filesystem;

// Stores shards in memory; keys are "<scene>/<f0>_<f1>" (or one constant key on request).
class MemoryOutput : public ShardOutput {
 public:
  bool constant_key = false;
  int64_t fail_shard = -1;  // WriteShard of this shard throws InputError
  std::vector<int64_t> plan;
  std::map<int64_t, std::vector<EncodedSample>> shards;
  int64_t writes = 0;
  bool finished = false;
  // Guards shards and writes while RunBuild runs (shared: the tests copy outputs).
  std::shared_ptr<std::mutex> mutex = std::make_shared<std::mutex>();

  std::string SampleKey(const std::string& scene, const std::string& f0,
                        const std::string& f1) const override {
    return constant_key ? "same/key" : scene + "/" + f0 + "_" + f1;
  }
  void WritePlan(const std::vector<int64_t>& sizes) override { plan = sizes; }
  // WriteShard runs on RunBuild's writer thread, concurrently with IsShardComplete.
  bool IsShardComplete(int64_t s) const override {
    std::lock_guard<std::mutex> lock(*mutex);
    return shards.count(s) > 0;
  }
  int64_t WriteShard(int64_t s, const std::vector<EncodedSample>& samples) override {
    if (s == fail_shard) throw InputError("shard " + std::to_string(s), "disk full (test)");
    std::lock_guard<std::mutex> lock(*mutex);
    ++writes;
    shards[s] = samples;
    int64_t bytes = 0;
    for (const auto& x : samples) bytes += x.bytes;
    return bytes;
  }
  void Finish() override { finished = true; }
  void ExportLoftr(const std::string&, const std::vector<LoftrRow>&,
                   const std::map<std::string, std::array<double, 9>>&) override {}
};

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

std::string Bytes(const MemoryOutput& out) {
  std::string all;
  for (const auto& [s, samples] : out.shards) {
    for (const auto& x : samples) {
      all += x.key + "\n";
      for (const auto& [name, bytes] : x.fields) all += name + ":" + bytes;
      all += x.pair_line.dump();
    }
  }
  return all;
}

TEST(Pipeline, SameSamplesOnAnyThreadCountAndTaskSplit) {
  const Recipe r = SmallRecipe(Dataset());
  MemoryOutput one;
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_one");
  nlohmann::json summary;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    summary = RunBuild(r, o, &one, nullptr);
  }
  ASSERT_TRUE(summary["complete"].get<bool>());
  EXPECT_TRUE(one.finished);
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
  MemoryOutput split;
  BuildOptions t;
  t.out_dir = test::ScratchDir("pipeline_tasks");
  t.tasks = 3;
  for (const char* stage : {"select", "write"}) {
    for (int k = 2; k >= 0; --k) {
      t.task = k;
      t.stage = stage;
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
      RunBuild(r, t, &split, nullptr);
    }
  }
  EXPECT_EQ(Bytes(one), Bytes(split));
  EXPECT_EQ(split.writes, static_cast<int64_t>(plan.size()));
  EXPECT_TRUE(split.finished);
}

// One sample per shard: the write pipeline has many shard ends in flight at once (more
// shards than tokens); 1 thread, 2 threads and 2 threads in 3 tasks give the same bytes,
// every shard written once, in plan order.
TEST(Pipeline, OneSampleShardsSameBytesOnOneAndTwoThreads) {
  Recipe r = SmallRecipe(Dataset());
  r.shards.samples_per_shard = 1;
  auto run = [&](int threads, int tasks, const std::string& name) {
    MemoryOutput out;
    BuildOptions o;
    o.out_dir = test::ScratchDir(name);
    o.tasks = tasks;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    for (const char* stage : tasks > 1 ? std::vector<const char*>{"select", "write"}
                                       : std::vector<const char*>{"all"}) {
      o.stage = stage;
      for (int k = 0; k < tasks; ++k) {
        o.task = k;
        RunBuild(r, o, &out, nullptr);
      }
    }
    return out;
  };
  const MemoryOutput one = run(1, 1, "pipeline_sps1_t1");
  const MemoryOutput two = run(2, 1, "pipeline_sps1_t2");
  const MemoryOutput tasks = run(2, 3, "pipeline_sps1_tasks");
  ASSERT_GE(one.plan.size(), 8u);
  EXPECT_EQ(one.writes, static_cast<int64_t>(one.plan.size()));
  EXPECT_EQ(two.writes, static_cast<int64_t>(one.plan.size()));
  EXPECT_EQ(tasks.writes, static_cast<int64_t>(one.plan.size()));
  for (const auto& [shard, samples] : two.shards) EXPECT_EQ(samples.size(), 1u) << shard;
  EXPECT_EQ(Bytes(one), Bytes(two));
  EXPECT_EQ(Bytes(one), Bytes(tasks));
}

// An InputError in a sample in the middle of the pipeline (a selected frame gone from the
// dataset) propagates from RunBuild; its shard and every later one are not written, and
// a re-run after the fix writes exactly the missing shards, byte for byte as one run.
// A failing shard write propagates the same way.
TEST(Pipeline, ErrorsMidPipelinePropagateAndWriteNoLaterShard) {
  const Recipe r = SmallRecipe(Dataset());
  MemoryOutput good;
  {
    BuildOptions o;
    o.out_dir = test::ScratchDir("pipeline_err_good");
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    RunBuild(r, o, &good, nullptr);
  }
  ASSERT_GE(good.plan.size(), 3u);
  // The selection of the first scene, then one of its pairs in shard 1 made stale.
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_err");
  MemoryOutput out;
  o.stage = "select";
  RunBuild(r, o, &out, nullptr);
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
  j["frame0"] = "no-such-frame";
  lines[bad] = j.dump();
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  io::WriteFileAtomic(files[0], text);
  o.stage = "all";
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    try {
      RunBuild(r, o, &out, nullptr);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("no longer in the dataset"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_LE(out.shards.size(), 1u);  // shard 0 at most (complete before the error)
  for (const auto& [shard, samples] : out.shards) EXPECT_EQ(shard, 0);
  EXPECT_FALSE(out.finished);
  // A write error of shard 1 (the selection repaired): also propagates, nothing after.
  io::WriteFileAtomic(files[0], original);
  out.fail_shard = 1;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    try {
      RunBuild(r, o, &out, nullptr);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("disk full (test)"), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(out.shards.count(1));
  EXPECT_FALSE(out.finished);
  // The re-run completes the split: the same bytes as the run without errors.
  out.fail_shard = -1;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    const nlohmann::json s = RunBuild(r, o, &out, nullptr);
    EXPECT_TRUE(s["complete"].get<bool>());
  }
  EXPECT_TRUE(out.finished);
  EXPECT_EQ(Bytes(out), Bytes(good));
}

TEST(Pipeline, ReRunReusesSelectionAndSkipsCompleteShards) {
  const Recipe r = SmallRecipe(Dataset());
  MemoryOutput out;
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_rerun");
  RunBuild(r, o, &out, nullptr);
  const std::string first = Bytes(out);
  out.shards.erase(2);
  const int64_t writes = out.writes;
  nlohmann::json s = RunBuild(r, o, &out, nullptr);
  EXPECT_EQ(out.writes, writes + 1);
  EXPECT_EQ(s["shards_written_this_run"], 1);
  EXPECT_EQ(s["shards_skipped_complete"], static_cast<int64_t>(out.plan.size()) - 1);
  EXPECT_EQ(s["scenes_reused"], 2);
  EXPECT_EQ(Bytes(out), first);
  // Another recipe (options digest) into the same folder is refused.
  Recipe other = r;
  other.seed = 99;
  EXPECT_THROW(RunBuild(other, o, &out, nullptr), InputError);
}

// recipe.json, the scenes' selections and the plan are published on a background thread
// (pipeline.cc, OrderedPublisher) but always before the first shard; an error of one of
// them is the build's error, and no shard is written after it.
class CheckingOutput : public MemoryOutput {
 public:
  std::string dir;
  bool refuse_plan = false;
  bool metadata_before_first_shard = false;
  void WritePlan(const std::vector<int64_t>& sizes) override {
    if (refuse_plan) throw InputError("plan", "refused (test)");
    MemoryOutput::WritePlan(sizes);
  }
  int64_t WriteShard(int64_t s, const std::vector<EncodedSample>& samples) override {
    {
      std::lock_guard<std::mutex> lock(*mutex);
      if (writes == 0) {
        int selections = 0;
        for (const auto& e : fs::directory_iterator(dir + "/selection")) {
          selections += e.path().extension() == ".json";
        }
        metadata_before_first_shard =
            fs::exists(dir + "/recipe.json") && selections == 2 && !plan.empty();
      }
    }
    return MemoryOutput::WriteShard(s, samples);
  }
};

TEST(Pipeline, MetadataIsPublishedBeforeTheFirstShardAndItsErrorsPropagate) {
  const Recipe r = SmallRecipe(Dataset());
  for (const int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    CheckingOutput out;
    BuildOptions o;
    o.out_dir = out.dir = test::ScratchDir("pipeline_metadata_" + std::to_string(threads));
    const nlohmann::json s = RunBuild(r, o, &out, nullptr);
    EXPECT_TRUE(s["complete"].get<bool>());
    EXPECT_TRUE(out.metadata_before_first_shard) << threads << " threads";
    EXPECT_GT(s["bytes_written"].get<int64_t>(), 0);

    CheckingOutput refused;
    refused.refuse_plan = true;
    BuildOptions o2;
    o2.out_dir = refused.dir = test::ScratchDir("pipeline_plan_refused_" + std::to_string(threads));
    try {
      RunBuild(r, o2, &refused, nullptr);
      ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("refused (test)"), std::string::npos) << e.what();
    }
    EXPECT_EQ(refused.writes, 0);
    EXPECT_TRUE(refused.shards.empty());
  }
}

TEST(Pipeline, KeyCollisionFailsBeforeAnyShard) {
  const Recipe r = SmallRecipe(Dataset());
  MemoryOutput out;
  out.constant_key = true;
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_collision");
  try {
    RunBuild(r, o, &out, nullptr);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("same key after sanitising"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(out.writes, 0);
  EXPECT_TRUE(out.plan.empty());
}

TEST(Pipeline, DryRunWritesNothing) {
  const Recipe r = SmallRecipe(Dataset());
  MemoryOutput out;
  BuildOptions o;
  o.out_dir = test::ScratchDir("pipeline_dry") + "/out";
  o.dry_run = true;
  nlohmann::json s = RunBuild(r, o, &out, nullptr);
  MemoryOutput real;
  BuildOptions w;
  w.out_dir = test::ScratchDir("pipeline_dry_real");
  const nlohmann::json written = RunBuild(r, w, &real, nullptr);
  EXPECT_EQ(s["samples"], written["samples"]);
  EXPECT_EQ(s["shards_planned"], written["shards_planned"]);
  EXPECT_EQ(s["drops"], written["drops"]);
  EXPECT_EQ(s["selected_overlap"], written["selected_overlap"]);
  EXPECT_FALSE(s["complete"].get<bool>());
  EXPECT_EQ(out.writes, 0);
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
  o.stage = "merge";
  EXPECT_FALSE(o.Check(&error));
}

int64_t KnownBits(const MemoryOutput& out) {
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
  auto run = [&](const std::string& scope, const std::string& mode, const std::string& name) {
    Recipe x = r;
    x.occupancy.scope = scope;
    x.occupancy.mode = mode;
    x.occupancy.window = 2;
    x.occupancy.scene_stride = 2;
    MemoryOutput out;
    BuildOptions o;
    o.out_dir = test::ScratchDir("pipeline_scope_" + name);
    RunBuild(x, o, &out, nullptr);
    return out;
  };
  const MemoryOutput pair = run("pair", "octomap", "pair");
  const MemoryOutput window = run("window", "octomap", "window");
  const MemoryOutput scene = run("scene", "octomap", "scene");
  const MemoryOutput two = run("pair", "two_point", "two");
  const int64_t k_pair = KnownBits(pair);
  EXPECT_GT(k_pair, 0);
  EXPECT_GE(KnownBits(window), k_pair);
  EXPECT_GT(KnownBits(scene), 0);
  EXPECT_NE(Bytes(scene), Bytes(pair));
  EXPECT_GT(KnownBits(two), 0);
  EXPECT_NE(Bytes(two), Bytes(pair));
}

}  // namespace
}  // namespace gt::pairs

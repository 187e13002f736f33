// Split layout: part records, merge (index.json, pairs.jsonl) and validate, including the
// failures they must catch (missing / corrupt shards and part records), through the
// library and through `occgt merge` / `occgt validate`.
//
// With OCCGT_SHARDS_DEMO_OUT=<dir> set, ShardsDemo.WriteDemoSplit writes a small split
// with the field set of `occgt build` to <dir> and merges it with the occgt binary; the
// Python integration test tests/integration/shards_test.py reads that folder.
#include "libgt/shards/split.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/md5.h"
#include "libgt/io/npy.h"
#include "libgt/shards/loftr_export.h"
#include "tests/support/test_support.h"

namespace gt::shards {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The four sample and line schemas a --schemas folder holds beside index.schema.json.
const char* const kSampleSchemas[] = {"sample.schema.json", "views_sample.schema.json",
                                      "pairs_line.schema.json", "views_line.schema.json"};

// A schemas folder with schemas/index.schema.json and sample / line schemas that accept any
// document: the demo samples here are not `occgt build` samples, so the pipeline's schemas
// of them do not apply (their checking is tested with a schema of this test below).
std::string SchemasDir() {
  static const std::string dir = [] {
    const std::string d = test::ScratchDir("shards_schemas_index_only");
    fs::copy_file(std::string(OCCGT_SOURCE_DIR) + "/schemas/index.schema.json",
                  d + "/index.schema.json");
    for (const char* name : kSampleSchemas) io::WriteFileAtomic(d + "/" + name, "{}\n");
    return d;
  }();
  return dir;
}

// Every schema accepts any document: the structural checks alone.
std::string PermissiveSchemasDir() {
  static const std::string dir = [] {
    const std::string d = test::ScratchDir("shards_schemas_permissive");
    io::WriteFileAtomic(d + "/index.schema.json", "{}\n");
    for (const char* name : kSampleSchemas) io::WriteFileAtomic(d + "/" + name, "{}\n");
    return d;
  }();
  return dir;
}

// A sample like the ones `occgt build` writes (small arrays).
Sample PairSample(const std::string& scene, int f0, int f1, std::mt19937* rng, int w = 16,
                  int h = 12, const std::string& digest = "") {
  Sample s;
  s.key = MakeSampleKey(scene, std::to_string(f0), std::to_string(f1));
  json meta;
  if (!digest.empty()) {
    meta["key"] = s.key;
    meta["options_digest"] = digest;
  }
  meta["scene"] = scene;
  meta["frame0"] = f0;
  meta["frame1"] = f1;
  s.fields.push_back({"json", meta.dump()});
  std::vector<uint8_t> label(static_cast<size_t>(w * h));
  for (auto& v : label) v = static_cast<uint8_t>((*rng)() % 6);
  s.fields.push_back({"label01.npy", io::EncodeNpy<uint8_t>({h, w}, label)});
  for (auto& v : label) v = static_cast<uint8_t>((*rng)() % 6);
  s.fields.push_back({"label10.npy", io::EncodeNpy<uint8_t>({h, w}, label)});
  std::vector<int32_t> matches(static_cast<size_t>(5 * 2));
  for (auto& v : matches) v = static_cast<int32_t>((*rng)() % 48);
  s.fields.push_back({"matches.npy", io::EncodeNpy<int32_t>({5, 2}, matches)});
  std::vector<float> depth(static_cast<size_t>(w * h));
  for (auto& v : depth) v = 0.5f + static_cast<float>((*rng)() % 400) / 100.0f;
  s.fields.push_back({"depth0.npy", io::EncodeNpy<float>({h, w}, depth)});
  cv::Mat image(h, w, CV_8UC3);
  for (int i = 0; i < h * w * 3; ++i) image.data[i] = static_cast<uint8_t>((*rng)() % 256);
  std::vector<uint8_t> png;
  cv::imencode(".png", image, png);
  s.fields.push_back({"image0.png", std::string(png.begin(), png.end())});
  return s;
}

// Validation of the splits of this file, whose samples are not `occgt build`'s: the structure
// only (a pair sample's value checks are tested in sample_check_test.cc and with real builds).
ValidateOptions StructureOnly(const std::string& schemas_dir) {
  ValidateOptions o;
  o.schemas_dir = schemas_dir;
  o.values = false;
  return o;
}

std::string PairLine(const std::string& scene, int f0, int f1, double overlap) {
  json line;
  line["scene"] = scene;
  line["frame0"] = f0;
  line["frame1"] = f1;
  line["overlap_01"] = overlap;
  return line.dump();
}

struct DemoPair {
  std::string scene;
  int f0, f1;
};
std::vector<DemoPair> DemoPairs() {
  std::vector<DemoPair> pairs;
  for (int k = 0; k < 7; ++k) pairs.push_back({"scene0707_00", 15 * k, 15 * k + 300});
  for (int k = 0; k < 4; ++k) pairs.push_back({"hospital/Easy/P036", k, k + 10});
  return pairs;
}

// Writes a 3-shard split (4 + 4 + 3 samples; 11 shards with samples_per_shard 1) with plan
// and part records.
void WriteSplit(const std::string& dir, const std::string& split = "train",
                int64_t samples_per_shard = 4, const std::string& digest = "") {
  const auto pairs = DemoPairs();
  const SplitPlan plan =
      PlanEqualShards(split, static_cast<int64_t>(pairs.size()), samples_per_shard);
  WritePlan(dir, plan);
  std::mt19937 rng(5);
  size_t next = 0;
  for (size_t s = 0; s < plan.shard_nsamples.size(); ++s) {
    SplitShardWriter writer(dir, split, static_cast<int64_t>(s), digest);
    for (int64_t k = 0; k < plan.shard_nsamples[s]; ++k, ++next) {
      const DemoPair& p = pairs[next];
      writer.Add(PairSample(p.scene, p.f0, p.f1, &rng, 16, 12, digest),
                 PairLine(p.scene, p.f0, p.f1, 0.1 * static_cast<double>(next % 9)));
    }
    writer.Finish();
  }
}

std::string Md5sumTool(const std::string& path) {
  const auto r = test::RunShell("md5sum '" + path + "'");
  EXPECT_EQ(r.exit_code, 0);
  return r.stdout_text.substr(0, 32);
}

TEST(Split, PlanCutsEquallyAndRoundTrips) {
  const SplitPlan plan = PlanEqualShards("val", 10, 4);
  EXPECT_EQ(plan.shard_nsamples, (std::vector<int64_t>{4, 4, 2}));
  EXPECT_TRUE(PlanEqualShards("val", 0, 4).shard_nsamples.empty());
  EXPECT_EQ(PlanEqualShards("val", 8, 4).shard_nsamples, (std::vector<int64_t>{4, 4}));
  const std::string dir = test::ScratchDir("shards_split_plan");
  WritePlan(dir, plan);
  EXPECT_EQ(ReadPlan(dir, "val").shard_nsamples, plan.shard_nsamples);
  EXPECT_EQ(ListPlannedSplits(dir), std::vector<std::string>{"val"});
  EXPECT_EQ(ShardFileName("val", 12), "val-000012.tar");
  EXPECT_EQ(PartRecordPath(dir, "val", 3), dir + "/parts/val-000003.json");
  EXPECT_THROW(WritePlan(dir, PlanEqualShards("bad/name", 1, 1)), InputError);
  io::WriteFileAtomic(PlanPath(dir, "broken"), "{\"split\": \"broken\", \"nshards\": 2}");
  EXPECT_THROW(ReadPlan(dir, "broken"), InputError);
}

TEST(Split, MergeWritesIndexAndPairsMatchingTheFiles) {
  const std::string dir = test::ScratchDir("shards_split_merge");
  WriteSplit(dir);
  for (int s = 0; s < 3; ++s) EXPECT_TRUE(IsShardComplete(dir, "train", s, true));
  EXPECT_FALSE(IsShardComplete(dir, "train", 3));

  MergeOptions options;
  options.schemas_dir = SchemasDir();
  const MergeResult result = MergeSplit(dir, options);
  EXPECT_EQ(result.split, "train");
  EXPECT_EQ(result.nshards, 3);
  EXPECT_EQ(result.nsamples, 11);

  const json index = json::parse(io::ReadFileBytes(dir + "/index.json"));
  EXPECT_EQ(index["__kind__"], "wids-shard-index-v1");
  EXPECT_EQ(index["wids_version"], 1);
  EXPECT_EQ(index["name"], "train");
  ASSERT_EQ(index["shardlist"].size(), 3u);
  const std::vector<int> expected_counts = {4, 4, 3};
  int64_t bytes = 0;
  for (int s = 0; s < 3; ++s) {
    const json& e = index["shardlist"][s];
    const std::string url = ShardFileName("train", s);
    EXPECT_EQ(e["url"], url);
    EXPECT_EQ(e["nsamples"], expected_counts[s]);
    EXPECT_EQ(e["md5sum"], Md5sumTool(dir + "/" + url));  // recomputed independently
    EXPECT_EQ(e["filesize"], static_cast<int64_t>(fs::file_size(dir + "/" + url)));
    EXPECT_EQ(static_cast<int64_t>(ReadShardSamples(dir + "/" + url).size()), expected_counts[s]);
    bytes += e["filesize"].get<int64_t>();
  }
  EXPECT_EQ(result.total_bytes, bytes);
  EXPECT_TRUE(ValidateJsonAgainstSchema(index.dump(), SchemasDir() + "/index.schema.json").empty());

  // pairs.jsonl: one line per sample, in shard order, naming the shard and key holding it.
  const auto lines = io::ReadLines(dir + "/pairs.jsonl");
  const auto pairs = DemoPairs();
  ASSERT_EQ(lines.size(), pairs.size());
  for (size_t i = 0; i < lines.size(); ++i) {
    const json line = json::parse(lines[i]);
    EXPECT_EQ(line["scene"], pairs[i].scene);
    EXPECT_EQ(line["frame0"], pairs[i].f0);
    const std::string shard = ShardFileName("train", static_cast<int64_t>(i / 4));
    EXPECT_EQ(line["shard"], shard);
    EXPECT_EQ(line["key"], MakeSampleKey(pairs[i].scene, std::to_string(pairs[i].f0),
                                         std::to_string(pairs[i].f1)));
    EXPECT_NO_THROW(ReadShardSample(dir + "/" + shard, line["key"]));
  }
  const json summary = json::parse(MergeSummaryJson(result));
  EXPECT_EQ(summary["pairs_per_scene"]["scene0707_00"], 7);
  EXPECT_EQ(summary["pairs_per_scene"]["hospital/Easy/P036"], 4);

  EXPECT_TRUE(ValidateSplit(dir, StructureOnly(SchemasDir())).empty());

  // Deterministic: the same samples in another folder give identical bytes.
  const std::string dir2 = test::ScratchDir("shards_split_merge_again");
  WriteSplit(dir2);
  MergeSplit(dir2, options);
  for (const std::string& f :
       std::vector<std::string>{"index.json", "pairs.jsonl", "train-000000.tar", "train-000002.tar",
                                "parts/train-000001.json"}) {
    EXPECT_EQ(io::ReadFileBytes(dir + "/" + f), io::ReadFileBytes(dir2 + "/" + f)) << f;
  }
}

// Expects MergeSplit (with MergeOptions::verify = `verify`) to throw an InputError whose
// message is one line containing `needle`, and no index.
void ExpectMergeFails(const std::string& dir, const std::string& needle, bool verify = false) {
  fs::remove(dir + "/index.json");
  fs::remove(dir + "/pairs.jsonl");
  try {
    MergeOptions options;
    options.schemas_dir = SchemasDir();
    options.verify = verify;
    MergeSplit(dir, options);
    ADD_FAILURE() << "merge accepted a broken split; expected " << needle;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  for (const char* f : {"/index.json", "/pairs.jsonl", "/pairs.jsonl.tmp", "/index.json.tmp"}) {
    EXPECT_FALSE(fs::exists(dir + f)) << f;
  }
}

// Merges (trusting the records) and expects success with an index.
void ExpectMergeSucceeds(const std::string& dir) {
  fs::remove(dir + "/index.json");
  MergeOptions options;
  options.schemas_dir = SchemasDir();
  EXPECT_NO_THROW(MergeSplit(dir, options));
  EXPECT_TRUE(fs::exists(dir + "/index.json"));
}

json ReadRecord(const std::string& dir, int64_t shard) {
  return json::parse(io::ReadFileBytes(PartRecordPath(dir, "train", shard)));
}
void WriteRecord(const std::string& dir, int64_t shard, const json& record) {
  io::WriteFileAtomic(PartRecordPath(dir, "train", shard), record.dump(1) + "\n");
}

TEST(Split, MergeFailsNamingAMissingOrCorruptShard) {
  {
    const std::string dir = test::ScratchDir("shards_merge_missing_tar");
    WriteSplit(dir);
    fs::remove(dir + "/train-000001.tar");
    ExpectMergeFails(dir,
                     "train-000001.tar: missing shard (re-run the occgt build or tuples "
                     "command that wrote the split: it writes a missing shard again)");
  }
  {
    const std::string dir = test::ScratchDir("shards_merge_missing_part");
    WriteSplit(dir);
    fs::remove(dir + "/parts/train-000002.json");
    ExpectMergeFails(dir, "train-000002.tar: missing part record");
  }
  {
    const std::string dir = test::ScratchDir("shards_merge_corrupt_part");
    WriteSplit(dir);
    const std::string record = PartRecordPath(dir, "train", 2);
    io::WriteFileAtomic(record, io::ReadFileBytes(record).substr(0, 100));  // cut mid-JSON
    ExpectMergeFails(dir, "train-000002.tar: bad part record: " + record + ": not valid JSON");
  }
  {
    const std::string dir = test::ScratchDir("shards_merge_bad_md5_field");
    WriteSplit(dir);
    json rec = ReadRecord(dir, 0);
    rec["md5sum"] = "not-a-digest";
    WriteRecord(dir, 0, rec);
    ExpectMergeFails(dir, "train-000000.tar: bad part record: ");
    rec["md5sum"] = 12;
    WriteRecord(dir, 0, rec);
    ExpectMergeFails(dir, "train-000000.tar: bad part record: ");
  }
  {
    // A record whose sample count disagrees with its own keys.
    const std::string dir = test::ScratchDir("shards_merge_record_counts");
    WriteSplit(dir);
    json rec = ReadRecord(dir, 1);
    rec["nsamples"] = 3;
    WriteRecord(dir, 1, rec);
    ExpectMergeFails(dir, "train-000001.tar: bad part record: ");
  }
  {
    // A pair line that does not name its key, and a key another shard holds.
    const std::string dir = test::ScratchDir("shards_merge_record_keys");
    WriteSplit(dir);
    const json good = ReadRecord(dir, 1);
    json rec = good;
    rec["pairs"][2]["key"] = rec["keys"][1];
    WriteRecord(dir, 1, rec);
    ExpectMergeFails(dir, "train-000001.tar: bad part record: " + PartRecordPath(dir, "train", 1) +
                              ": pairs[2]");
    rec = good;
    rec["keys"][3] = ReadRecord(dir, 0)["keys"][0];
    rec["pairs"][3]["key"] = rec["keys"][3];
    WriteRecord(dir, 1, rec);
    ExpectMergeFails(dir,
                     "train-000001.tar: sample key scene0707_00/0_300 appears in an earlier "
                     "shard, train-000000.tar");
  }
  {
    const std::string dir = test::ScratchDir("shards_merge_truncated");
    WriteSplit(dir);
    const std::string path = dir + "/train-000000.tar";
    io::WriteFileAtomic(path, io::ReadFileBytes(path).substr(0, 2048));
    ExpectMergeFails(dir, "train-000000.tar: size 2048 differs from the recorded");
    ExpectMergeFails(dir, "; delete it (re-run the occgt build or tuples command");
    // One byte more is caught as well.
    WriteSplit(dir);
    io::WriteFileAtomic(path, io::ReadFileBytes(path) + "x");
    ExpectMergeFails(dir, "train-000000.tar: size");
  }
  {
    // Consistent record and tar, but fewer samples than the plan promised.
    const std::string dir = test::ScratchDir("shards_merge_plan_mismatch");
    WriteSplit(dir);
    SplitPlan plan = ReadPlan(dir, "train");
    plan.shard_nsamples[2] = 5;
    WritePlan(dir, plan);
    ExpectMergeFails(dir, "train-000002.tar: holds 3 samples, the plan says 5");
  }
  {
    const std::string dir = test::ScratchDir("shards_merge_no_plan");
    WriteSplit(dir);
    fs::remove(PlanPath(dir, "train"));
    ExpectMergeFails(dir, "parts");
  }
}

TEST(Split, MergeTrustsRecordedDigestsAndVerifyAndValidateDoNot) {
  {
    // Same size, other bytes: the merge trusts the record (it reads no tar) and publishes
    // the recorded MD5; --verify and validate re-hash and catch it.
    const std::string dir = test::ScratchDir("shards_merge_flipped_byte");
    WriteSplit(dir);
    const std::string path = dir + "/train-000001.tar";
    const std::string recorded_md5 = ReadRecord(dir, 1)["md5sum"];
    std::string bytes = io::ReadFileBytes(path);
    bytes[700] ^= 0x01;  // inside the first member's data: same size, other MD5
    io::WriteFileAtomic(path, bytes);
    ExpectMergeSucceeds(dir);
    const json index = json::parse(io::ReadFileBytes(dir + "/index.json"));
    EXPECT_EQ(index["shardlist"][1]["md5sum"], recorded_md5);
    EXPECT_NE(recorded_md5, io::Md5Hex(bytes));
    std::string all;
    for (const auto& p : ValidateSplit(dir, StructureOnly(SchemasDir()))) all += p + "\n";
    EXPECT_NE(all.find(path + ": md5 " + io::Md5Hex(bytes) + " differs from index.json's " +
                       recorded_md5),
              std::string::npos)
        << all;
    ExpectMergeFails(
        dir,
        "train-000001.tar: md5 " + io::Md5Hex(bytes) + " differs from the recorded " + recorded_md5,
        /*verify=*/true);
  }
  {
    // A tar replaced by a different valid shard with a matching record: only reading the
    // tar (verify, validate) finds that its keys are not the record's.
    const std::string dir = test::ScratchDir("shards_merge_swapped");
    WriteSplit(dir);
    fs::copy_file(dir + "/train-000000.tar", dir + "/train-000001.tar",
                  fs::copy_options::overwrite_existing);
    json rec = ReadRecord(dir, 1);
    rec["md5sum"] = io::Md5HexOfFile(dir + "/train-000001.tar");
    rec["filesize"] = fs::file_size(dir + "/train-000001.tar");
    WriteRecord(dir, 1, rec);
    ExpectMergeSucceeds(dir);
    EXPECT_FALSE(ValidateSplit(dir, StructureOnly(SchemasDir())).empty());
    ExpectMergeFails(dir, "train-000001.tar: sample keys in the tar differ from", true);
  }
  {
    // Verify on a good split passes and writes the same index as the trusted merge.
    const std::string dir = test::ScratchDir("shards_merge_verify_good");
    WriteSplit(dir);
    ExpectMergeSucceeds(dir);
    const std::string trusted = io::ReadFileBytes(dir + "/index.json");
    MergeOptions options;
    options.schemas_dir = SchemasDir();
    options.verify = true;
    EXPECT_NO_THROW(MergeSplit(dir, options));
    EXPECT_EQ(io::ReadFileBytes(dir + "/index.json"), trusted);
    // A problem in two shards: verify names the first one in shard order.
    for (const char* name : {"train-000002.tar", "train-000001.tar"}) {
      std::string bytes = io::ReadFileBytes(dir + "/" + name);
      bytes[1000] ^= 0x10;
      io::WriteFileAtomic(dir + "/" + name, bytes);
    }
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      ExpectMergeFails(dir, "train-000001.tar: md5", true);
    }
  }
  {
    // Problems of two kinds: shard 0's bytes changed (an MD5 only --verify sees) and shard
    // 2 truncated (a size the record checks see): the first in shard order is named, shard
    // 0, not the one the cheaper check found first (it named shard 2).
    const std::string dir = test::ScratchDir("shards_merge_verify_order");
    WriteSplit(dir);
    std::string bytes = io::ReadFileBytes(dir + "/train-000000.tar");
    bytes[1000] ^= 0x10;
    io::WriteFileAtomic(dir + "/train-000000.tar", bytes);
    fs::resize_file(dir + "/train-000002.tar", 1000);
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      ExpectMergeFails(dir, "train-000000.tar: md5", true);
    }
    // Without --verify the record checks alone see shard 2.
    ExpectMergeFails(dir, "train-000002.tar: size 1000 differs from the recorded");
  }
}

TEST(Split, AShardOfAnotherBuildIsRefusedByMergeAndValidate) {
  // Two builds of one split name into two folders (other data or options, so another
  // options digest); shard 1 and its part record copied from the second into the first: the
  // merge and validate named nothing and published a split of mixed data.
  const std::string a = test::ScratchDir("shards_digest_a");
  const std::string b = test::ScratchDir("shards_digest_b");
  const std::string da(32, 'a'), db(32, 'b');
  WriteSplit(a, "train", 4, da);
  WriteSplit(b, "train", 4, db);
  ExpectMergeSucceeds(a);
  ASSERT_TRUE(ValidateSplit(a, StructureOnly(SchemasDir())).empty());
  EXPECT_EQ(ReadRecord(a, 1)["options_digest"], da);
  for (const char* f : {"/train-000001.tar", "/parts/train-000001.json"}) {
    fs::copy_file(b + f, a + f, fs::copy_options::overwrite_existing);
  }
  const std::string want = "written by another build: options digest " + db + ", the split's is " +
                           da + " (train-000000.tar)";
  // validate reads the samples' digests (index.json names the copied shard's size and MD5).
  json index = json::parse(io::ReadFileBytes(a + "/index.json"));
  index["shardlist"][1]["md5sum"] = io::Md5HexOfFile(a + "/train-000001.tar");
  index["shardlist"][1]["filesize"] = fs::file_size(a + "/train-000001.tar");
  io::WriteFileAtomic(a + "/index.json", index.dump(2) + "\n");
  std::string all;
  for (const auto& p : ValidateSplit(a, StructureOnly(SchemasDir()))) all += p + "\n";
  EXPECT_NE(all.find(a + "/train-000001.tar: " + want), std::string::npos) << all;
  ExpectMergeFails(a, "train-000001.tar: " + want);
  // With a recipe.json, its digest is the split's.
  io::WriteFileAtomic(a + "/recipe.json", json{{"options_digest", db}}.dump());
  all.clear();
  ExpectMergeFails(a, "train-000000.tar: written by another build: options digest " + da +
                          ", the split's is " + db + " (recipe.json)");
  // A sample json whose key is not its member's (a sample's members renamed).
  const std::string c = test::ScratchDir("shards_digest_key");
  WritePlan(c, PlanEqualShards("train", 1, 4));
  std::mt19937 rng(3);
  Sample s = PairSample("scene0707_00", 0, 15, &rng, 16, 12, da);
  s.key = MakeSampleKey("scene0707_00", "0", "30");
  {
    SplitShardWriter writer(c, "train", 0, da);
    writer.Add(std::move(s), PairLine("scene0707_00", 0, 30, 0.5));
    writer.Finish();
  }
  ExpectMergeSucceeds(c);
  const auto problems = ValidateSplit(c, StructureOnly(SchemasDir()));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0], c + "/train-000000.tar: scene0707_00/0_30.json: its \"key\" is "
                             "\"scene0707_00/0_15\", not the member's scene0707_00/0_30");
}

TEST(Split, ValidateReportsEveryProblemOnItsOwnLine) {
  const std::string dir = test::ScratchDir("shards_validate_problems");
  WriteSplit(dir);
  MergeSplit(dir, MergeOptions{});
  ASSERT_TRUE(ValidateSplit(dir, StructureOnly(SchemasDir())).empty());

  std::string bytes = io::ReadFileBytes(dir + "/train-000000.tar");
  bytes[900] ^= 0x20;
  io::WriteFileAtomic(dir + "/train-000000.tar", bytes);
  fs::remove(dir + "/train-000002.tar");
  const auto problems = ValidateSplit(dir, StructureOnly(SchemasDir()));
  std::string all;
  for (const auto& p : problems) {
    EXPECT_EQ(p.find('\n'), std::string::npos);
    all += p + "\n";
  }
  EXPECT_NE(all.find("train-000000.tar: md5"), std::string::npos) << all;
  EXPECT_NE(all.find("train-000002.tar: missing shard"), std::string::npos) << all;
  // The pairs.jsonl lines of the missing shard add no line of their own (they added one
  // "is not in shard" line per sample after the one real problem).
  EXPECT_EQ(all.find("pairs.jsonl"), std::string::npos) << all;
  EXPECT_EQ(all.find("train-000001.tar"), std::string::npos) << all;

  // A corrupt .npy header inside an otherwise consistent shard is found by reading it.
  const std::string dir2 = test::ScratchDir("shards_validate_npy");
  WriteSplit(dir2);
  MergeSplit(dir2, MergeOptions{});
  const std::string shard = dir2 + "/train-000001.tar";
  std::string tar = io::ReadFileBytes(shard);
  const size_t magic = tar.find("\x93NUMPY");
  ASSERT_NE(magic, std::string::npos);
  tar[magic + 1] = 'X';
  io::WriteFileAtomic(shard, tar);
  json index = json::parse(io::ReadFileBytes(dir2 + "/index.json"));
  index["shardlist"][1]["md5sum"] = io::Md5Hex(tar);
  io::WriteFileAtomic(dir2 + "/index.json", index.dump(2));
  const auto p2 = ValidateSplit(dir2, StructureOnly(SchemasDir()));
  ASSERT_EQ(p2.size(), 1u);
  EXPECT_NE(p2[0].find("bad .npy"), std::string::npos) << p2[0];
  // The shard's path once (the member's error repeated "<shard>:<member>" after it).
  EXPECT_EQ(p2[0].find(shard, 1), std::string::npos) << p2[0];

  // A shard the index does not list, a leftover temporary file, and a pair line whose
  // key is not a string: each one problem line, never an exception.
  const std::string dir3 = test::ScratchDir("shards_validate_extra");
  WriteSplit(dir3);
  MergeSplit(dir3, MergeOptions{});
  fs::copy_file(dir3 + "/train-000000.tar", dir3 + "/train-000099.tar");
  io::WriteFileAtomic(dir3 + "/stale.tar.tmp", "x");
  std::vector<std::string> lines = io::ReadLines(dir3 + "/pairs.jsonl");
  const std::string line0 = lines[0];
  json first = json::parse(lines[0]);
  first["key"] = 7;
  lines[0] = first.dump();
  WriteJsonLines(dir3 + "/pairs.jsonl", lines);
  std::string all3;
  for (const auto& p : ValidateSplit(dir3, StructureOnly(SchemasDir()))) all3 += p + "\n";
  EXPECT_NE(all3.find("train-000099.tar: shard not listed in index.json"), std::string::npos)
      << all3;
  EXPECT_NE(all3.find("stale.tar.tmp: temporary file left"), std::string::npos) << all3;
  EXPECT_NE(all3.find("pairs.jsonl:1: fields \"key\" and \"shard\": expected strings"),
            std::string::npos)
      << all3;
  EXPECT_EQ(all3.find("out of order"), std::string::npos) << all3;  // the bad line is line 1

  // Lines in another order than the samples: the first one out of place is named, once.
  lines = io::ReadLines(dir3 + "/pairs.jsonl");
  lines[0] = line0;
  const std::string key1 = json::parse(lines[1])["key"].get<std::string>();
  const std::string key2 = json::parse(lines[2])["key"].get<std::string>();
  std::swap(lines[1], lines[2]);
  WriteJsonLines(dir3 + "/pairs.jsonl", lines);
  fs::remove(dir3 + "/train-000099.tar");
  fs::remove(dir3 + "/stale.tar.tmp");
  EXPECT_EQ(ValidateSplit(dir3, StructureOnly(SchemasDir())),
            std::vector<std::string>{dir3 + "/pairs.jsonl:2: key \"" + key2 +
                                     "\" is out of order: the shards hold \"" + key1 +
                                     "\" here (one line per sample, in shard order)"});

  // index.json that breaks the schema.
  index["__kind__"] = "something-else";
  io::WriteFileAtomic(dir2 + "/index.json", index.dump(2));
  const auto p3 = ValidateSplit(dir2, StructureOnly(SchemasDir()));
  ASSERT_FALSE(p3.empty());
  EXPECT_NE(p3[0].find("index.schema.json"), std::string::npos) << p3[0];
}

// index.json as the readers (ShardDataset, occgt eval) take it: the merge's entries back, and
// one error naming the field for what no reader can use; validate reports the same entry
// problems as lines.
TEST(Split, ReadShardIndexGivesTheMergedShardsAndNamesBadEntries) {
  const std::string dir = test::ScratchDir("shards_read_index");
  WriteSplit(dir);
  const MergeResult merged = MergeSplit(dir, MergeOptions{});
  const ShardIndex index = ReadShardIndex(dir);
  EXPECT_EQ(index.path, dir + "/index.json");
  EXPECT_EQ(index.name, "train");
  ASSERT_EQ(index.shards.size(), merged.parts.size());
  for (size_t i = 0; i < index.shards.size(); ++i) {
    EXPECT_EQ(index.shards[i].url, merged.parts[i].url);
    EXPECT_EQ(index.shards[i].nsamples, merged.parts[i].info.nsamples);
    EXPECT_EQ(index.shards[i].filesize, merged.parts[i].info.filesize);
    EXPECT_EQ(index.shards[i].md5sum, merged.parts[i].info.md5sum);
  }
  const json good = json::parse(io::ReadFileBytes(index.path));
  struct Case {
    std::function<void(json&)> edit;
    std::string message;  // after "<dir>/index.json: "
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["shardlist"][1]["url"] = "../train-000001.tar"; },
       "shardlist[1].url: \"../train-000001.tar\" is not a file name in the split's folder (the "
       "folder holding index.json)"},
      {[&](json& j) { j["shardlist"][0]["url"] = dir + "/train-000000.tar"; },
       "shardlist[0].url: \"" + dir +
           "/train-000000.tar\" is not a file name in the split's folder (the folder holding "
           "index.json)"},
      {[](json& j) { j["shardlist"][0]["url"] = ".."; }, "shardlist[0].url: \"..\" is not"},
      {[](json& j) { j["shardlist"][0]["url"] = 3; }, "shardlist[0].url: expected a string"},
      {[](json& j) { j["shardlist"][2]["nsamples"] = -1; },
       "shardlist[2].nsamples: expected an integer >= 0"},
      {[](json& j) { j["shardlist"][2]["nsamples"] = "3"; },
       "shardlist[2].nsamples: expected an integer >= 0"},
      {[](json& j) { j["shardlist"][0].erase("filesize"); },
       "shardlist[0].filesize: expected an integer >= 0"},
      {[](json& j) { j["shardlist"][0]["filesize"] = 1.5; },
       "shardlist[0].filesize: expected an integer >= 0"},
      {[](json& j) { j["shardlist"][0]["md5sum"] = 7; }, "shardlist[0].md5sum: expected a string"},
      // A shard listed twice: its samples were read twice (ShardDataset gave 32 of 24).
      {[](json& j) { j["shardlist"][2] = j["shardlist"][0]; },
       "shardlist[2].url: \"train-000000.tar\" repeats shardlist[0]"},
      {[](json& j) { j["shardlist"][1] = "train-000001.tar"; },
       "shardlist[1]: expected an object {url, nsamples, md5sum, filesize}"},
      {[](json& j) { j["name"] = 1; }, "name: expected a string"},
      {[](json& j) { j["shardlist"] = json::object(); },
       "expected an object with a \"shardlist\" array"},
  };
  for (const Case& c : cases) {
    json edited = good;
    c.edit(edited);
    io::WriteFileAtomic(index.path, edited.dump(2));
    try {
      ReadShardIndex(dir);
      ADD_FAILURE() << "expected InputError: " << c.message;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(index.path + ": " + c.message, 0), 0u) << e.what();
    }
  }
  // validate: the same entry problem, as one line; the other shards are still checked.
  json edited = good;
  edited["shardlist"][1]["url"] = "../train-000001.tar";
  edited["shardlist"][2].erase("md5sum");
  io::WriteFileAtomic(index.path, edited.dump(2));
  const std::vector<std::string> problems =
      ValidateSplit(dir, StructureOnly(PermissiveSchemasDir()));
  ASSERT_GE(problems.size(), 3u);
  EXPECT_EQ(problems[0], index.path +
                             ": shardlist[1].url: \"../train-000001.tar\" is not a file name in "
                             "the split's folder (the folder holding index.json)");
  EXPECT_EQ(problems[1], index.path + ": shardlist[2].md5sum: missing");
  EXPECT_EQ(problems[2], dir + "/train-000001.tar: shard not listed in index.json");
  // With the real index schema, its violations of one document are one line (valijson gave
  // one per level: four lines for one bad url), beside the hand-written line.
  const std::vector<std::string> with_schema = ValidateSplit(dir, StructureOnly(SchemasDir()));
  size_t schema_lines = 0;
  for (const std::string& p : with_schema) {
    schema_lines += p.find("index.schema.json: ") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(schema_lines, 1u) << with_schema.size();
  // A shard listed twice: one line, not one "repeats" line per sample.
  edited = good;
  edited["shardlist"].push_back(good["shardlist"][1]);
  io::WriteFileAtomic(index.path, edited.dump(2));
  const std::vector<std::string> twice = ValidateSplit(dir, StructureOnly(PermissiveSchemasDir()));
  ASSERT_FALSE(twice.empty());
  EXPECT_EQ(twice[0], index.path + ": shardlist[" + std::to_string(good["shardlist"].size()) +
                          "].url: \"train-000001.tar\" repeats shardlist[1]");
  for (const std::string& p : twice) EXPECT_EQ(p.find("repeats\n"), std::string::npos) << p;
  for (const std::string& p : twice) EXPECT_EQ(p.find(": sample "), std::string::npos) << p;
  fs::remove(index.path);
  try {
    ReadShardIndex(dir);
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), index.path +
                                         ": missing (expected the split's wids shard index, "
                                         "written by occgt build or occgt merge)");
  }
}

TEST(Split, SampleJsonAndPairLinesAreCheckedAgainstSchemasByVerifyAndValidate) {
  const std::string schemas = test::ScratchDir("shards_schemas_strict");
  fs::copy_file(SchemasDir() + "/index.schema.json", schemas + "/index.schema.json");
  auto write_schema = [&](const std::string& file, const std::string& frame_type) {
    io::WriteFileAtomic(schemas + "/" + file,
                        R"({"type": "object", "required": ["scene", "frame0"],
                            "properties": {"frame0": {"type": ")" +
                            frame_type + R"("}}})");
  };
  const std::string dir = test::ScratchDir("shards_merge_schema");
  WriteSplit(dir);
  MergeOptions options;
  options.schemas_dir = schemas;
  write_schema("sample.schema.json", "integer");
  write_schema("pairs_line.schema.json", "integer");
  io::WriteFileAtomic(schemas + "/views_sample.schema.json", "{}\n");
  io::WriteFileAtomic(schemas + "/views_line.schema.json", "{}\n");
  MergeOptions verify = options;
  verify.verify = true;
  EXPECT_NO_THROW(MergeSplit(dir, options));
  EXPECT_NO_THROW(MergeSplit(dir, verify));
  EXPECT_TRUE(ValidateSplit(dir, StructureOnly(schemas)).empty());

  // Content against the schemas is checked by --verify and validate; the default merge
  // trusts what the tasks wrote (it reads no tar and checks no line against a schema).
  write_schema("sample.schema.json", "string");  // the samples hold integers
  EXPECT_NO_THROW(MergeSplit(dir, options));
  try {
    MergeSplit(dir, verify);
    ADD_FAILURE() << "sample JSON not checked";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("train-000000.tar: scene0707_00/0_300.json: "
                                         "sample.schema.json"),
              std::string::npos)
        << e.what();
  }
  auto problems = ValidateSplit(dir, StructureOnly(schemas));
  EXPECT_EQ(problems.size(), 11u);  // one per sample

  write_schema("sample.schema.json", "integer");
  write_schema("pairs_line.schema.json", "string");
  EXPECT_NO_THROW(MergeSplit(dir, options));
  try {
    MergeSplit(dir, verify);
    ADD_FAILURE() << "pair lines not checked";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("parts/train-000000.json: pairs[0]: "
                                         "pairs_line.schema.json"),
              std::string::npos)
        << e.what();
  }
  problems = ValidateSplit(dir, StructureOnly(schemas));
  ASSERT_EQ(problems.size(), 11u);
  EXPECT_NE(problems[0].find("pairs.jsonl:1: pairs_line.schema.json"), std::string::npos)
      << problems[0];
}

TEST(Split, CommandsMergeAndValidate) {
  const std::string dir = test::ScratchDir("shards_split_cli");
  // A folder that is not there, or holds no plan yet: named, with what makes the plan.
  auto missing = test::RunOccgt("merge '" + dir + "/none'");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_EQ(missing.stderr_text,
            "occgt: error: " + dir + "/none: expected a split folder (occgt build's --out)\n");
  missing = test::RunOccgt("merge '" + dir + "'");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.stderr_text.find("found 0 (the write stage of occgt build writes it"),
            std::string::npos)
      << missing.stderr_text;
  WriteSplit(dir);
  auto r = test::RunOccgt("merge --schemas '" + SchemasDir() + "' '" + dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_NE(r.stdout_text.find("11 samples"), std::string::npos) << r.stdout_text;
  const json summary = json::parse(io::ReadFileBytes(dir + "/summary.json"));
  EXPECT_EQ(summary["samples"], 11);
  EXPECT_EQ(summary["kind"], "occgt-merge-summary");
  // A summary.json written by `occgt build` (another document) is kept as it is.
  io::WriteFileAtomic(dir + "/summary.json", "{\"recipe\": \"x.yaml\"}\n");
  r = test::RunOccgt("merge --schemas '" + SchemasDir() + "' '" + dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_EQ(io::ReadFileBytes(dir + "/summary.json"), "{\"recipe\": \"x.yaml\"}\n");
  r = test::RunOccgt("validate --structure-only --schemas '" + SchemasDir() + "' '" + dir + "'");
  EXPECT_EQ(r.exit_code, 0) << r.stdout_text << r.stderr_text;

  std::string bytes = io::ReadFileBytes(dir + "/train-000002.tar");
  bytes[1000] ^= 0x04;
  io::WriteFileAtomic(dir + "/train-000002.tar", bytes);
  r = test::RunOccgt("validate --structure-only --schemas '" + SchemasDir() + "' '" + dir + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.stdout_text.find("train-000002.tar: md5"), std::string::npos) << r.stdout_text;
  // The default merge trusts the recorded digest (same size): it passes; --verify fails
  // with one line naming the shard.
  r = test::RunOccgt("merge --schemas '" + SchemasDir() + "' '" + dir + "'");
  EXPECT_EQ(r.exit_code, 0) << r.stderr_text;
  r = test::RunOccgt("merge --verify --threads 2 --schemas '" + SchemasDir() + "' '" + dir + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.stderr_text.find("train-000002.tar: md5"), std::string::npos) << r.stderr_text;
  EXPECT_EQ(std::count(r.stderr_text.begin(), r.stderr_text.end(), '\n'), 1) << r.stderr_text;
  // A missing tar fails the default merge with one line naming it.
  fs::remove(dir + "/train-000001.tar");
  r = test::RunOccgt("merge --schemas '" + SchemasDir() + "' '" + dir + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.stderr_text.find("train-000001.tar: missing shard"), std::string::npos)
      << r.stderr_text;
  EXPECT_EQ(std::count(r.stderr_text.begin(), r.stderr_text.end(), '\n'), 1) << r.stderr_text;
}

TEST(Split, DeprecatedMergeFlagsAreAcceptedWithANote) {
  const std::string dir = test::ScratchDir("shards_merge_old_flags");
  WriteSplit(dir);
  auto r =
      test::RunOccgt("merge --no-md5 --no-read --schemas '" + SchemasDir() + "' '" + dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_NE(r.stdout_text.find("11 samples"), std::string::npos) << r.stdout_text;
  EXPECT_NE(r.stderr_text.find("--no-md5 is ignored"), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("use --verify"), std::string::npos) << r.stderr_text;
  r = test::RunOccgt("merge --verify --no-md5 '" + dir + "'");
  EXPECT_NE(r.exit_code, 0);
}

TEST(Split, ValidateOutputDoesNotDependOnTheThreadCount) {
  // 11 one-sample shards, several of them broken in different ways.
  const std::string dir = test::ScratchDir("shards_validate_threads");
  WriteSplit(dir, "train", 1);
  MergeSplit(dir, MergeOptions{});
  for (int s : {2, 6, 9}) {
    const std::string path = dir + "/" + ShardFileName("train", s);
    std::string bytes = io::ReadFileBytes(path);
    bytes[600 + s] ^= 0x08;
    io::WriteFileAtomic(path, bytes);
  }
  fs::remove(dir + "/" + ShardFileName("train", 4));
  fs::copy_file(dir + "/train-000000.tar", dir + "/train-000007.tar",
                fs::copy_options::overwrite_existing);  // keys repeat, size and md5 differ
  const std::string shard8 = dir + "/train-000008.tar";
  io::WriteFileAtomic(shard8, io::ReadFileBytes(shard8).substr(0, 1024 + 100));
  std::vector<std::vector<std::string>> runs;
  for (int threads : {1, 2, 1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    runs.push_back(ValidateSplit(dir, StructureOnly(SchemasDir())));
  }
  ASSERT_GE(runs[0].size(), 7u);
  for (size_t k = 1; k < runs.size(); ++k) EXPECT_EQ(runs[k], runs[0]) << "run " << k;
  // Problems come in shard order.
  std::string all;
  for (const auto& p : runs[0]) all += p + "\n";
  size_t last = 0;
  for (int s : {2, 4, 6, 7, 8, 9}) {
    const size_t at = all.find(ShardFileName("train", s) + ":");
    ASSERT_NE(at, std::string::npos) << s << "\n" << all;
    EXPECT_GE(at, last) << s << "\n" << all;
    last = at;
  }
  EXPECT_NE(all.find("train-000007.tar: sample scene0707_00/0_300 repeats"), std::string::npos)
      << all;
  // The command: the same stdout with 1 and 2 threads.
  const auto one = test::RunOccgt("validate --threads 1 --structure-only --schemas '" +
                                  SchemasDir() + "' '" + dir + "'");
  const auto two = test::RunOccgt("validate --threads 2 --structure-only --schemas '" +
                                  SchemasDir() + "' '" + dir + "'");
  EXPECT_EQ(one.exit_code, 1);
  EXPECT_EQ(two.exit_code, 1);
  EXPECT_EQ(one.stdout_text, two.stdout_text);
  EXPECT_EQ(one.stderr_text, two.stderr_text);
  std::string expected;
  for (const auto& p : runs[0]) expected += p + "\n";
  EXPECT_EQ(one.stdout_text, expected);
  EXPECT_NE(test::RunOccgt("validate --threads -1 '" + dir + "'").exit_code, 0);
}

// Leaves a demo split (shards, merged indices, LoFTR export) in $OCCGT_SHARDS_DEMO_OUT for
// tests/integration/shards_test.py; without the variable it writes to a scratch folder
// and checks the same files exist.
TEST(ShardsDemo, WriteDemoSplit) {
  const char* env = std::getenv("OCCGT_SHARDS_DEMO_OUT");
  const std::string dir =
      env != nullptr && *env ? std::string(env) : test::ScratchDir("shards_demo");
  fs::create_directories(dir);
  WriteSplit(dir);
  const auto r = test::RunOccgt("merge --schemas '" + SchemasDir() + "' '" + dir + "'");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  std::vector<LoftrPair> pairs;
  SceneIntrinsics intrinsics;
  int i = 0;
  for (const DemoPair& p : DemoPairs()) {
    LoftrPair lp;
    lp.scene = p.scene;
    lp.frame0 = p.f0;
    lp.frame1 = p.f1;
    lp.score = 0.1 * (i++ % 9);
    lp.cam1_from_cam0 = {1, 0, 0, 0.1 * i, 0, 1, 0, 0, 0, 0, 1, 0};
    pairs.push_back(lp);
    intrinsics[p.scene] = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  }
  ExportLoftrTrain(dir + "/loftr", pairs, intrinsics, LoftrExportOptions{});
  ExportLoftrTest(dir + "/loftr_test", pairs, intrinsics, LoftrExportOptions{});
  for (const std::string& f :
       std::vector<std::string>{"index.json", "pairs.jsonl", "summary.json", "loftr/intrinsics.npz",
                                "loftr/train_list.txt", "loftr_test/test.npz"}) {
    EXPECT_TRUE(fs::exists(dir + "/" + f)) << f;
  }
}

}  // namespace
}  // namespace gt::shards

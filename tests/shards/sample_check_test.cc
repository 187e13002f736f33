// The value checks of a stored pair sample (shards/sample_check.h): every sample of a real
// build passes, and each kind of damage to its members or json is named.
#include "libgt/shards/sample_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "libgt/io/npy.h"
#include "libgt/pipeline/build.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/synthetic.h"
#include "libgt/shards/sample.h"
#include "libgt/shards/split.h"
#include "libgt/shards/tar_shard.h"
#include "tests/support/decoded_sample.h"
#include "tests/support/test_support.h"

namespace gt::shards {
namespace {

using nlohmann::json;

// One sample as the checks take it: decoded members.
struct Decoded : test::DecodedSample {
  std::vector<std::string> Problems() const {
    std::vector<std::string> p = CheckPairSampleMembers(meta, fields);
    for (std::string& q : CheckPairSampleValues(meta, arrays, ImageViews())) p.push_back(q);
    return p;
  }
};

Decoded Decode(const Sample& s) { return {test::DecodeSample(s)}; }

// Every sample of a build of the synthetic dataset with labels, depth, images and occupancy
// in both encodings (gzip-compressed members).
const std::vector<Decoded>& Built() {
  static const std::vector<Decoded> samples = [] {
    const std::string data = test::ScratchDir("sample_check_data");
    pipeline::SyntheticDatasetOptions o;
    o.scenes = 2;
    o.frames = 12;
    o.width = 64;
    o.height = 48;
    pipeline::EnsureSyntheticDataset(data, o);
    const std::string yaml = R"(
name: check
split: check
resolution: [64, 48]
dataset: {format: generic, root: )" +
                             data + R"(, min_valid_depth_fraction: 0.2}
selection: {max_frame_gap: 4, score_stride: 2, overlap: [0.05, 1.0], quota_per_scene: 8}
patches: {stride: 4}
occupancy: {voxel_m: 0.1, far_m: 8.0, bins: 16, encoding: both}
sample: {image: png, depth: true, labels: true, occupancy: true, compression: deflate}
shards: {samples_per_shard: 100}
)";
    const pipeline::Recipe r = pipeline::ParseRecipe(yaml, "check.yaml", "/");
    const std::string out = test::ScratchDir("sample_check_out");
    pipeline::BuildOptions b;
    b.out_dir = out;
    pipeline::RunBuild(r, b, nullptr);
    std::vector<Decoded> all;
    for (const Sample& s : ReadShardSamples(ShardPath(out, "check", 0))) all.push_back(Decode(s));
    return all;
  }();
  return samples;
}

// The first sample with matches of every type.
Decoded Rich() {
  for (const Decoded& d : Built()) {
    const json& m = d.meta.at("matches");
    if (m.at("vv") > 0 && m.at("vo") > 0 && m.at("ov") > 0) return d;
  }
  ADD_FAILURE() << "no sample with vv, vo and ov matches";
  return Built().front();
}

// The one problem of `d`, which must start with `field` and contain `words`.
void ExpectProblem(const Decoded& d, const std::string& field, const std::string& words) {
  const std::vector<std::string> p = d.Problems();
  ASSERT_FALSE(p.empty()) << "no problem found; expected " << field << ": ..." << words;
  EXPECT_EQ(p.front().rfind(field + ": ", 0), 0u) << p.front();
  EXPECT_NE(p.front().find(words), std::string::npos) << p.front();
}

TEST(SampleCheck, EverySampleOfABuildIsConsistent) {
  ASSERT_GE(Built().size(), 3u);
  int64_t matches = 0;
  for (const Decoded& d : Built()) {
    EXPECT_EQ(d.Problems(), std::vector<std::string>{}) << d.key;
    EXPECT_TRUE(d.arrays.count("occ0_dense.npy") && d.arrays.count("known1.npy")) << d.key;
    matches += d.meta.at("matches").at("total").get<int64_t>();
  }
  EXPECT_GT(matches, 0);
}

TEST(SampleCheck, LabelCodeOutOfRange) {
  Decoded d = Rich();
  d.Data<uint8_t>("label01.npy")[64 * 3 + 5] = 9;
  ExpectProblem(d, "label01.npy", "pixel (5, 3) holds 9; expected a label code 0..5");
}

TEST(SampleCheck, LabelCountsDifferFromTheJsonsMetrics) {
  Decoded d = Rich();
  uint8_t* l = d.Data<uint8_t>("label10.npy");
  // A pixel off the score grid (odd row and column): only the full metrics change.
  for (int p = 64 + 1;; p += 2) {
    if (l[p] == 2) {
      l[p] = 4;  // VISIBLE -> INCONSISTENT
      break;
    }
  }
  ExpectProblem(d, "label10.npy", "VISIBLE count is");
  d = Rich();
  d.meta["score_metrics"]["01"]["occlusion_ratio"] = 0.5;
  ExpectProblem(d, "label01.npy", "the json's score_metrics[\"01\"] says 0.5");
}

TEST(SampleCheck, DepthNotFiniteOrDisagreeingWithNoDepth) {
  Decoded d = Rich();
  d.Data<float>("depth0.npy")[7] = std::nanf("");
  ExpectProblem(d, "depth0.npy", "pixel (7, 0) holds nan; expected metres >= 0");
  d = Rich();
  float* z = d.Data<float>("depth1.npy");
  const uint8_t* l = d.Data<uint8_t>("label10.npy");
  int p = 0;
  while (l[p] == 0) ++p;
  z[p] = 0;  // invalid depth under a label other than NO_DEPTH
  ExpectProblem(d, "depth1.npy", "invalid in label_options' range");
}

// A recipe's labels.overrides.max_depth_m: .inf is stored as null (JSON has no infinity):
// no upper limit, as the schemas say, not a json problem (10012e9 reported one).
TEST(SampleCheck, AnUnboundedDepthRangeIsNullInTheJson) {
  Decoded d = Rich();
  d.meta["label_options"]["max_depth_m"] = nullptr;
  EXPECT_EQ(d.Problems(), std::vector<std::string>{});
  d.Data<float>("depth0.npy")[3] = 0;  // NO_DEPTH still checked against the range
  const std::vector<std::string> p = d.Problems();
  ASSERT_FALSE(p.empty());
  EXPECT_NE(p.front().find("[0.05, inf] m"), std::string::npos) << p.front();
}

TEST(SampleCheck, CellsAreTheLabelsAtTheAnchors) {
  Decoded d = Rich();
  uint8_t* c = d.Data<uint8_t>("cells0.npy");
  c[0] = c[0] == 1 ? 2 : 1;
  ExpectProblem(d, "cells0.npy", "cell 0 holds");
}

TEST(SampleCheck, MatchesOutOfGridTypeOrderAndRule) {
  Decoded d = Rich();
  d.Data<int32_t>("matches.npy")[1] = 16 * 12;  // row 0's cell in image 1: one past the grid
  ExpectProblem(d, "matches.npy", "row 0 names cell 192 of image 1, which has 192 cells");
  d = Rich();
  d.Data<uint8_t>("match_type.npy")[0] = 7;
  ExpectProblem(d, "match_type.npy", "row 0 is 7");
  d = Rich();
  const int64_t total = d.meta["matches"]["total"].get<int64_t>();
  d.Data<uint8_t>("match_type.npy")[total - 1] = 0;  // the last ov claimed as a vv
  ExpectProblem(d, "matches.npy", "is out of the order");
  d = Rich();
  float* xy = d.Data<float>("match_xy.npy");
  xy[0] += 4;  // one cell to the right (or off the grid)
  ExpectProblem(d, "match_xy.npy", "row 0 (");
  d = Rich();
  d.meta["matches"]["vv"] = d.meta["matches"]["vv"].get<int64_t>() - 1;
  d.meta["matches"]["vo"] = d.meta["matches"]["vo"].get<int64_t>() + 1;
  ExpectProblem(d, "match_type.npy", "vv matches, the json's matches.vv says");
}

TEST(SampleCheck, OccupancyWordsDenseAndCounts) {
  Decoded d = Rich();
  d.Data<uint64_t>("occ0.npy")[3] |= ~d.Data<uint64_t>("known0.npy")[3] & 0xFFFF;
  ExpectProblem(d, "occ0.npy", "cell 3: expected occupied bins within the known ones");
  d = Rich();
  d.Data<uint8_t>("occ1_dense.npy")[5] = 7;
  ExpectProblem(d, "occ1_dense.npy", "the words occ1/known1 say");
  d = Rich();
  d.meta["occupancy"]["counts0"]["free"] = 1;
  ExpectProblem(d, "occ0.npy", "free bins, the json's occupancy.counts0 says 1");
}

TEST(SampleCheck, JsonPosesAndIntrinsics) {
  Decoded d = Rich();
  d.meta["T_0to1"][0][3] = d.meta["T_0to1"][0][3].get<double>() + 0.01;
  ExpectProblem(d, "json", "T_0to1 differs from cam1_from_cam0");
  d = Rich();
  d.meta["K1"][0][1] = 0.5;
  ExpectProblem(d, "json", "K1: expected [[fx, 0, cx]");
  d = Rich();
  d.meta["world_from_cam0"][0][0] = 2.0;
  ExpectProblem(d, "json", "world_from_cam0: ");
}

TEST(SampleCheck, MembersAndImages) {
  Decoded d = Rich();
  d.fields.erase("depth1.npy");
  d.arrays.erase("depth1.npy");
  ExpectProblem(d, "depth1.npy", "missing (the sample holds the other depth)");
  d = Rich();
  d.fields.erase("occ1_dense.npy");
  d.arrays.erase("occ1_dense.npy");
  ExpectProblem(d, "occ1_dense.npy", "missing (the json's occupancy.encoding is \"both\")");
  d = Rich();
  d.fields.insert("extra.npy");
  ExpectProblem(d, "extra.npy", "not a member of a pair sample");
  d = Rich();
  d.images["image1.png"] = d.images["image1.png"].substr(0, 60);
  ExpectProblem(d, "image1.png", "truncated PNG");
  d = Rich();
  std::string& png = d.images["image0.png"];
  png[19] = static_cast<char>(png[19] + 1);  // IHDR width 64 -> 65
  ExpectProblem(d, "image0.png", "image is 65x48, expected the json's resolution 64x48");
}

}  // namespace
}  // namespace gt::shards

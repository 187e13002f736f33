// The value checks of a stored N-view sample (shards/views_sample_check.h): every sample of a
// real `occgt tuples --shards` build passes, its seen_by is views_truth's count, and each kind
// of damage to its members or json is named.
#include "libgt/shards/views_sample_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "libgt/io/npy.h"
#include "libgt/pipeline/covisibility.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/synthetic.h"
#include "libgt/pipeline/tuple_stage.h"
#include "libgt/shards/sample.h"
#include "libgt/shards/split.h"
#include "libgt/shards/tar_shard.h"
#include "libgt/truth/views_truth.h"
#include "tests/support/decoded_sample.h"
#include "tests/support/test_support.h"

namespace gt::shards {
namespace {

using nlohmann::json;

// One N-view sample as the checks take it: decoded members.
struct Decoded : test::DecodedSample {
  std::vector<std::string> Problems(std::vector<uint8_t>* seen_by = nullptr) const {
    std::vector<std::string> p = CheckViewsSampleMembers(meta, fields);
    for (std::string& q : CheckViewsSampleValues(meta, arrays, ImageViews(), seen_by)) {
      p.push_back(q);
    }
    return p;
  }
  int Views() const { return meta.at("num_views").get<int>(); }
  int Width() const { return meta.at("resolution")[0].get<int>(); }
  int Height() const { return meta.at("resolution")[1].get<int>(); }
  int64_t Tracks() const { return meta.at("tracks").at("count").get<int64_t>(); }
};

Decoded Decode(const Sample& s) { return {test::DecodeSample(s)}; }

// Every sample of `occgt covis` + `occgt tuples --shards` of the synthetic dataset: tuples of
// 3 or 4 views with images and tracks, tracks queried in view 1, deflate members.
const std::vector<Decoded>& Built() {
  static const std::vector<Decoded> samples = [] {
    const std::string data = test::ScratchDir("views_sample_check_data");
    pipeline::SyntheticDatasetOptions o;
    o.scenes = 1;
    o.frames = 10;
    o.width = 64;
    o.height = 48;
    pipeline::EnsureSyntheticDataset(data, o);
    const std::string yaml = R"(
name: vcheck
split: vcheck
seed: 3
resolution: [64, 48]
dataset: {format: generic, root: )" +
                             data + R"(, min_valid_depth_fraction: 0.2}
selection:
  pruning: {frustum: false, max_distance_m: 100, max_view_angle_deg: 180}
  score_stride: 2
  views: [3, 4]
  tuples: {edge_threshold: 0.05, restarts: 4, quota_per_scene: 4, num_tracks: 40, query_view: 1}
occupancy: {enabled: false}
sample: {image: png, depth: true, labels: true, occupancy: false, compression: deflate}
shards: {samples_per_shard: 100}
)";
    const pipeline::Recipe r = pipeline::ParseRecipe(yaml, "vcheck.yaml", "/");
    pipeline::CovisibilityOptions c;
    c.out_dir = test::ScratchDir("views_sample_check_out");
    pipeline::RunCovisibility(r, c, [](int64_t, int64_t) {});
    pipeline::RunTuples(r, c.out_dir, /*write_shards=*/true);
    std::vector<Decoded> all;
    for (const Sample& s : ReadShardSamples(ShardPath(c.out_dir + "/views", "vcheck", 0))) {
      all.push_back(Decode(s));
    }
    return all;
  }();
  return samples;
}

// The first sample with tracks VISIBLE and OCCLUDED in some view other than the query view.
Decoded Rich() {
  for (const Decoded& d : Built()) {
    Decoded copy = d;
    const uint8_t* state = copy.Data<uint8_t>("track_state.npy");
    bool visible = false, occluded = false;
    for (int j = 0; j < d.Views(); ++j) {
      for (int64_t k = 0; j != 1 && k < d.Tracks(); ++k) {
        visible |= state[j * d.Tracks() + k] == 0;
        occluded |= state[j * d.Tracks() + k] == 1;
      }
    }
    if (visible && occluded) return copy;
  }
  ADD_FAILURE() << "no sample with VISIBLE and OCCLUDED tracks off the query view";
  return Built().front();
}

// The first problem of `d`, which must start with `field` and contain `words`.
void ExpectProblem(const Decoded& d, const std::string& field, const std::string& words) {
  const std::vector<std::string> p = d.Problems();
  ASSERT_FALSE(p.empty()) << "no problem found; expected " << field << ": ..." << words;
  EXPECT_EQ(p.front().rfind(field + ": ", 0), 0u) << p.front();
  EXPECT_NE(p.front().find(words), std::string::npos) << p.front();
}

// The first (view, track) of `d` off the query view in `state`.
std::pair<int, int64_t> TrackIn(Decoded& d, uint8_t state) {
  const uint8_t* s = d.Data<uint8_t>("track_state.npy");
  for (int j = 0; j < d.Views(); ++j) {
    for (int64_t k = 0; j != 1 && k < d.Tracks(); ++k) {
      if (s[j * d.Tracks() + k] == state) return {j, k};
    }
  }
  ADD_FAILURE() << "no track in state " << int(state);
  return {0, 0};
}

TEST(ViewsSampleCheck, EverySampleOfABuildIsConsistentAndItsSeenByIsTheCount) {
  ASSERT_GE(Built().size(), 2u);
  for (const Decoded& d : Built()) {
    std::vector<uint8_t> seen_by;
    EXPECT_EQ(d.Problems(&seen_by), std::vector<std::string>{}) << d.key;
    EXPECT_EQ(d.meta.at("tracks").at("query_view"), 1) << d.key;
    EXPECT_GT(d.Tracks(), 0) << d.key;
    EXPECT_EQ(d.images.size(), static_cast<size_t>(d.Views())) << d.key;
    Decoded c = d;
    const size_t plane = static_cast<size_t>(d.Width()) * d.Height();
    const truth::SeenBy want = truth::CountSeenBy(c.Data<uint32_t>("visible_in.npy"),
                                                  c.Data<uint8_t>("valid.npy"), d.Views(), plane);
    EXPECT_EQ(seen_by, want.seen_by) << d.key;
  }
}

TEST(ViewsSampleCheck, ValidIsTheDepthsMaskAndDepthIsFinite) {
  Decoded d = Rich();
  const float* z = d.Data<float>("depth2.npy");
  int p = 0;
  while (!(z[p] > 0)) ++p;
  d.Data<uint8_t>("valid.npy")[2 * 64 * 48 + p] = 0;
  ExpectProblem(d, "valid.npy",
                "view 2 pixel (" + std::to_string(p % 64) + ", " + std::to_string(p / 64) +
                    ") holds 0; its depth");
  d = Rich();
  d.Data<float>("depth0.npy")[70] = std::nanf("");
  ExpectProblem(d, "depth0.npy", "pixel (6, 1) holds nan; expected metres >= 0");
  d = Rich();
  d.meta["label_options"]["max_depth_m"] = 0.5;  // every stored valid pixel is now too far
  ExpectProblem(d, "valid.npy", "in label_options' range [");
}

TEST(ViewsSampleCheck, AnUnboundedDepthRangeIsNullInTheJson) {
  Decoded d = Rich();
  d.meta["label_options"]["max_depth_m"] = nullptr;
  EXPECT_EQ(d.Problems(), std::vector<std::string>{});
}

TEST(ViewsSampleCheck, CamerasEqualTheJsons) {
  Decoded d = Rich();
  d.Data<double>("intrinsics.npy")[9 + 2] += 0.5;  // view 1's cx
  ExpectProblem(d, "intrinsics.npy", "view 1 (0, 2) holds");
  d = Rich();
  d.Data<double>("world_from_cam.npy")[16 * 2 + 3] += 1e-9;  // view 2's t_x
  ExpectProblem(d, "world_from_cam.npy", "the json's world_from_cam[2] says");
  d = Rich();
  d.meta["world_from_cam"][1][0][0] = 2.0;
  ExpectProblem(d, "json", "world_from_cam[1]: ");
  d = Rich();
  d.meta["K"][0][1][0] = 0.5;
  ExpectProblem(d, "json", "K[0]: expected [[fx, 0, cx]");
  d = Rich();
  d.meta["frames"][1]["id"] = d.meta["frames"][0]["id"];
  ExpectProblem(d, "json", "appears twice");
}

TEST(ViewsSampleCheck, BitsAndMetrics) {
  Decoded d = Rich();
  d.Data<uint32_t>("visible_in.npy")[0] |= 1u << 7;  // a view the tuple does not have
  ExpectProblem(d, "visible_in.npy", "bit for a view >= ");
  // A VISIBLE bit off the diagonal cleared: every structural rule still holds, the counts
  // do not.
  d = Rich();
  uint32_t* vis = d.Data<uint32_t>("visible_in.npy");
  size_t p = 0;
  while ((vis[p] & ~1u) == 0) ++p;  // view 0: a pixel visible in another view
  const uint32_t others = vis[p] & ~1u;
  vis[p] &= ~(others & (~others + 1));  // its lowest such bit
  ExpectProblem(d, "visible_in.npy", "its counts.VISIBLE is ");
  d = Rich();
  d.meta["metrics"]["counts"]["OCCLUDED"] = d.meta["metrics"]["counts"]["OCCLUDED"].get<int>() + 1;
  ExpectProblem(d, "occluded_in.npy", "the json's metrics.counts.OCCLUDED says");
  d = Rich();
  d.meta["metrics"]["valid"] = 3;
  ExpectProblem(d, "valid.npy", "its valid is ");
  d = Rich();
  d.meta["metrics"]["occlusion_ratio_visible"] = 0.5;
  ExpectProblem(d, "occluded_in.npy", "its occlusion_ratio_visible is ");
}

TEST(ViewsSampleCheck, QueriesAreTheSamplingRules) {
  Decoded d = Rich();
  int32_t* q = d.Data<int32_t>("queries.npy");
  std::swap(q[0], q[2]);  // two queries' u swapped: no longer the rule's pixels
  std::swap(q[1], q[3]);
  ExpectProblem(d, "queries.npy", "query 0 is (");
  d = Rich();
  d.meta["tracks"]["seed"] = d.meta["tracks"]["seed"].get<uint64_t>() + 1;
  ExpectProblem(d, "queries.npy", "with tracks.seed ");
}

TEST(ViewsSampleCheck, TracksAgreeWithTheBitsAndTheirDepths) {
  Decoded d = Rich();
  auto [j, k] = TrackIn(d, 0);
  d.Data<uint8_t>("track_state.npy")[j * d.Tracks() + k] = 2;  // VISIBLE -> OUT_OF_VIEW
  ExpectProblem(d, "track_state.npy",
                "is OUT_OF_VIEW while bit " + std::to_string(j) + " of visible_in is set");
  d = Rich();
  std::tie(j, k) = TrackIn(d, 1);
  d.Data<uint8_t>("track_state.npy")[j * d.Tracks() + k] = 4;  // OCCLUDED -> INCONSISTENT
  ExpectProblem(d, "track_state.npy",
                "is INCONSISTENT while bit " + std::to_string(j) + " of occluded_in is set");
  d = Rich();
  d.Data<float>("track_xy.npy")[2 * (1 * d.Tracks() + 0)] += 1;  // query view 1, track 0
  ExpectProblem(d, "track_state.npy", "at its own view is (");
  d = Rich();
  std::tie(j, k) = TrackIn(d, 0);
  d.Data<float>("track_depth.npy")[j * d.Tracks() + k] = std::nanf("");
  ExpectProblem(d, "track_depth.npy", "expected NaN exactly where track_xy is");
}

TEST(ViewsSampleCheck, MembersShapesAndImages) {
  Decoded d = Rich();
  d.fields.erase("depth1.npy");
  d.arrays.erase("depth1.npy");
  ExpectProblem(d, "depth1.npy", "missing (the json's num_views is ");
  d = Rich();
  d.fields.erase("image2.png");
  d.images.erase("image2.png");
  ExpectProblem(d, "image2.png", "missing (the json's image.format is \"png\")");
  d = Rich();
  d.fields.insert("label01.npy");
  ExpectProblem(d, "label01.npy", "not a member of an N-view sample");
  d = Rich();
  d.arrays.at("valid.npy").shape = {1, 48 * 64};
  ExpectProblem(d, "valid.npy", "expected |u1 [");
  d = Rich();
  d.images["image1.png"] = d.images["image1.png"].substr(0, 60);
  ExpectProblem(d, "image1.png", "truncated PNG");
  d = Rich();
  d.meta["image"] = nullptr;
  const std::vector<std::string> p = d.Problems();
  ASSERT_FALSE(p.empty());
  EXPECT_NE(p.front().find("not a member of an N-view sample"), std::string::npos) << p.front();
}

}  // namespace
}  // namespace gt::shards

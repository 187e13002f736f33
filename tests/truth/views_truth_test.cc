// libgt/truth/views_truth: the N-view bitmasks equal the pair labels (LabelDirection, called
// directly here) for every ordered pair i != j, bit for bit, and the diagonal is the view's
// depth mask (equal to the pair labeller's self-answer under the default preset); tracks equal
// the pair warps at the query pixels, and the query pixels themselves in the query view;
// statistics against a count done here; the same result with 1 and 2 threads; the sampling
// rule; bad inputs named.
#include "libgt/truth/views_truth.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/synth/dataset.h"
#include "libgt/truth/working_frame.h"
#include "tests/support/test_support.h"

namespace gt::truth {
namespace {

// A synthetic room of 24 frames at 80×60 (exact ray-cast depth), generated once.
const Scene& SynthScene() {
  static const Scene scene = [] {
    const std::string dir = test::ScratchDir("views_truth_synth");
    synth::SynthOptions o;
    o.scenes = 1;
    o.frames_per_scene = 24;
    o.width = 80;
    o.height = 60;
    synth::WriteSyntheticDataset(dir, o);
    const auto reader = datasets::MakeReader(gt::DatasetFormat::kGeneric);
    return reader->ReadScene(dir, reader->ListScenes(dir).at(0));
  }();
  return scene;
}

std::vector<WorkingFrame> Views(const std::vector<int>& indices) {
  std::vector<WorkingFrame> out;
  for (int i : indices) out.push_back(LoadWorkingFrame(SynthScene().frames[i], {80, 60}));
  return out;
}

ViewsTruthOptions Options(const std::string& preset) {
  ViewsTruthOptions o;
  o.labels = LabelPreset(preset);
  if (o.labels.dataset_depth_range) {
    ApplyDatasetDepthRange(SynthScene().min_depth_m, SynthScene().max_depth_m, &o.labels);
  }
  o.num_tracks = 100;
  o.query_view = 1;
  o.seed = 7;
  return o;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool SameFloat(float a, float b) {  // bit for bit (NaN == NaN of the same bits)
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// Every ordered pair i != j against LabelDirection, the diagonal against the depth mask;
// returns the number of VISIBLE and OCCLUDED bits seen off the diagonal (the scene must have
// both for the test to mean anything).
void ExpectBitsEqualPairLabels(const std::vector<WorkingFrame>& views, const ViewsTruth& t,
                               const LabelOptions& lo, int64_t* visible, int64_t* occluded) {
  const int n = static_cast<int>(views.size());
  const size_t hw = static_cast<size_t>(t.width) * t.height;
  for (int i = 0; i < n; ++i) {
    int64_t diagonal_mismatches = 0;
    for (size_t p = 0; p < hw; ++p) {
      diagonal_mismatches += ((t.visible_in[hw * i + p] >> i) & 1u) != t.valid[hw * i + p];
      diagonal_mismatches += (t.occluded_in[hw * i + p] >> i) & 1u;
    }
    EXPECT_EQ(diagonal_mismatches, 0) << "view " << i << " against itself";
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      const DirectionLabels l =
          LabelDirection(*views[i].depth, views[i].camera, *views[j].depth, views[j].camera,
                         RelativePose(views[i].world_from_cam, views[j].world_from_cam), lo);
      int64_t mismatches = 0;
      for (size_t p = 0; p < hw; ++p) {
        const bool vis = (t.visible_in[hw * i + p] >> j) & 1u;
        const bool occ = (t.occluded_in[hw * i + p] >> j) & 1u;
        const PixelLabel label = static_cast<PixelLabel>(l.labels[p]);
        mismatches += vis != (label == PixelLabel::kVisible);
        mismatches += occ != (label == PixelLabel::kOccluded);
        *visible += vis;
        *occluded += occ;
      }
      EXPECT_EQ(mismatches, 0) << "views " << i << " -> " << j;
    }
  }
  for (size_t p = 0; p < t.visible_in.size(); ++p) {  // no bit above N
    ASSERT_EQ(t.visible_in[p] >> n, 0u);
    ASSERT_EQ(t.occluded_in[p] >> n, 0u);
  }
}

TEST(ComputeViewsTruth, BitsEqualThePairLabelsForEveryOrderedPair) {
  const std::vector<WorkingFrame> views = Views({0, 2, 5, 8, 11, 14, 17, 20});
  for (const char* preset : {"default", "occ2net", "loftr", "occ2net-compat"}) {
    SCOPED_TRACE(preset);
    const ViewsTruthOptions o = Options(preset);
    const ViewsTruth t = ComputeViewsTruth(views, o);
    ASSERT_EQ(t.num_views, 8);
    ASSERT_EQ(t.width, 80);
    ASSERT_EQ(t.height, 60);
    int64_t visible = 0, occluded = 0;
    ExpectBitsEqualPairLabels(views, t, o.labels, &visible, &occluded);
    EXPECT_GT(visible, 1000);  // the frames overlap ...
    EXPECT_GT(occluded, 10);   // ... and the room's furniture occludes
  }
}

TEST(ComputeViewsTruth, TracksEqualThePairWarpsAtTheQueryPixels) {
  const std::vector<WorkingFrame> views = Views({0, 2, 5, 8, 11, 14, 17, 20});
  ViewsTruthOptions o = Options("default");
  o.num_tracks = 1000;
  const ViewsTruth t = ComputeViewsTruth(views, o);
  const size_t nq = t.num_queries();
  ASSERT_EQ(nq, 1000u);
  const int q = o.query_view;
  std::set<int> states;
  for (int j = 0; j < 8; ++j) {
    const Rigid3d j_from_q = RelativePose(views[q].world_from_cam, views[j].world_from_cam);
    const DirectionLabels l = LabelDirection(*views[q].depth, views[q].camera, *views[j].depth,
                                             views[j].camera, j_from_q, o.labels);
    for (size_t k = 0; k < nq; ++k) {
      const int u = t.queries[2 * k], v = t.queries[2 * k + 1];
      const size_t p = static_cast<size_t>(v) * 80 + u;
      const uint8_t state = t.track_state[nq * j + k];
      if (j == q) {  // the query pixel itself, visible (the queries are valid pixels)
        EXPECT_EQ(t.track_xy[2 * (nq * j + k)], static_cast<float>(u));
        EXPECT_EQ(t.track_xy[2 * (nq * j + k) + 1], static_cast<float>(v));
        EXPECT_EQ(t.track_depth[nq * j + k], views[q].depth->at(u, v));
        EXPECT_EQ(state, static_cast<uint8_t>(TrackState::kVisible));
      } else {
        EXPECT_TRUE(SameFloat(t.track_xy[2 * (nq * j + k)], l.warped_xy[2 * p])) << j << " " << k;
        EXPECT_TRUE(SameFloat(t.track_xy[2 * (nq * j + k) + 1], l.warped_xy[2 * p + 1]));
        EXPECT_EQ(state, static_cast<uint8_t>(TrackStateOf(l.at(u, v)))) << j << " " << k;
      }
      states.insert(state);
      // The depth there: z of the point in camera j, to float rounding (double here).
      const float d = views[q].depth->at(u, v);
      const Eigen::Vector3d p_in_q(d * (u - views[q].camera.cx) / views[q].camera.fx,
                                   d * (v - views[q].camera.cy) / views[q].camera.fy, d);
      const double z = (j_from_q * p_in_q).z();
      const float got = t.track_depth[nq * j + k];
      if (z > o.labels.min_depth_m) {
        EXPECT_NEAR(got, z, 1e-4 * std::abs(z) + 1e-5) << j << " " << k;
      } else {
        EXPECT_TRUE(std::isnan(got));
      }
      // The state agrees with the bitmasks of the query view.
      const uint32_t bit = 1u << j;
      EXPECT_EQ(state == static_cast<uint8_t>(TrackState::kVisible),
                (t.visible_in[80 * 60 * q + p] & bit) != 0);
      EXPECT_EQ(state == static_cast<uint8_t>(TrackState::kOccluded),
                (t.occluded_in[80 * 60 * q + p] & bit) != 0);
    }
  }
  EXPECT_GE(states.size(), 3u);  // visible, out of view and occluded at least
  // Given queries are used as they are (no depth at one of them: NO_DEPTH everywhere).
  std::vector<int32_t> given = {0, 0, 79, 59, 40, 30};
  const ViewsTruth g = ComputeViewsTruth(views, o, given);
  EXPECT_EQ(g.queries, given);
  EXPECT_EQ(g.num_queries(), 3u);
  // A given query without valid depth is NO_DEPTH in its own view too, with NaN position.
  std::vector<WorkingFrame> holed = views;
  auto depth = std::make_shared<DepthImage>(*views[q].depth);
  depth->values_m[30 * 80 + 40] = 0.0f;
  holed[q].depth = depth;
  const ViewsTruth h = ComputeViewsTruth(holed, o, given);
  for (int j = 0; j < 8; ++j) {
    EXPECT_EQ(h.track_state[3 * j + 2], static_cast<uint8_t>(TrackState::kNoDepth)) << j;
    EXPECT_TRUE(std::isnan(h.track_xy[2 * (3 * j + 2)])) << j;
    EXPECT_TRUE(std::isnan(h.track_depth[3 * j + 2])) << j;
  }
}

// The diagonal is the depth mask by definition; the pair labeller's answer for a view against
// itself (the identity pose, as RelativePose computes it) agrees with it under the default
// preset (pixel-area bounds, nearest lookup), pixel for pixel. Under occ2net-compat it does
// not: its projection epsilon pulls every pixel a little towards the principal point, and the
// truncating lookup then reads the neighbouring pixel (docs/MULTIVIEW.md).
TEST(ComputeViewsTruth, DiagonalIsTheDepthMaskAsThePairLabellerSaysUnderTheDefaultPreset) {
  const std::vector<WorkingFrame> views = Views({0, 5, 11});
  for (const char* preset : {"default", "occ2net-compat"}) {
    SCOPED_TRACE(preset);
    const ViewsTruthOptions o = Options(preset);
    const ViewsTruth t = ComputeViewsTruth(views, o);
    const size_t hw = 80 * 60;
    int64_t differ = 0;
    for (int i = 0; i < 3; ++i) {
      const DirectionLabels self =
          LabelDirection(*views[i].depth, views[i].camera, *views[i].depth, views[i].camera,
                         RelativePose(views[i].world_from_cam, views[i].world_from_cam), o.labels);
      for (size_t p = 0; p < hw; ++p) {
        ASSERT_EQ((t.visible_in[hw * i + p] >> i) & 1u, t.valid[hw * i + p]);
        differ += (self.labels[p] == static_cast<uint8_t>(PixelLabel::kVisible)) !=
                  (t.valid[hw * i + p] == 1);
      }
    }
    if (std::string(preset) == "default") {
      EXPECT_EQ(differ, 0);
    } else {
      EXPECT_GT(differ, 0);  // the reason the diagonal is not the self-pair's labels
    }
  }
}

TEST(ComputeViewsTruth, StatisticsCountTheOtherViewsThatSeeAPixel) {
  const std::vector<WorkingFrame> views = Views({0, 1, 2, 6, 12});
  const ViewsTruthOptions o = Options("default");
  const ViewsTruth t = ComputeViewsTruth(views, o);
  const size_t hw = 80 * 60;
  std::vector<int64_t> hist(25, 0);
  for (int i = 0; i < 5; ++i) {
    for (size_t p = 0; p < hw; ++p) {
      const float d = views[i].depth->values_m[p];
      const bool ok = IsValidDepth(d, o.labels.min_depth_m, o.labels.max_depth_m);
      ASSERT_EQ(t.valid[hw * i + p], ok ? 1 : 0);
      int k = 0;
      for (int j = 0; j < 5; ++j) k += j != i && ((t.visible_in[hw * i + p] >> j) & 1u);
      ASSERT_EQ(t.seen_by[hw * i + p], k);
      if (ok) ++hist[5 * i + k];
      // A pixel with valid depth is VISIBLE in its own view (identity pose, default preset).
      EXPECT_EQ((t.visible_in[hw * i + p] >> i) & 1u, ok ? 1u : 0u);
    }
  }
  EXPECT_EQ(t.seen_by_histogram, hist);
}

TEST(CountSeenBy, StoredBitmasksGiveTheStatisticsOfComputeViewsTruth) {
  for (const std::vector<int>& indices : {std::vector<int>{3}, std::vector<int>{0, 1, 2, 6, 12}}) {
    ViewsTruthOptions o = Options("default");
    o.query_view = 0;  // one view: its own
    const ViewsTruth t = ComputeViewsTruth(Views(indices), o);
    const SeenBy s = CountSeenBy(t.visible_in.data(), t.valid.data(), t.num_views,
                                 static_cast<size_t>(t.width) * t.height);
    EXPECT_TRUE(std::equal(s.seen_by.begin(), s.seen_by.end(), t.seen_by.begin(), t.seen_by.end()));
    EXPECT_EQ(s.histogram, t.seen_by_histogram);
  }
}

TEST(CountSeenBy, RefusesBitsOfAbsentViewsAndValidOtherThanZeroOrOne) {
  std::vector<uint32_t> vis = {1u, 3u, 2u, 0u};  // 2 views of 2 pixels
  std::vector<uint8_t> valid = {1, 1, 1, 0};
  const SeenBy s = CountSeenBy(vis.data(), valid.data(), 2, 2);
  EXPECT_EQ(s.seen_by, (std::vector<uint8_t>{0, 1, 0, 0}));
  EXPECT_EQ(s.histogram, (std::vector<int64_t>{1, 1, 1, 0}));
  vis[3] = 4u;  // view 2 of 2 views
  EXPECT_EQ(ErrorOf([&] { CountSeenBy(vis.data(), valid.data(), 2, 2); }),
            "visible_in: bit for a view >= 2 (the number of views) set at element 3");
  vis[3] = 0u;
  valid[2] = 7;
  EXPECT_EQ(ErrorOf([&] { CountSeenBy(vis.data(), valid.data(), 2, 2); }),
            "valid: expected 0 or 1, got 7 at element 2");
  EXPECT_EQ(ErrorOf([&] { CountSeenBy(vis.data(), valid.data(), 33, 0); }),
            "visible_in: expected 1..32 views, got 33");
  // 32 views: every bit is a view's.
  std::vector<uint32_t> all(32, ~0u);
  std::vector<uint8_t> ones(32, 1);
  const SeenBy full = CountSeenBy(all.data(), ones.data(), 32, 1);
  EXPECT_EQ(full.seen_by, std::vector<uint8_t>(32, 31));
  EXPECT_EQ(full.histogram[31], 1);
}

// What every ComputeViewsTruth result satisfies, under every preset, and one damaged element
// of each kind refused by name.
TEST(CheckStoredViewsTruth, PassesEveryComputedResultAndNamesEachDamage) {
  const auto check = [](const ViewsTruth& t) {
    CheckStoredViewsTruth(t.visible_in.data(), t.occluded_in.data(), t.valid.data(), t.num_views,
                          static_cast<size_t>(t.width) * t.height, t.track_xy.data(),
                          t.track_state.data(), t.num_queries());
  };
  for (const char* preset : {"default", "occ2net", "loftr", "occ2net-compat"}) {
    ViewsTruthOptions o = Options(preset);
    o.query_view = 1;
    const ViewsTruth t = ComputeViewsTruth(Views({0, 1, 2, 6, 12}), o);
    EXPECT_EQ(ErrorOf([&] { check(t); }), "") << preset;
    // It returns the statistics ComputeViewsTruth gave (the arrays are read once).
    const SeenBy s =
        CheckStoredViewsTruth(t.visible_in.data(), t.occluded_in.data(), t.valid.data(),
                              t.num_views, static_cast<size_t>(t.width) * t.height,
                              t.track_xy.data(), t.track_state.data(), t.num_queries());
    EXPECT_TRUE(std::equal(s.seen_by.begin(), s.seen_by.end(), t.seen_by.begin(), t.seen_by.end()))
        << preset;
    EXPECT_EQ(s.histogram, t.seen_by_histogram) << preset;
  }
  const ViewsTruth good = ComputeViewsTruth(Views({0, 2, 6}), Options("default"));
  const size_t hw = static_cast<size_t>(good.width) * good.height;
  size_t p = 0;  // a valid pixel of view 0 that view 1 sees (bits 0 and 1)
  while (!(good.valid[p] == 1 && (good.visible_in[p] & 2u))) ++p;
  size_t invalid = 0;  // a pixel of view 0 without depth
  while (good.valid[invalid] == 1) ++invalid;
  ASSERT_LT(p, hw);
  ASSERT_LT(invalid, hw);
  size_t k = 0;  // a track VISIBLE in view 1
  while (good.track_state[good.num_queries() + k] != static_cast<uint8_t>(TrackState::kVisible)) {
    ++k;
  }
  const size_t in1 = good.num_queries() + k;
  struct Case {
    std::function<void(ViewsTruth&)> damage;
    std::string message;
  };
  const std::string at_p = " at element " + std::to_string(p);
  const std::vector<Case> cases = {
      {[&](ViewsTruth& t) { t.visible_in[p] |= 8u; },
       "visible_in: bit for a view >= 3 (the number of views) set" + at_p},
      {[&](ViewsTruth& t) { t.occluded_in[p] |= 1u << 31; },
       "occluded_in: bit for a view >= 3 (the number of views) set" + at_p},
      {[&](ViewsTruth& t) { t.valid[p] = 2; }, "valid: expected 0 or 1, got 2" + at_p},
      {[&](ViewsTruth& t) { t.occluded_in[p] |= 2u; },
       "occluded_in: a pixel both VISIBLE (visible_in) and OCCLUDED in one view" + at_p},
      {[&](ViewsTruth& t) { t.valid[p] = 0; },
       "visible_in: a bit set for a pixel without valid depth (valid = 0)" + at_p},
      {[&](ViewsTruth& t) { t.occluded_in[invalid] = 4u; },
       "occluded_in: a bit set for a pixel without valid depth (valid = 0) at element " +
           std::to_string(invalid)},
      {[&](ViewsTruth& t) { t.visible_in[p] &= ~1u; },
       "visible_in: view 0's own bit (the diagonal) not set for a valid pixel" + at_p},
      {[&](ViewsTruth& t) { t.track_state[in1] = 5; },
       "track_state: expected 0..4, got 5 at element " + std::to_string(in1)},
      {[&](ViewsTruth& t) { t.track_xy[2 * in1 + 1] = std::numeric_limits<float>::infinity(); },
       "track_xy: expected (x, y) both finite or both NaN at element " + std::to_string(2 * in1)},
      {[&](ViewsTruth& t) { t.track_xy[2 * in1] = std::numeric_limits<float>::quiet_NaN(); },
       "track_xy: expected (x, y) both finite or both NaN at element " + std::to_string(2 * in1)},
      {[&](ViewsTruth& t) {
         t.track_xy[2 * in1] = t.track_xy[2 * in1 + 1] = std::numeric_limits<float>::quiet_NaN();
       },
       "track_xy: NaN for a track whose state is VISIBLE (a projected point has a position) at "
       "element " +
           std::to_string(2 * in1)},
  };
  for (const Case& c : cases) {
    ViewsTruth t = good;
    c.damage(t);
    EXPECT_EQ(ErrorOf([&] { check(t); }), c.message);
  }
  ViewsTruth t = good;  // a track state that is not projected may have no position
  t.track_state[in1] = static_cast<uint8_t>(TrackState::kOutOfView);
  t.track_xy[2 * in1] = t.track_xy[2 * in1 + 1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(ErrorOf([&] { check(t); }), "");
}

TEST(ComputeViewsTruth, IdenticalViewsSeeEachOther) {
  const std::vector<WorkingFrame> views = Views({4, 4, 4});
  const ViewsTruth t = ComputeViewsTruth(views, Options("default"));
  for (size_t p = 0; p < t.visible_in.size(); ++p) {
    ASSERT_EQ(t.visible_in[p], t.valid[p] ? 7u : 0u);
    ASSERT_EQ(t.occluded_in[p], 0u);
  }
}

TEST(ComputeViewsTruth, SameBytesWithOneAndTwoThreads) {
  const std::vector<WorkingFrame> views = Views({0, 3, 6, 9, 12, 15});
  const ViewsTruthOptions o = Options("default");
  ViewsTruth a, b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    a = ComputeViewsTruth(views, o);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    b = ComputeViewsTruth(views, o);
  }
  EXPECT_EQ(a.visible_in, b.visible_in);
  EXPECT_EQ(a.occluded_in, b.occluded_in);
  EXPECT_EQ(a.seen_by, b.seen_by);
  EXPECT_EQ(a.seen_by_histogram, b.seen_by_histogram);
  EXPECT_EQ(a.queries, b.queries);
  EXPECT_EQ(0, std::memcmp(a.track_xy.data(), b.track_xy.data(), a.track_xy.size() * 4));
  EXPECT_EQ(0, std::memcmp(a.track_depth.data(), b.track_depth.data(), a.track_depth.size() * 4));
  EXPECT_EQ(a.track_state, b.track_state);
}

TEST(SampleQueries, DistinctValidPixelsInRasterOrderDeterminedByTheSeed) {
  const WorkingFrame f = Views({5})[0];
  LabelOptions lo = LabelPreset("default");
  const std::vector<int32_t> a = SampleQueries(*f.depth, lo, 300, 1);
  ASSERT_EQ(a.size(), 600u);
  EXPECT_EQ(a, SampleQueries(*f.depth, lo, 300, 1));
  EXPECT_NE(a, SampleQueries(*f.depth, lo, 300, 2));
  std::vector<int> raster;
  for (size_t k = 0; k < a.size(); k += 2) {
    EXPECT_TRUE(IsValidDepth(f.depth->at(a[k], a[k + 1]), lo.min_depth_m, lo.max_depth_m));
    raster.push_back(a[k + 1] * 80 + a[k]);
  }
  EXPECT_TRUE(std::is_sorted(raster.begin(), raster.end()));
  EXPECT_EQ(std::set<int>(raster.begin(), raster.end()).size(), raster.size());
  // More tracks than valid pixels: every valid pixel once.
  lo.max_depth_m = 2.0;  // fewer valid pixels
  int64_t valid = 0;
  for (float d : f.depth->values_m) valid += IsValidDepth(d, lo.min_depth_m, lo.max_depth_m);
  EXPECT_EQ(SampleQueries(*f.depth, lo, 100000, 3).size(), 2u * valid);
}

TEST(ComputeViewsTruth, BadInputsAreNamed) {
  const std::vector<WorkingFrame> few = Views({0, 1});
  const ViewsTruthOptions o = Options("default");
  std::vector<WorkingFrame> many(33, few[0]);
  EXPECT_EQ(ErrorOf([&] { ComputeViewsTruth(many, o); }), "views: expected 1..32 views, got 33");
  EXPECT_EQ(ErrorOf([&] { ComputeViewsTruth({}, o); }), "views: expected 1..32 views, got 0");
  std::vector<WorkingFrame> sized = few;
  sized[1] = LoadWorkingFrame(SynthScene().frames[1], {40, 30});
  EXPECT_EQ(ErrorOf([&] { ComputeViewsTruth(sized, o); }),
            "views[1].depth: expected 80x60 (the size of view 0), got 40x30");
  std::vector<WorkingFrame> posed = few;
  posed[1].world_from_cam.matrix()(0, 0) = 2.0;  // not a rotation
  EXPECT_NE(ErrorOf([&] { ComputeViewsTruth(posed, o); }).find("views[1].world_from_cam: "),
            std::string::npos);
  ViewsTruthOptions q = o;
  q.query_view = 2;
  EXPECT_EQ(ErrorOf([&] { ComputeViewsTruth(few, q); }),
            "options: query_view: expected < 2 (the number of views), got 2");
  EXPECT_NE(ErrorOf([&] {
              ComputeViewsTruth(few, o, std::vector<int32_t>{80, 0});
            }).find("queries: expected pixels (u, v) inside the 80x60 image, got (80, 0)"),
            std::string::npos);
  ViewsTruthOptions neg = o;
  neg.num_tracks = -1;
  EXPECT_EQ(ErrorOf([&] { ComputeViewsTruth(few, neg); }),
            "options: num_tracks: expected >= 0, got -1");
}

}  // namespace
}  // namespace gt::truth

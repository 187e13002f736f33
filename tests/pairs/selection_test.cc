// Pair selection: candidates, pruning, scoring on analytic scenes (closed-form overlap),
// filters with min/mean/max aggregation, quota, balancing, seeded sampling, drop counts
// that add up, and determinism under the number of threads.
#include "libgt/pairs/selection.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>
#include <set>

#include "libgt/core/error.h"
#include "libgt/io/npy.h"
#include "tests/support/test_support.h"

namespace gt::pairs {
namespace {

constexpr int kW = 64, kH = 48;

Camera TestCamera() {
  Camera c;
  c.width = kW;
  c.height = kH;
  c.fx = c.fy = 32.0;
  c.cx = 31.5;
  c.cy = 23.5;
  return c;
}

Rigid3d Translated(double x, double y, double z) {
  Rigid3d t = Rigid3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

// A scene of frames looking down +z at a fronto-parallel plane at z = plane_m (world),
// camera i at x = x_m[i]. Depth of every pixel is plane_m - camera z.
Scene PlaneScene(const std::string& dir, const std::vector<double>& x_m, double plane_m = 2.0,
                 double valid_fraction = 1.0) {
  Scene scene;
  scene.name = "plane";
  for (size_t i = 0; i < x_m.size(); ++i) {
    Frame f;
    f.id = std::to_string(i);
    f.number = static_cast<int64_t>(i);
    f.depth_camera = TestCamera();
    f.world_from_cam = Translated(x_m[i], 0, 0);
    std::vector<float> depth(kW * kH, static_cast<float>(plane_m));
    const int invalid_rows = static_cast<int>(std::lround((1.0 - valid_fraction) * kH));
    for (int v = 0; v < invalid_rows; ++v) {
      for (int u = 0; u < kW; ++u) depth[v * kW + u] = 0.0f;
    }
    f.depth.path = dir + "/d" + std::to_string(i) + ".npy";
    f.depth.format = DepthFormat::kNpyFloat32;
    io::WriteNpy<float>(f.depth.path, {kH, kW}, depth);
    scene.frames.push_back(f);
  }
  return scene;
}

std::vector<Camera> Cameras(const Scene& scene) {
  std::vector<Camera> cams;
  for (const auto& f : scene.frames) cams.push_back(f.depth_camera);
  return cams;
}

int64_t Sum(const DropCounts& d, const std::string& prefix) {
  int64_t n = 0;
  for (const auto& [k, v] : d) n += k.rfind(prefix, 0) == 0 ? v : 0;
  return n;
}

TEST(Candidates, CountsMatchClosedForm) {
  std::vector<size_t> kept = {0, 2, 3, 7, 9, 11};
  EXPECT_EQ(GenerateCandidates(kept, 0).size(), 15u);  // n(n-1)/2
  EXPECT_EQ(GenerateCandidates(kept, 1).size(), 5u);
  // gap g: sum over a of min(g, n-1-a)
  for (int g = 1; g <= 7; ++g) {
    size_t expected = 0;
    for (size_t a = 0; a < kept.size(); ++a) expected += std::min<size_t>(g, kept.size() - 1 - a);
    auto c = GenerateCandidates(kept, g);
    EXPECT_EQ(c.size(), expected) << g;
    std::set<std::pair<size_t, size_t>> unique;
    for (const auto& p : c) {
      EXPECT_LT(p.i0, p.i1);
      unique.insert({p.i0, p.i1});
    }
    EXPECT_EQ(unique.size(), c.size());
  }
  EXPECT_TRUE(GenerateCandidates({4}, 0).empty());
}

TEST(Pruning, ViewAngleAndFrustumAnalytic) {
  const Rigid3d a = Rigid3d::Identity();
  Rigid3d turned = Rigid3d::Identity();
  turned.linear() = Eigen::AngleAxisd(M_PI / 3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(ViewAngleDeg(a, turned), 60.0, 1e-9);
  Rigid3d back = Rigid3d::Identity();
  back.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(ViewAngleDeg(a, back), 180.0, 1e-9);
  const Camera cam = TestCamera();
  EXPECT_TRUE(FrustumsIntersect(cam, a, 2.0, cam, Translated(0.5, 0, 0)));
  // B behind A, looking backwards: A's frustum (z > 0) is behind B.
  Rigid3d b = back;
  b.translation() = Eigen::Vector3d(0, 0, -1);
  EXPECT_FALSE(FrustumsIntersect(cam, a, 2.0, cam, b));
  // Far sideways (the field of view is 90°: at 2 m it spans x in [-2, 2]; at 4 m [-4, 4]).
  EXPECT_FALSE(FrustumsIntersect(cam, a, 2.0, cam, Translated(50, 0, 0)));
}

TEST(Pruning, DropCountsAddUp) {
  const std::string dir = test::ScratchDir("pairs_prune");
  Scene scene = PlaneScene(dir, {0.0, 0.2, 0.5, 3.0, 60.0});
  std::map<size_t, double> medians;
  for (size_t i = 0; i < scene.frames.size(); ++i) medians[i] = 2.0;
  auto cands = GenerateCandidates({0, 1, 2, 3, 4}, 0);
  PruningOptions o;
  o.max_distance_m = 10.0;
  DropCounts drops;
  auto kept = PruneCandidates(scene, Cameras(scene), cands, medians, o, &drops);
  EXPECT_EQ(kept.size() + Sum(drops, "prune."), cands.size());
  EXPECT_EQ(drops["prune.distance"], 4);  // every pair with frame 4 (>= 57 m apart)
  EXPECT_EQ(drops["prune.frustum"], 0);   // 90° field of view: 3 m apart still overlap at 4 m
  for (const auto& c : kept) EXPECT_NE(c.i1, 4u);
}

TEST(Scoring, SidewaysShiftOverPlaneHasClosedFormOverlap) {
  const std::string dir = test::ScratchDir("pairs_score");
  // Plane at 2 m, fx = 32: a shift of 1 m moves the image by 16 px of 64: overlap 48/64.
  Scene scene = PlaneScene(dir, {0.0, 1.0, 0.5});
  DepthCache cache(scene, kW, kH);
  DropCounts drops;
  auto scored = ScorePairs(scene, Cameras(scene), GenerateCandidates({0, 1, 2}, 0),
                           LabelPreset("default"), 1, &cache, &drops);
  ASSERT_EQ(scored.size(), 3u);
  EXPECT_TRUE(drops.empty());
  EXPECT_DOUBLE_EQ(scored[0].m01.overlap, 48.0 / 64.0);
  EXPECT_DOUBLE_EQ(scored[0].m10.overlap, 48.0 / 64.0);
  EXPECT_DOUBLE_EQ(scored[1].m01.overlap, 56.0 / 64.0);  // 0.5 m: 8 px
  EXPECT_DOUBLE_EQ(scored[0].m01.occlusion_ratio, 0.0);
  EXPECT_EQ(scored[0].m01.counts[static_cast<int>(PixelLabel::kVisible)], 48 * kH);
  // Stride 4 samples every 4th column and row: columns 16..60 of 0,4,..,60 are in view.
  auto strided =
      ScorePairs(scene, Cameras(scene), {{0, 1}}, LabelPreset("default"), 4, &cache, &drops);
  EXPECT_DOUBLE_EQ(strided[0].m01.overlap, 12.0 / 16.0);
}

TEST(Scan, StrideUnusableAndLowDepthAreCounted) {
  const std::string dir = test::ScratchDir("pairs_scan");
  Scene scene = PlaneScene(dir, {0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6});
  scene.frames[2].usable = false;
  scene.frames[4].depth.path = dir + "/missing.npy";
  Scene low = PlaneScene(dir + "/low", {0}, 2.0, 0.05);
  scene.frames[6].depth = low.frames[0].depth;
  DepthCache cache(scene, kW, kH);
  FrameScanOptions o;
  o.min_valid_depth_fraction = 0.5;
  ScanResult r = ScanFrames(scene, o, &cache);
  EXPECT_EQ(r.kept, (std::vector<size_t>{0, 1, 3, 5}));
  EXPECT_EQ(r.drops["scan.unusable"], 1);
  EXPECT_EQ(r.drops["scan.read_error"], 1);
  EXPECT_EQ(r.drops["scan.low_valid_depth"], 1);
  EXPECT_EQ(static_cast<int64_t>(r.kept.size()) + Sum(r.drops, "scan."), r.frames_total);
  EXPECT_DOUBLE_EQ(r.median_depth_m[0], 2.0);
  o.frame_stride = 2;
  DepthCache cache2(scene, kW, kH);
  ScanResult s = ScanFrames(scene, o, &cache2);
  EXPECT_EQ(s.kept, (std::vector<size_t>{0}));  // 2 unusable, 4 unreadable, 6 low depth
  EXPECT_EQ(s.drops["scan.stride"], 3);
}

TEST(DepthCache, EvictsLeastRecentlyUsedWithinBudget) {
  const std::string dir = test::ScratchDir("pairs_cache");
  Scene scene = PlaneScene(dir, {0, 1, 2, 3, 4});
  const size_t map_bytes = kW * kH * sizeof(float);
  DepthCache cache(scene, kW, kH, 2 * map_bytes);
  cache.Get(0);
  cache.Get(1);
  cache.Get(0);  // hit; 1 is now least recent
  cache.Get(2);  // evicts 1
  EXPECT_LE(cache.bytes(), 2 * map_bytes);
  EXPECT_EQ(cache.hits(), 1);
  cache.Get(0);  // still cached
  EXPECT_EQ(cache.hits(), 2);
  EXPECT_TRUE(cache.Contains(0));
  EXPECT_TRUE(cache.Contains(2));
  EXPECT_FALSE(cache.Contains(1));  // evicted
  EXPECT_FALSE(cache.Contains(4));  // never read
  cache.Get(1);                     // was evicted
  EXPECT_EQ(cache.misses(), 4);
  EXPECT_TRUE(cache.Contains(1));
  // Resizing to another working resolution.
  DepthCache half(scene, kW / 2, kH / 2, map_bytes);
  EXPECT_EQ(half.Get(3)->width, kW / 2);
}

ScoredPair Fake(size_t i0, size_t i1, double ov01, double ov10, double oc01 = 0, double oc10 = 0) {
  ScoredPair p;
  p.pair = {i0, i1};
  p.m01.overlap = ov01;
  p.m10.overlap = ov10;
  p.m01.occlusion_ratio = oc01;
  p.m10.occlusion_ratio = oc10;
  return p;
}

TEST(Filters, AggregationMinMeanMax) {
  std::vector<ScoredPair> s = {Fake(0, 1, 0.2, 0.6)};
  EXPECT_DOUBLE_EQ(PairOverlap(s[0], Aggregate::kMin), 0.2);
  EXPECT_DOUBLE_EQ(PairOverlap(s[0], Aggregate::kMean), 0.4);
  EXPECT_DOUBLE_EQ(PairOverlap(s[0], Aggregate::kMax), 0.6);
  SelectionOptions o;
  o.overlap_lo = 0.3;
  o.overlap_hi = 0.5;
  for (auto [agg, n] :
       {std::pair{Aggregate::kMin, 0u}, {Aggregate::kMean, 1u}, {Aggregate::kMax, 0u}}) {
    o.aggregate = agg;
    DropCounts d;
    EXPECT_EQ(FilterAndSample(s, o, 1, &d).size(), n) << AggregateName(agg);
    EXPECT_EQ(d["filter.overlap"], 1 - static_cast<int64_t>(n));
  }
  // Occlusion metric choice.
  ScoredPair v = Fake(0, 1, 0.5, 0.5, 0.1, 0.3);
  v.m01.occlusion_ratio_visible = 0.5;
  v.m10.occlusion_ratio_visible = 0.7;
  EXPECT_DOUBLE_EQ(PairOcclusion(v, Aggregate::kMean, OcclusionMetric::kImage), 0.2);
  EXPECT_DOUBLE_EQ(PairOcclusion(v, Aggregate::kMean, OcclusionMetric::kVisible), 0.6);
  EXPECT_DOUBLE_EQ(PairOcclusion(v, Aggregate::kMax, OcclusionMetric::kImage), 0.3);
}

TEST(Filters, VisibleOverlapKeepsPairsThatSeeTheSameSurfaces) {
  // Two pairs with the same overlap and occlusion: one sees its partner (visible 0.3 / 0.25),
  // one only through walls (0.3 one way, 0.02 the other).
  std::vector<ScoredPair> s = {Fake(0, 1, 0.6, 0.6, 0.3, 0.3), Fake(1, 2, 0.6, 0.6, 0.3, 0.3)};
  s[0].m01.consistent_overlap = 0.30;
  s[0].m10.consistent_overlap = 0.25;
  s[1].m01.consistent_overlap = 0.30;
  s[1].m10.consistent_overlap = 0.02;
  EXPECT_DOUBLE_EQ(PairVisibleOverlap(s[1], Aggregate::kMin), 0.02);
  EXPECT_DOUBLE_EQ(PairVisibleOverlap(s[1], Aggregate::kMean), 0.16);
  SelectionOptions o;
  o.overlap_lo = 0.4;
  o.occlusion_lo = 0.2;
  DropCounts none;
  EXPECT_EQ(FilterAndSample(s, o, 1, &none).size(), 2u);  // the default [0, 1] keeps both
  EXPECT_TRUE(none.empty());
  o.visible_overlap_lo = 0.1;  // weaker direction (min, the default) must see 10 %
  DropCounts d;
  EXPECT_EQ(FilterAndSample(s, o, 1, &d), std::vector<size_t>{0});
  EXPECT_EQ(d, (DropCounts{{"filter.visible_overlap", 1}}));
  o.visible_aggregate = Aggregate::kMean;  // mean 0.16 passes
  EXPECT_EQ(FilterAndSample(s, o, 1, &d).size(), 2u);
  o.visible_aggregate = Aggregate::kMin;
  o.visible_overlap_hi = 0.2;  // upper bound: 0.25 is too visible
  DropCounts d2;
  EXPECT_TRUE(FilterAndSample(s, o, 1, &d2).empty());
  EXPECT_EQ(d2["filter.visible_overlap"], 2);
  std::string error;
  o.visible_overlap_lo = 0.5;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_EQ(error, "selection.visible_overlap: expected [lo, hi] with 0 <= lo <= hi <= 1");
}

std::vector<ScoredPair> RandomScored(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<ScoredPair> s;
  for (size_t k = 0; k < n; ++k)
    s.push_back(Fake(k, k + 1 + k % 3, u(rng), u(rng), u(rng) * 0.5, u(rng) * 0.5));
  return s;
}

TEST(Filters, PropertyDropsAddUpQuotaHoldsAndFiltersAreRespected) {
  for (uint64_t trial = 0; trial < 50; ++trial) {
    std::mt19937_64 rng(trial);
    auto scored = RandomScored(1 + rng() % 300, trial);
    SelectionOptions o;
    o.overlap_lo = (rng() % 50) / 100.0;
    o.overlap_hi = o.overlap_lo + (rng() % 50) / 100.0;
    o.occlusion_lo = (rng() % 20) / 100.0;
    o.quota_per_scene = static_cast<int>(rng() % 40);
    o.balance_bins = static_cast<int>(rng() % 4);
    o.aggregate = static_cast<Aggregate>(rng() % 3);
    DropCounts d;
    auto chosen = FilterAndSample(scored, o, trial, &d);
    EXPECT_EQ(static_cast<int64_t>(chosen.size()) + Sum(d, ""),
              static_cast<int64_t>(scored.size()));
    if (o.quota_per_scene > 0) {
      EXPECT_LE(chosen.size(), static_cast<size_t>(o.quota_per_scene));
    }
    std::set<size_t> unique(chosen.begin(), chosen.end());
    EXPECT_EQ(unique.size(), chosen.size());
    for (size_t k : chosen) {
      const double ov = PairOverlap(scored[k], o.aggregate);
      EXPECT_GE(ov, o.overlap_lo);
      EXPECT_LE(ov, o.overlap_hi);
      EXPECT_GE(PairOcclusion(scored[k], o.aggregate, OcclusionMetric::kImage), o.occlusion_lo);
    }
    for (size_t i = 1; i < chosen.size(); ++i) {
      const auto& a = scored[chosen[i - 1]].pair;
      const auto& b = scored[chosen[i]].pair;
      EXPECT_TRUE(a.i0 < b.i0 || (a.i0 == b.i0 && a.i1 < b.i1));
    }
    // Same seed, same result; the filter-only count is the quota when enough pass.
    DropCounts d2;
    EXPECT_EQ(FilterAndSample(scored, o, trial, &d2), chosen);
    EXPECT_EQ(d2, d);
  }
}

TEST(Filters, QuotaSamplesDependOnSeedOnly) {
  auto scored = RandomScored(200, 3);
  SelectionOptions o;
  o.quota_per_scene = 20;
  DropCounts d;
  auto a = FilterAndSample(scored, o, SceneSeed(0, "scene0707_00"), &d);
  auto b = FilterAndSample(scored, o, SceneSeed(0, "scene0707_00"), &d);
  auto c = FilterAndSample(scored, o, SceneSeed(1, "scene0707_00"), &d);
  auto e = FilterAndSample(scored, o, SceneSeed(0, "scene0708_00"), &d);
  EXPECT_EQ(a.size(), 20u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_NE(a, e);
  EXPECT_NE(SceneSeed(0, "a"), SceneSeed(0, "b"));
}

TEST(Filters, BalancingTakesEquallyFromOverlapBins) {
  // 30 pairs in [0, 0.5), 6 in [0.5, 1]: two bins, no quota → 6 + 6.
  std::vector<ScoredPair> s;
  for (int k = 0; k < 30; ++k) s.push_back(Fake(k, k + 1, 0.1 + k * 0.01, 0.1 + k * 0.01));
  for (int k = 0; k < 6; ++k) s.push_back(Fake(100 + k, 101 + k, 0.6 + k * 0.05, 0.6 + k * 0.05));
  SelectionOptions o;
  o.balance_bins = 2;
  DropCounts d;
  auto chosen = FilterAndSample(s, o, 9, &d);
  int low = 0, high = 0;
  for (size_t k : chosen) (PairOverlap(s[k], o.aggregate) < 0.5 ? low : high)++;
  EXPECT_EQ(low, 6);
  EXPECT_EQ(high, 6);
  EXPECT_EQ(d["sample.balance"], 24);
  // With a quota of 10: 5 + 5.
  o.quota_per_scene = 10;
  DropCounts d2;
  chosen = FilterAndSample(s, o, 9, &d2);
  low = high = 0;
  for (size_t k : chosen) (PairOverlap(s[k], o.aggregate) < 0.5 ? low : high)++;
  EXPECT_EQ(low, 5);
  EXPECT_EQ(high, 5);
}

TEST(Filters, APartialBalancingRoundTakesRandomBins) {
  // 3 bins of 10 pairs and a quota of 7: two full rounds (6), and the 7th pair from one bin,
  // any of the three depending on the seed (it was always the lowest-overlap bin). With as
  // many bins as the quota allows one pair each (100 bins, quota 20, pairs in every bin),
  // the pairs spread over the whole range.
  std::vector<ScoredPair> s;
  for (int b = 0; b < 3; ++b) {
    for (int k = 0; k < 10; ++k) {
      const double ov = 0.1 + b * 0.3 + k * 0.01;
      s.push_back(Fake(b * 100 + k, b * 100 + k + 1, ov, ov));
    }
  }
  SelectionOptions o;
  o.overlap_lo = 0.1;
  o.overlap_hi = 1.0;
  o.balance_bins = 3;
  o.quota_per_scene = 7;
  std::set<int> extra_bins;
  for (uint64_t seed = 0; seed < 30; ++seed) {
    DropCounts d;
    const auto chosen = FilterAndSample(s, o, seed, &d);
    ASSERT_EQ(chosen.size(), 7u);
    int count[3] = {0, 0, 0};
    for (size_t k : chosen) count[k / 10]++;
    for (int b = 0; b < 3; ++b) {
      EXPECT_GE(count[b], 2) << seed;
      if (count[b] == 3) extra_bins.insert(b);
    }
    EXPECT_EQ(d["sample.quota"], 23);
  }
  EXPECT_EQ(extra_bins.size(), 3u);  // each bin got the 7th pair for some seed

  std::vector<ScoredPair> spread;
  for (int k = 0; k < 200; ++k) {
    const double ov = 0.1 + 0.8 * (k + 0.5) / 200.0;
    spread.push_back(Fake(k, k + 1, ov, ov));
  }
  o.overlap_hi = 0.9;
  o.balance_bins = 100;
  o.quota_per_scene = 20;
  DropCounts d;
  const auto chosen = FilterAndSample(spread, o, 5, &d);
  ASSERT_EQ(chosen.size(), 20u);
  int above_half = 0;
  for (size_t k : chosen) above_half += PairOverlap(spread[k], o.aggregate) > 0.5;
  EXPECT_GT(above_half, 3);  // all 20 had overlap <= 0.2 before
  EXPECT_LT(above_half, 17);
}

TEST(Scoring, IdenticalResultsOnOneAndManyThreads) {
  const std::string dir = test::ScratchDir("pairs_threads");
  std::vector<double> xs;
  for (int i = 0; i < 12; ++i) xs.push_back(0.13 * i);
  Scene scene = PlaneScene(dir, xs, 2.5, 0.8);
  auto cands = GenerateCandidates(
      [&] {
        std::vector<size_t> k;
        for (size_t i = 0; i < xs.size(); ++i) k.push_back(i);
        return k;
      }(),
      0);
  auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    DepthCache cache(scene, kW, kH, 3 * kW * kH * sizeof(float));  // forces evictions
    DropCounts d;
    auto scored = ScorePairs(scene, Cameras(scene), cands, LabelPreset("default"), 2, &cache, &d);
    SelectionOptions o;
    o.overlap_lo = 0.3;
    o.quota_per_scene = 10;
    auto chosen = FilterAndSample(scored, o, SceneSeed(5, scene.name), &d);
    std::vector<std::tuple<size_t, size_t, double, double>> out;
    for (size_t k : chosen) {
      out.emplace_back(scored[k].pair.i0, scored[k].pair.i1, scored[k].m01.overlap,
                       scored[k].m10.occlusion_ratio);
    }
    return out;
  };
  const auto one = run(1);
  EXPECT_EQ(one.size(), 10u);
  EXPECT_EQ(one, run(2));
  EXPECT_EQ(one, run(4));
}

// "All pairs" of a scene larger than the cache: blocked visiting keeps decodes far below
// one per pair, and the results equal those of a cache that holds everything.
TEST(Scoring, BlockedVisitBoundsDecodesForAllPairs) {
  const std::string dir = test::ScratchDir("pairs_blocked");
  std::vector<double> xs;
  std::vector<size_t> kept;
  for (int i = 0; i < 40; ++i) {
    xs.push_back(0.01 * i);
    kept.push_back(i);
  }
  Scene scene = PlaneScene(dir, xs);
  const auto cands = GenerateCandidates(kept, 0);  // 780 pairs
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  DepthCache small(scene, kW, kH, 16 * kW * kH * sizeof(float));  // 16 maps, blocks of 4
  DepthCache big(scene, kW, kH, 64 * kW * kH * sizeof(float));
  DropCounts d;
  auto a = ScorePairs(scene, Cameras(scene), cands, LabelPreset("default"), 4, &small, &d);
  auto b = ScorePairs(scene, Cameras(scene), cands, LabelPreset("default"), 4, &big, &d);
  ASSERT_EQ(a.size(), cands.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].pair, cands[k]);
    EXPECT_EQ(a[k].m01.counts, b[k].m01.counts);
    EXPECT_EQ(a[k].m10.counts, b[k].m10.counts);
  }
  EXPECT_EQ(big.misses(), 40);
  // 10 blocks of 4 frames: 55 block pairs, each needing at most 8 maps (4 when i0's block
  // is reused): well under the 1560 lookups and under a quarter of the pair count.
  EXPECT_LE(small.misses(), 10 * 4 + 55 * 4) << small.misses();
  EXPECT_LT(small.misses(), static_cast<int64_t>(cands.size()) / 2);
}

}  // namespace
}  // namespace gt::pairs

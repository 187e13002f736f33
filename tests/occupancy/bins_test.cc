// Bin edges (closed forms per spacing), bin lookup, option checks and parsers, and the
// packed (occ/known words) vs dense encodings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "libgt/core/error.h"
#include "libgt/occupancy/edge_index.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/pair_occupancy.h"

namespace gt::occupancy {
namespace {

TEST(BinEdges, LinearIsEvenlySpacedInDepth) {
  BinOptions o;
  o.near_m = 0.5;
  o.far_m = 8.5;
  o.num_bins = 64;
  const auto e = BinEdges(o);
  ASSERT_EQ(e.size(), 65u);
  for (int k = 0; k <= 64; ++k) EXPECT_NEAR(e[k], 0.5 + k * 0.125, 1e-12) << k;
}

TEST(BinEdges, LogIsEvenlySpacedInLogDepth) {
  BinOptions o;
  o.near_m = 0.25;
  o.far_m = 16.0;  // ratio 64 = 2^6: every 64/6 bins doubles
  o.num_bins = 6;
  o.spacing = BinSpacing::kLog;
  const auto e = BinEdges(o);
  ASSERT_EQ(e.size(), 7u);
  for (int k = 0; k <= 6; ++k) EXPECT_NEAR(e[k], 0.25 * std::pow(2.0, k), 1e-12) << k;
}

TEST(BinEdges, InverseIsEvenlySpacedInDisparity) {
  BinOptions o;
  o.near_m = 0.5;  // disparity 2
  o.far_m = 10.0;  // disparity 0.1
  o.num_bins = 19;
  o.spacing = BinSpacing::kInverse;
  const auto e = BinEdges(o);
  for (int k = 0; k <= 19; ++k) EXPECT_NEAR(1.0 / e[k], 2.0 - 0.1 * k, 1e-12) << k;
  for (int k = 0; k < 19; ++k) EXPECT_LT(e[k], e[k + 1]);
}

TEST(BinEdges, BinOfDepthIsHalfOpen) {
  BinOptions o;
  o.near_m = 1.0;
  o.far_m = 5.0;
  o.num_bins = 4;
  const auto e = BinEdges(o);  // 1 2 3 4 5
  EXPECT_EQ(BinOfDepth(e, 0.999), -1);
  EXPECT_EQ(BinOfDepth(e, 1.0), 0);
  EXPECT_EQ(BinOfDepth(e, 1.999), 0);
  EXPECT_EQ(BinOfDepth(e, 2.0), 1);
  EXPECT_EQ(BinOfDepth(e, 4.999), 3);
  EXPECT_EQ(BinOfDepth(e, 5.0), -1);
  EXPECT_EQ(BinOfDepth(e, std::nan("")), -1);
}

TEST(Options, ChecksRejectBadValues) {
  std::string why;
  BinOptions b;
  EXPECT_TRUE(b.Check(&why));
  b.num_bins = 65;
  EXPECT_FALSE(b.Check(&why));
  b = BinOptions();
  b.far_m = b.near_m;
  EXPECT_FALSE(b.Check(&why));
  b = BinOptions();
  b.near_m = 0;
  EXPECT_FALSE(b.Check(&why));
  // Edges that overflow: far / near = 1e600 in log spacing (infinite edges, written as null
  // in JSON), a near of 5e-310 in inverse spacing (1 / near is infinite).
  b = BinOptions();
  b.near_m = 1e-300;
  b.far_m = 1e300;
  b.spacing = BinSpacing::kLog;
  EXPECT_FALSE(b.Check(&why));
  EXPECT_NE(why.find("the log bin edges of near_m 1e-300, far_m 1e+300 and 64 bins are not "
                     "finite and increasing"),
            std::string::npos)
      << why;
  b = BinOptions();
  b.near_m = 5e-310;
  b.spacing = BinSpacing::kInverse;
  EXPECT_FALSE(b.Check(&why));
  b.near_m = 1e-10;  // tiny, but every edge finite and increasing
  EXPECT_TRUE(b.Check(&why)) << why;
  FusionOptions f;
  EXPECT_TRUE(f.Check(&why));
  f.voxel_m = 0;
  EXPECT_FALSE(f.Check(&why));
  f = FusionOptions();
  f.scope = FusionScope::kWindow;
  EXPECT_TRUE(f.Check(&why));  // the default window, 2
  f.window = 0;
  EXPECT_FALSE(f.Check(&why));
  f = FusionOptions();
  f.scope = FusionScope::kScene;
  f.scene_stride = 0;
  EXPECT_FALSE(f.Check(&why));
}

TEST(Options, ParsersRoundTripAndRejectUnknownNames) {
  FusionOptions f;
  ParseFusionScope("window:3", &f);
  EXPECT_EQ(f.scope, FusionScope::kWindow);
  EXPECT_EQ(f.window, 3);
  EXPECT_EQ(FusionScopeName(f), "window:3");
  ParseFusionScope("scene:10", &f);
  EXPECT_EQ(f.scope, FusionScope::kScene);
  EXPECT_EQ(FusionScopeName(f), "scene:10");
  ParseFusionScope("pair", &f);
  EXPECT_EQ(FusionScopeName(f), "pair");
  EXPECT_THROW(ParseFusionScope("window:", &f), InputError);
  EXPECT_THROW(ParseFusionScope("window:0", &f), InputError);
  EXPECT_THROW(ParseFusionScope("scene:-2", &f), InputError);
  EXPECT_THROW(ParseFusionScope("all", &f), InputError);
  for (auto s : {"linear", "log", "inverse"}) EXPECT_EQ(BinSpacingName(ParseBinSpacing(s)), s);
  EXPECT_THROW(ParseBinSpacing("quadratic"), InputError);
  for (auto s : {"exact", "center"}) EXPECT_EQ(TraversalName(ParseTraversal(s)), s);
  EXPECT_THROW(ParseTraversal("centre"), InputError);
  for (auto s : {"octomap", "two_point"}) EXPECT_EQ(OccupancyModeName(ParseOccupancyMode(s)), s);
  EXPECT_THROW(ParseOccupancyMode("voxels"), InputError);
}

TEST(Options, ScopeFrameIndices) {
  Scene scene;
  scene.frames.resize(10);
  scene.frames[4].usable = false;
  FusionOptions f;
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f), (std::vector<size_t>{2, 7}));
  ParseFusionScope("window:1", &f);
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f), (std::vector<size_t>{1, 2, 3, 6, 7, 8}));
  std::vector<size_t> unusable = {99};
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f, &unusable), (std::vector<size_t>{1, 2, 3, 6, 7, 8}));
  EXPECT_TRUE(unusable.empty());  // frame 4 is outside the window
  ParseFusionScope("window:2", &f);
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f, &unusable),
            (std::vector<size_t>{0, 1, 2, 3, 5, 6, 7, 8, 9}));
  EXPECT_EQ(unusable, (std::vector<size_t>{4}));  // left out, to be listed
  // Every 4th usable frame: the usable ones are 0 1 2 3 5 6 7 8 9, so 0, 5 and 9; every
  // unusable frame is left out of a scene scope.
  ParseFusionScope("scene:4", &f);
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f, &unusable), (std::vector<size_t>{0, 5, 9}));
  EXPECT_EQ(unusable, (std::vector<size_t>{4}));
  // Never none while a frame is usable: a first frame that is not (the frames at positions
  // 0, S, 2S, ... all unusable gave an empty map, every bin unknown, without a word).
  scene.frames[0].usable = false;
  ParseFusionScope("scene:10", &f);
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f), (std::vector<size_t>{1}));
  ParseFusionScope("scene:3", &f);
  EXPECT_EQ(ScopeFrameIndices(scene, 2, 7, f), (std::vector<size_t>{1, 5, 8}));
  EXPECT_THROW(ScopeFrameIndices(scene, 2, 10, f), InputError);
}

// Packed and dense encodings agree on random volumes (occ a subset of known).
TEST(Encoding, DenseMatchesPackedBits) {
  std::mt19937_64 rng(3);
  FrustumVolume v;
  v.width = 7;
  v.height = 5;
  BinOptions o;
  o.num_bins = 64;
  v.edges_m = BinEdges(o);
  for (int i = 0; i < v.width * v.height; ++i) {
    const uint64_t known = rng();
    v.known.push_back(known);
    v.occ.push_back(known & rng());
  }
  const auto dense = DenseVolume(v);
  ASSERT_EQ(dense.size(), 64u * 7 * 5);
  VolumeCounts expect;
  for (int k = 0; k < 64; ++k) {
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 7; ++x) {
        const size_t i = y * 7 + x;
        const uint8_t d = dense[(static_cast<size_t>(k) * 5 + y) * 7 + x];
        const bool known = (v.known[i] >> k) & 1, occ = (v.occ[i] >> k) & 1;
        EXPECT_EQ(d, !known ? 255 : (occ ? 1 : 0));
        expect.occupied += d == 1;
        expect.free += d == 0;
        expect.unknown += d == 255;
      }
    }
  }
  const VolumeCounts c = CountBins(v);
  EXPECT_EQ(c.occupied, expect.occupied);
  EXPECT_EQ(c.free, expect.free);
  EXPECT_EQ(c.unknown, expect.unknown);
}

TEST(Encoding, FewerBinsLeaveHighBitsUnset) {
  FrustumVolume v;
  v.width = v.height = 1;
  BinOptions o;
  o.num_bins = 3;
  v.edges_m = BinEdges(o);
  v.known = {0b111};
  v.occ = {0b010};
  EXPECT_EQ(DenseVolume(v), (std::vector<uint8_t>{0, 1, 0}));
}

// The bin lookup of the exact binning (edge_index.h) against a plain search of the edges,
// at random depths, at every edge and one ulp either side of it, for every spacing, one bin,
// and bins far narrower than the lookup table allows (its loop path).
TEST(EdgeIndex, FirstAndLastMatchASearchOfTheEdges) {
  std::vector<BinOptions> settings(6);
  settings[1].spacing = BinSpacing::kLog;
  settings[2].spacing = BinSpacing::kInverse;
  settings[2].num_bins = 37;
  settings[3].num_bins = 1;
  settings[4].spacing = BinSpacing::kLog;  // first bins ~0.3 um wide
  settings[4].near_m = 1e-6;
  settings[5].spacing = BinSpacing::kInverse;
  settings[5].near_m = 0.3;
  settings[5].far_m = 5.0;
  std::mt19937 rng(3);
  for (const BinOptions& o : settings) {
    const std::vector<double> e = BinEdges(o);
    const int D = static_cast<int>(e.size()) - 1;
    const EdgeIndex index(e);
    auto first = [&](double z) {  // first k with e_{k+1} > z
      int k = 0;
      while (k < D - 1 && e[k + 1] <= z) ++k;
      return k;
    };
    auto last = [&](double z) {  // last k with e_k < z
      int k = D - 1;
      while (k > 0 && e[k] >= z) --k;
      return k;
    };
    std::vector<double> zs;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 20000; ++i) {
      zs.push_back(e.front() + unit(rng) * (e.back() - e.front()));
      // Log-uniform too: the narrow bins near e_0 get their share.
      zs.push_back(e.front() * std::pow(e.back() / e.front(), unit(rng)));
    }
    for (double edge : e) {
      zs.push_back(edge);
      zs.push_back(std::nextafter(edge, 0.0));
      zs.push_back(std::nextafter(edge, 1e9));
    }
    int64_t checked = 0;
    for (double z : zs) {
      if (z >= e.front() && z < e.back()) {
        ASSERT_EQ(index.First(z), first(z)) << "z " << z << " near " << o.near_m;
        ++checked;
      }
      if (z > e.front() && z <= e.back()) {
        ASSERT_EQ(index.Last(z), last(z)) << "z " << z << " near " << o.near_m;
        ++checked;
      }
    }
    EXPECT_GT(checked, 70000);
  }
}

}  // namespace
}  // namespace gt::occupancy

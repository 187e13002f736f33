// pairs::SampleTuples (libgt/pairs/tuples.h): neighbours are the graph's pairs scoring at least
// edge_threshold, never a pair the graph lacks (a pruned one), even at threshold 0.
#include "libgt/pairs/tuples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

namespace gt::pairs {
namespace {

// Frames 0..3; the graph holds (0, 1) scored 0 both ways and (1, 2) scored 0.5; frame 3 and the
// pairs (0, 2), (0, 3), (1, 3), (2, 3) were pruned.
CovisibilityPairs SparseGraph() {
  CovisibilityPairs g;
  g.num_frames = 4;
  g.i = {0, 1};
  g.j = {1, 2};
  g.c_ij = {0.0f, 0.5f};
  g.c_ji = {0.0f, 0.5f};
  return g;
}

TEST(Tuples, ThresholdZeroKeepsToThePairsOfTheGraph) {
  TupleOptions o;
  o.edge_threshold = 0.0;
  o.quota = 50;
  o.restarts = 4;
  o.min_views = o.max_views = 2;
  DropCounts drops;
  std::set<std::set<int32_t>> seen;
  for (const Tuple& t : SampleTuples(SparseGraph(), o, 7, &drops)) {
    seen.insert(std::set<int32_t>(t.frames.begin(), t.frames.end()));
  }
  // The scored pairs, (0, 1) at score 0 included; no pair with frame 3 nor (0, 2).
  EXPECT_EQ(seen, (std::set<std::set<int32_t>>{{0, 1}, {1, 2}}));
  // Three views: only the walk 0 - 1 - 2 (through 1), never frame 3.
  o.min_views = o.max_views = 3;
  const std::vector<Tuple> three = SampleTuples(SparseGraph(), o, 7, &drops);
  ASSERT_EQ(three.size(), 1u);
  EXPECT_EQ(std::set<int32_t>(three[0].frames.begin(), three[0].frames.end()),
            (std::set<int32_t>{0, 1, 2}));
  // Four views: frame 3 has no neighbour, so no walk reaches 4 (min_views 4): none.
  o.min_views = o.max_views = 4;
  drops.clear();
  EXPECT_TRUE(SampleTuples(SparseGraph(), o, 7, &drops).empty());
  EXPECT_GT(drops["tuples.too_small"], 0);
}

TEST(Tuples, ThresholdIsInclusiveOnScoredPairs) {
  TupleOptions o;
  o.edge_threshold = 0.5;
  o.quota = 20;
  o.min_views = o.max_views = 2;
  DropCounts drops;
  const std::vector<Tuple> tuples = SampleTuples(SparseGraph(), o, 3, &drops);
  ASSERT_EQ(tuples.size(), 1u);  // (1, 2) reaches 0.5; (0, 1) does not
  EXPECT_EQ(std::set<int32_t>(tuples[0].frames.begin(), tuples[0].frames.end()),
            (std::set<int32_t>{1, 2}));
}

TEST(Tuples, BoundsAreComparedWithTheExactMean) {
  // c_ij + c_ji rounds down in float32: the mean was 0.78819441795 < the exact 0.78819444776,
  // and a bound equal to the exact mean dropped the pair (edge_threshold, pair_covisibility's
  // lo, min_spread alike).
  CovisibilityPairs g;
  g.num_frames = 2;
  g.i = {0};
  g.j = {1};
  g.c_ij = {0.7384259104728699f};
  g.c_ji = {0.8379629850387573f};
  const double exact = 0.5 * (static_cast<double>(g.c_ij[0]) + static_cast<double>(g.c_ji[0]));
  ASSERT_LT(static_cast<double>(0.5f * (g.c_ij[0] + g.c_ji[0])), exact);  // the float mean
  EXPECT_EQ(PairScore(g, 0), exact);
  TupleOptions o;
  o.min_views = o.max_views = 2;
  o.quota = 5;
  DropCounts drops;
  for (int bound = 0; bound < 3; ++bound) {
    o.edge_threshold = bound == 0 ? exact : 0.25;
    o.pair_lo = bound == 1 ? exact : 0.0;
    o.min_spread_score = bound == 2 ? exact : 0.0;
    EXPECT_EQ(SampleTuples(g, o, 1, &drops).size(), 1u) << bound;
    // Just above the mean: none.
    const double above = std::nextafter(exact, 1.0);
    o.edge_threshold = bound == 0 ? above : 0.25;
    o.pair_lo = bound == 1 ? above : 0.0;
    o.min_spread_score = bound == 2 ? above : 0.0;
    EXPECT_TRUE(SampleTuples(g, o, 1, &drops).empty()) << bound;
  }
}

TEST(Tuples, APartialBalancingRoundTakesRandomBins) {
  // A chain of 40 frames whose pairs score 0.9, 0.6 or 0.3 in turn: 2-view tuples of
  // occlusion 0.1, 0.4 or 0.7 (1 - c with o = self = 1), one per occlusion bin of 3. A quota
  // of 4: one full round, and the 4th tuple from one bin, any of the three depending on the
  // seed (it was always the first, lowest-occlusion one).
  CovisibilityPairs g;
  g.num_frames = 40;
  const float kScores[] = {0.9f, 0.6f, 0.3f};
  for (int a = 0; a + 1 < 40; ++a) {
    g.i.push_back(a);
    g.j.push_back(a + 1);
    g.c_ij.push_back(kScores[a % 3]);
    g.c_ji.push_back(kScores[a % 3]);
    g.o_ij.push_back(1.0f);
    g.o_ji.push_back(1.0f);
  }
  g.self.assign(40, 1.0f);
  TupleOptions o;
  o.min_views = o.max_views = 2;
  o.edge_threshold = 0.0;
  o.quota = 4;
  o.balance_occlusion = 3;
  std::set<int> doubled;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    DropCounts drops;
    const std::vector<Tuple> tuples = SampleTuples(g, o, seed, &drops);
    ASSERT_EQ(tuples.size(), 4u);
    int count[3] = {0, 0, 0};
    for (const Tuple& t : tuples) {
      const int group = t.frames[0] < t.frames[1] ? t.frames[0] % 3 : t.frames[1] % 3;
      ++count[group];
    }
    for (int b = 0; b < 3; ++b) {
      EXPECT_GE(count[b], 1) << seed;  // one full round
      if (count[b] == 2) doubled.insert(b);
    }
  }
  EXPECT_EQ(doubled.size(), 3u);  // each bin took the 4th tuple for some seed
}

}  // namespace
}  // namespace gt::pairs

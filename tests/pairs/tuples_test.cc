// pairs::SampleTuples (libgt/pairs/tuples.h): neighbours are the graph's pairs scoring at least
// edge_threshold, never a pair the graph lacks (a pruned one), even at threshold 0.
#include "libgt/pairs/tuples.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace gt::pairs

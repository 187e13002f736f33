// Seeded N-view tuples grown on a scene's covisibility graph (docs/MULTIVIEW.md "Tuples"):
// a walk with backtracking on the thresholded graph, as MapAnything samples its views.
//
// Graph: F frames, pairs (i, j) with both directions' visible overlap c_ij, c_ji
// (pipeline/covisibility.h). The score of a pair is (c_ij + c_ji) / 2, computed in double from
// the graph's float32 values (exact: a bound equal to a pair's mean keeps the pair), 0 for a
// pair not in the graph; two frames are neighbours when their pair is in the graph and its score >=
// edge_threshold (a pair the pruning dropped is never one, even at edge_threshold 0).
//
// One tuple: its size N is drawn in [min_views, max_views]; a start frame is drawn among the
// frames with a neighbour; then, with a stack holding the walk, a frame is drawn among the
// neighbours of the top of the stack that are not in the tuple and that keep every pair of
// the tuple within [pair_lo, pair_hi] (the score of the new frame with each chosen one); it is
// added and pushed; a top with no such neighbour is popped (backtracking). The walk stops at N
// frames or an empty stack; up to `restarts` more walks start from a frame drawn among those
// not tried yet; the first walk of N frames is the tuple, else the longest if it has at least
// min_views frames, else none (counted). The spread bound: the tuple's smallest pair score
// must be >= min_spread_score (0 = off; every pair then sees every other pair's views).
// A tuple equal (as a set) to one drawn before is dropped and counted. `quota` tuples per
// scene at most, from at most 4·quota + 16 draws. With balance_occlusion, 4·quota tuples are
// drawn and taken round robin from equal occlusion bins; a round that the quota ends part way
// takes its tuples from bins in a seeded order (no occlusion range favoured).
//
// Determinism: std::mt19937_64(seed) raw outputs only (UniformBelow of selection.h),
// candidate lists in increasing frame index; no threads. Frames of a tuple are listed in the
// order they were added (the first is the start, a natural reference view).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libgt/pairs/selection.h"

namespace gt::pairs {

// The largest quota: 4·quota + 16 draws (and with balance_occlusion 4·quota candidates held
// in memory) stay far inside int64 and an afternoon's run.
inline constexpr int kMaxTupleQuota = 1000000;

struct TupleOptions {
  int min_views = 2, max_views = 2;  // recipe `tuples.views`: N or [min, max]; 2..32
  double edge_threshold = 0.25;      // neighbours: graph pairs scoring >= this (MapAnything: 0.25)
  double pair_lo = 0.0, pair_hi = 1.0;  // every pair of a tuple within [lo, hi]
  double min_spread_score = 0.0;        // unused bound when 0 (see above)
  int restarts = 4;                     // extra walks per tuple
  int quota = 100;                      // tuples per scene, 1..kMaxTupleQuota
  // > 0: balance the tuples on their occlusion (TupleOcclusion) over this many equal bins of
  // [lo, hi], the smallest and largest occlusion of the scene's candidates: 4·quota candidates
  // are sampled as above (quota 4·quota, same seed), then taken round robin over the bins
  // (ascending, each bin in draw order) until the quota; the rest are dropped
  // ("tuples.balance"). 0 = off. In [0, 100].
  int balance_occlusion = 0;

  bool Check(std::string* error) const;
};

struct CovisibilityPairs {
  int num_frames = 0;
  std::vector<int32_t> i, j;      // i < j
  std::vector<float> c_ij, c_ji;  // visible overlap of i → j and j → i
  // Needed by balance_occlusion only (else may be empty): overlap of i → j and j → i, and each
  // frame's visible overlap with itself (covisibility.h o_ij, o_ji, self).
  std::vector<float> o_ij, o_ji, self;
};

struct Tuple {
  std::vector<int32_t> frames;  // indices into the graph's frames, in the order added
  double occlusion = 0;         // TupleOcclusion, set when balance_occlusion > 0
};

// The graph's estimate of a tuple's occlusion: over the ordered pairs (a, b), a != b, the
// in-view mass v_ab = o_ab · self_a (in-view valid pixels of a over the sampled grid, exact
// when a frame sees all its valid pixels, as under the default preset) and its part not
// VISIBLE m_ab = max(0, v_ab − c_ab) (OCCLUDED, INCONSISTENT or UNKNOWN); returns
// Σ m_ab / Σ v_ab (0 when Σ v_ab = 0), summed in the tuple's order, a then b, in double. A
// pair absent from the graph contributes nothing. Requires o_ij, o_ji and self.
double TupleOcclusion(const CovisibilityPairs& graph, const std::vector<int32_t>& frames);

// Tuples of one scene; drops: "tuples.too_small" (no walk reached min_views),
// "tuples.duplicate", "tuples.spread", "tuples.balance".
std::vector<Tuple> SampleTuples(const CovisibilityPairs& graph, const TupleOptions& options,
                                uint64_t seed, DropCounts* drops);

// The graph's pair index of every pair of frames, dense [F, F]: (a, b) and (b, a) -> p, -1
// for a pair the graph lacks and on the diagonal.
std::vector<int32_t> PairIndexMatrix(const CovisibilityPairs& graph);
// The score of the graph's pair p: (c_ij + c_ji) / 2 in double.
double PairScore(const CovisibilityPairs& graph, size_t p);

}  // namespace gt::pairs

#include "libgt/pairs/tuples.h"

#include <algorithm>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "libgt/core/error.h"

namespace gt::pairs {

bool TupleOptions::Check(std::string* error) const {
  if (min_views < 2 || max_views > 32 || min_views > max_views) {
    *error = "views: expected N or [min, max] with 2 <= min <= max <= 32";
    return false;
  }
  if (!(edge_threshold >= 0 && edge_threshold <= 1)) {
    *error = "edge_threshold: expected a number in [0, 1]";
    return false;
  }
  if (!(pair_lo >= 0 && pair_lo <= pair_hi && pair_hi <= 1)) {
    *error = "pair_covisibility: expected [lo, hi] with 0 <= lo <= hi <= 1";
    return false;
  }
  if (!(min_spread_score >= 0 && min_spread_score <= 1)) {
    *error = "min_spread: expected a number in [0, 1]";
    return false;
  }
  if (restarts < 0) return *error = "restarts: expected an integer >= 0", false;
  if (quota < 1 || quota > kMaxTupleQuota) {
    return *error = "quota_per_scene: expected an integer in [1, " +
                    std::to_string(kMaxTupleQuota) + "], got " + std::to_string(quota),
           false;
  }
  if (balance_occlusion < 0 || balance_occlusion > 100) {
    return *error = "balance_occlusion: expected an integer in [0, 100]", false;
  }
  return true;
}

std::vector<int32_t> PairIndexMatrix(const CovisibilityPairs& g) {
  const size_t f = static_cast<size_t>(g.num_frames);
  GT_ASSERT(g.i.size() <= static_cast<size_t>(std::numeric_limits<int32_t>::max()));
  std::vector<int32_t> at(f * f, -1);
  for (size_t p = 0; p < g.i.size(); ++p) {
    const size_t i = static_cast<size_t>(g.i[p]), j = static_cast<size_t>(g.j[p]);
    GT_ASSERT(i < f && j < f && i != j);
    at[i * f + j] = static_cast<int32_t>(p);
    at[j * f + i] = static_cast<int32_t>(p);
  }
  return at;
}

double PairScore(const CovisibilityPairs& g, size_t p) {
  // Exact: the sum of two float32 values is exact in double, and so is its half.
  return 0.5 * (static_cast<double>(g.c_ij[p]) + static_cast<double>(g.c_ji[p]));
}

double TupleOcclusion(const CovisibilityPairs& g, const std::vector<int32_t>& frames) {
  const size_t f = static_cast<size_t>(g.num_frames);
  if (g.o_ij.size() != g.i.size() || g.o_ji.size() != g.i.size() || g.self.size() != f) {
    throw InputError("tuples", "balance_occlusion: the graph has no overlap (o_ij, o_ji, self)");
  }
  // (a, b) -> pair index, for the tuple's pairs only.
  std::map<std::pair<int32_t, int32_t>, size_t> at;
  std::set<int32_t> members(frames.begin(), frames.end());
  for (size_t p = 0; p < g.i.size(); ++p) {
    if (members.count(g.i[p]) && members.count(g.j[p])) at[{g.i[p], g.j[p]}] = p;
  }
  double in_view = 0, hidden = 0;
  for (int32_t a : frames) {
    for (int32_t b : frames) {
      if (a == b) continue;
      auto it = at.find({std::min(a, b), std::max(a, b)});
      if (it == at.end()) continue;
      const size_t p = it->second;
      const double o = a < b ? g.o_ij[p] : g.o_ji[p];
      const double c = a < b ? g.c_ij[p] : g.c_ji[p];
      const double v = o * static_cast<double>(g.self[a]);
      in_view += v;
      hidden += std::max(0.0, v - c);
    }
  }
  return in_view > 0 ? hidden / in_view : 0.0;
}

namespace {

// Up to `quota` distinct tuples from at most 4·quota + 16 draws (the walk of the header;
// o.quota and o.balance_occlusion are not used).
std::vector<Tuple> DrawTuples(const CovisibilityPairs& g, const TupleOptions& o, int64_t quota,
                              uint64_t seed, DropCounts* drops);

}  // namespace

std::vector<Tuple> SampleTuples(const CovisibilityPairs& g, const TupleOptions& o, uint64_t seed,
                                DropCounts* drops) {
  std::string error;
  if (!o.Check(&error)) throw InputError("tuples", error);
  if (o.balance_occlusion > 0) {
    std::vector<Tuple> pool = DrawTuples(g, o, 4 * static_cast<int64_t>(o.quota), seed, drops);
    const int nb = o.balance_occlusion;
    std::vector<std::vector<size_t>> bins(nb);
    double lo = 1, hi = 0;
    for (Tuple& t : pool) {
      t.occlusion = TupleOcclusion(g, t.frames);
      lo = std::min(lo, t.occlusion);
      hi = std::max(hi, t.occlusion);
    }
    for (size_t k = 0; k < pool.size(); ++k) {
      const int b = hi > lo ? static_cast<int>((pool[k].occlusion - lo) / (hi - lo) * nb) : 0;
      bins[std::clamp(b, 0, nb - 1)].push_back(k);
    }
    std::vector<Tuple> out;
    std::mt19937_64 order_rng(seed + 1);  // a stream of its own: the pool's draws are seed's
    for (size_t k : TakeRoundRobin(bins, std::min(pool.size(), static_cast<size_t>(o.quota)),
                                   pool.size(), &order_rng)) {
      out.push_back(pool[k]);
    }
    if (pool.size() > out.size()) {
      (*drops)["tuples.balance"] += static_cast<int64_t>(pool.size() - out.size());
    }
    return out;
  }
  return DrawTuples(g, o, o.quota, seed, drops);
}

namespace {

std::vector<Tuple> DrawTuples(const CovisibilityPairs& g, const TupleOptions& o, int64_t quota,
                              uint64_t seed, DropCounts* drops) {
  const int f = g.num_frames;
  const std::vector<int32_t> at = PairIndexMatrix(g);
  const auto sc = [&](int a, int b) {
    const int32_t p = at[static_cast<size_t>(a) * f + b];
    return p < 0 ? 0.0 : PairScore(g, static_cast<size_t>(p));
  };
  // Neighbours are pairs of the graph only: a pair it lacks (pruned) scores 0 but is not one,
  // even at edge_threshold 0. Each list in increasing frame index.
  std::vector<std::vector<int>> neighbours(f);
  for (size_t p = 0; p < g.i.size(); ++p) {
    if (PairScore(g, p) >= o.edge_threshold) {
      neighbours[g.i[p]].push_back(g.j[p]);
      neighbours[g.j[p]].push_back(g.i[p]);
    }
  }
  for (std::vector<int>& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  std::vector<int> starts;
  for (int a = 0; a < f; ++a) {
    if (!neighbours[a].empty()) starts.push_back(a);
  }
  std::vector<Tuple> out;
  if (starts.empty()) return out;
  std::mt19937_64 rng(seed);
  std::set<std::vector<int32_t>> seen;
  const int64_t draws = 4 * quota + 16;
  for (int64_t d = 0; d < draws && static_cast<int64_t>(out.size()) < quota; ++d) {
    const int n = o.min_views + static_cast<int>(UniformBelow(
                                    static_cast<uint64_t>(o.max_views - o.min_views + 1), &rng));
    std::vector<char> tried(f, 0);
    std::vector<int> best;
    for (int walk = 0; walk <= o.restarts; ++walk) {
      std::vector<int> pool;
      for (int a : starts) {
        if (!tried[a]) pool.push_back(a);
      }
      if (pool.empty()) break;
      const int start = pool[UniformBelow(pool.size(), &rng)];
      std::vector<int> chosen = {start}, stack = {start};
      std::vector<char> in(f, 0);
      in[start] = 1;
      tried[start] = 1;
      while (static_cast<int>(chosen.size()) < n && !stack.empty()) {
        std::vector<int> next;
        for (int b : neighbours[stack.back()]) {
          if (in[b]) continue;
          bool ok = true;
          for (int c : chosen) {
            const double s = sc(b, c);
            ok = ok && s >= o.pair_lo && s <= o.pair_hi;
          }
          if (ok) next.push_back(b);
        }
        if (next.empty()) {
          stack.pop_back();
          continue;
        }
        const int b = next[UniformBelow(next.size(), &rng)];
        chosen.push_back(b);
        stack.push_back(b);
        in[b] = 1;
        tried[b] = 1;
      }
      if (chosen.size() > best.size()) best = chosen;
      if (static_cast<int>(best.size()) == n) break;
    }
    if (static_cast<int>(best.size()) < o.min_views) {
      ++(*drops)["tuples.too_small"];
      continue;
    }
    if (o.min_spread_score > 0) {
      bool ok = true;
      for (size_t a = 0; a < best.size(); ++a) {
        for (size_t b = a + 1; b < best.size(); ++b)
          ok = ok && sc(best[a], best[b]) >= o.min_spread_score;
      }
      if (!ok) {
        ++(*drops)["tuples.spread"];
        continue;
      }
    }
    std::vector<int32_t> key(best.begin(), best.end());
    std::sort(key.begin(), key.end());
    if (!seen.insert(key).second) {
      ++(*drops)["tuples.duplicate"];
      continue;
    }
    Tuple t;
    t.frames.assign(best.begin(), best.end());
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace

}  // namespace gt::pairs

#include "libgt/pairs/tuples.h"

#include <algorithm>
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
  if (quota < 1) return *error = "quota_per_scene: expected an integer >= 1", false;
  return true;
}

std::vector<float> PairScores(const CovisibilityPairs& g) {
  const size_t f = static_cast<size_t>(g.num_frames);
  std::vector<float> s(f * f, 0.0f);
  for (size_t p = 0; p < g.i.size(); ++p) {
    const size_t i = static_cast<size_t>(g.i[p]), j = static_cast<size_t>(g.j[p]);
    GT_ASSERT(i < f && j < f && i != j);
    const float v = 0.5f * (g.c_ij[p] + g.c_ji[p]);
    s[i * f + j] = v;
    s[j * f + i] = v;
  }
  return s;
}

std::vector<Tuple> SampleTuples(const CovisibilityPairs& g, const TupleOptions& o, uint64_t seed,
                                DropCounts* drops) {
  std::string error;
  if (!o.Check(&error)) throw InputError("tuples", error);
  const int f = g.num_frames;
  const std::vector<float> score = PairScores(g);
  const auto sc = [&](int a, int b) { return score[static_cast<size_t>(a) * f + b]; };
  std::vector<std::vector<int>> neighbours(f);
  for (int a = 0; a < f; ++a) {
    for (int b = 0; b < f; ++b) {
      if (a != b && sc(a, b) >= o.edge_threshold) neighbours[a].push_back(b);
    }
  }
  std::vector<int> starts;
  for (int a = 0; a < f; ++a) {
    if (!neighbours[a].empty()) starts.push_back(a);
  }
  std::vector<Tuple> out;
  if (starts.empty()) return out;
  std::mt19937_64 rng(seed);
  std::set<std::vector<int32_t>> seen;
  const int draws = 4 * o.quota + 16;
  for (int d = 0; d < draws && static_cast<int>(out.size()) < o.quota; ++d) {
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
            const float s = sc(b, c);
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

}  // namespace gt::pairs

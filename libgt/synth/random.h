// Portable seeded randomness for the synthetic generator: SplitMix64 (Steele, Lea, Flood,
// "Fast splittable pseudorandom number generators", OOPSLA 2014). Unlike the standard
// <random> distributions, whose algorithms are implementation-defined, every value here is
// specified bit for bit, so the same seed gives the same dataset with any compiler.
#pragma once

#include <cstdint>

#include "libgt/core/hash.h"

namespace gt::synth {

// Seed of a child stream (e.g. scene i of a dataset seed).
inline uint64_t ChildSeed(uint64_t seed, uint64_t index) { return Mix64(Mix64(seed) ^ index); }

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    state_ += 0x9e3779b97f4a7c15ull;
    uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [lo, hi] (hi - lo small; the modulo bias is below 2^-50).
  int Int(int lo, int hi) {
    return lo + static_cast<int>(Next() % static_cast<uint64_t>(hi - lo + 1));
  }
  bool Coin() { return (Next() >> 63) != 0; }

 private:
  uint64_t state_;
};

}  // namespace gt::synth

// 64-bit mixing for seeds and hash keys that must be the same on every machine.
#pragma once

#include <cstdint>

namespace gt {

// SplitMix64's output function applied to x (Steele, Lea, Flood, "Fast splittable
// pseudorandom number generators", OOPSLA 2014): a bijective 64-bit mixer, specified bit
// for bit, used to derive seeds and to order items by a seeded hash.
inline uint64_t Mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace gt

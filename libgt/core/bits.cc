#include "libgt/core/bits.h"

namespace gt {
namespace {

template <typename Word>
__attribute__((target("popcnt"))) int64_t CountSetBitsPopcnt(const Word* words, size_t n) {
  int64_t bits = 0;
  for (size_t i = 0; i < n; ++i) bits += __builtin_popcountll(words[i]);
  return bits;
}

template <typename Word>
int64_t CountSetBitsGeneric(const Word* words, size_t n) {
  int64_t bits = 0;
  for (size_t i = 0; i < n; ++i) bits += __builtin_popcountll(words[i]);
  return bits;
}

template <typename Word>
int64_t CountSetBitsOf(const Word* words, size_t n) {
  static const bool has_popcnt = __builtin_cpu_supports("popcnt");
  return has_popcnt ? CountSetBitsPopcnt(words, n) : CountSetBitsGeneric(words, n);
}

}  // namespace

int64_t CountSetBits(const uint64_t* words, size_t n) { return CountSetBitsOf(words, n); }

int64_t CountSetBits(const uint32_t* words, size_t n) { return CountSetBitsOf(words, n); }

}  // namespace gt

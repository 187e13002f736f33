// Bit counts of occupancy words (one bit per depth bin), shared by the occupancy volumes and
// the value checks of stored samples.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gt {

// Number of set bits in words[0, n). Without -mpopcnt, __builtin_popcountll is a call into
// libgcc per word; the POPCNT instruction is used where the CPU has it (same result).
int64_t CountSetBits(const uint64_t* words, size_t n);

}  // namespace gt

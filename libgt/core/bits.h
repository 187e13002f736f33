// Bit counts of occupancy words (one bit per depth bin) and N-view bitmasks, shared by the
// occupancy volumes and the value checks of stored samples.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gt {

// Number of set bits in words[0, n). Without -mpopcnt, __builtin_popcountll is a call into
// libgcc per word; the POPCNT instruction is used where the CPU has it (same result).
int64_t CountSetBits(const uint64_t* words, size_t n);
// The same over 32-bit words (the N-view visibility bitmasks).
int64_t CountSetBits(const uint32_t* words, size_t n);

}  // namespace gt

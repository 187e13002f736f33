// .npz (zip of .npy members) bytes -> gt::io::ParseNpz (libzip from memory, member names,
// compression methods, sizes, then ParseNpy of each member).
#include <cstdint>

#include "libgt/io/npy.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "fuzz.npz";
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    for (const auto& [key, a] : gt::io::ParseNpz(gt::fuzz::Bytes(data, size), name)) {
      if (a.data.size() != static_cast<size_t>(a.NumElements()) * a.ItemSize()) std::abort();
    }
  });
  return 0;
}

// Pickle bytes -> gt::io::ReadPickle (LoFTR's MegaDepth scene_info files): a value or one
// InputError, never a crash, whatever the opcodes, sizes, memo keys or nesting; a value read
// is written back (PickleBytes) and read again to the same bytes.
#include <cstdint>
#include <string>

#include "libgt/core/error.h"
#include "libgt/io/pickle.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = gt::fuzz::Bytes(data, size);
  gt::fuzz::ExpectValueOrInputError("scene_info.npz", [&] {
    const gt::io::PyValue v = gt::io::ReadPickle(bytes, "scene_info.npz");
    const std::string again = gt::io::PickleBytes(v);
    if (gt::io::PickleBytes(gt::io::ReadPickle(again, "again")) != again) __builtin_trap();
  });
  return 0;
}

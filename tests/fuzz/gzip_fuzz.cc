// gzip bytes -> gt::io::GunzipBytes, GunzipInto and GunzipNpy (compressed shard members,
// sample.compression: deflate): the plain bytes or one InputError, never a crash or a large
// allocation, whatever the trailer claims; both entry points agree, and what is read is
// written again (GzipBytes) and reads back the same.
#include <cstdint>
#include <string>

#include "libgt/core/error.h"
#include "libgt/io/gzip.h"
#include "libgt/io/npy.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = gt::fuzz::Bytes(data, size);
  std::string plain;
  bool ok = false;
  gt::fuzz::ExpectValueOrInputError("m.npy.gz", [&] {
    plain = gt::io::GunzipBytes(bytes, "m.npy.gz", size_t{1} << 24);
    ok = true;
  });
  if (ok) {
    std::string into(plain.size(), '\0');
    gt::io::GunzipInto(bytes, into.data(), into.size(), "into");  // must not throw now
    if (into != plain) __builtin_trap();
    if (gt::io::GunzipBytes(gt::io::GzipBytes(plain, 1), "again") != plain) __builtin_trap();
  } else if (size <= 1 << 16) {
    // The exact-size entry point refuses it too, at the size the trailer claims (bounded).
    const uint32_t claimed = gt::io::GzipTrailerSize(bytes);
    std::string into(claimed <= (1u << 20) ? claimed : 0, '\0');
    gt::fuzz::ExpectValueOrInputError("into", [&] {
      gt::io::GunzipInto(bytes, into.data(), into.size(), "into");
      __builtin_trap();  // GunzipBytes refused these bytes: GunzipInto must as well
    });
  }
  // A .npy inside: inflated only to its header's size, and then the same bytes.
  std::string npy;
  bool npy_ok = false;
  gt::fuzz::ExpectValueOrInputError("npy", [&] {
    npy = gt::io::GunzipNpy(bytes, "m.npy.gz");
    npy_ok = true;
  });
  if (npy_ok && (ok ? npy != plain : npy.size() <= (size_t{1} << 24))) __builtin_trap();
  return 0;
}

// Colour image header bytes (PNG IHDR, JPEG segments up to the start of frame, Netpbm) ->
// gt::io::DecodeImageSize, the in-memory twin of ReadImageSize (readers call it for every
// colour image whose size the dataset does not state).
#include <cstdint>

#include "libgt/io/depth_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = "color/0.jpg";
  gt::fuzz::ExpectValueOrInputError(path, [&] {
    const gt::io::ImageSize s = gt::io::DecodeImageSize(gt::fuzz::Bytes(data, size), path);
    if (s.width <= 0 || s.height <= 0) std::abort();  // a size is always positive
  });
  return 0;
}

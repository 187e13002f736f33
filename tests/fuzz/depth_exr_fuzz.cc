// OpenEXR depth bytes -> gt::io::DecodeDepth through an in-memory Imf::IStream: header,
// channel choice by suffix (Z, Y, V or Blender's "<layer>.Depth.Z"), data window, pixels.
#include <cstdint>

#include "libgt/io/depth_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gt::DepthSource src;
  src.path = "depth/0.exr";
  src.format = gt::DepthFormat::kExr;
  gt::fuzz::ExpectValueOrInputError(src.path, [&] {
    const gt::DepthImage d = gt::io::DecodeDepth(gt::fuzz::Bytes(data, size), src);
    if (d.values_m.size() != static_cast<size_t>(d.width) * d.height) std::abort();
  });
  return 0;
}

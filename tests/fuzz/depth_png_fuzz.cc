// 16-bit PNG (and PGM) depth bytes -> gt::io::DecodeDepth through cv::imdecode, with the
// size check from the PNG header before decoding.
#include <cstdint>

#include "libgt/io/depth_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gt::DepthSource src;
  src.path = "depth/0.png";
  src.format = gt::DepthFormat::kPng16;
  src.scale_m_per_unit = 0.001;
  src.invalid_value = 65535;
  gt::fuzz::ExpectValueOrInputError(src.path, [&] {
    const gt::DepthImage d = gt::io::DecodeDepth(gt::fuzz::Bytes(data, size), src);
    if (d.values_m.size() != static_cast<size_t>(d.width) * d.height) std::abort();
  });
  return 0;
}

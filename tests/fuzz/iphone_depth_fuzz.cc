// ScanNet++ iPhone depth.bin bytes -> gt::io::DecodeIphoneDepth (libgt/io/iphone_depth.h).
// The first byte picks the encoding: even, one record's payload (an LZ4 block of uint16 mm,
// or raw deflate of float32 m); odd, a whole-file raw-deflate stream, whose frame index is
// the second byte % 4. A map that decodes is 256x192 with every value finite and >= 0
// (0 = no depth).
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "libgt/io/iphone_depth.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  gt::DepthSource src;
  src.path = "iphone/depth.bin";
  src.width = gt::io::kIphoneDepthWidth;
  src.height = gt::io::kIphoneDepthHeight;
  const bool whole_file = (data[0] & 1) != 0;
  src.format = whole_file ? gt::DepthFormat::kIphoneBinDeflate : gt::DepthFormat::kIphoneBinRecord;
  src.frame_index = whole_file ? data[1] % 4 : 0;
  src.range = {0, size - 2};
  gt::fuzz::ExpectValueOrInputError(src.path, [&] {
    const gt::DepthImage d = gt::io::DecodeIphoneDepth(gt::fuzz::Bytes(data + 2, size - 2), src);
    if (d.width != gt::io::kIphoneDepthWidth || d.height != gt::io::kIphoneDepthHeight ||
        d.values_m.size() != static_cast<size_t>(d.width) * d.height) {
      std::abort();
    }
    for (const float v : d.values_m) {
      if (!std::isfinite(v) || v < 0.0f) std::abort();
    }
  });
  return 0;
}

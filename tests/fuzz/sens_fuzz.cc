// ScanNet .sens bytes -> gt::datasets::ParseSensIndex (header fields, compression codes, image
// sizes, frame count and per-frame byte counts checked against the file's size), then the
// depth decoder on the first frames' payloads (zlib or raw uint16, inflated size checked).
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "libgt/io/depth_io.h"
#include "libgt/datasets/sens.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "fuzz.sens";
  const gt::datasets::SensReadAt read_at = [&](uint64_t offset, size_t n, void* dst) {
    if (offset > size || n > size - offset) std::abort();  // the parser checks before reading
    std::memcpy(dst, data + offset, n);
  };
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const gt::datasets::SensIndex index = gt::datasets::ParseSensIndex(name, size, read_at);
    gt::DepthSource src;
    src.path = name;
    src.format = index.depth_compression == gt::datasets::SensDepthCompression::kZlib
                     ? gt::DepthFormat::kSensZlib
                     : gt::DepthFormat::kSensRaw;
    src.scale_m_per_unit = 1.0 / index.depth_shift;
    src.width = index.depth_width;
    src.height = index.depth_height;
    // Decoding allocates width x height: only small maps, so that each run stays fast.
    if (int64_t{src.width} * src.height > (int64_t{1} << 20)) return;
    for (size_t i = 0; i < std::min<size_t>(index.frames.size(), 3); ++i) {
      const gt::ByteRange& r = index.frames[i].depth;
      if (r.offset > size || r.size > size - r.offset) std::abort();  // the table's invariant
      if (index.frames[i].color.offset + index.frames[i].color.size > r.offset) std::abort();
      src.range = r;
      (void)gt::io::DecodeDepth(
          gt::fuzz::Bytes(data + r.offset, static_cast<size_t>(r.size)), src);
    }
  });
  return 0;
}

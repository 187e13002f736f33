// Colour image bytes (PNG, JPEG, Netpbm) -> gt::io::DecodeImageBytes (libgt/io/codec.h):
// the Netpbm parser, and the libpng / libjpeg wrappers with their longjmp error paths.
// Like the readers (ReadColorResized compares the header size with the camera's first),
// the target decodes only images whose header declares at most 2^22 pixels, so that a
// tiny file declaring a huge JPEG does not hit libFuzzer's memory limit.
#include <cstdint>

#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = "color/0.png";
  const std::string_view bytes = gt::fuzz::Bytes(data, size);
  gt::fuzz::ExpectValueOrInputError(path, [&] {
    const gt::io::ImageSize s = gt::io::DecodeImageSize(bytes, path);
    if (int64_t{s.width} * s.height > (int64_t{1} << 22)) return;
    for (const auto order : {gt::io::ChannelOrder::kRgb, gt::io::ChannelOrder::kBgr}) {
      const cv::Mat m = gt::io::DecodeImageBytes(bytes, order, path);
      if (m.empty() || (m.channels() != 1 && m.channels() != 3 && m.channels() != 4)) {
        std::abort();  // a decoded image always has pixels and 1, 3 or 4 channels
      }
    }
  });
  return 0;
}

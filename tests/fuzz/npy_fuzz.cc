// .npy bytes -> gt::io::ParseNpy (header dict, version, dtype, shape/size checks), then the
// typed view and the depth decoder that the TartanAir/generic readers use.
#include <cstdint>

#include "libgt/io/depth_io.h"
#include "libgt/io/npy.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "fuzz.npy";
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const gt::io::NpyArray a = gt::io::ParseNpy(gt::fuzz::Bytes(data, size), name);
    if (a.data.size() != static_cast<size_t>(a.NumElements()) * a.ItemSize()) std::abort();
    if (a.descr == "<f4") (void)a.As<float>(name);
  });
  gt::DepthSource src;
  src.path = name;
  src.format = gt::DepthFormat::kNpyFloat32;
  gt::fuzz::ExpectValueOrInputError(
      name, [&] { (void)gt::io::DecodeDepth(gt::fuzz::Bytes(data, size), src); });
  return 0;
}

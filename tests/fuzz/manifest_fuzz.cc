// The generic JSON scene manifest (schemas/manifest.schema.json) validated by
// gt::datasets::ParseGenericManifest: JSON syntax, field types, K, poses, depth sources.
#include <cstdint>

#include "libgt/datasets/readers.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // A folder that does not exist: relative depth/colour paths resolve to nothing.
  const std::string name = "/nonexistent-occgt-fuzz/scene.json";
  gt::datasets::ReaderOptions options;
  options.check_depth_files = false;
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const gt::Scene scene =
        gt::datasets::ParseGenericManifest(gt::fuzz::Bytes(data, size), name, "", options);
    if (scene.frames.empty()) std::abort();
    for (const gt::Frame& f : scene.frames) {
      std::string error;
      if (!f.depth_camera.Check(&error)) std::abort();
      if (f.usable && !f.world_from_cam.matrix().allFinite()) std::abort();
    }
  });
  return 0;
}

// The real 7-Scenes sample of ../shared/data (frames 150-199 at 640x480), read once, for
// the benchmarks of the build pipeline (pairs_bench.cc, build_bench.cc).
#pragma once

#include <string>

#include "libgt/core/frame.h"
#include "libgt/datasets/reader.h"
#include "tests/support/test_support.h"

namespace gt::bench {

inline const Scene& SevenScenesSample() {
  static const Scene scene = [] {
    const std::string root = std::string(OCCGT_SHARED_DATA) + "/sevenscenes";
    auto reader = datasets::MakeReader(gt::DatasetFormat::kSevenScenes);
    return reader->ReadScene(root, reader->ListScenes(root).at(0));
  }();
  return scene;
}

}  // namespace gt::bench

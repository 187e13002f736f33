// HDF5 depth maps (libgt/io/hdf5_depth.h, MegaDepth's depths/*.h5): a map written with
// WriteHdf5Depth reads back through ReadDepth (file) and DecodeDepth (bytes) with every
// invalid marker as 0; a wrong size, a file that is not HDF5 and cut files are one error
// naming the file.
#include "libgt/io/hdf5_depth.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <thread>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "tests/support/test_support.h"

namespace gt::io {
namespace {
namespace fs = std::filesystem;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

DepthImage Sample() {
  DepthImage d(5, 3);
  for (int i = 0; i < 15; ++i) d.values_m[static_cast<size_t>(i)] = 1.5f + 0.25f * i;
  d.at(0, 0) = 0.0f;  // MegaDepth's invalid marker
  d.at(1, 0) = std::numeric_limits<float>::quiet_NaN();
  d.at(2, 0) = -3.0f;
  return d;
}

void CheckRead(const DepthImage& d) {
  ASSERT_EQ(d.width, 5);
  ASSERT_EQ(d.height, 3);
  EXPECT_EQ(d.at(0, 0), 0.0f);
  EXPECT_EQ(d.at(1, 0), 0.0f);
  EXPECT_EQ(d.at(2, 0), 0.0f);
  for (int i = 3; i < 15; ++i) EXPECT_EQ(d.values_m[static_cast<size_t>(i)], 1.5f + 0.25f * i);
}

TEST(Hdf5Depth, RoundTripThroughFileAndBytes) {
  const std::string path = (fs::path(test::ScratchDir("hdf5_depth")) / "a.h5").string();
  WriteHdf5Depth(path, Sample());
  EXPECT_FALSE(FileExists(path + ".tmp"));
  DepthSource src;
  src.path = path;
  src.format = DepthFormat::kHdf5;
  CheckRead(ReadDepth(src, 5, 3));
  CheckRead(ReadDepth(src));
  const std::string bytes = ReadFileBytes(path);
  CheckRead(DecodeDepth(bytes, src, 5, 3));
  EXPECT_EQ(ErrorOf([&] { ReadDepth(src, 6, 3); }), path + ": depth is 5x3, expected 6x3");
  EXPECT_EQ(ErrorOf([&] { DecodeDepth(bytes, src, 5, 4); }), path + ": depth is 5x3, expected 5x4");
  // Cut images: one error each, never a crash or a partial map.
  for (size_t n : {size_t{0}, size_t{7}, size_t{100}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string e = ErrorOf([&] { DecodeDepth(bytes.substr(0, n), src); });
    EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << n << ": " << e;
  }
}

// Files and images decoded from many threads at once each give their own values (HDF5
// would share two open in-memory files of one name).
TEST(Hdf5Depth, ManyThreads) {
  const fs::path dir = test::ScratchDir("hdf5_threads");
  std::vector<std::string> bytes;
  std::vector<DepthSource> sources;
  for (int k = 0; k < 4; ++k) {
    DepthImage d(4, 2, 1.0f + k);
    DepthSource src;
    src.path = (dir / (std::to_string(k) + ".h5")).string();
    src.format = DepthFormat::kHdf5;
    WriteHdf5Depth(src.path, d);
    bytes.push_back(ReadFileBytes(src.path));
    sources.push_back(src);
  }
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 20; ++i) {
        const int k = (t + i) % 4;
        const DepthImage a =
            DecodeDepth(bytes[static_cast<size_t>(k)], sources[static_cast<size_t>(k)]);
        const DepthImage b = ReadDepth(sources[static_cast<size_t>(k)], 4, 2);
        if (a.at(3, 1) != 1.0f + k || b.at(3, 1) != 1.0f + k) ++wrong;
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(wrong.load(), 0);
}

TEST(Hdf5Depth, NotHdf5) {
  const std::string path = (fs::path(test::ScratchDir("hdf5_not")) / "a.h5").string();
  test::RunShell("printf 'not hdf5' > '" + path + "'");
  DepthSource src;
  src.path = path;
  src.format = DepthFormat::kHdf5;
  EXPECT_EQ(ErrorOf([&] { ReadDepth(src); }),
            path + ": not an HDF5 file (missing, unreadable or damaged)");
  EXPECT_EQ(ErrorOf([&] { DecodeDepth("not hdf5", src); }),
            path + ": not an HDF5 file (no HDF5 signature at byte 0)");
  src.path += ".missing";
  EXPECT_NE(ErrorOf([&] { ReadDepth(src); }).find("not an HDF5 file"), std::string::npos);
}

}  // namespace
}  // namespace gt::io

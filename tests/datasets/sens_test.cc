// ScanNet raw .sens (libgt/datasets/sens.h): a .sens written here byte by byte (raw uint16 depth
// and raw RGB colour, or zlib depth; the JPEG/PNG colour paths are covered by
// integration/sens) read back through the ScanNet reader: the offset table, depth values
// = raw / depthShift, the colour bytes, lost tracking, frames read in any order and from
// many threads at once (one shared descriptor), and the bad-input errors of the header.
#include "libgt/datasets/sens.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <thread>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/image.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {
namespace fs = std::filesystem;

constexpr int kDw = 6, kDh = 4, kCw = 3, kCh = 2, kFrames = 4;

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

uint16_t RawDepth(int frame, int i) {
  return static_cast<uint16_t>(i == 0 ? 0 : 500 + 37 * frame + i);
}
uint8_t RawColor(int frame, int i) { return static_cast<uint8_t>(frame * 31 + i); }

// A .sens of kFrames frames; frame 2 lost tracking; depth zlib (1) or raw (0).
std::string SensBytes(int32_t depth_compression) {
  std::string b;
  Put<uint32_t>(&b, 4);
  const std::string name = "test";
  Put<uint64_t>(&b, name.size());
  b += name;
  const float kc[16] = {2.5f, 0, 1, 0, 0, 2.5f, 0.5f, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const float kd[16] = {5, 0, 2.5f, 0, 0, 5, 1.5f, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const float eye[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (const float* m : {kc, eye, kd, eye}) b.append(reinterpret_cast<const char*>(m), 64);
  Put<int32_t>(&b, 0);  // raw RGB colour
  Put<int32_t>(&b, depth_compression);
  for (uint32_t v : {kCw, kCh, kDw, kDh}) Put<uint32_t>(&b, v);
  Put<float>(&b, 1000.0f);
  Put<uint64_t>(&b, kFrames);
  for (int f = 0; f < kFrames; ++f) {
    float pose[16];
    std::memcpy(pose, eye, sizeof(pose));
    pose[3] = 0.25f * f;
    if (f == 2) std::fill(pose, pose + 16, -std::numeric_limits<float>::infinity());
    b.append(reinterpret_cast<const char*>(pose), 64);
    std::string color, depth;
    for (int i = 0; i < kCw * kCh * 3; ++i) color.push_back(static_cast<char>(RawColor(f, i)));
    for (int i = 0; i < kDw * kDh; ++i) Put<uint16_t>(&depth, RawDepth(f, i));
    if (depth_compression == 1) {
      uLongf n = compressBound(depth.size());
      std::string z(n, '\0');
      EXPECT_EQ(compress(reinterpret_cast<Bytef*>(z.data()), &n,
                         reinterpret_cast<const Bytef*>(depth.data()), depth.size()),
                Z_OK);
      z.resize(n);
      depth = z;
    }
    Put<uint64_t>(&b, 0);
    Put<uint64_t>(&b, 0);
    Put<uint64_t>(&b, color.size());
    Put<uint64_t>(&b, depth.size());
    b += color + depth;
  }
  Put<uint64_t>(&b, 0);  // numIMU
  return b;
}

std::string WriteScene(const std::string& test, const std::string& bytes) {
  const fs::path dir = fs::path(test::ScratchDir("sens_" + test)) / "scene0001_00";
  fs::create_directories(dir);
  std::ofstream((dir / "scene0001_00.sens").string(), std::ios::binary) << bytes;
  return dir.string();
}

void CheckScene(const Scene& scene, DepthFormat format) {
  ASSERT_EQ(scene.frames.size(), size_t{kFrames});
  EXPECT_EQ(scene.NumUsable(), size_t{kFrames - 1});
  EXPECT_EQ(scene.frames[2].unusable_reason, "pose: non-finite pose entries (lost tracking)");
  EXPECT_EQ(scene.frames[2].unusable_detail,
            scene.path + "/scene0001_00.sens: frame 2: non-finite value");
  for (int f : {3, 0, 1}) {  // any order
    const Frame& fr = scene.frames[static_cast<size_t>(f)];
    EXPECT_EQ(fr.id, std::to_string(f));
    EXPECT_EQ(fr.depth.format, format);
    EXPECT_DOUBLE_EQ(fr.world_from_cam.translation().x(), 0.25 * f);
    EXPECT_EQ(fr.depth_camera.width, kDw);
    EXPECT_DOUBLE_EQ(fr.depth_camera.fx, 5.0);
    EXPECT_DOUBLE_EQ(fr.depth_camera.cy, 1.5);
    EXPECT_EQ(fr.color_camera.width, kCw);
    EXPECT_DOUBLE_EQ(fr.color_camera.fx, 2.5);
    const DepthImage d = ReadDepth(fr.depth, kDw, kDh);
    for (int i = 0; i < kDw * kDh; ++i) {
      const float expected = i == 0 ? 0.0f : static_cast<float>(RawDepth(f, i) * (1.0 / 1000.0));
      ASSERT_EQ(d.values_m[static_cast<size_t>(i)], expected) << f << " " << i;
    }
    const ColorImage c = ReadFrameColor(fr);
    ASSERT_EQ(c.rgb.size(), size_t{kCw * kCh * 3});
    for (int i = 0; i < kCw * kCh * 3; ++i)
      ASSERT_EQ(c.rgb[static_cast<size_t>(i)], RawColor(f, i));
  }
}

TEST(Sens, RawAndZlibDepthRawColour) {
  for (int32_t dc : {0, 1}) {
    const std::string dir = WriteScene("ok" + std::to_string(dc), SensBytes(dc));
    const auto reader = MakeReader(gt::DatasetFormat::kScanNet);
    EXPECT_EQ(reader->ListScenes(fs::path(dir).parent_path().string()),
              std::vector<std::string>{"scene0001_00"});
    CheckScene(reader->ReadScene(dir, ""),
               dc == 1 ? DepthFormat::kSensZlib : DepthFormat::kSensRaw);
  }
}

TEST(Sens, ThreadsShareTheFile) {
  const std::string dir = WriteScene("threads", SensBytes(1));
  const Scene scene = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  std::vector<std::thread> threads;
  std::vector<int> ok(8, 0);
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (int k = 0; k < 50; ++k) {
        const int f = (t + k) % kFrames == 2 ? 0 : (t + k) % kFrames;
        const DepthImage d = ReadDepth(scene.frames[static_cast<size_t>(f)].depth);
        if (d.values_m[1] != static_cast<float>(RawDepth(f, 1) * (1.0 / 1000.0))) return;
      }
      ok[static_cast<size_t>(t)] = 1;
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(std::count(ok.begin(), ok.end(), 1), 8);
}

// The header's fields and the first frame's, at their byte offsets.
constexpr size_t kNameEnd = 4 + 8 + 4;
constexpr size_t kColorCompression = kNameEnd + 4 * 64;
constexpr size_t kNumFrames = kColorCompression + 8 + 16 + 4;
constexpr size_t kFrame0 = kNumFrames + 8;

std::string Patched(std::string b, size_t offset, uint64_t value, size_t bytes) {
  std::memcpy(&b[offset], &value, bytes);
  return b;
}

std::string ErrorOf(const std::string& name, const std::string& bytes) {
  const std::string dir = WriteScene(name, bytes);
  try {
    (void)MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(dir + "/scene0001_00.sens"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    return what;
  }
  ADD_FAILURE() << name << ": no error";
  return "";
}

TEST(Sens, BadInputIsOneLine) {
  const std::string good = SensBytes(1);
  EXPECT_NE(ErrorOf("cut_header", good.substr(0, 100)).find("file ends at byte 100"),
            std::string::npos);
  EXPECT_NE(ErrorOf("cut_frames", good.substr(0, kFrame0 + 96 + 5))
                .find("numFrames: 4, but the file holds at most 1 frame headers"),
            std::string::npos);
  EXPECT_NE(ErrorOf("cut_payload", good.substr(0, good.size() - 8 - 10))
                .find("frame 3: colorBytes 18 + depthBytes"),
            std::string::npos);
  EXPECT_NE(ErrorOf("count", Patched(good, kNumFrames, 1u << 30, 8)).find("numFrames: 1073741824"),
            std::string::npos);
  EXPECT_NE(ErrorOf("bytes", Patched(good, kFrame0 + 64 + 24, uint64_t{1} << 62, 8))
                .find("run past the end of the file"),
            std::string::npos);
  EXPECT_NE(ErrorOf("width", Patched(good, kColorCompression + 16, 70000, 4))
                .find("depthWidth: 70000, expected an image size in 1..65536"),
            std::string::npos);
  EXPECT_NE(ErrorOf("occi", Patched(good, kColorCompression + 4, 2, 4))
                .find("depthCompression: 2 (OCCI, proprietary) is not supported"),
            std::string::npos);
  EXPECT_NE(ErrorOf("raw_size", Patched(SensBytes(0), kFrame0 + 64 + 24, 10, 8))
                .find("frame 0: depthBytes 10, expected 48 (raw uint16 depth)"),
            std::string::npos);
  EXPECT_NE(ErrorOf("name", Patched(good, 4, uint64_t{1} << 40, 8)).find("sensor name length"),
            std::string::npos);
}

// A bad frame of a .sens names the frame's index: its pose (lost tracking, a non-rigid
// rotation) or a frame without depth bytes makes it unusable; its header's errors name it.
TEST(Sens, BadFrameNamesItsIndex) {
  constexpr size_t kFrameBytes = 64 + 32 + kCw * kCh * 3 + kDw * kDh * 2;  // raw payloads
  std::string b = SensBytes(0);
  const float scaled = 2.0f;  // frame 1: R(0, 0) = 2, not orthonormal
  std::memcpy(&b[kFrame0 + kFrameBytes], &scaled, 4);
  b = Patched(b, kFrame0 + 3 * kFrameBytes + 64 + 24, 0, 8);  // frame 3: depthBytes 0
  const std::string dir = WriteScene("bad_frames", b);
  const std::string path = dir + "/scene0001_00.sens";
  const Scene scene = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  ASSERT_EQ(scene.frames.size(), size_t{kFrames});
  EXPECT_TRUE(scene.frames[0].usable);
  EXPECT_EQ(scene.frames[1].unusable_reason,
            "pose: rotation is not orthonormal (|R^T R - I| > 0.001)");
  EXPECT_EQ(scene.frames[1].unusable_detail,
            path + ": frame 1: rotation is not orthonormal (|R^T R - I| = 3 > 0.001)");
  EXPECT_EQ(scene.frames[2].unusable_detail, path + ": frame 2: non-finite value");
  EXPECT_EQ(scene.frames[3].unusable_reason, "depth: missing file");
  EXPECT_EQ(scene.frames[3].unusable_detail,
            path + ": frame 3: depthBytes is 0 (no depth payload)");
  try {
    (void)MakeReader(gt::DatasetFormat::kScanNet)
        ->ReadScene(
            WriteScene("bad_size", Patched(SensBytes(0), kFrame0 + kFrameBytes + 64 + 24, 10, 8)),
            "");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().substr(e.where().rfind(".sens")), ".sens: frame 1") << e.what();
    EXPECT_NE(std::string(e.what()).find("depthBytes 10, expected 48"), std::string::npos)
        << e.what();
  }
}

TEST(Sens, DamagedZlibPayloadNamesItsOffset) {
  std::string b = SensBytes(1);
  const std::string dir = WriteScene("zlib", b);
  const Scene scene = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  const ByteRange r = scene.frames[0].depth.range;
  for (uint64_t i = 2; i < r.size; ++i) b[r.offset + i] = '\x5a';
  const std::string dir2 = WriteScene("zlib2", b);
  const Scene scene2 = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir2, "");
  try {
    (void)ReadDepth(scene2.frames[0].depth);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(": frame 0 (depth payload at byte " +
                                         std::to_string(r.offset) + ")"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace gt::datasets

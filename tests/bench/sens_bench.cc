// ScanNet raw .sens read in place (libgt/io/sens.h): listing a scene (the offset table from
// the frame headers) and decoding one frame (pread + zlib depth 640x480 + JPEG colour
// 1296x968, ScanNet's usual sizes). The .sens files are written at start-up under the
// build tree from the real 7-Scenes sample (depth as it is; colour resized to 1296x968,
// JPEG quality 90), page cache warm. docs/PERFORMANCE.md quotes the figures.
#include <benchmark/benchmark.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "libgt/io/reader.h"
#include "tests/bench/seven_scenes_sample.h"

namespace gt::bench {
namespace {

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// A .sens of `frames` frames, each with the same colour and depth payloads.
std::string WriteSens(const std::string& name, int frames, const std::string& color,
                      const std::string& depth) {
  const std::string dir = test::ScratchDir("sens_bench_" + name) + "/" + name;
  std::filesystem::create_directories(dir);
  std::string h;
  Put<uint32_t>(&h, 4);
  Put<uint64_t>(&h, 0);
  const float kc[16] = {1170, 0, 647.5f, 0, 0, 1170, 483.5f, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const float kd[16] = {585, 0, 320, 0, 0, 585, 240, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const float eye[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (const float* m : {kc, eye, kd, eye}) h.append(reinterpret_cast<const char*>(m), 64);
  Put<int32_t>(&h, 2);
  Put<int32_t>(&h, 1);
  for (uint32_t v : {1296u, 968u, 640u, 480u}) Put<uint32_t>(&h, v);
  Put<float>(&h, 1000.0f);
  Put<uint64_t>(&h, static_cast<uint64_t>(frames));
  std::string frame;
  frame.append(reinterpret_cast<const char*>(eye), 64);
  for (uint64_t v : {uint64_t{0}, uint64_t{0}, uint64_t{color.size()}, uint64_t{depth.size()}}) {
    Put<uint64_t>(&frame, v);
  }
  frame += color + depth;
  std::ofstream out(dir + "/" + name + ".sens", std::ios::binary);
  out << h;
  for (int i = 0; i < frames; ++i) out << frame;
  out.write("\0\0\0\0\0\0\0\0", 8);
  return dir;
}

struct Payloads {
  std::string color, depth;
};

const Payloads& RealPayloads() {
  static const Payloads p = [] {
    const Frame& f = SevenScenesSample().frames.at(0);
    const io::ColorImage c = io::ReadColor(f.color_path);
    cv::Mat rgb(c.height, c.width, CV_8UC3, const_cast<uint8_t*>(c.rgb.data())), big;
    cv::resize(rgb, big, cv::Size(1296, 968), 0, 0, cv::INTER_LINEAR);
    Payloads out;
    out.color = io::EncodeJpegBytes(big, io::ChannelOrder::kRgb, 90, "bench");
    const DepthImage d = io::ReadDepth(f.depth);
    std::vector<uint16_t> raw(d.values_m.size());
    for (size_t i = 0; i < raw.size(); ++i) {
      raw[i] = static_cast<uint16_t>(std::lround(d.values_m[i] * 1000.0f));
    }
    uLongf n = compressBound(raw.size() * 2);
    out.depth.resize(n);
    compress(reinterpret_cast<Bytef*>(out.depth.data()), &n,
             reinterpret_cast<const Bytef*>(raw.data()), raw.size() * 2);
    out.depth.resize(n);
    return out;
  }();
  return p;
}

// Listing: the header and 2000 frame headers, payloads skipped (1 KiB payloads here: the
// cost is one 96-byte pread per frame, whatever the payload size).
void BM_ListScene(benchmark::State& state) {
  const std::string dir = WriteSens("list", 2000, std::string(512, 'c'), std::string(512, 'd'));
  const auto reader = io::MakeReader("scannet");
  for (auto _ : state) {
    const Scene s = reader->ReadScene(dir, "");
    benchmark::DoNotOptimize(s.frames.size());
  }
  state.counters["frames"] = 2000;
}
BENCHMARK(BM_ListScene)->Unit(benchmark::kMillisecond);

// One frame: depth (pread + inflate + metres) and colour (pread + JPEG decode), full size.
void BM_DecodeFrame(benchmark::State& state) {
  const Payloads& p = RealPayloads();
  const std::string dir = WriteSens("frame", 3, p.color, p.depth);
  const Scene s = io::MakeReader("scannet")->ReadScene(dir, "");
  const Frame& f = s.frames.at(1);
  for (auto _ : state) {
    const DepthImage d = io::ReadDepth(f.depth, 640, 480);
    const io::ColorImage c = io::ReadFrameColor(f);
    benchmark::DoNotOptimize(d.values_m.data());
    benchmark::DoNotOptimize(c.rgb.data());
  }
  state.counters["jpeg_KB"] = static_cast<double>(p.color.size()) / 1024;
  state.counters["zlib_KB"] = static_cast<double>(p.depth.size()) / 1024;
}
BENCHMARK(BM_DecodeFrame)->Unit(benchmark::kMillisecond);

void BM_DecodeDepthOnly(benchmark::State& state) {
  const Payloads& p = RealPayloads();
  const std::string dir = WriteSens("depth", 3, p.color, p.depth);
  const Scene s = io::MakeReader("scannet")->ReadScene(dir, "");
  for (auto _ : state)
    benchmark::DoNotOptimize(io::ReadDepth(s.frames.at(1).depth).values_m.data());
}
BENCHMARK(BM_DecodeDepthOnly)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gt::bench

BENCHMARK_MAIN();

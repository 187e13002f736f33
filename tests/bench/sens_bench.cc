// ScanNet raw .sens read in place (libgt/datasets/sens.h): listing a scene (the offset table from
// the frame headers) and decoding one frame (pread + zlib depth 640x480 + JPEG colour
// 1296x968, ScanNet's usual sizes), and scoring a scene for pair selection from a .sens
// against the same frames in the exported layout (pose/, depth/ 16-bit PNG, color/,
// intrinsic/). The files are written at start-up under the build tree from the real 7-Scenes
// sample (depth as it is; colour resized to 1296x968, JPEG quality 90), page cache warm.
// docs/PERFORMANCE.md quotes the figures.
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
#include "libgt/datasets/reader.h"
#include "libgt/pairs/selection.h"
#include "libgt/truth/working_frame.h"
#include "tests/bench/seven_scenes_sample.h"

namespace gt::bench {
namespace {

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// A version-4 header: JPEG colour 1296x968 (K 1170, 647.5, 483.5), zlib depth 640x480 with
// depth K `kd` (default 585, 320, 240), depth shift 1000, `frames` frames.
std::string SensHeader(uint64_t frames,
                       const Eigen::Matrix3d& kd =
                           (Eigen::Matrix3d() << 585, 0, 320, 0, 585, 240, 0, 0, 1).finished()) {
  std::string h;
  Put<uint32_t>(&h, 4);
  Put<uint64_t>(&h, 0);
  const float kc[16] = {1170, 0, 647.5f, 0, 0, 1170, 483.5f, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float kdm[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) kdm[4 * r + c] = static_cast<float>(kd(r, c));
  }
  const float eye[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (const float* m : {kc, eye, static_cast<const float*>(kdm), eye}) {
    h.append(reinterpret_cast<const char*>(m), 64);
  }
  Put<int32_t>(&h, 2);
  Put<int32_t>(&h, 1);
  for (uint32_t v : {1296u, 968u, 640u, 480u}) Put<uint32_t>(&h, v);
  Put<float>(&h, 1000.0f);
  Put<uint64_t>(&h, frames);
  return h;
}

// A .sens of `frames` frames, each with the same colour and depth payloads.
std::string WriteSens(const std::string& name, int frames, const std::string& color,
                      const std::string& depth) {
  const std::string dir = test::ScratchDir("sens_bench_" + name) + "/" + name;
  std::filesystem::create_directories(dir);
  const std::string h = SensHeader(static_cast<uint64_t>(frames));
  const float eye[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
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

// Bytes this process has read through read/pread so far (/proc/self/io "rchar").
double BytesReadSoFar() {
  std::ifstream io("/proc/self/io");
  std::string key;
  double value = 0;
  while (io >> key >> value) {
    if (key == "rchar:") return value;
  }
  return 0;
}

// Listing: the header and 5000 frame headers, payloads skipped (1 KiB payloads here: the
// cost is one 96-byte pread per frame, whatever the payload size). Counters: the bytes read
// per listing (rchar) against the file's size.
void BM_ListScene(benchmark::State& state) {
  const int frames = 5000;
  const std::string dir = WriteSens("list", frames, std::string(512, 'c'), std::string(512, 'd'));
  const auto reader = datasets::MakeReader(gt::DatasetFormat::kScanNet);
  const double before = BytesReadSoFar();
  for (auto _ : state) {
    const Scene s = reader->ReadScene(dir, "");
    benchmark::DoNotOptimize(s.frames.size());
  }
  state.counters["frames"] = frames;
  state.counters["bytes_read"] =
      (BytesReadSoFar() - before) / static_cast<double>(state.iterations());
  state.counters["file_bytes"] =
      static_cast<double>(std::filesystem::file_size(dir + "/list.sens"));
}
BENCHMARK(BM_ListScene)->Unit(benchmark::kMillisecond);

// One frame: depth (pread + inflate + metres) and colour (pread + JPEG decode), full size.
void BM_DecodeFrame(benchmark::State& state) {
  const Payloads& p = RealPayloads();
  const std::string dir = WriteSens("frame", 3, p.color, p.depth);
  const Scene s = datasets::MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
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
  const Scene s = datasets::MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  for (auto _ : state)
    benchmark::DoNotOptimize(io::ReadDepth(s.frames.at(1).depth).values_m.data());
}
BENCHMARK(BM_DecodeDepthOnly)->Unit(benchmark::kMillisecond);

// The 50 frames of the 7-Scenes sample, each with its own depth and pose, written as one
// .sens (zlib depth, the 1296x968 JPEG colour) and as the exported layout (16-bit PNG
// depth in mm, the same JPEG as color/<n>.jpg, pose text, intrinsic_depth.txt).
struct TwoLayouts {
  std::string sens_dir, export_dir;
};

const TwoLayouts& SampleBothWays() {
  static const TwoLayouts t = [] {
    const Scene& sample = SevenScenesSample();
    const Payloads& p = RealPayloads();
    TwoLayouts out;
    out.sens_dir = test::ScratchDir("sens_bench_score") + "/seven";
    out.export_dir = test::ScratchDir("sens_bench_score_export") + "/seven";
    for (const char* sub : {"pose", "depth", "color", "intrinsic"}) {
      std::filesystem::create_directories(out.export_dir + "/" + sub);
    }
    std::filesystem::create_directories(out.sens_dir);
    const Eigen::Matrix3d K = sample.frames.at(0).depth_camera.K();
    std::ofstream(out.export_dir + "/intrinsic/intrinsic_depth.txt")
        << K(0, 0) << " 0 " << K(0, 2) << " 0\n0 " << K(1, 1) << " " << K(1, 2)
        << " 0\n0 0 1 0\n0 0 0 1\n";
    std::string frames;
    for (size_t i = 0; i < sample.frames.size(); ++i) {
      const Frame& f = sample.frames[i];
      const DepthImage d = io::ReadDepth(f.depth);
      cv::Mat mm(d.height, d.width, CV_16UC1);
      for (int v = 0; v < d.height; ++v) {
        for (int u = 0; u < d.width; ++u) {
          mm.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(d.at(u, v) * 1000.0f));
        }
      }
      const std::string n = std::to_string(i);
      std::ofstream(out.export_dir + "/depth/" + n + ".png", std::ios::binary)
          << io::EncodePngBytes(mm, io::ChannelOrder::kRgb, 6, "bench");
      std::ofstream(out.export_dir + "/color/" + n + ".jpg", std::ios::binary) << p.color;
      const Eigen::Matrix4d T = f.world_from_cam.matrix();
      std::ofstream pose(out.export_dir + "/pose/" + n + ".txt");
      float m[16];
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
          pose << T(r, c) << (c == 3 ? "\n" : " ");
          m[4 * r + c] = static_cast<float>(T(r, c));
        }
      }
      uLongf z = compressBound(mm.total() * 2);
      std::string depth(z, '\0');
      compress(reinterpret_cast<Bytef*>(depth.data()), &z, mm.data, mm.total() * 2);
      depth.resize(z);
      frames.append(reinterpret_cast<const char*>(m), 64);
      for (uint64_t v :
           {uint64_t{0}, uint64_t{0}, uint64_t{p.color.size()}, uint64_t{depth.size()}}) {
        Put<uint64_t>(&frames, v);
      }
      frames += p.color + depth;
    }
    // The header of WriteSens with this scene's depth K and frame count.
    std::string h = SensHeader(static_cast<uint64_t>(sample.frames.size()), K);
    std::ofstream sens(out.sens_dir + "/seven.sens", std::ios::binary);
    sens << h << frames;
    sens.write("\0\0\0\0\0\0\0\0", 8);
    return out;
  }();
  return t;
}

// Pair selection's scoring work on one scene: the frame scan (every depth map decoded and
// resized, cold cache) and both directions of the pairs 8 frames apart at score_stride 8.
void ScoreScene(benchmark::State& state, const std::string& dir) {
  const Scene scene = datasets::MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  std::vector<Camera> cams;
  for (const auto& f : scene.frames) cams.push_back(truth::WorkingCamera(f, {640, 480}));
  LabelOptions labels = LabelPreset("default");
  labels.min_depth_m = scene.min_depth_m;
  labels.max_depth_m = scene.max_depth_m;
  pairs::FrameScanOptions o;
  o.min_depth_m = scene.min_depth_m;
  o.max_depth_m = scene.max_depth_m;
  int64_t scored = 0;
  for (auto _ : state) {
    pairs::DepthCache cache(scene, 640, 480);
    const pairs::ScanResult r = pairs::ScanFrames(scene, o, &cache);
    std::vector<pairs::CandidatePair> candidates;
    for (size_t k = 0; k + 8 < r.kept.size(); ++k) candidates.push_back({r.kept[k], r.kept[k + 8]});
    pairs::DropCounts drops;
    auto s = pairs::ScorePairs(scene, cams, candidates, labels, 8, &cache, &drops);
    benchmark::DoNotOptimize(s.data());
    scored = static_cast<int64_t>(s.size());
  }
  state.counters["frames"] = static_cast<double>(scene.frames.size());
  state.counters["pairs"] = static_cast<double>(scored);
}

void BM_ScoreSceneSens(benchmark::State& state) { ScoreScene(state, SampleBothWays().sens_dir); }
BENCHMARK(BM_ScoreSceneSens)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ScoreSceneExported(benchmark::State& state) {
  ScoreScene(state, SampleBothWays().export_dir);
}
BENCHMARK(BM_ScoreSceneExported)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace gt::bench

BENCHMARK_MAIN();

// Throughput of the build pipeline on the real 7-Scenes sample (640×480, 50 frames):
// scoring a candidate pair (both directions, score_stride 8, depth cached), the frame scan
// (decode + resize + valid fraction + median). One full sample: build_bench.cc.
// Figures and commands: docs/PERFORMANCE.md.
#include <benchmark/benchmark.h>

#include "libgt/datasets/reader.h"
#include "libgt/pairs/selection.h"
#include "libgt/truth/working_frame.h"
#include "tests/bench/seven_scenes_sample.h"
#include "tests/support/test_support.h"

namespace gt::pairs {
namespace {

std::vector<Camera> Cameras(const Scene& scene) {
  std::vector<Camera> cams;
  for (const auto& f : scene.frames) cams.push_back(truth::WorkingCamera(f, {640, 480}));
  return cams;
}

void BM_ScorePair(benchmark::State& state) {
  const Scene& scene = bench::SevenScenesSample();
  const auto cams = Cameras(scene);
  DepthCache cache(scene, 640, 480);
  LabelOptions labels = LabelPreset("default");
  labels.min_depth_m = scene.min_depth_m;
  labels.max_depth_m = scene.max_depth_m;
  std::vector<CandidatePair> pairs;
  for (size_t i = 0; i + 8 < scene.frames.size(); ++i) pairs.push_back({i, i + 8});
  for (const auto& p : pairs) cache.Get(p.i0), cache.Get(p.i1);  // decode outside the loop
  DropCounts drops;
  const int stride = static_cast<int>(state.range(0));
  for (auto _ : state) {
    auto scored = ScorePairs(scene, cams, pairs, labels, stride, &cache, &drops);
    benchmark::DoNotOptimize(scored.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(pairs.size()));
}
BENCHMARK(BM_ScorePair)->Arg(8)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ScanFrames(benchmark::State& state) {
  const Scene& scene = bench::SevenScenesSample();
  FrameScanOptions o;
  o.min_depth_m = scene.min_depth_m;
  o.max_depth_m = scene.max_depth_m;
  for (auto _ : state) {
    DepthCache cache(scene, 640, 480);  // cold: every depth PNG decoded
    ScanResult r = ScanFrames(scene, o, &cache);
    benchmark::DoNotOptimize(r.kept.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scene.frames.size()));
}
BENCHMARK(BM_ScanFrames)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace gt::pairs

BENCHMARK_MAIN();

// truth::ComputeViewsTruth of 8 views of the real 7-Scenes sample (every 6th usable frame
// from the first, as tests/bench/views_bench.py picks them) at 640x480, 512 tracks, the
// default preset with the scene's depth range, on one TBB thread: the C++ part of
// occgt.views_ground_truth (docs/PERFORMANCE.md "N views"; issue 34), without Python's
// conversions. For profiling the labelling (perf record on this binary has symbols).
// Freed memory stays in the process, as in the occgt binary (apps/main.cc) and the Python
// module: otherwise every repetition faults the 25 MB of results in afresh, which took
// 115 ms a call here against 26 ms from Python.
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <tbb/global_control.h>

#include <vector>

#include "libgt/truth/views_truth.h"
#include "libgt/truth/working_frame.h"
#include "tests/bench/seven_scenes_sample.h"

namespace {

const std::vector<gt::truth::WorkingFrame>& Views() {
  static const std::vector<gt::truth::WorkingFrame> views = [] {
    const gt::Scene& scene = gt::bench::SevenScenesSample();
    std::vector<const gt::Frame*> usable;
    for (const gt::Frame& f : scene.frames) {
      if (f.usable) usable.push_back(&f);
    }
    std::vector<gt::truth::WorkingFrame> out;
    for (size_t i = 0; i < usable.size() && out.size() < 8; i += 6) {
      out.push_back(gt::truth::LoadWorkingFrame(*usable[i], {640, 480}));
    }
    return out;
  }();
  return views;
}

void BM_ViewsTruth8(benchmark::State& state) {
  const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const gt::Scene& scene = gt::bench::SevenScenesSample();
  gt::truth::ViewsTruthOptions o;
  o.labels = gt::LabelPreset("default");
  gt::ApplyDatasetDepthRange(scene.min_depth_m, scene.max_depth_m, &o.labels);
  o.num_tracks = 512;
  const auto& views = Views();
  if (views.size() != 8) state.SkipWithError("expected 8 usable frames");
  for (auto _ : state) {
    const gt::truth::ViewsTruth t = gt::truth::ComputeViewsTruth(views, o);
    benchmark::DoNotOptimize(t.visible_in.data());
  }
}
BENCHMARK(BM_ViewsTruth8)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // as apps/main.cc KeepFreedMemory
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

// truth::ComputeViewsTruth of 8 views of the real 7-Scenes sample (every 6th usable frame
// from the first, as tests/bench/views_bench.py picks them) at 640x480, 512 tracks, the
// default preset with the scene's depth range, on one TBB thread: the C++ part of
// occgt.views_ground_truth (docs/PERFORMANCE.md "N views"; issue 34), without Python's
// conversions. For profiling the labelling (perf record on this binary has symbols).
#include <benchmark/benchmark.h>
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

BENCHMARK_MAIN();

// Coarse patch matches of one pair at 640x480, stride 8 (80x60 cells), one thread
// (GROUND_TRUTH.md §4, libgt/geometry/patches.h), from the labels of both directions:
//  - BM_PatchMatches/<mutual>: ComputePatchMatches alone (labels computed once, outside);
//  - BM_LabelsAndPatchMatches: both label directions + matches, the per-pair share of a
//    sample's labels and matches in the write stage.
// Scene: tests/bench/two_view_scene.h (a box in front of a wall, B moved 0.9 m sideways and
// yawed 9°).
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <cmath>

#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "tests/bench/two_view_scene.h"

namespace {

using Scene = gt::bench::TwoViewScene;
const Scene& GetScene() { return gt::bench::GetTwoViewScene(); }

void BM_PatchMatches(benchmark::State& state) {
  const Scene& s = GetScene();
  const gt::Rigid3d a_from_b = s.b_from_a.inverse();
  const gt::LabelOptions o = gt::LabelPreset("default");
  const auto l01 = gt::LabelDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o);
  const auto l10 = gt::LabelDirection(s.depth_b, s.cam, s.depth_a, s.cam, a_from_b, o);
  gt::PatchOptions p;
  p.mutual = state.range(0) != 0;
  size_t matches = 0;
  for (auto _ : state) {
    auto m = gt::ComputePatchMatches(l01, l10, p);
    matches = m.size();
    benchmark::DoNotOptimize(m.matches.data());
  }
  state.counters["matches"] = static_cast<double>(matches);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PatchMatches)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

void BM_LabelsAndPatchMatches(benchmark::State& state) {
  const Scene& s = GetScene();
  const gt::Rigid3d a_from_b = s.b_from_a.inverse();
  const gt::LabelOptions o = gt::LabelPreset("default");
  const gt::PatchOptions p;
  for (auto _ : state) {
    const auto l01 = gt::LabelDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o);
    const auto l10 = gt::LabelDirection(s.depth_b, s.cam, s.depth_a, s.cam, a_from_b, o);
    auto m = gt::ComputePatchMatches(l01, l10, p);
    benchmark::DoNotOptimize(m.matches.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LabelsAndPatchMatches)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

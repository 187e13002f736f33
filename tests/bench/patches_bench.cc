// Coarse patch matches of one pair at 640x480, stride 8 (80x60 cells), one thread
// (GROUND_TRUTH.md §4, libgt/geometry/patches.h), from the labels of both directions:
//  - BM_PatchMatches/<mutual>: ComputePatchMatches alone (labels computed once, outside);
//  - BM_LabelsAndPatchMatches: both label directions + matches, the per-pair share of a
//    sample's labels and matches in the write stage.
// Scene: the box in front of a wall of tests/bench/labels_bench.cc (B moved 0.9 m sideways
// and yawed 9°).
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <cmath>

#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "tests/geometry/reference.h"

namespace {

struct Scene {
  gt::Camera cam;
  gt::DepthImage depth_a, depth_b;
  gt::Rigid3d b_from_a, a_from_b;
};

const Scene& GetScene() {
  static const Scene scene = [] {
    Scene s;
    s.cam.width = 640;
    s.cam.height = 480;
    s.cam.fx = s.cam.fy = 500;
    s.cam.cx = 319.5;
    s.cam.cy = 239.5;
    std::vector<gt::test::Rect> rects;
    rects.push_back({2, 5.0, {-1e9, -1e9}, {1e9, 1e9}});
    rects.push_back({2, 2.5, {-0.5, -0.4}, {0.5, 0.4}});
    rects.push_back({0, 0.5, {-0.4, 2.5}, {0.4, 3.2}});
    gt::Rigid3d world_from_b = gt::Rigid3d::Identity();
    world_from_b.linear() = Eigen::AngleAxisd(-9 * M_PI / 180, Eigen::Vector3d::UnitY()).matrix();
    world_from_b.translation() = Eigen::Vector3d(0.9, 0.1, -0.2);
    s.depth_a = gt::test::Render(rects, s.cam, gt::Rigid3d::Identity()).depth;
    s.depth_b = gt::test::Render(rects, s.cam, world_from_b).depth;
    s.b_from_a = gt::RelativePose(gt::Rigid3d::Identity(), world_from_b);
    s.a_from_b = s.b_from_a.inverse();
    return s;
  }();
  return scene;
}

void BM_PatchMatches(benchmark::State& state) {
  const Scene& s = GetScene();
  const gt::LabelOptions o = gt::LabelPreset("default");
  const auto l01 = gt::LabelDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o);
  const auto l10 = gt::LabelDirection(s.depth_b, s.cam, s.depth_a, s.cam, s.a_from_b, o);
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
  const gt::LabelOptions o = gt::LabelPreset("default");
  const gt::PatchOptions p;
  for (auto _ : state) {
    const auto l01 = gt::LabelDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o);
    const auto l10 = gt::LabelDirection(s.depth_b, s.cam, s.depth_a, s.cam, s.a_from_b, o);
    auto m = gt::ComputePatchMatches(l01, l10, p);
    benchmark::DoNotOptimize(m.matches.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LabelsAndPatchMatches)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

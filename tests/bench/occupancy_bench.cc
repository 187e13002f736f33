// Occupancy target speed: both cameras of a real pair at 640x480, 5 cm voxels, pair fusion,
// one thread (the target: <= 100 ms for fusion + both volumes), broken down into
// back-projection, fusion and binning, next to a naive use of OctoMap for the same output
// (OcTree::insertPointCloud of every valid point of both frames without discretization, each
// with its camera centre and max range, then OcTree::search at every bin centre of both
// cameras). Peak memory: run one benchmark under /usr/bin/time -v. Figures and commands:
// docs/PERFORMANCE.md, section "Occupancy".
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <memory>

#include "libgt/io/depth_io.h"
#include "libgt/datasets/reader.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "tests/occupancy/reference_traversal.h"
#include "tests/support/test_support.h"

namespace gt::occupancy {
namespace {

struct PairData {
  DepthImage d0, d1;
  FusionInput in0, in1;
};

// arg 0: TartanAir hospital 0/20, arg 1: 7-Scenes 150/190.
const PairData& Data(int which) {
  static PairData pairs[2];
  static bool loaded[2] = {false, false};
  PairData& p = pairs[which];
  if (loaded[which]) return p;
  const std::string format = which == 0 ? "tartanair" : "sevenscenes";
  const std::string root =
      gt::test::SharedData(which == 0 ? "tartanair/hospital_sample" : "sevenscenes/rgbd-frames");
  const Scene s = datasets::MakeReader(ParseDatasetFormat(format))->ReadScene(root, "");
  const int64_t n0 = which == 0 ? 0 : 150, n1 = which == 0 ? 20 : 190;
  for (const Frame& f : s.frames) {
    if (f.number != n0 && f.number != n1) continue;
    DepthImage& d = f.number == n0 ? p.d0 : p.d1;
    FusionInput& in = f.number == n0 ? p.in0 : p.in1;
    d = ResizeDepthNearest(io::ReadDepth(f.depth), 640, 480);
    in = {&d, f.depth_camera.Resized(640, 480), f.world_from_cam, s.min_depth_m, s.max_depth_m};
  }
  loaded[which] = true;
  return p;
}

void SetLabel(benchmark::State& state) {
  state.SetLabel(state.range(0) == 0 ? "tartanair 0/20" : "7-scenes 150/190");
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  state.counters["maxrss_MB"] = ru.ru_maxrss / 1024.0;
}

// The whole target: fuse the pair, bin both cameras (exact traversal).
void BM_PairTotal(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    PairOccupancy out =
        ComputePairOccupancy(p.in0, p.in1, FusionOptions(), BinOptions(), OccupancyMode::kOctomap);
    benchmark::DoNotOptimize(out.cam0.occ.data());
  }
  SetLabel(state);
}

// The same with bin-centre sampling: the output of the naive baseline below.
void BM_PairTotalCenter(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  BinOptions b;
  b.traversal = Traversal::kCenter;
  for (auto _ : state) {
    PairOccupancy out =
        ComputePairOccupancy(p.in0, p.in1, FusionOptions(), b, OccupancyMode::kOctomap);
    benchmark::DoNotOptimize(out.cam0.occ.data());
  }
  SetLabel(state);
}

void BM_BackProject(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    auto a = BackProjectValid(p.in0);
    auto b = BackProjectValid(p.in1);
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(b.data());
  }
  SetLabel(state);
}

void BM_BackProjectAndDownsample(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    for (const FusionInput* in : {&p.in0, &p.in1}) {
      auto pts = DownsampleVoxelCentroids(BackProjectValid(*in), 0.05, nullptr);
      benchmark::DoNotOptimize(pts.data());
    }
  }
  SetLabel(state);
}

// Own engine (the default): back-projection + OctoMap-equivalent ray casting.
void BM_Fuse(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    OccupancyMap map = FuseOccupancy({p.in0, p.in1}, FusionOptions());
    benchmark::DoNotOptimize(map.resolution_m());
  }
  SetLabel(state);
}

// The same map with OctoMap's own discretized insertPointCloud (the reference engine).
void BM_FuseOctomapDiscretized(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  FusionOptions o;
  o.engine = FusionEngine::kOctomap;
  for (auto _ : state) {
    OccupancyMap map = FuseOccupancy({p.in0, p.in1}, o);
    benchmark::DoNotOptimize(map.resolution_m());
  }
  SetLabel(state);
}

// Voxel-grid downsampling before the (discretized) insertion, off by default.
void BM_FuseWithDownsample(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  FusionOptions o;
  o.downsample = true;
  for (auto _ : state) {
    OccupancyMap map = FuseOccupancy({p.in0, p.in1}, o);
    benchmark::DoNotOptimize(map.resolution_m());
  }
  SetLabel(state);
}

// Building the OctoMap OcTree from the own voxel store (only when asked: --save-octree).
void BM_BuildOctree(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    state.PauseTiming();
    auto map = std::make_unique<OccupancyMap>(FuseOccupancy({p.in0, p.in1}, FusionOptions()));
    state.ResumeTiming();
    benchmark::DoNotOptimize(map->NumLeafNodes());
    state.PauseTiming();
    map.reset();
    state.ResumeTiming();
  }
  SetLabel(state);
}

void Project(benchmark::State& state, Traversal traversal) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  const OccupancyMap map = FuseOccupancy({p.in0, p.in1}, FusionOptions());
  BinOptions b;
  b.traversal = traversal;
  for (auto _ : state) {
    FrustumVolume v0 = ProjectToFrustum(map, p.in0.camera, p.in0.world_from_cam, b);
    FrustumVolume v1 = ProjectToFrustum(map, p.in1.camera, p.in1.world_from_cam, b);
    benchmark::DoNotOptimize(v0.occ.data());
    benchmark::DoNotOptimize(v1.occ.data());
  }
  SetLabel(state);
}
void BM_ProjectExactBothCams(benchmark::State& state) { Project(state, Traversal::kExact); }
// The previous exact traversal (voxel by voxel through mixed blocks), kept as the tests'
// reference (tests/occupancy/reference_traversal.h): same output, for the speed-up.
void BM_ProjectExactReferenceBothCams(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  const OccupancyMap map = FuseOccupancy({p.in0, p.in1}, FusionOptions());
  const BinOptions b;
  for (auto _ : state) {
    FrustumVolume v0 =
        reference::ProjectToFrustumReference(map, p.in0.camera, p.in0.world_from_cam, b);
    FrustumVolume v1 =
        reference::ProjectToFrustumReference(map, p.in1.camera, p.in1.world_from_cam, b);
    benchmark::DoNotOptimize(v0.occ.data());
    benchmark::DoNotOptimize(v1.occ.data());
  }
  SetLabel(state);
}
void BM_ProjectCenterBothCams(benchmark::State& state) { Project(state, Traversal::kCenter); }

// Naive: OctoMap's insertPointCloud with one ray per valid point (no downsampling, no
// discretization), then OcTree::search (OccupancyMap::StateAt of an OctoMap-engine map) at
// every bin centre of both cameras (the center approximation's output).
void BM_NaivePairTotal(benchmark::State& state) {
  const PairData& p = Data(static_cast<int>(state.range(0)));
  FusionOptions o;
  o.engine = FusionEngine::kOctomap;
  o.downsample = false;
  o.discretize = false;
  const BinOptions b;
  const std::vector<double> e = BinEdges(b);
  for (auto _ : state) {
    OccupancyMap map = FuseOccupancy({p.in0, p.in1}, o);
    int64_t occupied = 0;
    for (const FusionInput* in : {&p.in0, &p.in1}) {
      const Camera half = in->camera.HalfGrid();
      const Eigen::Matrix3d R = in->world_from_cam.linear();
      const Eigen::Vector3d t = in->world_from_cam.translation();
      for (int v = 0; v < half.height; ++v) {
        for (int u = 0; u < half.width; ++u) {
          const Eigen::Vector3d d = R * half.CamFromImg(u, v, 1.0);
          for (int k = 0; k < b.num_bins; ++k)
            occupied += map.StateAt(t + 0.5 * (e[k] + e[k + 1]) * d) == 1;
        }
      }
    }
    benchmark::DoNotOptimize(occupied);
  }
  SetLabel(state);
}

BENCHMARK(BM_PairTotal)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PairTotalCenter)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BackProject)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BackProjectAndDownsample)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fuse)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FuseWithDownsample)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FuseOctomapDiscretized)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildOctree)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectExactBothCams)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectExactReferenceBothCams)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectCenterBothCams)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NaivePairTotal)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace
}  // namespace gt::occupancy

BENCHMARK_MAIN();

// Rendered depth (libgt/render): a 640x480 planar depth map of a >= 1 M triangle mesh on one
// core, Embree's coherent streams (the renderer) against a plain rtcIntersect1 loop in the
// same run, and the BVH build of a >= 2 M triangle mesh. The meshes are tessellated spheres
// (tests/render/scenes.h): the camera stands inside a 3 m sphere of 1.31 M triangles (every
// ray hits, a room's worst case), turning between frames. Counters: rays per second, and the
// bytes of the mesh arrays and of Embree's copy + BVH (its memory monitor).
// Targets (docs/PERFORMANCE.md): render <= 25 ms and >= 1.5x the rtcIntersect1 loop; build
// <= 2 s.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>

#include "libgt/render/mesh_renderer.h"
#include "tests/render/scenes.h"

namespace gt::render {
namespace {

const TriangleMesh& SphereRoom() {
  static const TriangleMesh mesh =
      test::IcoSphere(Eigen::Vector3d(0.4, -0.2, 0.3), 3.0, 8);  // 1.31 M
  return mesh;
}

const MeshRenderer& SphereRoomRenderer() {
  static const MeshRenderer renderer(SphereRoom());
  return renderer;
}

void RenderLoop(benchmark::State& state, RayBatching batching) {
  tbb::global_control one_core(tbb::global_control::max_allowed_parallelism, 1);
  const MeshRenderer& renderer = SphereRoomRenderer();
  const Camera camera = Camera::FromK(
      (Eigen::Matrix3d() << 585, 0, 319.5, 0, 585, 239.5, 0, 0, 1).finished(), 640, 480);
  RenderOptions options;
  options.batching = batching;
  int frame = 0;
  for (auto _ : state) {
    Rigid3d pose = Rigid3d::Identity();
    pose.linear() = Eigen::AngleAxisd(0.1 * (frame % 60), Eigen::Vector3d(0.2, 1, 0.1).normalized())
                        .toRotationMatrix();
    ++frame;
    RenderedDepth depth = renderer.Render(camera, pose, options);
    benchmark::DoNotOptimize(depth.depth_m.data);
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(640.0 * 480 * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["triangles"] = static_cast<double>(renderer.NumTriangles());
  state.counters["mesh_MB"] =
      (SphereRoom().vertices_m.size() * 4 + SphereRoom().triangles.size() * 4) / 1e6;
  state.counters["embree_MB"] = renderer.EmbreeBytes() / 1e6;
}

void BM_Render640x480Coherent1Core(benchmark::State& state) {
  RenderLoop(state, RayBatching::kCoherent);
}
BENCHMARK(BM_Render640x480Coherent1Core)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

void BM_Render640x480Intersect1Loop1Core(benchmark::State& state) {
  RenderLoop(state, RayBatching::kSingleRay);
}
BENCHMARK(BM_Render640x480Intersect1Loop1Core)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

// BVH build of two 1.31 M-triangle spheres (2.62 M triangles); state.range(0) threads.
void BM_BuildBvh2_6M(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
  TriangleMesh mesh = test::IcoSphere(Eigen::Vector3d(0, 0, 0), 3.0, 8);
  const TriangleMesh second = test::IcoSphere(Eigen::Vector3d(1, 0, 0), 1.0, 8);
  const uint32_t offset = static_cast<uint32_t>(mesh.NumVertices());
  mesh.vertices_m.insert(mesh.vertices_m.end(), second.vertices_m.begin(), second.vertices_m.end());
  for (uint32_t i : second.triangles) mesh.triangles.push_back(i + offset);
  size_t embree_bytes = 0;
  for (auto _ : state) {
    MeshRenderer renderer(mesh);
    embree_bytes = renderer.EmbreeBytes();
    benchmark::DoNotOptimize(&renderer);
  }
  state.counters["triangles"] = static_cast<double>(mesh.NumTriangles());
  state.counters["mesh_MB"] = (mesh.vertices_m.size() * 4 + mesh.triangles.size() * 4) / 1e6;
  state.counters["embree_MB"] = embree_bytes / 1e6;
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_MB"] = usage.ru_maxrss / 1e3;  // the process so far (kB -> MB)
}
BENCHMARK(BM_BuildBvh2_6M)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

}  // namespace
}  // namespace gt::render

BENCHMARK_MAIN();

// Rendered depth (libgt/render): a 640x480 planar depth map of a >= 1 M triangle mesh on one
// core, Embree's coherent streams (the renderer) against a plain rtcIntersect1 loop in the
// same run, and the BVH build of a >= 2 M triangle mesh. The meshes are tessellated spheres
// (tests/render/scenes.h): the camera stands inside a 3 m sphere of 1.31 M triangles (every
// ray hits, a room's worst case), turning between frames. Counters: rays per second, and the
// bytes of the mesh arrays and of Embree's copy + BVH (its memory monitor).
// Targets (docs/PERFORMANCE.md): render <= 25 ms and >= 1.5x the rtcIntersect1 loop; build
// <= 2 s.
// A ScanNet++ DSLR frame loaded at 640x480 on one core (target <= 60 ms): occgt's own
// ScanNet++-layout fixture (synth::WriteScanNetPPSynth, fisheye DSLR images of 640x480) read
// by the ScanNet++ reader, its mesh replaced by a 1.31 M-triangle sphere around the cameras;
// one load = the colour undistorted (io::ReadFrameColor) + depth rendered in the undistorted
// camera with the anonymisation mask remapped and applied (truth::LoadWorkingDepth, source
// mesh), against the render alone of the same frames in the same run.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "libgt/datasets/reader.h"
#include "libgt/io/image.h"
#include "libgt/render/frame_depth.h"
#include "libgt/render/mesh_renderer.h"
#include "libgt/synth/scannetpp_layout.h"
#include "libgt/truth/working_frame.h"
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

// A binary little-endian PLY (float x y z; faces list uchar int).
void WritePly(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << mesh.NumVertices()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
      << mesh.NumTriangles() << "\nproperty list uchar int vertex_indices\nend_header\n";
  out.write(reinterpret_cast<const char*>(mesh.vertices_m.data()),
            static_cast<std::streamsize>(mesh.vertices_m.size() * sizeof(float)));
  for (size_t t = 0; t < mesh.NumTriangles(); ++t) {
    const unsigned char three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    out.write(reinterpret_cast<const char*>(&mesh.triangles[3 * t]), 3 * sizeof(uint32_t));
  }
}

// The fixture's DSLR scene (640x480 images), its mesh a 1.31 M-triangle sphere 1 m beyond
// the farthest camera from the cameras' centroid (every ray hits, as in a room).
const Scene& DslrScene() {
  static const Scene scene = [] {
    char tmpl[] = "/tmp/occgt-bench-scannetpp-XXXXXX";
    const std::string dir = mkdtemp(tmpl);
    synth::ScanNetPPSynthOptions o;
    o.frames = 6;
    o.dslr_width = 640;
    o.dslr_height = 480;
    synth::WriteScanNetPPSynth(dir, o);
    datasets::ReaderOptions ro;
    ro.scannetpp_device = datasets::ScanNetPPDevice::kDslr;
    const auto reader = datasets::MakeReader(DatasetFormat::kScanNetPP, ro);
    Scene s = reader->ReadScene(dir, reader->ListScenes(dir).front());
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    int n = 0;
    for (const Frame& f : s.frames) {
      if (f.usable) centroid += f.world_from_cam.translation(), ++n;
    }
    centroid /= n;
    double radius = 0;
    for (const Frame& f : s.frames) {
      if (f.usable) radius = std::max(radius, (f.world_from_cam.translation() - centroid).norm());
    }
    s.mesh_path = dir + "/sphere.ply";
    WritePly(test::IcoSphere(centroid, radius + 1.0, 8), s.mesh_path);
    std::fprintf(stderr, "ScanNet++ fixture (640x480 DSLR, 1.31 M-triangle mesh) in %s\n",
                 dir.c_str());
    return s;
  }();
  return scene;
}

std::vector<const Frame*> UsableFrames(const Scene& scene) {
  std::vector<const Frame*> frames;
  for (const Frame& f : scene.frames) {
    if (f.usable) frames.push_back(&f);
  }
  return frames;
}

// One DSLR frame at 640x480: colour undistorted, depth rendered in the undistorted camera,
// the mask remapped and applied.
void BM_ScanNetPPDslrFrameLoad640x480_1Core(benchmark::State& state) {
  tbb::global_control one_core(tbb::global_control::max_allowed_parallelism, 1);
  const Scene& scene = DslrScene();
  const std::vector<const Frame*> frames = UsableFrames(scene);
  FrameDepthOptions depth;
  depth.source = DepthSourceMode::kMesh;
  const truth::Resolution resolution{640, 480};
  SharedMeshRenderer(scene.mesh_path);  // the BVH, built once outside the timing
  size_t k = 0, masked = 0;
  for (auto _ : state) {
    const Frame& f = *frames[k++ % frames.size()];
    const io::ColorImage color = io::ReadFrameColor(f);
    const DepthImage d = truth::LoadWorkingDepth(scene, f, resolution, depth);
    benchmark::DoNotOptimize(color.rgb.data());
    for (float v : d.values_m) masked += v == 0;
  }
  state.counters["frames"] = static_cast<double>(frames.size());
  state.counters["depth0_px_per_frame"] = static_cast<double>(masked) / state.iterations();
}
BENCHMARK(BM_ScanNetPPDslrFrameLoad640x480_1Core)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

// The render alone of the same frames (the baseline of the row in docs/PERFORMANCE.md).
void BM_ScanNetPPDslrRenderOnly640x480_1Core(benchmark::State& state) {
  tbb::global_control one_core(tbb::global_control::max_allowed_parallelism, 1);
  const Scene& scene = DslrScene();
  const std::vector<const Frame*> frames = UsableFrames(scene);
  const auto renderer = SharedMeshRenderer(scene.mesh_path);
  const truth::Resolution resolution{640, 480};
  size_t k = 0;
  for (auto _ : state) {
    const Frame& f = *frames[k++ % frames.size()];
    RenderedDepth d =
        renderer->Render(truth::WorkingCamera(f, resolution), f.world_from_cam, RenderOptions());
    benchmark::DoNotOptimize(d.depth_m.data);
  }
}
BENCHMARK(BM_ScanNetPPDslrRenderOnly640x480_1Core)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
}  // namespace gt::render

BENCHMARK_MAIN();

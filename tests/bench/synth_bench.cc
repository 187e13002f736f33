// Synthetic generator speed: one 640x480 view (depth + colour + ids) of a generated room,
// and one frame's encoding (npy + PNG bytes, no disk). Target: the default dataset (2 rooms
// x 24 frames) in a few seconds of CPU.
#include <benchmark/benchmark.h>

#include "libgt/io/npy.h"
#include "libgt/synth/dataset.h"
#include "libgt/synth/render.h"

namespace gt::synth {
namespace {

void BM_RenderView640x480(benchmark::State& state) {
  const SynthScene scene = MakeRoomScene(SynthSceneSeed(0, 0));
  const SynthOptions options;
  const Camera camera = SynthCamera(options);
  TrajectoryOptions t;
  const auto poses = Trajectory(scene, t);
  size_t i = 0;
  for (auto _ : state) {
    RenderedView view = RenderView(scene, camera, poses[i++ % poses.size()]);
    benchmark::DoNotOptimize(view.depth.values_m.data());
  }
}
BENCHMARK(BM_RenderView640x480)->Unit(benchmark::kMillisecond);

void BM_EncodeDepthNpy640x480(benchmark::State& state) {
  std::vector<float> depth(640 * 480, 2.5f);
  for (auto _ : state) {
    std::string bytes = io::EncodeNpy<float>({480, 640}, depth);
    benchmark::DoNotOptimize(bytes.data());
  }
}
BENCHMARK(BM_EncodeDepthNpy640x480)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gt::synth

BENCHMARK_MAIN();

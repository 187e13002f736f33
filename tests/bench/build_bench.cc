// One full sample of the real 7-Scenes sample (640×480) as `occgt build` writes it (labels,
// patch matches, pair-scope OctoMap occupancy, PNG images, depth), and the per-pair ground
// truth alone (truth::ComputePairTruth, the entry point of every caller).
// Figures and commands: docs/PERFORMANCE.md.
#include <benchmark/benchmark.h>

#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/sample.h"
#include "libgt/datasets/reader.h"
#include "libgt/pairs/selection.h"
#include "libgt/truth/pair_truth.h"
#include "tests/bench/seven_scenes_sample.h"
#include "tests/support/test_support.h"

namespace gt::pipeline {
namespace {

SampleOptions Options(const Scene& scene) {
  Recipe recipe = ParseRecipe(
      "name: b\ndataset: {format: sevenscenes, root: /x}\nsample: {depth: true}\n"
      "occupancy: {far_m: 8.0}\n",
      "bench.yaml", "/");
  SampleOptions o = RecipeSampleOptions(recipe);
  o.truth = RecipePairTruthOptions(recipe, scene);
  return o;
}

void BM_ComputeSample(benchmark::State& state) {
  const Scene& scene = bench::SevenScenesSample();
  SampleOptions options = Options(scene);
  // 0: everything; 1: without occupancy; 2: without occupancy and images.
  if (state.range(0) >= 1) options.truth.occupancy = false;
  if (state.range(0) >= 2) options.image = ImageFormat::kNone;
  pairs::DepthCache cache(scene, 640, 480);
  const truth::WorkingFrame f0{cache.Get(0), truth::WorkingCamera(scene.frames[0], {640, 480}),
                               scene.frames[0].world_from_cam};
  const truth::WorkingFrame f1{cache.Get(8), truth::WorkingCamera(scene.frames[8], {640, 480}),
                               scene.frames[8].world_from_cam};
  SelectedPair pair;
  for (auto _ : state) {
    EncodedSample s = ComputeSample(scene, 0, 8, pair, "k/0_8", f0, f1, options, nullptr, {});
    benchmark::DoNotOptimize(s.sample.fields.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ComputeSample)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The ground truth of one pair: 0 labels, metrics and matches; 1 with occupancy.
void BM_PairTruth(benchmark::State& state) {
  const Scene& scene = bench::SevenScenesSample();
  truth::PairTruthOptions o = Options(scene).truth;
  o.occupancy = state.range(0) == 1;
  const truth::WorkingFrame f0 = truth::LoadWorkingFrame(scene.frames[0], {640, 480});
  const truth::WorkingFrame f1 = truth::LoadWorkingFrame(scene.frames[8], {640, 480});
  for (auto _ : state) {
    truth::PairTruth t = truth::ComputePairTruth(f0, f1, o);
    benchmark::DoNotOptimize(t.labels.patches.matches.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PairTruth)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace gt::pipeline

BENCHMARK_MAIN();

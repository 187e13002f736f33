// One direction of pixel labels at 640x480 on one thread (GROUND_TRUTH.md §2):
//  - BM_LabelDirection: labels + warped positions of every pixel (libgt fast path);
//  - BM_ScoreDirection/<stride>: metrics only, no label maps;
//  - BM_BatchedBaseline: the same computation written the way LoFTR / Occ²Net do it in
//    PyTorch, as Eigen batched matrices (3xN homogeneous grid, K⁻¹, scale by depth, R|t,
//    K, divide, gather, compare), float32 like the tensors. The ratio of the two is the
//    speed-up quoted in docs/PERFORMANCE.md.
// Scene: the box in front of a wall of tests/geometry, B moved 0.9 m sideways and yawed.
#include <benchmark/benchmark.h>

#include <Eigen/Dense>

#include "libgt/geometry/labels.h"
#include "tests/geometry/reference.h"

namespace {

struct Scene {
  gt::Camera cam;
  gt::DepthImage depth_a, depth_b;
  gt::Rigid3d b_from_a;
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
    return s;
  }();
  return scene;
}

void BM_LabelDirection(benchmark::State& state) {
  const Scene& s = GetScene();
  const gt::LabelOptions o = gt::LabelPreset("default");
  for (auto _ : state) {
    auto l = gt::LabelDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o);
    benchmark::DoNotOptimize(l.labels.data());
  }
  state.SetItemsProcessed(state.iterations() * 640 * 480);
}
BENCHMARK(BM_LabelDirection)->Unit(benchmark::kMillisecond);

void BM_ScoreDirection(benchmark::State& state) {
  const Scene& s = GetScene();
  const gt::LabelOptions o = gt::LabelPreset("default");
  for (auto _ : state) {
    auto m = gt::ScoreDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o,
                                static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(m);
  }
}
BENCHMARK(BM_ScoreDirection)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);

// The batched tensor formulation, float32, one matrix op after another.
void BM_BatchedBaseline(benchmark::State& state) {
  const Scene& s = GetScene();
  const int w = 640, h = 480, n = w * h;
  const Eigen::Matrix3f k = s.cam.K().cast<float>();
  const Eigen::Matrix3f k_inv = k.inverse();
  const Eigen::Matrix3f r = s.b_from_a.linear().cast<float>();
  const Eigen::Vector3f t = s.b_from_a.translation().cast<float>();
  const Eigen::Map<const Eigen::RowVectorXf> depth0(s.depth_a.values_m.data(), n);
  int64_t visible = 0;
  for (auto _ : state) {
    Eigen::Matrix3Xf grid(3, n);  // homogeneous pixel grid (x, y, 1)
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) grid.col(v * w + u) << u, v, 1.0f;
    }
    Eigen::Matrix3Xf pts = grid.array().rowwise() * depth0.array();  // kpts_h * depth
    Eigen::Matrix3Xf cam0 = k_inv * pts;                             // K0⁻¹ @
    Eigen::Matrix3Xf cam1 = (r * cam0).colwise() + t;                // R @ + t
    Eigen::Matrix3Xf proj = k * cam1;                                // K1 @
    Eigen::RowVectorXf z = proj.row(2);
    Eigen::RowVectorXf x = proj.row(0).array() / z.array();
    Eigen::RowVectorXf y = proj.row(1).array() / z.array();
    Eigen::Array<bool, 1, Eigen::Dynamic> inside =
        (x.array() >= -0.5f) && (x.array() < w - 0.5f) && (y.array() >= -0.5f) &&
        (y.array() < h - 0.5f) && (cam1.row(2).array() > 0.0f) && (depth0.array() > 0.0f);
    Eigen::RowVectorXf depth1(n);  // gather
    for (int i = 0; i < n; ++i) {
      depth1[i] = inside[i] ? s.depth_b.values_m[static_cast<size_t>(std::floor(y[i] + 0.5f)) * w +
                                                 static_cast<size_t>(std::floor(x[i] + 0.5f))]
                            : 0.0f;
    }
    Eigen::RowVectorXf tol = (0.05f * cam1.row(2).array()).max(0.1f);
    Eigen::Array<bool, 1, Eigen::Dynamic> vis =
        inside && (depth1.array() > 0.0f) && ((cam1.row(2) - depth1).array().abs() <= tol.array());
    Eigen::Array<bool, 1, Eigen::Dynamic> occ =
        inside && (depth1.array() > 0.0f) && ((cam1.row(2) - depth1).array() > tol.array());
    visible = vis.count() + occ.count();
    benchmark::DoNotOptimize(visible);
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_BatchedBaseline)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

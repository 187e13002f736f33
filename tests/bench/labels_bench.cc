// One direction of pixel labels at 640x480 on one thread (GROUND_TRUTH.md §2):
//  - BM_LabelDirection: labels + warped positions of every pixel (libgt fast path);
//  - BM_ScoreDirection/<stride>: labels + metrics (counts), no label maps;
//  - BM_BatchedBaseline: the same labels and counts computed the way LoFTR's `warp_kpts`
//    (and Occ²Net's copy of it) does in PyTorch eager mode, op by op, each op producing a
//    whole-image float32 / int64 / bool tensor (here an Eigen array, each op vectorised by
//    Eigen). tests/bench/labels_torch_baseline.py runs the same op list in real torch.
//    The ratio baseline / fast path is the speed-up quoted in docs/PERFORMANCE.md.
// Scene: tests/bench/two_view_scene.h (a box in front of a wall, B moved 0.9 m sideways and
// yawed 9°).
#include <benchmark/benchmark.h>

#include <Eigen/Dense>

#include "libgt/geometry/labels.h"
#include "tests/bench/two_view_scene.h"

namespace {

using Scene = gt::bench::TwoViewScene;
const Scene& GetScene() { return gt::bench::GetTwoViewScene(); }

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

// The tensor formulation of LoFTR's warp_kpts, extended to the six labels and the counts of
// the `default` preset (GROUND_TRUTH.md §2) so that it computes what BM_ScoreDirection/1
// computes. One statement per tensor op of the torch code; every result is materialised
// as a new whole-image array, as eager mode does. L = W·H points.
using ArrayXb = Eigen::Array<bool, Eigen::Dynamic, 1>;
using ArrayXl = Eigen::Array<int64_t, Eigen::Dynamic, 1>;
using ArrayXu8 = Eigen::Array<uint8_t, Eigen::Dynamic, 1>;
using ArrayX2f = Eigen::Array<float, Eigen::Dynamic, 2, Eigen::RowMajor>;  // [L, 2]
using ArrayX2l = Eigen::Array<int64_t, Eigen::Dynamic, 2, Eigen::RowMajor>;
using MatrixX3f = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;  // [L, 3]

struct BaselineOut {
  ArrayXu8 labels;  // [L] PixelLabel codes
  ArrayX2f warped;  // [L, 2] (x, y) in B
  std::array<int64_t, gt::kNumPixelLabels> counts{};
};

// IsValidDepth as tensor ops: isfinite(d) & (d > 0) & (d >= min) & (d <= max).
ArrayXb ValidDepthMask(const Eigen::ArrayXf& d, float min_m, float max_m) {
  const ArrayXb finite = d.isFinite();
  const ArrayXb positive = d > 0.0f;
  const ArrayXb above = d >= min_m;
  const ArrayXb below = d <= max_m;
  const ArrayXb a = finite && positive;
  const ArrayXb b = a && above;
  return b && below;
}

BaselineOut BatchedBaseline(const gt::DepthImage& depth_a, const gt::DepthImage& depth_b,
                            const gt::Camera& cam, const gt::Rigid3d& b_from_a,
                            const gt::LabelOptions& o) {
  const int w = cam.width, h = cam.height;
  const Eigen::Index n = static_cast<Eigen::Index>(w) * h;
  const Eigen::Matrix3f k0 = cam.K().cast<float>(), k1 = k0;
  const Eigen::Matrix3f r = b_from_a.linear().cast<float>();
  const Eigen::Vector3f t = b_from_a.translation().cast<float>();
  const Eigen::Map<const Eigen::ArrayXf> depth0(depth_a.values_m.data(), n);
  const Eigen::Map<const Eigen::ArrayXf> depth1(depth_b.values_m.data(), n);
  const float min_m = static_cast<float>(o.min_depth_m), max_m = static_cast<float>(o.max_depth_m);
  const float abs_tol = static_cast<float>(o.abs_tol_m), rel_tol = static_cast<float>(o.rel_tol);

  // kpts0 = create_meshgrid(h, w) scaled to pixels: [L, 2] (x, y)
  ArrayX2f kpts0(n, 2);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) kpts0.row(static_cast<Eigen::Index>(v) * w + u) << u, v;
  }
  // kpts0_long = kpts0.round().long()
  const ArrayX2f kpts0_round = kpts0.round();
  const ArrayX2l kpts0_long = kpts0_round.cast<int64_t>();
  // kpts0_depth = depth0[kpts0_long[:, 1], kpts0_long[:, 0]]  (flat index, then gather)
  const ArrayXl idx0_row = kpts0_long.col(1) * w;
  const ArrayXl idx0 = idx0_row + kpts0_long.col(0);
  Eigen::ArrayXf kpts0_depth(n);
  for (Eigen::Index i = 0; i < n; ++i) kpts0_depth[i] = depth0[idx0[i]];
  // valid source depth (LoFTR: kpts0_depth != 0)
  const ArrayXb valid_mask = ValidDepthMask(kpts0_depth, min_m, max_m);
  // kpts0_h = cat([kpts0, ones], -1) * kpts0_depth[..., None]
  const Eigen::ArrayXf ones = Eigen::ArrayXf::Ones(n);
  Eigen::Array<float, Eigen::Dynamic, 3, Eigen::RowMajor> kpts0_cat(n, 3);
  kpts0_cat << kpts0, ones;
  const MatrixX3f kpts0_h = (kpts0_cat.colwise() * kpts0_depth).matrix();
  // kpts0_cam = K0.inverse() @ kpts0_h.transpose()  [3, L]
  const Eigen::Matrix3f k0_inv = k0.inverse();
  const Eigen::Matrix3Xf kpts0_cam = k0_inv * kpts0_h.transpose();
  // w_kpts0_cam = R @ kpts0_cam + t
  const Eigen::Matrix3Xf rotated = r * kpts0_cam;
  const Eigen::Matrix3Xf w_kpts0_cam = rotated.colwise() + t;
  // w_kpts0_depth_computed = w_kpts0_cam[2, :]  (a view)
  const auto z = w_kpts0_cam.row(2).transpose().array();
  // w_kpts0_h = (K1 @ w_kpts0_cam).transpose()  [L, 3]
  const MatrixX3f w_kpts0_h = (k1 * w_kpts0_cam).transpose();
  // w_kpts0 = w_kpts0_h[:, :2] / (w_kpts0_h[:, [2]] + eps)
  const Eigen::ArrayXf w_z = w_kpts0_h.col(2).array();  // advanced indexing copies
  const Eigen::ArrayXf w_z_eps = w_z + static_cast<float>(o.projection_eps_m);
  const ArrayX2f w_kpts0 = w_kpts0_h.leftCols<2>().array().colwise() / w_z_eps;
  // cheirality (absent in LoFTR / Occ²Net): z > min_depth
  const ArrayXb in_front = z > min_m;
  // covisible mask, pixel-area bounds: 4 comparisons and their product
  const ArrayXb x_lo = w_kpts0.col(0) >= -0.5f;
  const ArrayXb x_hi = w_kpts0.col(0) < w - 0.5f;
  const ArrayXb y_lo = w_kpts0.col(1) >= -0.5f;
  const ArrayXb y_hi = w_kpts0.col(1) < h - 0.5f;
  const ArrayXb cov_x = x_lo && x_hi;
  const ArrayXb cov_y = y_lo && y_hi;
  const ArrayXb cov_xy = cov_x && cov_y;
  const ArrayXb cov_z = cov_xy && in_front;
  const ArrayXb covisible_mask = cov_z && valid_mask;
  // w_kpts0_long = (w_kpts0 + 0.5).floor().long()  (nearest; LoFTR truncates: .long())
  const ArrayX2f w_half = w_kpts0 + 0.5f;
  const ArrayX2f w_floor = w_half.floor();
  ArrayX2l w_kpts0_long = w_floor.cast<int64_t>();
  // w_kpts0_long[~covisible_mask, :] = 0
  const ArrayXb not_covisible = !covisible_mask;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (not_covisible[i]) w_kpts0_long.row(i).setZero();
  }
  // w_kpts0_depth = depth1[w_kpts0_long[:, 1], w_kpts0_long[:, 0]]
  const ArrayXl idx1_row = w_kpts0_long.col(1) * w;
  const ArrayXl idx1 = idx1_row + w_kpts0_long.col(0);
  Eigen::ArrayXf w_kpts0_depth(n);
  for (Eigen::Index i = 0; i < n; ++i) w_kpts0_depth[i] = depth1[idx1[i]];
  const ArrayXb known_mask = ValidDepthMask(w_kpts0_depth, min_m, max_m);
  // consistency: τ = max(abs_tol, rel_tol · z); |z − d_B| <= τ visible, z − d_B > τ occluded
  const Eigen::ArrayXf rel = z * rel_tol;
  const Eigen::ArrayXf tol = rel.max(abs_tol);
  const Eigen::ArrayXf diff = z - w_kpts0_depth;
  const Eigen::ArrayXf abs_diff = diff.abs();
  const ArrayXb visible_mask = abs_diff <= tol;
  const ArrayXb occluded_mask = diff > tol;
  // labels = where(...) from the last rule to the first
  using gt::PixelLabel;
  const auto code = [](PixelLabel l) { return static_cast<uint8_t>(l); };
  const ArrayXu8 l0 = ArrayXu8::Constant(n, code(PixelLabel::kInconsistent));
  const ArrayXu8 l1 = occluded_mask.select(ArrayXu8::Constant(n, code(PixelLabel::kOccluded)), l0);
  const ArrayXu8 l2 = visible_mask.select(ArrayXu8::Constant(n, code(PixelLabel::kVisible)), l1);
  const ArrayXu8 l3 = known_mask.select(l2, ArrayXu8::Constant(n, code(PixelLabel::kUnknown)));
  const ArrayXu8 l4 =
      covisible_mask.select(l3, ArrayXu8::Constant(n, code(PixelLabel::kOutOfView)));
  BaselineOut out;
  out.labels = valid_mask.select(l4, ArrayXu8::Constant(n, code(PixelLabel::kNoDepth)));
  out.warped = w_kpts0;
  // counts = bincount(labels, minlength = 6)
  for (Eigen::Index i = 0; i < n; ++i) ++out.counts[out.labels[i]];
  return out;
}

void BM_BatchedBaseline(benchmark::State& state) {
  const Scene& s = GetScene();
  const gt::LabelOptions o = gt::LabelPreset("default");
  {  // Same computation: labels equal the fast path's except at float32 ties.
    const BaselineOut b = BatchedBaseline(s.depth_a, s.depth_b, s.cam, s.b_from_a, o);
    const gt::DirectionLabels l =
        gt::LabelDirection(s.depth_a, s.cam, s.depth_b, s.cam, s.b_from_a, o);
    int64_t differ = 0;
    for (size_t i = 0; i < l.labels.size(); ++i) differ += l.labels[i] != b.labels[i];
    state.counters["label_diff"] = static_cast<double>(differ);
    state.counters["visible"] = static_cast<double>(b.counts[2]);
    state.counters["occluded"] = static_cast<double>(b.counts[3]);
  }
  for (auto _ : state) {
    BaselineOut b = BatchedBaseline(s.depth_a, s.depth_b, s.cam, s.b_from_a, o);
    benchmark::DoNotOptimize(b.counts.data());
  }
  state.SetItemsProcessed(state.iterations() * 640 * 480);
}
BENCHMARK(BM_BatchedBaseline)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

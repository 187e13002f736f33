#include "libgt/geometry/labels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "libgt/core/error.h"

namespace gt {
namespace {

template <typename E, size_t N>
E ParseName(const std::string& name, const std::string& field, const char* const (&names)[N],
            const E (&values)[N]) {
  std::string expected;
  for (size_t i = 0; i < N; ++i) {
    if (name == names[i]) return values[i];
    expected += (i ? ", " : "") + std::string(names[i]);
  }
  throw InputError(field, "expected one of " + expected + ", got '" + name + "'");
}

// Everything the per-pixel loop needs, computed once per call.
struct Kernel {
  // q = d · (a·u + b·v + c) + k; z = q.z, (x, y) = (q.x, q.y) · 1 / (z + eps). Double here;
  // a·u is rounded to float once per call (Columns), b·v + c and k once per row.
  double a[3], b[3], c[3], k[3];
  // IsValidDepth(d, min, max) for a float d is exactly depth_lo <= d <= depth_hi: d > 0 is
  // d >= the smallest normal float, isfinite is d <= FLT_MAX, NaN fails both. No threshold is
  // a denormal, so the decisions are the same with denormals-are-zero set (core/depth.h).
  double depth_lo, depth_hi;
  double z_min;  // OUT_OF_VIEW unless z > z_min; -inf without cheirality (z is finite for
                 // every valid depth)
  // τ = max(abs_tol_m, max(rel_tol_db · d_B, rel_tol_z · z)): one of the two factors is 0,
  // so this is max(abs_tol_m, rel_tol · base) without a per-pixel choice of the base.
  double abs_tol_m, rel_tol_db, rel_tol_z;
  bool missing_zero;                  // invalid d_B compared as 0
  double eps;                         // added to z before dividing
  double x_min, x_max, y_min, y_max;  // inside iff x >= x_min && x < x_max (same for y)
  double lookup_offset;               // 0.5 nearest (floor(x + 0.5)), 0 truncate
  int width_b, height_b;
  const float* depth_b;
  // float32 thresholds giving the same decision for float values: d >= depth_lo_f is
  // d >= depth_lo, d <= depth_hi_f is d <= depth_hi, x >= x_min_f is x > 0 (strict) ...
  float depth_lo_f, depth_hi_f, z_min_f, x_min_f, x_max_f, y_min_f, y_max_f;
};

// The smallest float >= x and the largest float <= x (so that, for a float f, f >= x is
// f >= FloatAtLeast(x) and f <= x is f <= FloatAtMost(x)).
float FloatAtLeast(double x) {
  if (x > std::numeric_limits<float>::max()) return std::numeric_limits<float>::infinity();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}
float FloatAtMost(double x) {
  if (x < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::infinity();
  if (x > std::numeric_limits<float>::max()) return std::numeric_limits<float>::max();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

Kernel MakeKernel(const Camera& cam_a, const Camera& cam_b, const Rigid3d& b_from_a,
                  const DepthImage& depth_b, const LabelOptions& o) {
  Kernel kn;
  Eigen::Matrix3d a_inv = Eigen::Matrix3d::Identity();  // K_A⁻¹
  a_inv(0, 0) = 1.0 / cam_a.fx;
  a_inv(1, 1) = 1.0 / cam_a.fy;
  a_inv(0, 2) = -cam_a.cx / cam_a.fx;
  a_inv(1, 2) = -cam_a.cy / cam_a.fy;
  const Eigen::Matrix3d kb = cam_b.K();
  const Eigen::Matrix3d m = kb * b_from_a.linear() * a_inv;
  const Eigen::Vector3d t = kb * b_from_a.translation();
  for (int r = 0; r < 3; ++r) {
    kn.a[r] = m(r, 0);
    kn.b[r] = m(r, 1);
    kn.c[r] = m(r, 2);
    kn.k[r] = t(r);
  }
  const double inf = std::numeric_limits<double>::infinity();
  kn.depth_lo = std::max(o.min_depth_m, double{kMinPositiveDepthM});
  kn.depth_hi = std::min(o.max_depth_m, double{std::numeric_limits<float>::max()});
  kn.z_min = o.cheirality ? o.min_depth_m : -inf;
  kn.abs_tol_m = o.abs_tol_m;
  const bool observed = o.relative_to == RelativeTo::kObserved;
  kn.rel_tol_db = observed ? o.rel_tol : 0.0;
  kn.rel_tol_z = observed ? 0.0 : o.rel_tol;
  kn.missing_zero = o.missing_target == MissingTarget::kAsZeroDepth;
  kn.eps = o.projection_eps_m;
  if (o.bounds == Bounds::kPixelArea) {
    kn.x_min = -0.5;
    kn.y_min = -0.5;
    kn.x_max = cam_b.width - 0.5;
    kn.y_max = cam_b.height - 0.5;
  } else {  // x > 0, as x >= the smallest normal float (as depth: no denormal threshold)
    kn.x_min = std::numeric_limits<float>::min();
    kn.y_min = kn.x_min;
    kn.x_max = cam_b.width - 1.0;
    kn.y_max = cam_b.height - 1.0;
  }
  kn.lookup_offset = o.target_lookup == TargetLookup::kNearest ? 0.5 : 0.0;
  kn.width_b = cam_b.width;
  kn.height_b = cam_b.height;
  kn.depth_b = depth_b.values_m.data();
  kn.depth_lo_f = FloatAtLeast(kn.depth_lo);
  kn.depth_hi_f = FloatAtMost(kn.depth_hi);
  // For a float z: z > z_min  <=>  z > the largest float <= z_min.
  // z > 0 is z > the largest denormal (z >= the smallest normal float) in every FP mode.
  kn.z_min_f = !o.cheirality                           ? -std::numeric_limits<float>::infinity()
               : kn.z_min < double{kMinPositiveDepthM} ? std::nextafter(kMinPositiveDepthM, 0.0f)
                                                       : FloatAtMost(kn.z_min);
  kn.x_min_f = o.bounds == Bounds::kPixelArea ? -0.5f : std::numeric_limits<float>::min();
  kn.y_min_f = kn.x_min_f;
  // x < x_max  <=>  x < the smallest float >= x_max (W − 0.5 and W − 1 are floats anyway).
  kn.x_max_f = FloatAtLeast(kn.x_max);
  kn.y_max_f = FloatAtLeast(kn.y_max);
  return kn;
}

// The column terms a·u of the affine map in float32 for the sampled columns
// u = 0, stride, 2·stride, … (the same for every row; the kernel adds b·v + c per row).
struct Columns {
  std::vector<float> x, y, z;
  Columns() = default;
  Columns(const Kernel& kn, int n, int stride) : x(n), y(n), z(n) {
    for (int i = 0; i < n; ++i) Set(kn, i, i * stride);
  }
  // Entry i for column u (the same float products as above).
  void Set(const Kernel& kn, int i, int u) {
    const float ax = static_cast<float>(kn.a[0]), ay = static_cast<float>(kn.a[1]),
                az = static_cast<float>(kn.a[2]);
    const float uf = static_cast<float>(u);  // exact (below 2^24)
    x[i] = ax * uf;
    y[i] = ay * uf;
    z[i] = az * uf;
  }
};

// Pass 2 of the row kernel: out[i] = depth[idx[i]]. Scalar on purpose: g++ vectorises such
// a loop by emulating a gather (an extract, a load and an insert per lane, each lane waiting
// on the index arithmetic), and the hardware gather (-mtune-ctrl=use_gather) was slower
// still on this AMD EPYC, as were AVX-512 windows (16 lanes served by two loads of 32
// consecutive floats of B and a two-register permute, which covered 94 % of the used
// lanes: 1.2x the time of this loop); plain loads, with B's row prefetched a little ahead,
// are the cheapest lookup found (docs/PERFORMANCE.md "N views").
constexpr int kChunk = 256;
__attribute__((noinline, optimize("no-tree-vectorize"))) void GatherDepths(
    const float* __restrict depth, const int32_t* __restrict idx, int n, float* __restrict out) {
  constexpr int kAhead = 128;  // pixels: eight cache lines of B's row ahead
  int i = 0;
  for (; i + kAhead < n; ++i) {
    __builtin_prefetch(depth + idx[i + kAhead]);
    out[i] = depth[idx[i]];
  }
  for (; i < n; ++i) out[i] = depth[idx[i]];
}

// Labels the n sampled pixels u = 0, stride, 2·stride, … (cols) of row v of A, whose depths are
// dep[0 .. n), and, by mode:
//   kMaps    codes[i] = PixelLabel code (int32, so that the loop runs on 32-bit lanes only)
//            and xy[2i], xy[2i + 1] = warped (x, y) (NaN where not projected);
//   kCounts  adds the number of pixels of each label to counts[0 .. 6) (metrics: no maps);
//   kBits    sets bit `bit` of vis[i] / occ[i] when the label is VISIBLE / OCCLUDED (the
//            N-view bitmasks; other bits untouched);
//   kPoints  as kMaps, and z[i] = the projected depth (NaN where not projected).
// Every mode computes the label with the same operations, so they agree label for label.
//
// float32, like the tensors of LoFTR / Occ²Net: the per-row coefficients a, r = b·v + c, k
// are computed in double and rounded once; every threshold is converted to the float that
// gives the same decision for float values (Kernel::*_f), so the only departures from the
// double reference are rounding ties (docs/GROUND_TRUTH.md, "Arithmetic").
// Branch-free loops that GCC vectorises (-fopt-info-vec; the lookups apart): each decision of
// GROUND_TRUTH.md §2 is a compare and a select; the target pixel is clamped into the image
// (min/max, a NaN becomes 0) so that the read is always in bounds (its value is used only
// when the point is inside, where the clamp changes nothing); one reciprocal per pixel.
// The clones (AVX-512, AVX2, baseline x86-64, picked at load time) run the same IEEE
// operations on wider registers: gt_geometry is built with -ffp-contract=off (no FMA
// contraction, which g++ does by default whenever FMA is enabled, even with -std=c++17) and
// -fno-trapping-math (lets the selects be vectorised; values are unchanged), so every clone
// gives bit-identical results.
// The body is a template inlined into two non-template clone sets (clang refuses
// target_clones on a function template; g++ inlines the body and vectorises each clone).
enum class RowMode { kMaps, kCounts, kBits, kPoints };
struct RowOut {
  int32_t* __restrict codes = nullptr;   // kMaps, kPoints
  float* __restrict xy = nullptr;        // kMaps, kPoints
  float* __restrict z = nullptr;         // kPoints
  int64_t* __restrict counts = nullptr;  // kCounts
  uint32_t* __restrict vis = nullptr;    // kBits
  uint32_t* __restrict occ = nullptr;    // kBits
  int bit = 0;                           // kBits
};
template <RowMode kMode>
inline __attribute__((always_inline)) void LabelRowBody(
    const Kernel& kn, const float* __restrict col_x, const float* __restrict col_y,
    const float* __restrict col_z, const float* __restrict dep, int n, int v, const RowOut& out) {
  constexpr bool kMaps = kMode == RowMode::kMaps || kMode == RowMode::kPoints;
  int32_t* __restrict codes = out.codes;
  float* __restrict xy = out.xy;
  float* __restrict zs = out.z;
  uint32_t* __restrict vis = out.vis;
  uint32_t* __restrict occ = out.occ;
  const int bit = out.bit;
  const auto f = [](double x) { return static_cast<float>(x); };
  const double vv = v;
  const float rx = f(kn.b[0] * vv + kn.c[0]);
  const float ry = f(kn.b[1] * vv + kn.c[1]);
  const float rz = f(kn.b[2] * vv + kn.c[2]);
  const float kx = f(kn.k[0]), ky = f(kn.k[1]), kz = f(kn.k[2]), eps = f(kn.eps);
  const float lo = kn.depth_lo_f, hi = kn.depth_hi_f, z_min = kn.z_min_f;
  const bool missing_zero = kn.missing_zero;
  const float abs_tol = f(kn.abs_tol_m), rel_db = f(kn.rel_tol_db), rel_z = f(kn.rel_tol_z);
  const float x_min = kn.x_min_f, x_max = kn.x_max_f, y_min = kn.y_min_f, y_max = kn.y_max_f;
  const float offset = f(kn.lookup_offset);
  const int wb = kn.width_b;
  const float tx_cap = std::nextafter(static_cast<float>(kn.width_b), 0.0f);
  const float ty_cap = std::nextafter(static_cast<float>(kn.height_b), 0.0f);
  const float* __restrict depth_b = kn.depth_b;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int32_t c0 = 0, c1 = 0, c2 = 0, c3 = 0, c4 = 0;  // per-label counts (kCounts; 5 = the rest)
  // In chunks of kChunk pixels, three passes over L1-resident scratch: (1) the projection
  // and the target pixel's index, vectorised; (2) the depth lookups, scalar (GatherDepths);
  // (3) the decisions, vectorised. The values are those of one fused loop (the same
  // operations; floats stored and reloaded unchanged).
  alignas(64) float zs_c[kChunk], xs_c[kChunk], ys_c[kChunk], db_c[kChunk];
  alignas(64) int32_t idx_c[kChunk];
  for (int start = 0; start < n; start += kChunk) {
    const int m = std::min(kChunk, n - start);
    const float* __restrict d_c = dep + start;
    const float* __restrict cx_c = col_x + start;
    const float* __restrict cy_c = col_y + start;
    const float* __restrict cz_c = col_z + start;
    for (int i = 0; i < m; ++i) {
      const float d = d_c[i];
      const float z = d * (cz_c[i] + rz) + kz;
      const float inv = 1.0f / (z + eps);
      const float x = (d * (cx_c[i] + rx) + kx) * inv;
      const float y = (d * (cy_c[i] + ry) + ky) * inv;
      const float tx = std::min(tx_cap, std::max(0.0f, x + offset));
      const float ty = std::min(ty_cap, std::max(0.0f, y + offset));
      const int tu = static_cast<int>(tx), tv = static_cast<int>(ty);
      idx_c[i] = tv * wb + tu;
      zs_c[i] = z;
      xs_c[i] = x;
      ys_c[i] = y;
    }
    GatherDepths(depth_b, idx_c, m, db_c);
    for (int i = 0; i < m; ++i) {
      const float d = d_c[i];
      const float z = zs_c[i], x = xs_c[i], y = ys_c[i];
      const bool valid = (d >= lo) & (d <= hi);
      const bool projected = valid & (z > z_min);
      const bool inside = projected & (x >= x_min) & (x < x_max) & (y >= y_min) & (y < y_max);
      const float db_raw = db_c[i];
      const bool db_valid = (db_raw >= lo) & (db_raw <= hi);
      const float db = db_valid ? db_raw : 0.0f;
      const bool known = db_valid | missing_zero;
      const float tol = std::max(abs_tol, std::max(rel_db * db, rel_z * z));
      const float diff = z - db;
      const int32_t decided = std::abs(diff) <= tol ? 2 : diff > tol ? 3 : 4;
      const int32_t in_view = known ? decided : 5;
      const int32_t with_depth = inside ? in_view : 1;
      const int32_t label = valid ? with_depth : 0;
      const int o = start + i;
      if constexpr (kMaps) {
        codes[o] = label;
        xy[2 * o] = projected ? x : nan;
        xy[2 * o + 1] = projected ? y : nan;
        if constexpr (kMode == RowMode::kPoints) zs[o] = projected ? z : nan;
      } else if constexpr (kMode == RowMode::kBits) {
        vis[o] |= static_cast<uint32_t>(label == 2) << bit;
        occ[o] |= static_cast<uint32_t>(label == 3) << bit;
      } else {
        c0 += label == 0;
        c1 += label == 1;
        c2 += label == 2;
        c3 += label == 3;
        c4 += label == 4;
      }
    }
  }
  if constexpr (kMode == RowMode::kCounts) {
    int64_t* __restrict counts = out.counts;
    counts[0] += c0;
    counts[1] += c1;
    counts[2] += c2;
    counts[3] += c3;
    counts[4] += c4;
    counts[5] += n - (c0 + c1 + c2 + c3 + c4);
  }
}

__attribute__((target_clones("arch=x86-64-v4", "avx2", "default"))) void LabelRowMaps(
    const Kernel& kn, const Columns& cols, const float* __restrict dep, int n, int v,
    int32_t* __restrict codes, float* __restrict xy) {
  RowOut out;
  out.codes = codes;
  out.xy = xy;
  LabelRowBody<RowMode::kMaps>(kn, cols.x.data(), cols.y.data(), cols.z.data(), dep, n, v, out);
}

__attribute__((target_clones("arch=x86-64-v4", "avx2", "default"))) void LabelRowCounts(
    const Kernel& kn, const Columns& cols, const float* __restrict dep, int n, int v,
    int64_t* __restrict counts) {
  RowOut out;
  out.counts = counts;
  LabelRowBody<RowMode::kCounts>(kn, cols.x.data(), cols.y.data(), cols.z.data(), dep, n, v, out);
}

__attribute__((target_clones("arch=x86-64-v4", "avx2", "default"))) void LabelRowBits(
    const Kernel& kn, const Columns& cols, const float* __restrict dep, int n, int v, int bit,
    uint32_t* __restrict vis, uint32_t* __restrict occ) {
  RowOut out;
  out.vis = vis;
  out.occ = occ;
  out.bit = bit;
  LabelRowBody<RowMode::kBits>(kn, cols.x.data(), cols.y.data(), cols.z.data(), dep, n, v, out);
}

// One pixel (column entry i of cols, row v, depth d): its code, (x, y) and z.
void LabelPoint(const Kernel& kn, const Columns& cols, int i, float d, int v, int32_t* code,
                float* xy, float* z) {
  RowOut out;
  out.codes = code;
  out.xy = xy;
  out.z = z;
  LabelRowBody<RowMode::kPoints>(kn, cols.x.data() + i, cols.y.data() + i, cols.z.data() + i, &d, 1,
                                 v, out);
}

// labels[i] = codes[i] for i < n, and counts[k] += the number of codes k (0 .. 5; every
// code is one of them).
__attribute__((target_clones("arch=x86-64-v4", "avx2", "default"))) void StoreLabels(
    const int32_t* __restrict codes, int n, uint8_t* __restrict labels,
    int64_t* __restrict counts) {
  int32_t c0 = 0, c1 = 0, c2 = 0, c3 = 0, c4 = 0;
  for (int i = 0; i < n; ++i) {
    const int32_t code = codes[i];
    labels[i] = static_cast<uint8_t>(code);
    c0 += code == 0;
    c1 += code == 1;
    c2 += code == 2;
    c3 += code == 3;
    c4 += code == 4;
  }
  counts[0] += c0;
  counts[1] += c1;
  counts[2] += c2;
  counts[3] += c3;
  counts[4] += c4;
  counts[5] += n - (c0 + c1 + c2 + c3 + c4);
}

void CheckInputs(const DepthImage& depth_a, const Camera& cam_a, const DepthImage& depth_b,
                 const Camera& cam_b, const LabelOptions& options) {
  std::string error;
  if (!cam_a.Check(&error)) throw InputError("cam_a", error);
  if (!cam_b.Check(&error)) throw InputError("cam_b", error);
  if (!options.Check(&error)) throw InputError("label options", error);
  const auto check_depth = [](const DepthImage& d, const Camera& c, const char* name) {
    if (d.width != c.width || d.height != c.height ||
        d.values_m.size() != static_cast<size_t>(d.width) * d.height) {
      std::ostringstream msg;
      msg << "expected a " << c.width << "x" << c.height << " depth map (camera size), got "
          << d.width << "x" << d.height << " with " << d.values_m.size() << " values";
      throw InputError(name, msg.str());
    }
  };
  check_depth(depth_a, cam_a, "depth_a");
  check_depth(depth_b, cam_b, "depth_b");
}

}  // namespace

const char* PixelLabelName(PixelLabel label) {
  switch (label) {
    case PixelLabel::kNoDepth:
      return "NO_DEPTH";
    case PixelLabel::kOutOfView:
      return "OUT_OF_VIEW";
    case PixelLabel::kVisible:
      return "VISIBLE";
    case PixelLabel::kOccluded:
      return "OCCLUDED";
    case PixelLabel::kInconsistent:
      return "INCONSISTENT";
    case PixelLabel::kUnknown:
      return "UNKNOWN";
  }
  return "INVALID";
}

const char* RelativeToName(RelativeTo v) {
  return v == RelativeTo::kProjected ? "projected" : "observed";
}
const char* BoundsName(Bounds v) { return v == Bounds::kPixelArea ? "pixel-area" : "strict"; }
const char* TargetLookupName(TargetLookup v) {
  return v == TargetLookup::kNearest ? "nearest" : "truncate";
}
const char* MissingTargetName(MissingTarget v) {
  return v == MissingTarget::kUnknown ? "unknown" : "as-zero-depth";
}

RelativeTo ParseRelativeTo(const std::string& name, const std::string& field) {
  static const char* const kNames[] = {"projected", "observed"};
  static const RelativeTo kValues[] = {RelativeTo::kProjected, RelativeTo::kObserved};
  return ParseName(name, field, kNames, kValues);
}
Bounds ParseBounds(const std::string& name, const std::string& field) {
  static const char* const kNames[] = {"pixel-area", "strict"};
  static const Bounds kValues[] = {Bounds::kPixelArea, Bounds::kStrict};
  return ParseName(name, field, kNames, kValues);
}
TargetLookup ParseTargetLookup(const std::string& name, const std::string& field) {
  static const char* const kNames[] = {"nearest", "truncate"};
  static const TargetLookup kValues[] = {TargetLookup::kNearest, TargetLookup::kTruncate};
  return ParseName(name, field, kNames, kValues);
}
MissingTarget ParseMissingTarget(const std::string& name, const std::string& field) {
  static const char* const kNames[] = {"unknown", "as-zero-depth"};
  static const MissingTarget kValues[] = {MissingTarget::kUnknown, MissingTarget::kAsZeroDepth};
  return ParseName(name, field, kNames, kValues);
}

bool LabelOptions::Check(std::string* error) const {
  std::ostringstream msg;
  if (!std::isfinite(min_depth_m) || min_depth_m < 0) {
    msg << "min_depth_m must be finite and >= 0, got " << min_depth_m;
  } else if (std::isnan(max_depth_m) || max_depth_m <= min_depth_m) {
    msg << "max_depth_m must be > min_depth_m (" << min_depth_m << "), got " << max_depth_m;
  } else if (!std::isfinite(abs_tol_m) || abs_tol_m < 0) {
    msg << "abs_tol_m must be finite and >= 0, got " << abs_tol_m;
  } else if (!std::isfinite(rel_tol) || rel_tol < 0) {
    msg << "rel_tol must be finite and >= 0, got " << rel_tol;
  } else if (!std::isfinite(projection_eps_m) || projection_eps_m < 0) {
    msg << "projection_eps_m must be finite and >= 0, got " << projection_eps_m;
  } else {
    return true;
  }
  if (error) *error = msg.str();
  return false;
}

void ApplyDatasetDepthRange(double min_depth_m, double max_depth_m, LabelOptions* options) {
  if (!options->dataset_depth_range) return;
  options->min_depth_m = min_depth_m;
  options->max_depth_m = max_depth_m;
}

std::vector<std::string> PresetNames() {
  return {"default", "occ2net", "occ2net-compat", "loftr", "superglue", "megadepth"};
}

LabelOptions LabelPreset(const std::string& name) {
  LabelOptions o;  // default: max(0.1 m, 0.05 z), projected, pixel area, nearest, UNKNOWN
  if (name == "default") return o;
  if (name == "occ2net" || name == "occ2net-compat") {
    o.abs_tol_m = 0.1;
    o.rel_tol = 0.0;
    o.bounds = Bounds::kStrict;
    o.target_lookup = TargetLookup::kTruncate;
    if (name == "occ2net-compat") {
      o.missing_target = MissingTarget::kAsZeroDepth;
      o.cheirality = false;
      o.projection_eps_m = 1e-4;
      o.max_depth_m = std::numeric_limits<float>::max();  // finite float depths: all valid
      o.dataset_depth_range = false;
    }
    return o;
  }
  if (name == "loftr") {
    o.abs_tol_m = 0.0;
    o.rel_tol = 0.2;
    o.relative_to = RelativeTo::kObserved;
    o.bounds = Bounds::kStrict;
    o.target_lookup = TargetLookup::kTruncate;
    return o;
  }
  if (name == "superglue") {
    o.abs_tol_m = 0.0;
    o.rel_tol = 0.1;
    return o;
  }
  if (name == "megadepth") {  // MVS depth of an SfM scene: no metres, a looser relative test
    o.abs_tol_m = 0.0;
    o.rel_tol = 0.15;
    return o;
  }
  std::string expected;
  for (const auto& n : PresetNames()) expected += (expected.empty() ? "" : ", ") + n;
  throw InputError("--preset", "expected one of " + expected + ", got '" + name + "'");
}

DirectionLabels LabelDirection(const DepthImage& depth_a, const Camera& cam_a,
                               const DepthImage& depth_b, const Camera& cam_b,
                               const Rigid3d& b_from_a, const LabelOptions& options) {
  CheckInputs(depth_a, cam_a, depth_b, cam_b, options);
  const Kernel kn = MakeKernel(cam_a, cam_b, b_from_a, depth_b, options);
  DirectionLabels out;
  out.width = cam_a.width;
  out.height = cam_a.height;
  const size_t w = static_cast<size_t>(out.width);
  // The kernel writes the warp map in place (its allocator leaves the floats uninitialised:
  // no 2.4 MB zeroing at 640x480 before the kernel overwrites it) and the int32 codes of a
  // row into L1-resident scratch, which StoreLabels narrows into the label map and counts.
  out.labels.resize(w * out.height);
  out.warped_xy.resize(w * out.height * 2);
  std::array<int64_t, kNumPixelLabels> counts{};
  const Columns cols(kn, out.width, 1);
  std::vector<int32_t> codes(w);
  for (int v = 0; v < out.height; ++v) {
    LabelRowMaps(kn, cols, depth_a.values_m.data() + v * w, out.width, v, codes.data(),
                 out.warped_xy.data() + 2 * w * v);
    StoreLabels(codes.data(), out.width, out.labels.data() + w * v, counts.data());
  }
  out.counts = counts;
  return out;
}

void LabelDirectionBits(const DepthImage& depth_a, const Camera& cam_a,
                        const std::vector<BitTarget>& targets, const LabelOptions& options,
                        int row_begin, int row_end, uint32_t* visible_bits,
                        uint32_t* occluded_bits) {
  if (row_begin < 0 || row_end > cam_a.height || row_begin > row_end) {
    throw InputError("rows", "expected 0 <= begin <= end <= " + std::to_string(cam_a.height));
  }
  std::vector<Kernel> kernels;
  std::vector<Columns> columns;
  kernels.reserve(targets.size());
  columns.reserve(targets.size());
  for (const BitTarget& t : targets) {
    if (t.depth_b == nullptr || t.cam_b == nullptr)
      throw InputError("targets", "expected a depth map and a camera");
    if (t.bit < 0 || t.bit > 31)
      throw InputError("bit", "expected 0..31, got " + std::to_string(t.bit));
    CheckInputs(depth_a, cam_a, *t.depth_b, *t.cam_b, options);
    kernels.push_back(MakeKernel(cam_a, *t.cam_b, t.b_from_a, *t.depth_b, options));
    columns.emplace_back(kernels.back(), cam_a.width, 1);
  }
  // Targets outer, rows inner: consecutive rows of A land on consecutive rows of B, so the
  // depth lookups of one target run along B's memory, which the hardware prefetcher
  // follows; with the targets inner the N interleaved streams defeated it (the lookups
  // took twice as long). The bits are ORed, so the order does not change them.
  const size_t w = static_cast<size_t>(cam_a.width);
  for (size_t t = 0; t < targets.size(); ++t) {
    for (int v = row_begin; v < row_end; ++v) {
      LabelRowBits(kernels[t], columns[t], depth_a.values_m.data() + v * w, cam_a.width, v,
                   targets[t].bit, visible_bits + v * w, occluded_bits + v * w);
    }
  }
}

PointLabels LabelPoints(const DepthImage& depth_a, const Camera& cam_a, const DepthImage& depth_b,
                        const Camera& cam_b, const Rigid3d& b_from_a, const LabelOptions& options,
                        const std::vector<int32_t>& pixels_uv) {
  CheckInputs(depth_a, cam_a, depth_b, cam_b, options);
  if (pixels_uv.size() % 2 != 0) throw InputError("pixels", "expected (u, v) pairs");
  const size_t q = pixels_uv.size() / 2;
  const Kernel kn = MakeKernel(cam_a, cam_b, b_from_a, depth_b, options);
  Columns cols;
  cols.x.resize(q);
  cols.y.resize(q);
  cols.z.resize(q);
  for (size_t i = 0; i < q; ++i) {
    const int u = pixels_uv[2 * i], v = pixels_uv[2 * i + 1];
    if (u < 0 || u >= cam_a.width || v < 0 || v >= cam_a.height) {
      std::ostringstream msg;
      msg << "expected pixels inside the " << cam_a.width << "x" << cam_a.height << " image, got ("
          << u << ", " << v << ") at " << i;
      throw InputError("pixels", msg.str());
    }
    cols.Set(kn, static_cast<int>(i), u);
  }
  PointLabels out;
  out.labels.resize(q);
  out.xy.resize(2 * q);
  out.z_m.resize(q);
  const size_t w = static_cast<size_t>(cam_a.width);
  for (size_t i = 0; i < q; ++i) {
    const int u = pixels_uv[2 * i], v = pixels_uv[2 * i + 1];
    int32_t code = 0;
    LabelPoint(kn, cols, static_cast<int>(i), depth_a.values_m[v * w + u], v, &code, &out.xy[2 * i],
               &out.z_m[i]);
    out.labels[i] = static_cast<uint8_t>(code);
  }
  return out;
}

void FinishMetrics(DirectionMetrics* m) {
  const auto& c = m->counts;
  const int64_t vis = c[static_cast<int>(PixelLabel::kVisible)];
  const int64_t occ = c[static_cast<int>(PixelLabel::kOccluded)];
  const int64_t inc = c[static_cast<int>(PixelLabel::kInconsistent)];
  const int64_t unk = c[static_cast<int>(PixelLabel::kUnknown)];
  m->valid = m->sampled - c[static_cast<int>(PixelLabel::kNoDepth)];
  const auto ratio = [](int64_t num, int64_t den) {
    return den > 0 ? static_cast<double>(num) / static_cast<double>(den) : 0.0;
  };
  m->overlap = ratio(vis + occ + inc + unk, m->valid);
  m->consistent_overlap = ratio(vis, m->sampled);
  m->occlusion_ratio = ratio(occ, m->sampled);
  m->occlusion_ratio_visible = ratio(occ, vis + occ);
}

DirectionMetrics ScoreDirection(const DepthImage& depth_a, const Camera& cam_a,
                                const DepthImage& depth_b, const Camera& cam_b,
                                const Rigid3d& b_from_a, const LabelOptions& options,
                                int score_stride) {
  CheckInputs(depth_a, cam_a, depth_b, cam_b, options);
  if (score_stride < 1) throw InputError("score_stride", "expected >= 1");
  const Kernel kn = MakeKernel(cam_a, cam_b, b_from_a, depth_b, options);
  // Scratch rows reused for every row (no per-pixel allocation): the sampled depths of A
  // (stride > 1). Labels are counted in the labelling loop itself: no label map.
  const int n = (cam_a.width + score_stride - 1) / score_stride;
  std::vector<float> row_depth(score_stride > 1 ? n : 0);
  const Columns cols(kn, n, score_stride);
  DirectionMetrics m;
  const size_t w = static_cast<size_t>(cam_a.width);
  for (int v = 0; v < cam_a.height; v += score_stride) {
    const float* depth_row = depth_a.values_m.data() + v * w;
    if (score_stride > 1) {
      for (int i = 0; i < n; ++i) row_depth[i] = depth_row[static_cast<size_t>(i) * score_stride];
      depth_row = row_depth.data();
    }
    LabelRowCounts(kn, cols, depth_row, n, v, m.counts.data());
    m.sampled += n;
  }
  FinishMetrics(&m);
  return m;
}

namespace {

// Sets *counts to the number of codes 0 .. 5 among row[0], row[stride], … (n values); true if a
// value is not a label code. kStride 1: the stride is 1 (a contiguous, vectorised loop).
template <int kStride>
bool CountLabelCodes(const uint8_t* __restrict row, int n, int stride,
                     std::array<int32_t, kNumPixelLabels>* counts) {
  static_assert(kNumPixelLabels == 6, "one counter per label code below");
  int32_t c0 = 0, c1 = 0, c2 = 0, c3 = 0, c4 = 0, c5 = 0;
  uint8_t max_code = 0;
  for (int i = 0; i < n; ++i) {
    const uint8_t l = row[static_cast<size_t>(i) * (kStride == 1 ? 1 : stride)];
    c0 += l == 0;
    c1 += l == 1;
    c2 += l == 2;
    c3 += l == 3;
    c4 += l == 4;
    c5 += l == 5;
    max_code = std::max(max_code, l);
  }
  *counts = {c0, c1, c2, c3, c4, c5};
  return max_code >= kNumPixelLabels;
}

// CountLabelCodes<1> over a whole contiguous map: 16 byte lanes, each code counted in uint8
// lane counters flushed every 255 chunks (the loops are vectorised: about 6x faster than
// 32-bit counters per code); the tail as above.
bool CountLabelCodesContiguous(const uint8_t* __restrict codes, size_t n,
                               std::array<int64_t, kNumPixelLabels>* counts) {
  constexpr size_t kLanes = 16, kChunks = 255;
  std::array<int64_t, kNumPixelLabels> total{};
  uint8_t max_code = 0;
  size_t i = 0;
  while (n - i >= kLanes) {
    const size_t chunks = std::min(kChunks, (n - i) / kLanes);
    alignas(16) uint8_t lane[kNumPixelLabels][kLanes] = {};
    alignas(16) uint8_t lane_max[kLanes] = {};
    for (size_t c = 0; c < chunks; ++c, i += kLanes) {
      for (size_t j = 0; j < kLanes; ++j) {
        const uint8_t l = codes[i + j];
        for (int k = 0; k < kNumPixelLabels; ++k) lane[k][j] += l == k;
        lane_max[j] = std::max(lane_max[j], l);
      }
    }
    for (size_t j = 0; j < kLanes; ++j) {
      for (int k = 0; k < kNumPixelLabels; ++k) total[k] += lane[k][j];
      max_code = std::max(max_code, lane_max[j]);
    }
  }
  std::array<int32_t, kNumPixelLabels> tail{};
  const bool bad_tail = CountLabelCodes<1>(codes + i, static_cast<int>(n - i), 1, &tail);
  for (int k = 0; k < kNumPixelLabels; ++k) total[k] += tail[k];
  *counts = total;
  return bad_tail || max_code >= kNumPixelLabels;
}

}  // namespace

DirectionMetrics MetricsFromLabels(const DirectionLabels& labels, int score_stride) {
  if (score_stride < 1) throw InputError("score_stride", "expected >= 1");
  if (labels.labels.size() != static_cast<size_t>(labels.width) * labels.height) {
    throw InputError("labels", "label map size does not match width x height");
  }
  if (score_stride == 1 && labels.counts) {  // LabelDirection counted them
    DirectionMetrics m;
    m.counts = *labels.counts;
    m.sampled = static_cast<int64_t>(labels.labels.size());
    FinishMetrics(&m);
    return m;
  }
  return MetricsFromLabelCodes(labels.labels.data(), labels.width, labels.height, score_stride);
}

DirectionMetrics MetricsFromLabelCodes(const uint8_t* labels, int width, int height,
                                       int score_stride) {
  if (score_stride < 1) throw InputError("score_stride", "expected >= 1");
  DirectionMetrics m;
  if (score_stride == 1) {
    const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
    if (CountLabelCodesContiguous(labels, n, &m.counts)) {
      throw InputError("labels", "label code out of range");
    }
    m.sampled = static_cast<int64_t>(n);
    FinishMetrics(&m);
    return m;
  }
  const int n = (width + score_stride - 1) / score_stride;
  for (int v = 0; v < height; v += score_stride) {
    const uint8_t* row = labels + static_cast<size_t>(v) * width;
    // Branch-free counts, one check of the codes per row; the contiguous loop of
    // score_stride 1 (every pixel) is vectorised.
    std::array<int32_t, kNumPixelLabels> c{};
    const bool bad = score_stride == 1 ? CountLabelCodes<1>(row, n, 1, &c)
                                       : CountLabelCodes<0>(row, n, score_stride, &c);
    if (bad) throw InputError("labels", "label code out of range");
    for (int k = 0; k < kNumPixelLabels; ++k) m.counts[k] += c[k];
    m.sampled += n;
  }
  FinishMetrics(&m);
  return m;
}

}  // namespace gt

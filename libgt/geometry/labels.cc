#include "libgt/geometry/labels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

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
  // q = d · (col[u] + row(v)) + k, with col[u] = a·u and row(v) = b·v + c.
  double a[3], b[3], c[3], k[3];
  double min_depth_m, max_depth_m;
  double abs_tol_m, rel_tol;
  bool observed;                      // tolerance relative to d_B
  bool cheirality;                    // z <= min_depth_m → OUT_OF_VIEW before dividing
  bool missing_zero;                  // invalid d_B compared as 0
  double eps;                         // added to z before dividing
  double x_min, x_max, y_min, y_max;  // inside iff x >= x_min && x < x_max (same for y)
  double lookup_offset;               // 0.5 nearest (floor(x + 0.5)), 0 truncate
  int width_b, height_b;
  const float* depth_b;
};

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
  kn.min_depth_m = o.min_depth_m;
  kn.max_depth_m = o.max_depth_m;
  kn.abs_tol_m = o.abs_tol_m;
  kn.rel_tol = o.rel_tol;
  kn.observed = o.relative_to == RelativeTo::kObserved;
  kn.cheirality = o.cheirality;
  kn.missing_zero = o.missing_target == MissingTarget::kAsZeroDepth;
  kn.eps = o.projection_eps_m;
  const double inf = std::numeric_limits<double>::infinity();
  if (o.bounds == Bounds::kPixelArea) {
    kn.x_min = -0.5;
    kn.y_min = -0.5;
    kn.x_max = cam_b.width - 0.5;
    kn.y_max = cam_b.height - 0.5;
  } else {  // x > 0  <=>  x >= the smallest positive double
    kn.x_min = std::nextafter(0.0, inf);
    kn.y_min = kn.x_min;
    kn.x_max = cam_b.width - 1.0;
    kn.y_max = cam_b.height - 1.0;
  }
  kn.lookup_offset = o.target_lookup == TargetLookup::kNearest ? 0.5 : 0.0;
  kn.width_b = cam_b.width;
  kn.height_b = cam_b.height;
  kn.depth_b = depth_b.values_m.data();
  return kn;
}

// Scratch rows reused for every row of one call (no per-pixel allocation).
struct RowBuffers {
  std::vector<double> col_x, col_y, col_z;  // a·u for the sampled columns
  std::vector<double> z, x, y;
  std::vector<float> depth;
};

void PrepareColumns(const Kernel& kn, int width_a, int stride, RowBuffers* buf) {
  const int n = (width_a + stride - 1) / stride;
  buf->col_x.resize(n);
  buf->col_y.resize(n);
  buf->col_z.resize(n);
  buf->z.resize(n);
  buf->x.resize(n);
  buf->y.resize(n);
  buf->depth.resize(n);
  for (int i = 0; i < n; ++i) {
    const double u = static_cast<double>(i) * stride;
    buf->col_x[i] = kn.a[0] * u;
    buf->col_y[i] = kn.a[1] * u;
    buf->col_z[i] = kn.a[2] * u;
  }
}

// Labels the sampled pixels (u = 0, stride, 2·stride, …) of row v of A. labels_out gets
// one code per sampled pixel; xy_out (nullable) gets (x, y) per sampled pixel.
inline void LabelRow(const Kernel& kn, const float* depth_row_a, int v, int stride, RowBuffers* buf,
                     uint8_t* labels_out, float* xy_out) {
  const int n = static_cast<int>(buf->z.size());
  float* __restrict dep = buf->depth.data();
  if (stride == 1) {
    std::copy(depth_row_a, depth_row_a + n, dep);
  } else {
    for (int i = 0; i < n; ++i) dep[i] = depth_row_a[static_cast<size_t>(i) * stride];
  }
  const double vv = v;
  const double rx = kn.b[0] * vv + kn.c[0];
  const double ry = kn.b[1] * vv + kn.c[1];
  const double rz = kn.b[2] * vv + kn.c[2];
  const double kx = kn.k[0], ky = kn.k[1], kz = kn.k[2], eps = kn.eps;
  const double* __restrict cx = buf->col_x.data();
  const double* __restrict cy = buf->col_y.data();
  const double* __restrict cz = buf->col_z.data();
  double* __restrict zs = buf->z.data();
  double* __restrict xs = buf->x.data();
  double* __restrict ys = buf->y.data();
  // Pass 1 (vectorisable): projection of every sampled pixel, valid or not.
  for (int i = 0; i < n; ++i) {
    const double d = dep[i];
    const double qz = d * (cz[i] + rz) + kz;
    const double den = qz + eps;
    zs[i] = qz;
    xs[i] = (d * (cx[i] + rx) + kx) / den;
    ys[i] = (d * (cy[i] + ry) + ky) / den;
  }
  // Pass 2: the decisions of GROUND_TRUTH.md §2.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    const float d = dep[i];
    const double z = zs[i];
    const double x = xs[i], y = ys[i];
    PixelLabel label;
    bool projected = true;
    if (!IsValidDepth(d, kn.min_depth_m, kn.max_depth_m)) {
      label = PixelLabel::kNoDepth;
      projected = false;
    } else if (kn.cheirality && !(z > kn.min_depth_m)) {
      label = PixelLabel::kOutOfView;
      projected = false;
    } else if (!(x >= kn.x_min && x < kn.x_max && y >= kn.y_min && y < kn.y_max)) {
      label = PixelLabel::kOutOfView;
    } else {
      const int tu = std::min(static_cast<int>(x + kn.lookup_offset), kn.width_b - 1);
      const int tv = std::min(static_cast<int>(y + kn.lookup_offset), kn.height_b - 1);
      double db = kn.depth_b[static_cast<size_t>(tv) * kn.width_b + tu];
      bool known = IsValidDepth(static_cast<float>(db), kn.min_depth_m, kn.max_depth_m);
      if (!known && kn.missing_zero) {
        db = 0.0;
        known = true;
      }
      if (!known) {
        label = PixelLabel::kUnknown;
      } else {
        const double tol = std::max(kn.abs_tol_m, kn.rel_tol * (kn.observed ? db : z));
        const double diff = z - db;
        if (std::abs(diff) <= tol) {
          label = PixelLabel::kVisible;
        } else if (diff > tol) {
          label = PixelLabel::kOccluded;
        } else {
          label = PixelLabel::kInconsistent;
        }
      }
    }
    labels_out[i] = static_cast<uint8_t>(label);
    if (xy_out) {
      xy_out[2 * i] = projected ? static_cast<float>(x) : nan;
      xy_out[2 * i + 1] = projected ? static_cast<float>(y) : nan;
    }
  }
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

std::vector<std::string> PresetNames() {
  return {"default", "occ2net", "occ2net-compat", "loftr", "superglue"};
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
  out.labels.resize(w * out.height);
  out.warped_xy.resize(w * out.height * 2);
  RowBuffers buf;
  PrepareColumns(kn, out.width, 1, &buf);
  for (int v = 0; v < out.height; ++v) {
    LabelRow(kn, depth_a.values_m.data() + v * w, v, 1, &buf, out.labels.data() + v * w,
             out.warped_xy.data() + v * w * 2);
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
  RowBuffers buf;
  PrepareColumns(kn, cam_a.width, score_stride, &buf);
  std::vector<uint8_t> row_labels(buf.z.size());
  DirectionMetrics m;
  const size_t w = static_cast<size_t>(cam_a.width);
  for (int v = 0; v < cam_a.height; v += score_stride) {
    LabelRow(kn, depth_a.values_m.data() + v * w, v, score_stride, &buf, row_labels.data(),
             nullptr);
    for (uint8_t l : row_labels) ++m.counts[l];
    m.sampled += static_cast<int64_t>(row_labels.size());
  }
  FinishMetrics(&m);
  return m;
}

DirectionMetrics MetricsFromLabels(const DirectionLabels& labels, int score_stride) {
  if (score_stride < 1) throw InputError("score_stride", "expected >= 1");
  if (labels.labels.size() != static_cast<size_t>(labels.width) * labels.height) {
    throw InputError("labels", "label map size does not match width x height");
  }
  DirectionMetrics m;
  for (int v = 0; v < labels.height; v += score_stride) {
    for (int u = 0; u < labels.width; u += score_stride) {
      const uint8_t l = labels.labels[static_cast<size_t>(v) * labels.width + u];
      if (l >= kNumPixelLabels) throw InputError("labels", "label code out of range");
      ++m.counts[l];
      ++m.sampled;
    }
  }
  FinishMetrics(&m);
  return m;
}

}  // namespace gt

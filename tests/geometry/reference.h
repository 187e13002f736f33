// Test-only helpers for the geometry tests:
//  - ReferenceLabel: a slow, plainly written per-pixel labeller, straight from
//    GROUND_TRUTH.md §2 (double precision, step by step: unproject, transform, project),
//    to check the fast path in libgt/geometry/labels.cc against;
//  - a tiny ray caster for scenes of axis-aligned rectangles (walls, plates), giving exact
//    planar depth maps and the surface id seen by each pixel, for analytic tests.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/pose.h"
#include "libgt/geometry/labels.h"

namespace gt::test {

struct ReferenceResult {
  PixelLabel label = PixelLabel::kNoDepth;
  double x = std::numeric_limits<double>::quiet_NaN();
  double y = std::numeric_limits<double>::quiet_NaN();
};

inline ReferenceResult ReferenceLabel(const DepthImage& depth_a, const Camera& cam_a,
                                      const DepthImage& depth_b, const Camera& cam_b,
                                      const Rigid3d& b_from_a, const LabelOptions& o, int u,
                                      int v) {
  ReferenceResult r;
  const double d_a = depth_a.at(u, v);
  // 1. invalid source depth
  if (!IsValidDepth(depth_a.at(u, v), o.min_depth_m, o.max_depth_m)) {
    r.label = PixelLabel::kNoDepth;
    return r;
  }
  // 2. unproject and move into B
  const Eigen::Vector3d p_in_a((u - cam_a.cx) / cam_a.fx * d_a, (v - cam_a.cy) / cam_a.fy * d_a,
                               d_a);
  const Eigen::Vector3d p_in_b = b_from_a * p_in_a;
  const double z = p_in_b.z();
  // 3. cheirality, before any division
  if (o.cheirality && z <= o.min_depth_m) {
    r.label = PixelLabel::kOutOfView;
    return r;
  }
  // 4. project (K_B p) / (z + eps) and test the bounds
  const Eigen::Vector3d h = cam_b.K() * p_in_b;
  r.x = h.x() / (h.z() + o.projection_eps_m);
  r.y = h.y() / (h.z() + o.projection_eps_m);
  bool inside;
  if (o.bounds == Bounds::kPixelArea) {
    inside = r.x >= -0.5 && r.x < cam_b.width - 0.5 && r.y >= -0.5 && r.y < cam_b.height - 0.5;
  } else {
    inside = r.x > 0 && r.x < cam_b.width - 1 && r.y > 0 && r.y < cam_b.height - 1;
  }
  if (!inside) {
    r.label = PixelLabel::kOutOfView;
    return r;
  }
  // 5. target depth
  int tu, tv;
  if (o.target_lookup == TargetLookup::kNearest) {
    tu = static_cast<int>(std::floor(r.x + 0.5));
    tv = static_cast<int>(std::floor(r.y + 0.5));
  } else {
    tu = static_cast<int>(std::trunc(r.x));
    tv = static_cast<int>(std::trunc(r.y));
  }
  double d_b = depth_b.at(tu, tv);
  if (!IsValidDepth(depth_b.at(tu, tv), o.min_depth_m, o.max_depth_m)) {
    if (o.missing_target == MissingTarget::kUnknown) {
      r.label = PixelLabel::kUnknown;
      return r;
    }
    d_b = 0.0;
  }
  // 6. tolerance test
  const double base = o.relative_to == RelativeTo::kProjected ? z : d_b;
  const double tol = std::max(o.abs_tol_m, o.rel_tol * base);
  if (std::abs(z - d_b) <= tol) {
    r.label = PixelLabel::kVisible;
  } else if (z > d_b + tol) {
    r.label = PixelLabel::kOccluded;
  } else {
    r.label = PixelLabel::kInconsistent;
  }
  return r;
}

// An axis-aligned rectangle in world coordinates: the plane coordinate `axis` (0 x, 1 y,
// 2 z) equals `at`, and the two other coordinates lie in [lo, hi] (in axis order).
struct Rect {
  int axis = 2;
  double at = 0;
  double lo[2] = {-1e9, -1e9};
  double hi[2] = {1e9, 1e9};
};

// First intersection of the ray origin + t·dir (t > 1e-9) with the rectangles: t, and the
// index of the rectangle (-1 when none).
inline std::pair<double, int> CastRay(const std::vector<Rect>& scene, const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& dir) {
  double best_t = std::numeric_limits<double>::infinity();
  int best = -1;
  for (size_t k = 0; k < scene.size(); ++k) {
    const Rect& r = scene[k];
    if (dir[r.axis] == 0) continue;
    const double t = (r.at - origin[r.axis]) / dir[r.axis];
    if (!(t > 1e-9) || t >= best_t) continue;
    const Eigen::Vector3d p = origin + t * dir;
    int j = 0;
    bool in = true;
    for (int ax = 0; ax < 3; ++ax) {
      if (ax == r.axis) continue;
      in = in && p[ax] >= r.lo[j] && p[ax] <= r.hi[j];
      ++j;
    }
    if (in) {
      best_t = t;
      best = static_cast<int>(k);
    }
  }
  return {best_t, best};
}

// Exact planar depth (0 where no surface) and surface id per pixel (-1 where none).
struct Rendered {
  DepthImage depth;
  std::vector<int> surface;
};
inline Rendered Render(const std::vector<Rect>& scene, const Camera& cam,
                       const Rigid3d& world_from_cam) {
  Rendered out;
  out.depth = DepthImage(cam.width, cam.height, 0.0f);
  out.surface.assign(static_cast<size_t>(cam.width) * cam.height, -1);
  const Eigen::Vector3d origin = world_from_cam.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d ray_in_cam = cam.CamFromImg(u, v, 1.0);  // z = 1
      const Eigen::Vector3d dir = world_from_cam.linear() * ray_in_cam;
      const auto [t, id] = CastRay(scene, origin, dir);
      if (id < 0) continue;
      out.depth.at(u, v) = static_cast<float>(t);  // planar depth: ray has z = 1 in cam
      out.surface[static_cast<size_t>(v) * cam.width + u] = id;
    }
  }
  return out;
}

}  // namespace gt::test

// A slow, obviously-correct depth renderer for tests: every ray against every triangle in
// double precision (Moller-Trumbore), the nearest hit kept. It also says when a pixel is
// ambiguous - its ray passes within a hair of a triangle's edge, where float ray casters may
// legitimately hit either triangle or neither - so that comparisons can set those aside.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "libgt/core/pose.h"
#include "libgt/render/mesh.h"

namespace gt::render::test {

struct ReferenceHit {
  double depth_m = 0;      // planar z of the nearest hit within [near, far]; 0 = none
  int triangle = -1;       // its index, -1 = none
  bool ambiguous = false;  // an edge passes within edge_tolerance (barycentric) of the ray
};

// The ray from the camera centre along world_from_cam.linear() * (x, y, 1); t is planar z.
inline ReferenceHit ReferenceCast(const TriangleMesh& mesh, const Rigid3d& world_from_cam, double x,
                                  double y, double near_m, double far_m,
                                  double edge_tolerance = 1e-5) {
  const Eigen::Vector3d o = world_from_cam.translation();
  const Eigen::Vector3d d = world_from_cam.linear() * Eigen::Vector3d(x, y, 1.0);
  double best = std::numeric_limits<double>::infinity();
  int best_triangle = -1;
  double best_margin = 1;
  double nearest_near_miss = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < mesh.NumTriangles(); ++t) {
    auto vertex = [&](int k) {
      const float* p = &mesh.vertices_m[3 * mesh.triangles[3 * t + k]];
      return Eigen::Vector3d(p[0], p[1], p[2]);
    };
    const Eigen::Vector3d a = vertex(0), e1 = vertex(1) - a, e2 = vertex(2) - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;  // ray parallel to the triangle
    const Eigen::Vector3d s = o - a;
    const double bu = s.dot(p) / det;
    const Eigen::Vector3d q = s.cross(e1);
    const double bv = d.dot(q) / det;
    const double dist = e2.dot(q) / det;
    if (dist <= 0) continue;
    const double margin = std::min({bu, bv, 1 - bu - bv});
    if (margin >= 0) {
      if (dist < best) {
        best = dist;
        best_triangle = static_cast<int>(t);
        best_margin = margin;
      }
    } else if (margin > -edge_tolerance) {
      nearest_near_miss = std::min(nearest_near_miss, dist);
    }
  }
  ReferenceHit hit;
  hit.ambiguous = best_margin < edge_tolerance || nearest_near_miss <= best + 1e-3;
  if (best_triangle >= 0 && best >= near_m && best <= far_m) {
    hit.depth_m = best;
    hit.triangle = best_triangle;
  }
  // A hit just outside [near, far] is ambiguous too.
  if (best_triangle >= 0 && (std::abs(best - near_m) < 1e-4 || std::abs(best - far_m) < 1e-4)) {
    hit.ambiguous = true;
  }
  return hit;
}

}  // namespace gt::render::test

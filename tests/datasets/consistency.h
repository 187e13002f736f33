// A straightforward reprojection check for reader tests: every valid depth pixel of A is
// lifted with K_A, moved by b_from_a = inverse(world_from_b) * world_from_a, projected
// with K_B, and compared with B's depth at the nearest pixel: consistent when
// |z - d_B| <= rel_tol * z. The fraction is over pixels that land inside B on a valid depth.
#pragma once

#include <cmath>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/pose.h"

namespace gt::test {

struct Consistency {
  long compared = 0;
  long consistent = 0;
  double fraction() const { return compared > 0 ? static_cast<double>(consistent) / compared : 0; }
};

inline Consistency DepthConsistency(const DepthImage& depth_a, const Camera& cam_a,
                                    const Rigid3d& world_from_a, const DepthImage& depth_b,
                                    const Camera& cam_b, const Rigid3d& world_from_b,
                                    double min_depth_m, double max_depth_m, double rel_tol) {
  const Rigid3d b_from_a = world_from_b.inverse() * world_from_a;
  Consistency c;
  for (int v = 0; v < depth_a.height; ++v) {
    for (int u = 0; u < depth_a.width; ++u) {
      const float d = depth_a.at(u, v);
      if (!IsValidDepth(d, min_depth_m, max_depth_m)) continue;
      const Eigen::Vector3d p_in_b = b_from_a * cam_a.CamFromImg(u, v, d);
      const auto x = cam_b.ImgFromCam(p_in_b);
      if (!x || !cam_b.InPixelArea(x->x(), x->y())) continue;
      const int ub = static_cast<int>(std::lround(x->x()));
      const int vb = static_cast<int>(std::lround(x->y()));
      if (ub < 0 || vb < 0 || ub >= depth_b.width || vb >= depth_b.height) continue;
      const float db = depth_b.at(ub, vb);
      if (!IsValidDepth(db, min_depth_m, max_depth_m)) continue;
      ++c.compared;
      if (std::abs(p_in_b.z() - db) <= rel_tol * p_in_b.z()) ++c.consistent;
    }
  }
  return c;
}

}  // namespace gt::test

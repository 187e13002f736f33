// The two-view scene of the geometry benchmarks (labels_bench.cc, patches_bench.cc): a box
// in front of a wall (tests/geometry/reference.h's renderer), 640x480, f = 500, seen from
// A at the origin and from B moved 0.9 m sideways and yawed 9°.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/pose.h"
#include "tests/geometry/reference.h"

namespace gt::bench {

struct TwoViewScene {
  Camera cam;
  DepthImage depth_a, depth_b;
  Rigid3d b_from_a;
};

inline const TwoViewScene& GetTwoViewScene() {
  static const TwoViewScene scene = [] {
    TwoViewScene s;
    s.cam.width = 640;
    s.cam.height = 480;
    s.cam.fx = s.cam.fy = 500;
    s.cam.cx = 319.5;
    s.cam.cy = 239.5;
    std::vector<test::Rect> rects;
    rects.push_back({2, 5.0, {-1e9, -1e9}, {1e9, 1e9}});
    rects.push_back({2, 2.5, {-0.5, -0.4}, {0.5, 0.4}});
    rects.push_back({0, 0.5, {-0.4, 2.5}, {0.4, 3.2}});
    Rigid3d world_from_b = Rigid3d::Identity();
    world_from_b.linear() = Eigen::AngleAxisd(-9 * M_PI / 180, Eigen::Vector3d::UnitY()).matrix();
    world_from_b.translation() = Eigen::Vector3d(0.9, 0.1, -0.2);
    s.depth_a = test::Render(rects, s.cam, Rigid3d::Identity()).depth;
    s.depth_b = test::Render(rects, s.cam, world_from_b).depth;
    s.b_from_a = RelativePose(Rigid3d::Identity(), world_from_b);
    return s;
  }();
  return scene;
}

}  // namespace gt::bench

// Camera loops: rigid, smooth (bounded steps and small second differences), closed,
// clear of objects, and nearby frames show real occlusion (a point seen by frame i projects
// into frame i+k behind a nearer surface).
#include "libgt/synth/trajectory.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "libgt/core/pose.h"
#include "libgt/synth/render.h"

namespace gt::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

double AngleBetween(const Rigid3d& a, const Rigid3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

TEST(Trajectory, PosesAreRigidSmoothAndClosed) {
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const SynthScene scene = MakeRoomScene(seed);
    TrajectoryOptions o;
    o.frames = 24;
    const auto poses = Trajectory(scene, o);
    ASSERT_EQ(poses.size(), 24u);
    o.frames = 48;  // the same loop sampled twice as densely: every other pose is shared
    const auto dense = Trajectory(scene, o);
    const double a = scene.walk_semi_axes_m.maxCoeff();
    const double dtheta = 2 * kPi / 24;
    for (size_t i = 0; i < poses.size(); ++i) {
      EXPECT_FALSE(PoseProblem(poses[i].matrix()).has_value()) << *PoseProblem(poses[i].matrix());
      EXPECT_LT((poses[i].matrix() - dense[2 * i].matrix()).cwiseAbs().maxCoeff(), 1e-12);
      // The camera x axis (right) is horizontal: no roll.
      EXPECT_NEAR(poses[i].linear()(2, 0), 0.0, 1e-12);
      const Rigid3d& next = poses[(i + 1) % poses.size()];  // wraps: the loop is closed
      // Step bound: the centre moves along an ellipse (arc <= a * dtheta) plus the bob
      // (2 * bob * dtheta); the heading and pitch change by at most (1 + 2 sway) dtheta and
      // 3 pitch_sway dtheta.
      const double step_m = (next.translation() - poses[i].translation()).norm();
      EXPECT_LE(step_m, a * dtheta + 2 * o.bob_m * dtheta + 1e-9);
      EXPECT_GT(step_m, 0.01);
      EXPECT_LE(AngleBetween(poses[i], next),
                (1 + 2 * o.sway_rad) * dtheta + 3 * o.pitch_sway_rad * dtheta + 1e-9);
      // Smooth: second differences of the centre are much smaller than the steps.
      const Rigid3d& prev = poses[(i + poses.size() - 1) % poses.size()];
      const Eigen::Vector3d second =
          next.translation() - 2 * poses[i].translation() + prev.translation();
      EXPECT_LT(second.norm(), 0.35 * step_m + 1e-3);
    }
  }
}

TEST(Trajectory, CamerasStayClearOfObjectsAndSeeOcclusion) {
  Camera cam;
  cam.width = 160;
  cam.height = 120;
  cam.fx = cam.fy = 131.25;
  cam.cx = 79.5;
  cam.cy = 59.5;
  int pairs_with_occlusion = 0, pairs = 0;
  for (uint64_t seed = 0; seed < 4; ++seed) {
    const SynthScene scene = MakeRoomScene(seed);
    TrajectoryOptions o;
    const auto poses = Trajectory(scene, o);
    std::vector<DepthImage> depths;
    for (const auto& pose : poses) {
      depths.push_back(RenderDepth(scene, cam, pose));
      float min_depth = 1e9f;
      for (float d : depths.back().values_m) {
        ASSERT_GT(d, 0.0f);  // closed room, no holes here
        min_depth = std::min(min_depth, d);
      }
      EXPECT_GT(min_depth, 0.3f) << "a camera is too close to a surface";
    }
    for (size_t i = 0; i < poses.size(); ++i) {
      for (size_t k : {1, 2}) {
        const size_t j = (i + k) % poses.size();
        const Rigid3d b_from_a = RelativePose(poses[i], poses[j]);
        int occluded = 0, visible = 0;
        for (int v = 0; v < cam.height; v += 2) {
          for (int u = 0; u < cam.width; u += 2) {
            const Eigen::Vector3d p_in_b = b_from_a * cam.CamFromImg(u, v, depths[i].at(u, v));
            const auto x = cam.ImgFromCam(p_in_b, 0.05);
            if (!x || !cam.InPixelArea(x->x(), x->y())) continue;
            const float db = depths[j].at(static_cast<int>(std::lround(x->x())),
                                          static_cast<int>(std::lround(x->y())));
            if (db < p_in_b.z() - 0.1) {
              ++occluded;
            } else {
              ++visible;
            }
          }
        }
        ++pairs;
        EXPECT_GT(visible, 0) << "no overlap between frames " << i << " and " << j;
        pairs_with_occlusion += occluded > 20;
      }
    }
  }
  // Most nearby pairs have some occlusion (a pole, panel or box hides part of a wall).
  EXPECT_GT(pairs_with_occlusion, pairs / 2) << pairs_with_occlusion << " of " << pairs;
}

TEST(Trajectory, OptionsAreChecked) {
  TrajectoryOptions o;
  std::string error;
  EXPECT_TRUE(o.Check(&error)) << error;
  o.frames = 0;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_NE(error.find("frames"), std::string::npos);
  o = TrajectoryOptions();
  o.pitch_rad = 1.0;
  o.pitch_sway_rad = 0.5;
  EXPECT_FALSE(o.Check(&error));
  RoomOptions r;
  EXPECT_TRUE(r.Check(&error)) << error;
  r.max_boxes = r.min_boxes - 1;
  EXPECT_FALSE(r.Check(&error));
}

}  // namespace
}  // namespace gt::synth

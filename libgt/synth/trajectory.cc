// Camera loops for synthetic scenes (trajectory.h).
#include "libgt/synth/trajectory.h"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "libgt/core/error.h"

namespace gt::synth {

bool TrajectoryOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error != nullptr) *error = m;
    return false;
  };
  if (frames < 1 || frames > 100000) return fail("frames: expected 1..100000");
  if (!(bob_m >= 0.0 && bob_m <= 0.3)) return fail("bob_m: expected [0, 0.3]");
  if (!(sway_rad >= 0.0 && sway_rad <= 1.0)) return fail("sway_rad: expected [0, 1]");
  if (!(pitch_rad >= -0.8 && pitch_rad <= 0.8) || !(pitch_sway_rad >= 0.0) ||
      std::abs(pitch_rad) + pitch_sway_rad > 1.2) {
    return fail("pitch_rad, pitch_sway_rad: expected |pitch| + sway <= 1.2");
  }
  return true;
}

Rigid3d LookAlong(const Eigen::Vector3d& center_in_world, const Eigen::Vector3d& forward_in_world) {
  const Eigen::Vector3d up(0.0, 0.0, 1.0);
  const Eigen::Vector3d z = forward_in_world.normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();  // right
  GT_ASSERT(x.allFinite());
  const Eigen::Vector3d y = z.cross(x);  // down
  Rigid3d world_from_cam = Rigid3d::Identity();
  world_from_cam.linear().col(0) = x;
  world_from_cam.linear().col(1) = y;
  world_from_cam.linear().col(2) = z;
  world_from_cam.translation() = center_in_world;
  return world_from_cam;
}

std::vector<Rigid3d> Trajectory(const SynthScene& scene, const TrajectoryOptions& o) {
  std::vector<Rigid3d> poses;
  poses.reserve(o.frames);
  const double a = scene.walk_semi_axes_m.x(), b = scene.walk_semi_axes_m.y();
  for (int i = 0; i < o.frames; ++i) {
    const double theta = scene.walk_phase_rad + 2.0 * kPi * i / o.frames;
    const Eigen::Vector3d center(scene.walk_center_xy.x() + a * std::cos(theta),
                                 scene.walk_center_xy.y() + b * std::sin(theta),
                                 scene.eye_height_m + o.bob_m * std::sin(2.0 * theta));
    const double heading = theta + o.sway_rad * std::sin(2.0 * theta + 1.0);
    const double pitch = o.pitch_rad + o.pitch_sway_rad * std::sin(3.0 * theta);
    const Eigen::Vector3d forward(std::cos(pitch) * std::cos(heading),
                                  std::cos(pitch) * std::sin(heading), -std::sin(pitch));
    poses.push_back(LookAlong(center, forward));
  }
  return poses;
}

}  // namespace gt::synth

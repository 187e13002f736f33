// Smooth camera paths through a SynthScene: one closed loop around the walk ellipse.
//
// Frame i of n has the loop angle theta_i = walk_phase + 2 pi i / n. The camera centre is
//   c(theta) = walk_center + (a cos theta, b sin theta), at height eye + bob sin(2 theta);
// it looks outwards, towards the walls and the objects in front of them, along the
// heading theta + sway sin(2 theta + 1) with a downward pitch of
// pitch + pitch_sway sin(3 theta). Both are smooth periodic functions, so consecutive
// poses differ by a bounded step. Poses are world_from_cam in OpenCV camera axes (x right,
// y down, z forward) with world +z up, so there is no roll.
#pragma once

#include <vector>

#include "libgt/core/pose.h"
#include "libgt/synth/scene.h"

namespace gt::synth {

struct TrajectoryOptions {
  int frames = 24;              // poses on the loop
  double bob_m = 0.08;          // vertical oscillation amplitude (metres)
  double sway_rad = 0.2;        // heading oscillation amplitude around the outward radial
  double pitch_rad = 0.3;       // mean downward pitch
  double pitch_sway_rad = 0.1;  // pitch oscillation amplitude

  bool Check(std::string* error) const;
};

// world_from_cam of camera looking along `forward_in_world` (not vertical) from `center`.
Rigid3d LookAlong(const Eigen::Vector3d& center_in_world, const Eigen::Vector3d& forward_in_world);

std::vector<Rigid3d> Trajectory(const SynthScene& scene, const TrajectoryOptions& options);

}  // namespace gt::synth

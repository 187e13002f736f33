// Rigid poses. Every transform is named x_from_y: p_in_x = x_from_y * p_in_y.
// A frame's pose is world_from_cam (camera-to-world) in OpenCV camera axes.
// Relative pose of a pair: b_from_a = inverse(world_from_b) * world_from_a.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace gt {

using Rigid3d = Eigen::Isometry3d;

// Tolerance of the rigidity test |R^T R - I| (max abs entry); GROUND_TRUTH.md §1.
inline constexpr double kRigidTolerance = 1e-3;

// Why a 4x4 camera-to-world matrix cannot be used as a pose, or nullopt when it can:
// non-finite entries (ScanNet's lost tracking is written as -inf), a last row other than
// [0 0 0 1], |R^T R - I| > kRigidTolerance, or det R < 0.
std::optional<std::string> PoseProblem(const Eigen::Matrix4d& world_from_cam);

// The rigid transform of a validated matrix (R re-orthonormalised by SVD, so that
// small float rounding in text files does not accumulate).
Rigid3d RigidFromMatrix(const Eigen::Matrix4d& m);

// Translation + unit quaternion (x, y, z, w order as in TUM/TartanAir files).
// The quaternion must have a norm within 1e-3 of 1 (otherwise PoseProblemTQ reports it).
std::optional<std::string> PoseProblemTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw);
Rigid3d RigidFromTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw);

inline Rigid3d RelativePose(const Rigid3d& world_from_a, const Rigid3d& world_from_b) {
  return world_from_b.inverse(Eigen::Isometry) * world_from_a;  // b_from_a
}

}  // namespace gt

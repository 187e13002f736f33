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

// Tolerance of the quaternion norm test ||q| - 1| (PoseProblemTQ).
inline constexpr double kQuaternionNormTolerance = 1e-3;

// Why a 4x4 camera-to-world matrix cannot be used as a pose, or nullopt when it can:
// non-finite entries (ScanNet's lost tracking is written as -inf), a last row other than
// [0 0 0 1], |R^T R - I| > kRigidTolerance, or det R < 0.
std::optional<std::string> PoseProblem(const Eigen::Matrix4d& world_from_cam);

// What PoseProblem / PoseProblemTQ find, with the place in the pose it concerns, so that a
// reader can name the line or field of its input (libgt/datasets/text_parsing.h PoseLocator).
enum class PoseDefectKind { kNonFinite, kLastRow, kNotOrthonormal, kReflection, kQuaternionNorm };
struct PoseDefect {
  PoseDefectKind kind = PoseDefectKind::kNonFinite;
  // 4x4 matrices: the row (0..3) of the first non-finite entry (row-major order) and its
  // column; row 3 for kLastRow; for kNotOrthonormal the rotation row that departs most
  // (largest sum of |R R^T - I| over its row: the row holding a wrong value). -1 for
  // kReflection (rows 0..2 together) and for translation + quaternion poses (one record).
  int row = -1;
  int col = -1;      // kNonFinite of a matrix only
  std::string text;  // PoseProblem's (PoseProblemTQ's) words, with the measured value
};
std::optional<PoseDefect> FindPoseDefect(const Eigen::Matrix4d& world_from_cam);

// The rigid transform of a validated matrix (R re-orthonormalised by SVD, so that
// small float rounding in text files does not accumulate).
Rigid3d RigidFromMatrix(const Eigen::Matrix4d& m);

// Translation + unit quaternion (x, y, z, w order as in TUM/TartanAir files).
// The quaternion must have a norm within kQuaternionNormTolerance of 1 (otherwise
// PoseProblemTQ reports it).
std::optional<std::string> PoseProblemTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw);
std::optional<PoseDefect> FindPoseDefectTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw);
Rigid3d RigidFromTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw);

inline Rigid3d RelativePose(const Rigid3d& world_from_a, const Rigid3d& world_from_b) {
  return world_from_b.inverse(Eigen::Isometry) * world_from_a;  // b_from_a
}

}  // namespace gt

#include "libgt/core/pose.h"

#include <Eigen/SVD>
#include <cmath>
#include <sstream>

namespace gt {

std::optional<PoseDefect> FindPoseDefect(const Eigen::Matrix4d& m) {
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (!std::isfinite(m(r, c))) {
        return PoseDefect{PoseDefectKind::kNonFinite, r, c,
                          "non-finite pose entries (lost tracking)"};
      }
    }
  }
  if (std::abs(m(3, 0)) > 1e-6 || std::abs(m(3, 1)) > 1e-6 || std::abs(m(3, 2)) > 1e-6 ||
      std::abs(m(3, 3) - 1.0) > 1e-6) {
    return PoseDefect{PoseDefectKind::kLastRow, 3, -1, "last row of the pose is not [0 0 0 1]"};
  }
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > kRigidTolerance) {
    std::ostringstream s;
    s << "rotation is not orthonormal (|R^T R - I| = " << err << " > " << kRigidTolerance << ")";
    // Entry (i, j) of R R^T - I involves rows i and j only: a wrong value in row i shows in
    // the whole of row i, and in one entry of each other row.
    const Eigen::Vector3d row_error =
        (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().rowwise().sum();
    int worst = 0;
    for (int r = 1; r < 3; ++r) {
      if (row_error[r] > row_error[worst]) worst = r;
    }
    return PoseDefect{PoseDefectKind::kNotOrthonormal, worst, -1, s.str()};
  }
  if (R.determinant() < 0) {
    return PoseDefect{PoseDefectKind::kReflection, -1, -1, "rotation has det < 0 (a reflection)"};
  }
  return std::nullopt;
}

std::optional<std::string> PoseProblem(const Eigen::Matrix4d& m) {
  if (auto defect = FindPoseDefect(m)) return std::move(defect->text);
  return std::nullopt;
}

Rigid3d RigidFromMatrix(const Eigen::Matrix4d& m) {
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Rigid3d T = Rigid3d::Identity();
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = m.topRightCorner<3, 1>();
  return T;
}

std::optional<PoseDefect> FindPoseDefectTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q) {
  if (!t.allFinite() || !q.allFinite()) {
    return PoseDefect{PoseDefectKind::kNonFinite, -1, -1, "non-finite pose entries"};
  }
  const double n = q.norm();
  if (std::abs(n - 1.0) > kQuaternionNormTolerance) {
    std::ostringstream s;
    s << "quaternion norm is " << n << ", expected 1";
    return PoseDefect{PoseDefectKind::kQuaternionNorm, -1, -1, s.str()};
  }
  return std::nullopt;
}

std::optional<std::string> PoseProblemTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q) {
  if (auto defect = FindPoseDefectTQ(t, q)) return std::move(defect->text);
  return std::nullopt;
}

Rigid3d RigidFromTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw) {
  Eigen::Quaterniond q(q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]);
  q.normalize();
  Rigid3d T = Rigid3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = t;
  return T;
}

}  // namespace gt

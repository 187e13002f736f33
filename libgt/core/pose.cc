#include "libgt/core/pose.h"

#include <Eigen/SVD>
#include <cmath>
#include <sstream>

namespace gt {

std::optional<std::string> PoseProblem(const Eigen::Matrix4d& m) {
  if (!m.allFinite()) return std::string("non-finite pose entries (lost tracking)");
  if (std::abs(m(3, 0)) > 1e-6 || std::abs(m(3, 1)) > 1e-6 || std::abs(m(3, 2)) > 1e-6 ||
      std::abs(m(3, 3) - 1.0) > 1e-6) {
    return std::string("last row of the pose is not [0 0 0 1]");
  }
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > kRigidTolerance) {
    std::ostringstream s;
    s << "rotation is not orthonormal (|R^T R - I| = " << err << " > " << kRigidTolerance << ")";
    return s.str();
  }
  if (R.determinant() < 0) return std::string("rotation has det < 0 (a reflection)");
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

std::optional<std::string> PoseProblemTQ(const Eigen::Vector3d& t, const Eigen::Vector4d& q) {
  if (!t.allFinite() || !q.allFinite()) return std::string("non-finite pose entries");
  const double n = q.norm();
  if (std::abs(n - 1.0) > 1e-3) {
    std::ostringstream s;
    s << "quaternion norm is " << n << ", expected 1";
    return s.str();
  }
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

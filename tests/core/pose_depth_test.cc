// Pose validation, relative poses, depth resampling.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "libgt/core/depth.h"
#include "libgt/core/pose.h"

namespace gt {
namespace {

Rigid3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  Rigid3d T = Rigid3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng));
  return T;
}

TEST(Pose, RelativePoseComposes) {
  std::mt19937 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Rigid3d wa = RandomPose(rng), wb = RandomPose(rng);
    const Rigid3d b_from_a = RelativePose(wa, wb);
    const Rigid3d a_from_b = RelativePose(wb, wa);
    EXPECT_LT(((a_from_b * b_from_a).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
    const Eigen::Vector3d p_in_a(0.3, -0.2, 2.0);
    EXPECT_LT((wb * (b_from_a * p_in_a) - wa * p_in_a).norm(), 1e-12);
  }
}

TEST(Pose, ProblemsAreReported) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  EXPECT_FALSE(PoseProblem(m).has_value());
  m(0, 3) = -std::numeric_limits<double>::infinity();
  ASSERT_TRUE(PoseProblem(m).has_value());
  EXPECT_NE(PoseProblem(m)->find("non-finite"), std::string::npos);
  m = Eigen::Matrix4d::Identity();
  m(0, 0) = 1.01;
  ASSERT_TRUE(PoseProblem(m).has_value());
  EXPECT_NE(PoseProblem(m)->find("orthonormal"), std::string::npos);
  m = Eigen::Matrix4d::Identity();
  m(2, 2) = -1;
  ASSERT_TRUE(PoseProblem(m).has_value());
  EXPECT_NE(PoseProblem(m)->find("det"), std::string::npos);
  m = Eigen::Matrix4d::Identity();
  m(0, 0) = 1.0004;  // within tolerance (text rounding): 1.0004^2 - 1 < 1e-3
  EXPECT_FALSE(PoseProblem(m).has_value());
  EXPECT_LT((RigidFromMatrix(m).linear() - Eigen::Matrix3d::Identity()).norm(), 1e-3);
}

TEST(Pose, DefectsSayWhereInTheMatrix) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  EXPECT_FALSE(FindPoseDefect(m).has_value());
  m(2, 1) = std::nan("");
  m(3, 0) = std::numeric_limits<double>::infinity();  // later in row-major order
  auto d = FindPoseDefect(m);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, PoseDefectKind::kNonFinite);
  EXPECT_EQ(d->row, 2);
  EXPECT_EQ(d->col, 1);
  EXPECT_EQ(d->text, *PoseProblem(m));
  m = Eigen::Matrix4d::Identity();
  m(3, 2) = 1;
  d = FindPoseDefect(m);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, PoseDefectKind::kLastRow);
  EXPECT_EQ(d->row, 3);
  // One wrong value in a rotation row: that row, whichever it is.
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      m = Eigen::Matrix4d::Identity();
      m(row, col) += 0.5;
      d = FindPoseDefect(m);
      ASSERT_TRUE(d.has_value()) << row << col;
      EXPECT_EQ(d->kind, PoseDefectKind::kNotOrthonormal);
      EXPECT_EQ(d->row, row) << "wrong value at (" << row << ", " << col << ")";
      EXPECT_EQ(d->col, -1);
    }
  }
  // A row scaled by 2 in a rotated frame.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = R;
  m.row(2).head<3>() *= 2.0;
  d = FindPoseDefect(m);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->row, 2);
  m = Eigen::Matrix4d::Identity();
  m(1, 1) = -1;
  d = FindPoseDefect(m);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, PoseDefectKind::kReflection);
  EXPECT_EQ(d->row, -1);
}

TEST(Pose, QuaternionDefects) {
  EXPECT_FALSE(FindPoseDefectTQ({0, 0, 0}, {0, 0, 0, 1}).has_value());
  auto d = FindPoseDefectTQ({0, 0, 0}, {0, 0, 0, 2});
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, PoseDefectKind::kQuaternionNorm);
  EXPECT_EQ(d->text, "quaternion norm is 2, expected 1");
  EXPECT_EQ(d->row, -1);
  d = FindPoseDefectTQ({0, 0, std::numeric_limits<double>::infinity()}, {0, 0, 0, 1});
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->kind, PoseDefectKind::kNonFinite);
}

TEST(Pose, QuaternionNormChecked) {
  EXPECT_FALSE(PoseProblemTQ({0, 0, 0}, {0, 0, 0, 1}).has_value());
  EXPECT_TRUE(PoseProblemTQ({0, 0, 0}, {0, 0, 0, 2}).has_value());
  EXPECT_TRUE(PoseProblemTQ({0, std::nan(""), 0}, {0, 0, 0, 1}).has_value());
}

TEST(Depth, NearestResizeHalvesByTakingOneOfEachBlock) {
  DepthImage d(4, 2);
  for (int v = 0; v < 2; ++v)
    for (int u = 0; u < 4; ++u) d.at(u, v) = static_cast<float>(10 * v + u);
  const DepthImage h = ResizeDepthNearest(d, 2, 1);
  ASSERT_EQ(h.width, 2);
  // target pixel 0 covers source pixels 0..1, centre 0.5 -> floor(1.0) = 1
  EXPECT_EQ(h.at(0, 0), d.at(1, 1));
  EXPECT_EQ(h.at(1, 0), d.at(3, 1));
  const DepthImage same = ResizeDepthNearest(d, 4, 2);
  EXPECT_EQ(same.values_m, d.values_m);
  const DepthImage up = ResizeDepthNearest(d, 8, 4);
  EXPECT_EQ(up.at(0, 0), d.at(0, 0));
  EXPECT_EQ(up.at(7, 3), d.at(3, 1));
}

TEST(Depth, Validity) {
  EXPECT_FALSE(IsValidDepth(0.0f, 0.0, 10.0));
  EXPECT_FALSE(IsValidDepth(std::nanf(""), 0.0, 10.0));
  EXPECT_FALSE(IsValidDepth(std::numeric_limits<float>::infinity(), 0.0, 1e30));
  EXPECT_FALSE(IsValidDepth(0.05f, 0.1, 10.0));
  EXPECT_FALSE(IsValidDepth(1e4f, 0.1, 1000.0));
  EXPECT_TRUE(IsValidDepth(2.0f, 0.1, 10.0));
}

}  // namespace
}  // namespace gt

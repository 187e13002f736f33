// Lens models: the exact inverse (UndistortPixel) against OpenCV's forward projections
// (cv::projectPoints, cv::fisheye::projectPoints) at many pixels including the image border,
// DistortPoint against the same, the monotonic range, and Check.
#include "libgt/core/lens.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>
#include <vector>

namespace gt {
namespace {

// A ScanNet++-like DSLR fisheye at the resized images' size (1752 x 1168).
LensCamera DslrFisheye() {
  LensCamera lens;
  lens.pinhole.width = 1752;
  lens.pinhole.height = 1168;
  lens.pinhole.fx = 791.3;
  lens.pinhole.fy = 790.8;
  lens.pinhole.cx = 874.2;
  lens.pinhole.cy = 583.6;
  lens.model = LensModel::kOpenCvFisheye;
  lens.coeffs = {-0.0297, -0.0049, 0.0011, -0.0004, 0.0};
  return lens;
}

// A strong fisheye (wide field of view) whose corners are far off axis.
LensCamera WideFisheye() {
  LensCamera lens = DslrFisheye();
  lens.pinhole.fx = 700.0;  // the corners are ~84 degrees off axis
  lens.pinhole.fy = 700.0;
  lens.coeffs = {0.08, -0.02, 0.004, -0.0006, 0.0};
  return lens;
}

// An iPhone-like OPENCV camera (k1 k2 p1 p2) and a strongly distorted one with k3.
LensCamera PhoneOpenCv() {
  LensCamera lens;
  lens.pinhole.width = 1920;
  lens.pinhole.height = 1440;
  lens.pinhole.fx = 1445.1;
  lens.pinhole.fy = 1444.7;
  lens.pinhole.cx = 959.3;
  lens.pinhole.cy = 717.9;
  lens.model = LensModel::kOpenCv;
  lens.coeffs = {0.071, -0.171, 0.0012, -0.0007, 0.0};
  return lens;
}
LensCamera BarrelOpenCv() {
  LensCamera lens = PhoneOpenCv();
  lens.pinhole.fx = 1300.0;  // the corners are close to the fold (r = 1.82)
  lens.pinhole.fy = 1300.0;
  lens.coeffs = {-0.28, 0.09, 0.0021, -0.0015, -0.012};
  return lens;
}

// Pixels of the whole image: a grid, every pixel of the four border rows/columns (centres and
// the outer edges of the pixel area) and random ones.
std::vector<Eigen::Vector2d> TestPixels(const Camera& c) {
  std::vector<Eigen::Vector2d> px;
  const double w = c.width, h = c.height;
  for (double v = 0; v < h; v += 37) {
    for (double u = 0; u < w; u += 41) px.emplace_back(u, v);
  }
  for (double u = 0; u < w; u += 1) {
    px.emplace_back(u, 0);
    px.emplace_back(u, h - 1);
    px.emplace_back(u, -0.5);
    px.emplace_back(u, h - 0.5);
  }
  for (double v = 0; v < h; v += 1) {
    px.emplace_back(0, v);
    px.emplace_back(w - 1, v);
    px.emplace_back(-0.5, v);
    px.emplace_back(w - 0.5, v);
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> du(-0.5, w - 0.5), dv(-0.5, h - 0.5);
  for (int i = 0; i < 2000; ++i) px.emplace_back(du(rng), dv(rng));
  return px;
}

cv::Matx33d CvK(const Camera& c) { return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1}; }

// OpenCV's forward projection of the rays UndistortPixel found, one call for all of them.
std::vector<cv::Point2d> OpenCvProject(const LensCamera& lens,
                                       const std::vector<cv::Point3d>& rays) {
  std::vector<cv::Point2d> out;
  const cv::Vec3d zero(0, 0, 0);
  if (lens.model == LensModel::kOpenCvFisheye) {
    const cv::Vec4d d(lens.coeffs[0], lens.coeffs[1], lens.coeffs[2], lens.coeffs[3]);
    cv::fisheye::projectPoints(rays, out, zero, zero, CvK(lens.pinhole), d);
  } else {
    const std::vector<double> d(lens.coeffs.begin(), lens.coeffs.end());
    cv::projectPoints(rays, zero, zero, CvK(lens.pinhole), d, out);
  }
  return out;
}

void ExpectRoundTripsThroughOpenCv(const LensCamera& lens, double tol_px) {
  std::string error;
  ASSERT_TRUE(lens.Check(&error)) << error;
  const auto pixels = TestPixels(lens.pinhole);
  std::vector<cv::Point3d> rays;
  rays.reserve(pixels.size());
  for (const auto& px : pixels) {
    const auto ab = UndistortPixel(lens, px.x(), px.y());
    ASSERT_TRUE(ab.has_value()) << "pixel " << px.transpose();
    rays.emplace_back(ab->x(), ab->y(), 1.0);
  }
  const auto projected = OpenCvProject(lens, rays);
  double worst = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    const double err = std::hypot(projected[i].x - pixels[i].x(), projected[i].y - pixels[i].y());
    worst = std::max(worst, err);
    ASSERT_LE(err, tol_px) << "pixel " << pixels[i].transpose() << " -> " << projected[i];
    // The same ray at another depth projects to the same pixel with DistortPoint.
    const auto back = DistortPoint(lens, Eigen::Vector3d(rays[i].x, rays[i].y, 1.0) * 3.7);
    ASSERT_TRUE(back.has_value());
    ASSERT_LE((*back - pixels[i]).norm(), tol_px);
  }
  ::testing::Test::RecordProperty("worst_px", std::to_string(worst));
}

TEST(Lens, FisheyeInverseRoundTripsThroughCvFisheyeProjectPoints) {
  ExpectRoundTripsThroughOpenCv(DslrFisheye(), 1e-7);
  ExpectRoundTripsThroughOpenCv(WideFisheye(), 1e-7);
}

TEST(Lens, OpenCvInverseRoundTripsThroughCvProjectPoints) {
  ExpectRoundTripsThroughOpenCv(PhoneOpenCv(), 1e-7);
  ExpectRoundTripsThroughOpenCv(BarrelOpenCv(), 1e-7);
  LensCamera radial_only = BarrelOpenCv();
  radial_only.coeffs[2] = radial_only.coeffs[3] = 0.0;
  ExpectRoundTripsThroughOpenCv(radial_only, 1e-7);
}

TEST(Lens, DistortPointEqualsOpenCvProjection) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> dxy(-2.0, 2.0), dz(0.2, 6.0);
  for (const LensCamera& lens : {DslrFisheye(), WideFisheye(), PhoneOpenCv(), BarrelOpenCv()}) {
    std::vector<cv::Point3d> pts;
    for (int i = 0; i < 500; ++i) pts.emplace_back(dxy(rng), dxy(rng), dz(rng));
    const auto cv_px = OpenCvProject(lens, pts);
    for (size_t i = 0; i < pts.size(); ++i) {
      const auto px = DistortPoint(lens, {pts[i].x, pts[i].y, pts[i].z});
      ASSERT_TRUE(px.has_value());
      EXPECT_NEAR(px->x(), cv_px[i].x, 1e-7 * (1 + std::abs(cv_px[i].x)));
      EXPECT_NEAR(px->y(), cv_px[i].y, 1e-7 * (1 + std::abs(cv_px[i].y)));
    }
  }
}

TEST(Lens, InverseIsTighterThanOpenCvsFixedIterations) {
  // cv::fisheye::undistortPoints stops after a fixed number of iterations; the exact inverse
  // must be at least as good everywhere and reach ~1e-9 px at the corners of a wide lens.
  const LensCamera lens = WideFisheye();
  const std::vector<cv::Point2d> corners = {
      {-0.5, -0.5}, {1751.5, -0.5}, {-0.5, 1167.5}, {1751.5, 1167.5}};
  std::vector<cv::Point2d> cv_norm;
  cv::fisheye::undistortPoints(
      corners, cv_norm, CvK(lens.pinhole),
      cv::Vec4d(lens.coeffs[0], lens.coeffs[1], lens.coeffs[2], lens.coeffs[3]));
  for (size_t i = 0; i < corners.size(); ++i) {
    const auto ab = UndistortPixel(lens, corners[i].x, corners[i].y);
    ASSERT_TRUE(ab.has_value());
    const auto ours = DistortPoint(lens, {ab->x(), ab->y(), 1.0});
    const auto theirs = DistortPoint(lens, {cv_norm[i].x, cv_norm[i].y, 1.0});
    const double our_err = (*ours - Eigen::Vector2d(corners[i].x, corners[i].y)).norm();
    const double their_err = (*theirs - Eigen::Vector2d(corners[i].x, corners[i].y)).norm();
    EXPECT_LE(our_err, 1e-9);
    EXPECT_LE(our_err, their_err + 1e-12);
  }
}

TEST(Lens, PinholeIsTheCamera) {
  LensCamera lens;
  lens.pinhole = DslrFisheye().pinhole;
  for (const auto& px : TestPixels(lens.pinhole)) {
    const auto ab = UndistortPixel(lens, px.x(), px.y());
    ASSERT_TRUE(ab.has_value());
    const Eigen::Vector3d p = lens.pinhole.CamFromImg(px.x(), px.y(), 2.0);
    EXPECT_NEAR(ab->x(), p.x() / 2.0, 1e-15);
    EXPECT_NEAR(ab->y(), p.y() / 2.0, 1e-15);
    const auto back = DistortPoint(lens, p);
    EXPECT_NEAR((*back - px).norm(), 0.0, 1e-9);
  }
}

TEST(Lens, NoRayBeyondTheFold) {
  // OpenCV radial k1 = -0.3: r (1 - 0.3 r^2) peaks at r = 1/sqrt(0.9) with value
  // 2/3 * 1/sqrt(0.9) = 0.70273; distorted radii beyond have no ray, below they have one
  // inside the fold.
  LensCamera lens;
  lens.pinhole = {640, 480, 100.0, 100.0, 320.0, 240.0};
  lens.model = LensModel::kOpenCv;
  lens.coeffs = {-0.3, 0, 0, 0, 0};
  const double r_fold = 1.0 / std::sqrt(0.9);
  EXPECT_NEAR(MonotonicLimit(lens), r_fold, 1e-9);
  const double peak = r_fold * (1.0 - 0.3 * r_fold * r_fold);
  EXPECT_FALSE(UndistortPixel(lens, 320.0 + 100.0 * (peak + 1e-6), 240.0).has_value());
  const auto inside = UndistortPixel(lens, 320.0 + 100.0 * (peak - 1e-3), 240.0);
  ASSERT_TRUE(inside.has_value());
  EXPECT_LT(inside->norm(), r_fold);
  EXPECT_NEAR(inside->x() * (1.0 - 0.3 * inside->squaredNorm()), peak - 1e-3, 1e-12);

  // Fisheye k1 = -0.5: theta (1 - 0.5 theta^2) peaks at theta = sqrt(2/3).
  LensCamera fish;
  fish.pinhole = lens.pinhole;
  fish.model = LensModel::kOpenCvFisheye;
  fish.coeffs = {-0.5, 0, 0, 0, 0};
  const double t_fold = std::sqrt(2.0 / 3.0);
  EXPECT_NEAR(MonotonicLimit(fish), t_fold, 1e-9);
  const double t_peak = t_fold * (1.0 - 0.5 * t_fold * t_fold);
  EXPECT_FALSE(UndistortPixel(fish, 320.0, 240.0 + 100.0 * (t_peak + 1e-6)).has_value());
  const auto ray = UndistortPixel(fish, 320.0, 240.0 + 100.0 * (t_peak - 1e-3));
  ASSERT_TRUE(ray.has_value());
  EXPECT_LT(std::atan(ray->norm()), t_fold);

  // Without distortion a fisheye reaches at most 90 degrees: theta_d >= pi/2 has no ray.
  fish.coeffs = {0, 0, 0, 0, 0};
  EXPECT_NEAR(MonotonicLimit(fish), M_PI / 2, 1e-15);
  EXPECT_FALSE(UndistortPixel(fish, 320.0 + 100.0 * (M_PI / 2 + 1e-9), 240.0).has_value());
  const auto wide = UndistortPixel(fish, 320.0 + 100.0 * 1.5, 240.0);
  ASSERT_TRUE(wide.has_value());
  EXPECT_NEAR(wide->x(), std::tan(1.5), 1e-9);
}

TEST(Lens, PointsAtOrBehindTheCameraDoNotProject) {
  for (const LensCamera& lens : {DslrFisheye(), PhoneOpenCv()}) {
    EXPECT_FALSE(DistortPoint(lens, {0.1, 0.2, 0.0}).has_value());
    EXPECT_FALSE(DistortPoint(lens, {0.1, 0.2, -1.0}).has_value());
    EXPECT_FALSE(DistortPoint(lens, {0.1, std::nan(""), 1.0}).has_value());
  }
}

TEST(Lens, CheckNamesWhatIsWrong) {
  std::string error;
  LensCamera lens = DslrFisheye();
  EXPECT_TRUE(lens.Check(&error));
  lens.coeffs[4] = 0.1;
  EXPECT_FALSE(lens.Check(&error));
  EXPECT_NE(error.find("4 coefficients"), std::string::npos) << error;
  lens = DslrFisheye();
  lens.coeffs[1] = std::nan("");
  EXPECT_FALSE(lens.Check(&error));
  EXPECT_NE(error.find("finite"), std::string::npos) << error;
  lens = DslrFisheye();
  lens.pinhole.fx = -1;
  EXPECT_FALSE(lens.Check(&error));
  EXPECT_NE(error.find("focal"), std::string::npos) << error;
  lens = DslrFisheye();
  lens.model = LensModel::kPinhole;
  EXPECT_FALSE(lens.Check(&error));
  EXPECT_NE(error.find("pinhole"), std::string::npos) << error;
}

}  // namespace
}  // namespace gt

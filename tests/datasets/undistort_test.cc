// Undistortion into ScanNet++'s pinhole camera: the new-K rules (datasets/undistorted_camera.h),
// the remap maps against OpenCV's initUndistortRectifyMap, images of an analytic scene
// undistorted and compared with the pinhole camera's view, and masks.
#include "libgt/io/undistort.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>

#include "libgt/core/error.h"
#include "libgt/core/lens.h"
#include "libgt/datasets/colmap.h"
#include "libgt/datasets/undistorted_camera.h"

namespace gt {
namespace {

LensCamera DslrFisheye() {
  LensCamera lens;
  lens.pinhole = {876, 584, 395.6, 395.4, 437.1, 291.8};
  lens.model = LensModel::kOpenCvFisheye;
  lens.coeffs = {-0.0297, -0.0049, 0.0011, -0.0004, 0.0};
  return lens;
}
LensCamera PhoneOpenCv() {
  LensCamera lens;
  lens.pinhole = {480, 360, 361.3, 361.2, 239.8, 179.5};
  lens.model = LensModel::kOpenCv;
  lens.coeffs = {0.071, -0.171, 0.0012, -0.0007, 0.0};
  return lens;
}

TEST(ScanNetPPUndistortedCamera, FisheyeRule) {
  const LensCamera lens = DslrFisheye();
  const Camera c = datasets::ScanNetPPUndistortedCamera(lens, "cameras.txt", 1);
  EXPECT_EQ(c.width, 876);
  EXPECT_EQ(c.height, 584);
  EXPECT_EQ(c.cx, 438.0);  // w/2 in OpenCV's convention
  EXPECT_EQ(c.cy, 292.0);
  // balance 0: the undistorted image sees only rays of the distorted image (no border to
  // fill), up to OpenCV's own approximations of the field of view (a pixel).
  const io::UndistortMaps& maps = io::GetUndistortMaps(lens, c);
  double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
  for (int v = 0; v < c.height; ++v) {
    for (int u = 0; u < c.width; ++u) {
      min_x = std::min<double>(min_x, maps.map_x(v, u));
      max_x = std::max<double>(max_x, maps.map_x(v, u));
      min_y = std::min<double>(min_y, maps.map_y(v, u));
      max_y = std::max<double>(max_y, maps.map_y(v, u));
    }
  }
  EXPECT_GE(min_x, -1.5);
  EXPECT_GE(min_y, -1.5);
  EXPECT_LE(max_x, lens.pinhole.width + 0.5);
  EXPECT_LE(max_y, lens.pinhole.height + 0.5);
  // ...and not much less: the undistorted image is about as wide as the distorted one's centre
  // row, which a smaller focal length would not be.
  EXPECT_LE(std::min(min_x, min_y), 40.0);
}

TEST(ScanNetPPUndistortedCamera, OpenCvRuleCentresThePrincipalPoint) {
  const Camera c = datasets::ScanNetPPUndistortedCamera(PhoneOpenCv(), "cameras.txt", 1);
  EXPECT_DOUBLE_EQ(c.cx, (480 - 1) / 2.0);
  EXPECT_DOUBLE_EQ(c.cy, (360 - 1) / 2.0);
  EXPECT_GT(c.fx, 0.0);
  // alpha = 1: every pixel of the distorted image is kept: its corners land inside the new
  // image (up to OpenCV's sampled approximation of the outline, a pixel).
  const LensCamera lens = PhoneOpenCv();
  for (const auto& px : {Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(479.5, -0.5),
                         Eigen::Vector2d(-0.5, 359.5), Eigen::Vector2d(479.5, 359.5)}) {
    const auto ab = UndistortPixel(lens, px.x(), px.y());
    ASSERT_TRUE(ab.has_value());
    const auto in_new = c.ImgFromCam({ab->x(), ab->y(), 1.0});
    ASSERT_TRUE(in_new.has_value());
    EXPECT_GE(in_new->x(), -1.5) << px.transpose();
    EXPECT_LE(in_new->x(), 480.5) << px.transpose();
    EXPECT_GE(in_new->y(), -1.5) << px.transpose();
    EXPECT_LE(in_new->y(), 360.5) << px.transpose();
  }
}

TEST(UndistortMaps, EqualOpenCvsMaps) {
  for (const LensCamera& lens : {DslrFisheye(), PhoneOpenCv()}) {
    const Camera c = datasets::ScanNetPPUndistortedCamera(lens, "cameras.txt", 1);
    const cv::Matx33d K(lens.pinhole.fx, 0, lens.pinhole.cx, 0, lens.pinhole.fy, lens.pinhole.cy, 0,
                        0, 1);
    const cv::Matx33d new_k(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    cv::Mat cv_x, cv_y;
    if (lens.model == LensModel::kOpenCvFisheye) {
      cv::fisheye::initUndistortRectifyMap(
          K, cv::Vec4d(lens.coeffs[0], lens.coeffs[1], lens.coeffs[2], lens.coeffs[3]),
          cv::Matx33d::eye(), new_k, cv::Size(c.width, c.height), CV_32FC1, cv_x, cv_y);
    } else {
      const std::vector<double> d(lens.coeffs.begin(), lens.coeffs.end());
      cv::initUndistortRectifyMap(K, d, cv::Matx33d::eye(), new_k, cv::Size(c.width, c.height),
                                  CV_32FC1, cv_x, cv_y);
    }
    const io::UndistortMaps& maps = io::GetUndistortMaps(lens, c);
    double worst = 0;
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        worst = std::max<double>(worst, std::abs(maps.map_x(v, u) - cv_x.at<float>(v, u)));
        worst = std::max<double>(worst, std::abs(maps.map_y(v, u) - cv_y.at<float>(v, u)));
      }
    }
    EXPECT_LE(worst, 2e-3) << LensModelName(lens.model);
  }
}

// A smooth colour of the ray direction: what any camera sees of a far textured sphere.
cv::Vec3b RayColor(double a, double b) {
  const double n = std::sqrt(a * a + b * b + 1.0);
  auto ch = [](double x) { return cv::saturate_cast<uint8_t>(127.5 + 120.0 * x); };
  return {ch(std::sin(4.0 * a / n)), ch(std::cos(3.0 * b / n)), ch(std::sin(2.0 * (a + b) / n))};
}

TEST(UndistortImage, ReproducesThePinholeView) {
  for (const LensCamera& lens : {DslrFisheye(), PhoneOpenCv()}) {
    // The distorted image, rendered through the lens's exact rays.
    cv::Mat3b distorted(lens.pinhole.height, lens.pinhole.width);
    for (int v = 0; v < distorted.rows; ++v) {
      for (int u = 0; u < distorted.cols; ++u) {
        const auto ab = UndistortPixel(lens, u, v);
        ASSERT_TRUE(ab.has_value());
        distorted(v, u) = RayColor(ab->x(), ab->y());
      }
    }
    const Camera c = datasets::ScanNetPPUndistortedCamera(lens, "cameras.txt", 1);
    const cv::Mat3b out = io::UndistortImage(distorted, lens, c);
    ASSERT_EQ(out.cols, c.width);
    ASSERT_EQ(out.rows, c.height);
    // Pixels that see the distorted image (alpha = 1 keeps all of it, so the OPENCV camera's
    // corners see beyond it: BORDER_REFLECT_101 fills those, as the toolkit does).
    const io::UndistortMaps& maps = io::GetUndistortMaps(lens, c);
    std::vector<std::pair<int, int>> inside;
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        if (maps.map_x(v, u) >= 0 && maps.map_y(v, u) >= 0 &&
            maps.map_x(v, u) <= lens.pinhole.width - 1 &&
            maps.map_y(v, u) <= lens.pinhole.height - 1) {
          inside.emplace_back(u, v);
        }
      }
    }
    EXPECT_GT(inside.size(), size_t(c.width * c.height) * 8 / 10);
    double sum = 0;
    int n = 0, far = 0;
    for (const auto& [u, v] : inside) {
      {
        const cv::Vec3b want = RayColor((u - c.cx) / c.fx, (v - c.cy) / c.fy);
        for (int k = 0; k < 3; ++k) {
          const int d = std::abs(int(out(v, u)[k]) - int(want[k]));
          sum += d;
          far += d > 4;
          ++n;
        }
      }
    }
    EXPECT_LT(sum / n, 0.6) << LensModelName(lens.model);
    EXPECT_LT(double(far) / n, 0.002) << LensModelName(lens.model);
  }
}

TEST(UndistortMask, AnonymisedPixelsGrowAndTheBorderIsValid) {
  const LensCamera lens = DslrFisheye();
  const Camera c = datasets::ScanNetPPUndistortedCamera(lens, "cameras.txt", 1);
  cv::Mat1b mask(lens.pinhole.height, lens.pinhole.width, uint8_t(255));
  mask(cv::Rect(400, 250, 60, 40)).setTo(0);  // an anonymised box around the centre
  const cv::Mat1b out = io::UndistortMask(mask, lens, c);
  int zeros = 0;
  for (int v = 0; v < out.rows; ++v) {
    for (int u = 0; u < out.cols; ++u) {
      ASSERT_TRUE(out(v, u) == 0 || out(v, u) == 255);
      const auto px = DistortPoint(lens, {(u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0});
      const bool inside_box = px->x() >= 400 && px->x() <= 459 && px->y() >= 250 && px->y() <= 289;
      if (inside_box) {
        ASSERT_EQ(out(v, u), 0) << u << "," << v;
      }
      const bool clear = px->x() < 398 || px->x() > 461 || px->y() < 248 || px->y() > 291;
      if (clear) {
        ASSERT_EQ(out(v, u), 255) << u << "," << v;
      }
      zeros += out(v, u) == 0;
    }
  }
  EXPECT_GT(zeros, 60 * 40 / 2);
  // An image of the wrong size is refused.
  EXPECT_THROW(io::UndistortMask(cv::Mat1b(10, 10, uint8_t(255)), lens, c), InputError);
}

TEST(ColmapLensCamera, ConvertsModelsAndRefusesBadOnes) {
  datasets::ColmapCamera cam;
  cam.id = 1;
  cam.model = "OPENCV_FISHEYE";
  cam.width = 1752;
  cam.height = 1168;
  cam.params = {791.3, 790.8, 874.7, 584.1, -0.0297, -0.0049, 0.0011, -0.0004};
  const LensCamera lens = datasets::ColmapLensCamera(cam, "cameras.txt");
  EXPECT_EQ(lens.model, LensModel::kOpenCvFisheye);
  EXPECT_DOUBLE_EQ(lens.pinhole.cx, 874.2);  // COLMAP's +0.5 convention removed
  EXPECT_DOUBLE_EQ(lens.pinhole.cy, 583.6);
  EXPECT_DOUBLE_EQ(lens.coeffs[3], -0.0004);
  EXPECT_EQ(lens.coeffs[4], 0.0);
  cam.model = "OPENCV";
  EXPECT_EQ(datasets::ColmapLensCamera(cam, "cameras.txt").model, LensModel::kOpenCv);
  auto message = [&](const datasets::ColmapCamera& c) {
    try {
      datasets::ColmapLensCamera(c, "x/cameras.txt");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  datasets::ColmapCamera bad = cam;
  bad.model = "FOV";
  bad.params = {1, 2, 3, 4, 5};
  EXPECT_NE(message(bad).find("x/cameras.txt: camera 1: model FOV is not supported"),
            std::string::npos)
      << message(bad);
  bad = cam;
  bad.params[0] = -3;
  EXPECT_NE(message(bad).find("focal"), std::string::npos) << message(bad);
  bad = cam;
  bad.params.pop_back();
  EXPECT_NE(message(bad).find("8 parameters, got 7"), std::string::npos) << message(bad);
}

// Fisheye lenses that pass LensCamera::Check (the principal point has a ray) but whose
// strong negative k1 turns back inside the image: OpenCV's new K is then degenerate (for
// the DSLR's K, fx 0.87 px whatever k1 <= -0.3; for another K, NaN). One InputError naming
// the file and the camera, never such a camera; the real lens and a mild k1 still pass.
TEST(ScanNetPPUndistortedCamera, DegenerateNewCameraIsAnInputError) {
  for (const double k1 : {-0.3, -1.0}) {
    for (const double fx : {395.6, 600.0}) {
      LensCamera lens = DslrFisheye();
      lens.pinhole.fx = lens.pinhole.fy = fx;
      lens.coeffs = {k1, 0.0, 0.0, 0.0, 0.0};
      std::string error;
      ASSERT_TRUE(lens.Check(&error)) << error;
      try {
        const Camera c = datasets::ScanNetPPUndistortedCamera(lens, "x/cameras.txt", 7);
        ADD_FAILURE() << "k1 " << k1 << ", fx " << fx << ": expected an InputError, got fx "
                      << c.fx;
      } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.where(), "x/cameras.txt");
        EXPECT_NE(what.find("camera 7 (opencv_fisheye): no undistorted pinhole camera"),
                  std::string::npos)
            << what;
      }
    }
  }
  for (const double k1 : {-0.1, 0.3}) {
    LensCamera lens = DslrFisheye();
    lens.coeffs = {k1, 0.0, 0.0, 0.0, 0.0};
    const Camera c = datasets::ScanNetPPUndistortedCamera(lens, "x/cameras.txt", 7);
    EXPECT_GT(c.fx, 100.0) << k1;
  }
}

}  // namespace
}  // namespace gt

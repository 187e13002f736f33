// Cameras with lens distortion: pinhole, OpenCV (k1 k2 p1 p2 [k3]) and OpenCV fisheye (k1-k4).
//
// Pixel convention: OpenCV's, as core/camera.h (the first pixel's centre is (0, 0)). COLMAP's
// principal point puts the first pixel's centre at (0.5, 0.5); readers convert it
// (cx_opencv = cx_colmap - 0.5).
//
// With (a, b) = (x/z, y/z) the normalised coordinates of a point in camera coordinates:
//   kOpenCv:        r2 = a^2 + b^2, radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3,
//                   a' = a radial + 2 p1 a b + p2 (r2 + 2 a^2), b' = b radial + p1 (r2 + 2 b^2) + 2
//                   p2 a b
//   kOpenCvFisheye: r = |(a, b)|, theta = atan(r),
//                   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
//                   (a', b') = (theta_d / r) (a, b)
//   pixel = (fx a' + cx, fy b' + cy)
// which is what cv::projectPoints and cv::fisheye::projectPoints compute (no skew).
//
// UndistortPixel is the exact inverse, solved to convergence inside the model's monotonic
// range: for kOpenCv the radius where d/dr [r radial(r)] first vanishes (and a positive
// Jacobian at the solution), for kOpenCvFisheye the angle where d theta_d / d theta first
// vanishes (and below 90 degrees). Outside it the model folds over and a pixel has no single
// ray: nullopt.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

#include "libgt/core/camera.h"

namespace gt {

enum class LensModel { kPinhole, kOpenCv, kOpenCvFisheye };

// "pinhole", "opencv", "opencv_fisheye".
const char* LensModelName(LensModel model);

// A camera with lens distortion, in OpenCV's pixel convention (the first pixel's centre is
// (0, 0), as core/camera.h; COLMAP's cx, cy are converted by the reader: cx_opencv = cx_colmap -
// 0.5).
struct LensCamera {
  Camera pinhole;  // fx, fy, cx, cy and the size of the distorted image
  LensModel model = LensModel::kPinhole;
  std::array<double, 5>
      coeffs{};  // kOpenCv: k1 k2 p1 p2 k3; kOpenCvFisheye: k1 k2 k3 k4 (coeffs[4] = 0)

  // The pinhole camera is valid (Camera::Check), the coefficients finite, kPinhole has no
  // coefficients and kOpenCvFisheye has coeffs[4] = 0, and the principal point has a ray.
  bool Check(std::string* error) const;
};

// The normalised direction (x/z, y/z) of the ray through pixel (u, v): the exact inverse of
// the model's distortion (iterated to convergence, not OpenCV's fixed 5/10 iterations);
// nullopt where it has none (outside the model's monotonic range).
std::optional<Eigen::Vector2d> UndistortPixel(const LensCamera& lens, double u, double v);
// The pixel where a point in camera coordinates appears (distortion applied); nullopt when z <= 0.
std::optional<Eigen::Vector2d> DistortPoint(const LensCamera& lens,
                                            const Eigen::Vector3d& p_in_cam);

// The distorted normalised coordinates (a', b') of normalised coordinates (a, b) (above).
Eigen::Vector2d DistortNormalized(const LensCamera& lens, const Eigen::Vector2d& ab);
// The limit of the model's monotonic range: for kOpenCv the largest radius r = |(a, b)| (of
// the radial part), for kOpenCvFisheye the largest angle theta (radians, < pi/2); infinity
// for kPinhole (and for kOpenCv when the radial factor never turns).
double MonotonicLimit(const LensCamera& lens);

}  // namespace gt

#include "libgt/core/camera.h"

#include <cmath>
#include <sstream>

namespace gt {

Camera Camera::FromK(const Eigen::Matrix3d& K, int width, int height) {
  Camera c;
  c.width = width;
  c.height = height;
  c.fx = K(0, 0);
  c.fy = K(1, 1);
  c.cx = K(0, 2);
  c.cy = K(1, 2);
  return c;
}

bool Camera::IsPinholeMatrix(const Eigen::Matrix3d& K) {
  return K.allFinite() && K(0, 1) == 0 && K(1, 0) == 0 && K(2, 0) == 0 && K(2, 1) == 0 &&
         K(2, 2) == 1;
}

Eigen::Matrix3d Camera::K() const {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = fx;
  K(1, 1) = fy;
  K(0, 2) = cx;
  K(1, 2) = cy;
  return K;
}

bool Camera::Check(std::string* error) const {
  std::ostringstream msg;
  if (width <= 0 || height <= 0) {
    msg << "image size must be positive, got " << width << "x" << height;
  } else if (!std::isfinite(fx) || !std::isfinite(fy) || !std::isfinite(cx) || !std::isfinite(cy)) {
    msg << "K must be finite, got fx=" << fx << " fy=" << fy << " cx=" << cx << " cy=" << cy;
  } else if (fx <= 0 || fy <= 0) {
    msg << "focal lengths must be > 0, got fx=" << fx << " fy=" << fy;
  } else {
    return true;
  }
  if (error) *error = msg.str();
  return false;
}

std::optional<Eigen::Vector2d> Camera::ImgFromCam(const Eigen::Vector3d& p_in_cam,
                                                  double min_z_m) const {
  const double z = p_in_cam.z();
  if (!(z > min_z_m)) return std::nullopt;  // also rejects NaN
  return Eigen::Vector2d(fx * p_in_cam.x() / z + cx, fy * p_in_cam.y() / z + cy);
}

Eigen::Vector3d Camera::CamFromImg(double u, double v, double depth_m) const {
  return Eigen::Vector3d((u - cx) / fx * depth_m, (v - cy) / fy * depth_m, depth_m);
}

bool Camera::InPixelArea(double x, double y) const {
  return x >= -0.5 && x < width - 0.5 && y >= -0.5 && y < height - 0.5;
}

Camera Camera::Resized(int new_width, int new_height) const {
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  Camera c;
  c.width = new_width;
  c.height = new_height;
  c.fx = sx * fx;
  c.fy = sy * fy;
  c.cx = sx * (cx + 0.5) - 0.5;
  c.cy = sy * (cy + 0.5) - 0.5;
  return c;
}

Camera Camera::HalfGrid() const {
  Camera c = *this;
  c.width = width / 2;
  c.height = height / 2;
  c.fx = 0.5 * fx;
  c.fy = 0.5 * fy;
  c.cx = 0.5 * cx;
  c.cy = 0.5 * cy;
  return c;
}

}  // namespace gt

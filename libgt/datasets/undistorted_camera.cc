#include "libgt/datasets/undistorted_camera.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "libgt/core/error.h"

namespace gt::datasets {

Camera ScanNetPPUndistortedCamera(const LensCamera& lens, const std::string& cameras_path,
                                  int64_t camera_id) {
  const Camera& c = lens.pinhole;
  if (lens.model == LensModel::kPinhole) return c;
  const auto fail = [&](const std::string& why) {
    return InputError(cameras_path, "camera " + std::to_string(camera_id) + " (" +
                                        LensModelName(lens.model) +
                                        "): no undistorted pinhole camera: " + why);
  };
  const cv::Matx33d K(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Size size(c.width, c.height);
  cv::Matx33d new_k;
  Camera out = c;
  try {
    if (lens.model == LensModel::kOpenCvFisheye) {
      const cv::Vec4d d(lens.coeffs[0], lens.coeffs[1], lens.coeffs[2], lens.coeffs[3]);
      cv::fisheye::estimateNewCameraMatrixForUndistortRectify(K, d, size, cv::Matx33d::eye(), new_k,
                                                              /*balance=*/0.0);
      out.fx = new_k(0, 0);
      out.fy = new_k(1, 1);
      out.cx = c.width / 2.0;
      out.cy = c.height / 2.0;
    } else {
      const std::vector<double> d(lens.coeffs.begin(), lens.coeffs.end());
      const cv::Mat m = cv::getOptimalNewCameraMatrix(K, d, size, /*alpha=*/1.0, size, nullptr,
                                                      /*centerPrincipalPoint=*/true);
      out.fx = m.at<double>(0, 0);
      out.fy = m.at<double>(1, 1);
      out.cx = m.at<double>(0, 2);
      out.cy = m.at<double>(1, 2);
    }
  } catch (const cv::Exception& e) {
    throw fail(std::string("OpenCV: ") + e.what());
  }
  std::string error;
  if (!out.Check(&error)) throw fail(error);
  // Every pixel of the new camera must look along a ray the lens has (inside its monotonic
  // range; for balance 0 the new view lies inside the distorted image). OpenCV's estimate
  // degenerates for a lens outside that range at the image border (a strong negative k1):
  // a focal length under a pixel, a view of nearly 180 degrees.
  const double limit = MonotonicLimit(lens);
  for (const double u : {0.0, c.width - 1.0}) {
    for (const double v : {0.0, c.height - 1.0}) {
      const double r = std::hypot((u - out.cx) / out.fx, (v - out.cy) / out.fy);
      const double extent = lens.model == LensModel::kOpenCvFisheye ? std::atan(r) : r;
      if (!(extent <= limit)) {
        std::ostringstream msg;
        msg << "the new camera (fx " << out.fx << ", fy " << out.fy << ") sees pixel (" << u << ", "
            << v << ") along a ray outside the lens model's monotonic range ("
            << (lens.model == LensModel::kOpenCvFisheye ? "angle " : "radius ") << extent << " > "
            << limit << "): the distortion coefficients cannot describe this image";
        throw fail(msg.str());
      }
    }
  }
  return out;
}

}  // namespace gt::datasets

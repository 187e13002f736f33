#include "libgt/datasets/undistorted_camera.h"

#include <opencv2/calib3d.hpp>
#include <vector>

namespace gt::datasets {

Camera ScanNetPPUndistortedCamera(const LensCamera& lens) {
  const Camera& c = lens.pinhole;
  if (lens.model == LensModel::kPinhole) return c;
  const cv::Matx33d K(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Size size(c.width, c.height);
  cv::Matx33d new_k;
  Camera out = c;
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
  return out;
}

}  // namespace gt::datasets

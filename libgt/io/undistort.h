// Images of a distorted camera (core/lens.h) resampled into a pinhole camera: the remap maps
// and the colour and mask undistortion of ScanNet++'s toolkit (dslr/undistort.py): colour
// bilinear with BORDER_REFLECT_101, masks bilinear with a border of 255 then thresholded
// (< 255 -> 0: a pixel touched by an anonymised one is anonymised).
#pragma once

#include <opencv2/core.hpp>

#include "libgt/core/camera.h"
#include "libgt/core/lens.h"

namespace gt::io {

// For every pixel (u, v) of `undistorted`, the pixel of `lens` that sees the same ray
// (DistortPoint of the ray through (u, v)): float32 maps for cv::remap, both
// undistorted.height x undistorted.width. What cv::initUndistortRectifyMap (and its fisheye
// version) computes with R = I, in double precision. Cached per thread (the last 4 pairs);
// the reference is valid until the next call on the same thread.
struct UndistortMaps {
  cv::Mat1f map_x, map_y;
};
const UndistortMaps& GetUndistortMaps(const LensCamera& lens, const Camera& undistorted);

// image: lens.pinhole's size, CV_8UC1/3 (any channel order); the result has undistorted's size.
cv::Mat UndistortImage(const cv::Mat& image, const LensCamera& lens, const Camera& undistorted);
// mask: CV_8UC1 of lens.pinhole's size, 255 valid, anything else invalid. The result is 255
// or 0.
cv::Mat1b UndistortMask(const cv::Mat1b& mask, const LensCamera& lens, const Camera& undistorted);

}  // namespace gt::io

// The pinhole camera a distorted ScanNet++ camera is undistorted into (docs/DATASETS.md
// "ScanNet++"), by the rules of ScanNet++'s toolkit (dslr/undistort.py) and DUSt3R's
// preprocessing (datasets_preprocess/preprocess_scannetpp.py), same size as the distorted
// image:
//  - kOpenCvFisheye: fx, fy of cv::fisheye::estimateNewCameraMatrixForUndistortRectify(K, D,
//    (w, h), I, balance = 0), then the principal point put at (w/2, h/2) in OpenCV's pixel
//    convention (first pixel centre (0, 0)), as DUSt3R does after converting COLMAP's K to
//    OpenCV's. In COLMAP's convention that is ((w+1)/2, (h+1)/2); the exact image centre
//    would be ((w-1)/2, (h-1)/2): the principal point is half a pixel right of and below it.
//    (The toolkit sets w/2, h/2 on the K of nerfstudio/transforms.json, whose convention
//    it does not state.)
//  - kOpenCv: cv::getOptimalNewCameraMatrix(K, D, (w, h), alpha = 1, (w, h),
//    centerPrincipalPoint = true) (DUSt3R's rule for the iPhone's OPENCV camera).
//  - kPinhole: the camera itself.
// K is given to OpenCV in its own convention (lens.pinhole is already converted).
// Distortion coefficients that pass LensCamera::Check can still be so extreme that OpenCV
// finds no finite new focal length, throws, or returns a degenerate one (a pixel or less:
// a corner of the new camera then looks along a ray outside the lens model's monotonic
// range, MonotonicLimit). Each is an InputError naming the cameras file and the camera,
// "camera <id> (<model>): no undistorted pinhole camera: ...", never a camera whose rays the
// lens cannot have.
#pragma once

#include <cstdint>
#include <string>

#include "libgt/core/camera.h"
#include "libgt/core/lens.h"

namespace gt::datasets {

Camera ScanNetPPUndistortedCamera(const LensCamera& lens, const std::string& cameras_path,
                                  int64_t camera_id);

}  // namespace gt::datasets

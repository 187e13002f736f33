// Pictures of rendered depth for `occgt render` and `inspect pair`: depth maps as grey
// ramps (near = bright, 0 = black) and the sensor-vs-mesh classes of render/frame_depth.h
// as colours, side by side.
#pragma once

#include <opencv2/core.hpp>

#include "libgt/core/depth.h"
#include "libgt/render/frame_depth.h"

namespace gt::render {

// Grey ramp of a depth map over [0, max_depth_m]: 255 at 0 m falling to 32 at max_depth_m,
// 0 where the depth is 0 or invalid. CV_8UC3 (R = G = B).
cv::Mat DepthRamp(const DepthImage& depth, double max_depth_m);

// The class of each pixel (FrameDepth's rules) in colour, R G B: agree green, disagree red,
// mesh only blue, sensor only yellow, neither black.
cv::Mat AgreementPicture(const DepthImage& sensor, const DepthImage& mesh, double min_depth_m,
                         double max_depth_m, const FusedDepthOptions& options);

// [sensor | rendered | classes] when a sensor map is given, else the rendered ramp alone;
// CV_8UC3, R G B.
cv::Mat DepthComparisonPicture(const DepthImage* sensor, const DepthImage& mesh, double min_depth_m,
                               double max_depth_m, const FusedDepthOptions& options);

}  // namespace gt::render

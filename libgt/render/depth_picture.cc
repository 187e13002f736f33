#include "libgt/render/depth_picture.h"

#include <algorithm>
#include <cmath>

namespace gt::render {

cv::Mat DepthRamp(const DepthImage& depth, double max_depth_m) {
  cv::Mat3b out(depth.height, depth.width, cv::Vec3b(0, 0, 0));
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const float d = depth.at(u, v);
      if (!(d > 0) || !std::isfinite(d)) continue;
      const double t = std::min(1.0, d / max_depth_m);
      const auto g = static_cast<uint8_t>(std::lround(255 - 223 * t));
      out(v, u) = cv::Vec3b(g, g, g);
    }
  }
  return out;
}

cv::Mat AgreementPicture(const DepthImage& sensor, const DepthImage& mesh, double min_depth_m,
                         double max_depth_m, const FusedDepthOptions& options) {
  cv::Mat3b out(mesh.height, mesh.width, cv::Vec3b(0, 0, 0));
  for (int v = 0; v < mesh.height; ++v) {
    for (int u = 0; u < mesh.width; ++u) {
      DepthImage s(1, 1, sensor.at(u, v)), m(1, 1, mesh.at(u, v));
      const DepthAgreement a = CompareSensorAndMesh(s, m, min_depth_m, max_depth_m, options);
      cv::Vec3b c(0, 0, 0);
      if (a.agree) c = cv::Vec3b(40, 200, 60);
      if (a.disagree) c = cv::Vec3b(230, 40, 40);
      if (a.mesh_only) c = cv::Vec3b(50, 110, 240);
      if (a.sensor_only) c = cv::Vec3b(230, 210, 40);
      out(v, u) = c;
    }
  }
  return out;
}

cv::Mat DepthComparisonPicture(const DepthImage* sensor, const DepthImage& mesh, double min_depth_m,
                               double max_depth_m, const FusedDepthOptions& options) {
  double top = 0;
  for (float d : mesh.values_m) top = std::max<double>(top, std::isfinite(d) ? d : 0);
  if (top <= 0) top = 1;
  const cv::Mat rendered = DepthRamp(mesh, top);
  if (!sensor) return rendered;
  cv::Mat out;
  cv::hconcat(
      std::vector<cv::Mat>{DepthRamp(*sensor, top), rendered,
                           AgreementPicture(*sensor, mesh, min_depth_m, max_depth_m, options)},
      out);
  return out;
}

}  // namespace gt::render

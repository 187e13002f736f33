#include "libgt/io/undistort.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "libgt/core/error.h"

namespace gt::io {
namespace {

bool SameCamera(const Camera& a, const Camera& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
         a.cx == b.cx && a.cy == b.cy;
}

void CheckSize(const cv::Mat& image, const LensCamera& lens, const char* what) {
  if (image.cols != lens.pinhole.width || image.rows != lens.pinhole.height) {
    throw InputError(what, "image is " + std::to_string(image.cols) + "x" +
                               std::to_string(image.rows) + ", its camera is " +
                               std::to_string(lens.pinhole.width) + "x" +
                               std::to_string(lens.pinhole.height));
  }
}

}  // namespace

const UndistortMaps& GetUndistortMaps(const LensCamera& lens, const Camera& undistorted) {
  // A few entries per thread: a frame's colour, mask and depth maps alternate.
  struct Entry {
    LensCamera lens;
    Camera camera;
    UndistortMaps maps;
  };
  constexpr size_t kEntries = 4;
  thread_local std::vector<Entry> cache;  // most recently used last
  for (size_t i = 0; i < cache.size(); ++i) {
    const Entry& e = cache[i];
    if (SameCamera(e.lens.pinhole, lens.pinhole) && e.lens.model == lens.model &&
        e.lens.coeffs == lens.coeffs && SameCamera(e.camera, undistorted)) {
      std::rotate(cache.begin() + static_cast<long>(i), cache.begin() + static_cast<long>(i) + 1,
                  cache.end());
      return cache.back().maps;
    }
  }
  if (cache.size() == kEntries) cache.erase(cache.begin());
  Entry e{lens, undistorted, {}};
  e.maps.map_x.create(undistorted.height, undistorted.width);
  e.maps.map_y.create(undistorted.height, undistorted.width);
  for (int v = 0; v < undistorted.height; ++v) {
    float* mx = e.maps.map_x.ptr<float>(v);
    float* my = e.maps.map_y.ptr<float>(v);
    const double b = (v - undistorted.cy) / undistorted.fy;
    for (int u = 0; u < undistorted.width; ++u) {
      const double a = (u - undistorted.cx) / undistorted.fx;
      const Eigen::Vector2d px = DistortNormalized(lens, Eigen::Vector2d(a, b));
      mx[u] = static_cast<float>(lens.pinhole.fx * px.x() + lens.pinhole.cx);
      my[u] = static_cast<float>(lens.pinhole.fy * px.y() + lens.pinhole.cy);
    }
  }
  cache.push_back(std::move(e));
  return cache.back().maps;
}

cv::Mat UndistortImage(const cv::Mat& image, const LensCamera& lens, const Camera& undistorted) {
  CheckSize(image, lens, "undistort image");
  const UndistortMaps& maps = GetUndistortMaps(lens, undistorted);
  cv::Mat out;
  cv::remap(image, out, maps.map_x, maps.map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  return out;
}

cv::Mat1b UndistortMask(const cv::Mat1b& mask, const LensCamera& lens, const Camera& undistorted) {
  CheckSize(mask, lens, "undistort mask");
  const UndistortMaps& maps = GetUndistortMaps(lens, undistorted);
  cv::Mat1b out;
  cv::remap(mask, out, maps.map_x, maps.map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(255));
  for (int v = 0; v < out.rows; ++v) {
    uint8_t* row = out.ptr<uint8_t>(v);
    for (int u = 0; u < out.cols; ++u) row[u] = row[u] == 255 ? 255 : 0;
  }
  return out;
}

}  // namespace gt::io

#include "libgt/io/image.h"

#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"

namespace gt::io {
namespace {

ColorImage FromRgbMat(const cv::Mat& rgb) {
  ColorImage out;
  out.width = rgb.cols;
  out.height = rgb.rows;
  out.rgb.resize(static_cast<size_t>(rgb.cols) * rgb.rows * 3);
  for (int v = 0; v < rgb.rows; ++v) {
    std::memcpy(&out.rgb[static_cast<size_t>(v) * rgb.cols * 3], rgb.ptr<uint8_t>(v),
                static_cast<size_t>(rgb.cols) * 3);
  }
  return out;
}

}  // namespace

ColorImage ReadColor(const std::string& path) {
  if (!FileExists(path)) throw InputError(path, "cannot open file (missing or unreadable)");
  const std::string bytes = ReadFileBytes(path);
  cv::Mat m = DecodeImageBytes(bytes, ChannelOrder::kRgb, path);
  if (m.depth() == CV_16U) {
    m.convertTo(m, CV_8U, 1.0 / 257.0);
  } else if (m.depth() != CV_8U) {
    throw InputError(path, "expected an 8- or 16-bit image");
  }
  cv::Mat rgb;
  switch (m.channels()) {
    case 1:
      cv::cvtColor(m, rgb, cv::COLOR_GRAY2RGB);
      break;
    case 3:
      rgb = m;
      break;
    case 4:
      cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB);
      break;
    default:
      throw InputError(path, "expected 1, 3 or 4 channels, got " + std::to_string(m.channels()));
  }
  return FromRgbMat(rgb);
}

ColorImage ResizeColorBilinear(const ColorImage& image, int new_width, int new_height) {
  if (new_width <= 0 || new_height <= 0 || image.empty()) {
    throw InputError("resize", "expected a non-empty image and a positive target size");
  }
  if (new_width == image.width && new_height == image.height) return image;
  const cv::Mat src(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.rgb.data()));
  cv::Mat dst;
  cv::resize(src, dst, cv::Size(new_width, new_height), 0, 0, cv::INTER_LINEAR);
  return FromRgbMat(dst);
}

ColorImage ReadColorResized(const std::string& path, const Camera& camera, int new_width,
                            int new_height, Camera* resized_camera) {
  if (camera.width > 0 && FileExists(path)) {  // header size first: no decode of a wrong file
    const ImageSize header = ReadImageSize(path);
    if (header.width != camera.width || header.height != camera.height) {
      std::ostringstream s;
      s << "colour image is " << header.width << "x" << header.height << ", expected "
        << camera.width << "x" << camera.height;
      throw InputError(path, s.str());
    }
  }
  ColorImage image = ReadColor(path);
  if (camera.width > 0 && (image.width != camera.width || image.height != camera.height)) {
    std::ostringstream s;
    s << "colour image is " << image.width << "x" << image.height << ", expected " << camera.width
      << "x" << camera.height;
    throw InputError(path, s.str());
  }
  if (resized_camera) {
    Camera c = camera;
    if (c.width == 0) {
      c.width = image.width;
      c.height = image.height;
    }
    *resized_camera = c.Resized(new_width, new_height);
  }
  return ResizeColorBilinear(image, new_width, new_height);
}

}  // namespace gt::io

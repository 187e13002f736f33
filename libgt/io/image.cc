#include "libgt/io/image.h"

#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/undistort.h"

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

ColorImage DecodeColor(std::string_view bytes, const std::string& path) {
  ColorImage direct;  // JPEG colour (ScanNet's .sens and exports): no intermediate cv::Mat
  if (DecodeJpegRgbInto(bytes, path, &direct.rgb, &direct.width, &direct.height)) return direct;
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

std::string SizeMismatch(int width, int height, const Camera& camera) {
  std::ostringstream s;
  s << "colour image is " << width << "x" << height << ", expected " << camera.width << "x"
    << camera.height;
  return s.str();
}

// The decoded image checked against the frame's colour camera (when known), the camera
// resized with it, and the image resized bilinearly.
ColorImage CheckedResize(const ColorImage& image, const std::string& where, const Camera& camera,
                         int new_width, int new_height, Camera* resized_camera) {
  if (camera.width > 0 && (image.width != camera.width || image.height != camera.height)) {
    throw InputError(where, SizeMismatch(image.width, image.height, camera));
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

}  // namespace

ColorImage ReadColor(const std::string& path) {
  if (!FileExists(path)) throw InputError(path, "cannot open file (missing or unreadable)");
  return DecodeColor(ReadFileBytes(path), path);
}

ColorImage ReadFrameColor(const Frame& frame) {
  if (frame.color_lens) {
    // A distorted image: undistorted into the frame's pinhole colour camera.
    const ColorImage distorted = ReadColor(frame.color_path);
    const LensCamera& lens = *frame.color_lens;
    if (distorted.width != lens.pinhole.width || distorted.height != lens.pinhole.height) {
      throw InputError(frame.color_path,
                       SizeMismatch(distorted.width, distorted.height, lens.pinhole));
    }
    const cv::Mat src(distorted.height, distorted.width, CV_8UC3,
                      const_cast<uint8_t*>(distorted.rgb.data()));
    return FromRgbMat(UndistortImage(src, lens, frame.color_camera));
  }
  if (frame.color_range.size == 0) return ReadColor(frame.color_path);
  const int64_t index = frame.depth.frame_index;  // the frame's index in its container
  const std::string where =
      (index >= 0 ? ContainerFrameWhere(frame.color_path, index) : frame.color_path) +
      " (colour payload at byte " + std::to_string(frame.color_range.offset) + ")";
  const Camera& camera = frame.color_camera;
  if (frame.color_raw_rgb) {
    const uint64_t expected = uint64_t(camera.width) * uint64_t(camera.height) * 3;
    if (camera.width <= 0 || camera.height <= 0 || frame.color_range.size != expected) {
      throw InputError(where, "raw RGB colour: expected " + std::to_string(expected) + " bytes (" +
                                  std::to_string(camera.width) + "x" +
                                  std::to_string(camera.height) + "x3), got " +
                                  std::to_string(frame.color_range.size));
    }
  }
  const std::string bytes = ReadFileRange(frame.color_path, frame.color_range.offset,
                                          frame.color_range.size, "colour payload");
  if (frame.color_raw_rgb) {
    ColorImage out;
    out.width = camera.width;
    out.height = camera.height;
    out.rgb.assign(bytes.begin(), bytes.end());
    return out;
  }
  if (camera.width > 0) {  // header size first: no decode of a wrong payload
    const ImageSize header = DecodeImageSize(bytes, where);
    if (header.width != camera.width || header.height != camera.height) {
      throw InputError(where, SizeMismatch(header.width, header.height, camera));
    }
  }
  return DecodeColor(bytes, where);
}

void CheckFrameColorHeader(const Frame& frame) {
  if (frame.color_path.empty() || frame.color_range.size != 0) return;
  const ImageSize header = ReadImageSize(frame.color_path);
  // Behind a lens the file is the distorted image, of the lens's size.
  const Camera& camera = frame.color_lens ? frame.color_lens->pinhole : frame.color_camera;
  if (camera.width > 0 && (header.width != camera.width || header.height != camera.height)) {
    throw InputError(frame.color_path, SizeMismatch(header.width, header.height, camera));
  }
}

ColorImage ReadFrameColorResized(const Frame& frame, int new_width, int new_height,
                                 Camera* resized_camera) {
  if (frame.color_range.size == 0 && !frame.color_lens) {
    return ReadColorResized(frame.color_path, frame.color_camera, new_width, new_height,
                            resized_camera);
  }
  return CheckedResize(ReadFrameColor(frame), frame.color_path, frame.color_camera, new_width,
                       new_height, resized_camera);
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
      throw InputError(path, SizeMismatch(header.width, header.height, camera));
    }
  }
  return CheckedResize(ReadColor(path), path, camera, new_width, new_height, resized_camera);
}

}  // namespace gt::io

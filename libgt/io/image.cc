#include "libgt/io/image.h"

#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/files.h"

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

uint32_t BigEndian32At(std::string_view b, size_t i) {
  return (static_cast<uint32_t>(static_cast<unsigned char>(b[i])) << 24) |
         (static_cast<uint32_t>(static_cast<unsigned char>(b[i + 1])) << 16) |
         (static_cast<uint32_t>(static_cast<unsigned char>(b[i + 2])) << 8) |
         static_cast<uint32_t>(static_cast<unsigned char>(b[i + 3]));
}

}  // namespace

std::string PngDamage(std::string_view bytes) {
  static constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
  if (bytes.size() < 8 || bytes.compare(0, 8, std::string_view(kSignature, 8)) != 0) return "";
  size_t pos = 8;
  uint64_t width = 0, height = 0, bits_per_pixel = 0, idat_bytes = 0;
  while (true) {
    if (bytes.size() - pos < 12) {
      return "truncated PNG (file ends at byte " + std::to_string(bytes.size()) +
             " before the IEND chunk)";
    }
    const uint64_t length = BigEndian32At(bytes, pos);
    const std::string_view type = bytes.substr(pos + 4, 4);
    if (length > bytes.size() - pos - 12) {
      return "truncated PNG (chunk '" + std::string(type) + "' at byte " + std::to_string(pos) +
             " needs " + std::to_string(length) + " data bytes past the end of the file)";
    }
    if (type == "IHDR" && length >= 13) {
      width = BigEndian32At(bytes, pos + 8);
      height = BigEndian32At(bytes, pos + 12);
      const auto bit_depth = static_cast<unsigned char>(bytes[pos + 16]);
      const auto colour_type = static_cast<unsigned char>(bytes[pos + 17]);
      static const int kChannels[7] = {1, 0, 3, 1, 2, 0, 4};  // by PNG colour type
      bits_per_pixel = colour_type < 7 ? uint64_t{bit_depth} * kChannels[colour_type] : 0;
    } else if (type == "IDAT") {
      idat_bytes += length;
    }
    pos += 12 + length;
    if (type == "IEND") break;
  }
  // Deflate compresses at most ~1032:1, so less IDAT data than raw / 1032 cannot hold the
  // image (libpng would print "Not enough image data" after a full-size allocation).
  const uint64_t raw_bytes = height * ((width * bits_per_pixel + 7) / 8);
  if (raw_bytes / 1032 > idat_bytes + 64) {
    return "PNG image data too short (" + std::to_string(idat_bytes) + " compressed bytes for " +
           std::to_string(width) + "x" + std::to_string(height) + ")";
  }
  return "";
}

std::string JpegDamage(std::string_view bytes) {
  const auto at = [&](size_t i) { return static_cast<unsigned char>(bytes[i]); };
  if (bytes.size() < 2 || at(0) != 0xFF || at(1) != 0xD8) return "";
  const std::string truncated = "truncated JPEG (no end-of-image marker in " +
                                std::to_string(bytes.size()) + " bytes)";
  size_t pos = 2;
  while (true) {
    // A marker: 0xFF (fill bytes allowed), then its code.
    if (pos >= bytes.size() || at(pos) != 0xFF) return truncated;
    while (pos < bytes.size() && at(pos) == 0xFF) ++pos;
    if (pos >= bytes.size()) return truncated;
    const unsigned char marker = at(pos++);
    if (marker == 0xD9) return "";  // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (bytes.size() - pos < 2) return truncated;
    const size_t length = (static_cast<size_t>(at(pos)) << 8) | at(pos + 1);
    if (length < 2 || length > bytes.size() - pos) return truncated;
    pos += length;
    if (marker != 0xDA) continue;
    // Entropy-coded data after SOS: runs to the next marker other than a stuffed 0xFF00
    // or a restart marker.
    while (true) {
      if (bytes.size() - pos < 2) return truncated;
      if (at(pos) == 0xFF) {
        const unsigned char next = at(pos + 1);
        if (next != 0x00 && next != 0xFF && !(next >= 0xD0 && next <= 0xD7)) break;
        pos += next == 0xFF ? 1 : 2;
      } else {
        ++pos;
      }
    }
  }
}

ColorImage ReadColor(const std::string& path) {
  if (!FileExists(path)) throw InputError(path, "cannot open file (missing or unreadable)");
  const std::string bytes = ReadFileBytes(path);
  if (std::string e = PngDamage(bytes); !e.empty()) throw InputError(path, e);
  if (std::string e = JpegDamage(bytes); !e.empty()) throw InputError(path, e);
  cv::Mat m = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8U,
                                    const_cast<char*>(bytes.data())),
                           cv::IMREAD_UNCHANGED);
  if (m.empty()) throw InputError(path, "cannot decode image (corrupt or unsupported)");
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
      cv::cvtColor(m, rgb, cv::COLOR_BGR2RGB);
      break;
    case 4:
      cv::cvtColor(m, rgb, cv::COLOR_BGRA2RGB);
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

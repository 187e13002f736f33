#include "libgt/io/depth_io.h"

#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "libgt/core/camera.h"
#include "libgt/core/error.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/io/hdf5_depth.h"
#include "libgt/io/iphone_depth.h"
#include "libgt/io/npy.h"
#include "libgt/io/undistort.h"

namespace gt::io {
namespace {

// Depth values at or above this are background markers (Blender writes ~1e10).
constexpr float kHugeDepthM = 1e9f;

// Larger depth maps are rejected as implausible before any pixel buffer is allocated
// (a 16384 x 8192 float map is 512 MiB); each side is also at most 65536.
constexpr int64_t kMaxDepthPixels = int64_t{1} << 27;

bool PlausibleSize(int64_t width, int64_t height) {
  return width > 0 && height > 0 && width <= kMaxImageSidePx && height <= kMaxImageSidePx &&
         width * height <= kMaxDepthPixels;
}

// Refuses a size declared by a file header that differs from the expected one (when
// given), before any pixel buffer is allocated.
void CheckDeclaredSize(const std::string& path, int64_t width, int64_t height, int expected_width,
                       int expected_height) {
  if (expected_width > 0 && expected_height > 0 &&
      (width != expected_width || height != expected_height)) {
    throw InputError(path, "depth is " + std::to_string(width) + "x" + std::to_string(height) +
                               ", expected " + std::to_string(expected_width) + "x" +
                               std::to_string(expected_height));
  }
}

float Sanitize(float d) { return (std::isfinite(d) && d > 0.0f && d < kHugeDepthM) ? d : 0.0f; }
// In double before narrowing, so that values beyond float's range never reach the cast.
float Sanitize(double d) {
  return (std::isfinite(d) && d > 0.0 && d < kHugeDepthM) ? static_cast<float>(d) : 0.0f;
}

DepthImage DecodeNpyDepth(std::string_view bytes, const DepthSource& src) {
  const NpyArray a = ParseNpy(bytes, src.path);
  if (a.shape.size() != 2 && !(a.shape.size() == 3 && a.shape[2] == 1)) {
    std::ostringstream s;
    s << "expected a depth array of shape (H, W), got " << a.shape.size() << " dimensions";
    throw InputError(src.path, s.str());
  }
  if (a.fortran_order) throw InputError(src.path, "expected C order, got fortran_order");
  if (!PlausibleSize(a.shape[1], a.shape[0])) {
    throw InputError(src.path, "depth array has an empty or implausible shape");
  }
  DepthImage d(static_cast<int>(a.shape[1]), static_cast<int>(a.shape[0]));
  const size_t n = d.values_m.size();
  if (a.descr == "<f4") {
    const float* p = a.As<float>(src.path);
    for (size_t i = 0; i < n; ++i) d.values_m[i] = Sanitize(p[i]);
  } else if (a.descr == "<f8") {
    const double* p = a.As<double>(src.path);
    for (size_t i = 0; i < n; ++i) d.values_m[i] = Sanitize(p[i]);
  } else {
    throw InputError(src.path,
                     "expected float32 ('<f4') depth in metres, got dtype '" + a.descr + "'");
  }
  return d;
}

uint32_t BigEndian32(const unsigned char* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

// PNG: the IHDR chunk follows the 8-byte signature.
bool PngSize(std::string_view head, ImageSize* size) {
  static const unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (head.size() < 24 || std::memcmp(head.data(), kSig, 8) != 0) return false;
  if (head.compare(12, 4, "IHDR") != 0) return false;
  const auto* p = reinterpret_cast<const unsigned char*>(head.data());
  const uint32_t width = BigEndian32(p + 16);
  const uint32_t height = BigEndian32(p + 20);
  if (width == 0 || height == 0 || width > INT32_MAX || height > INT32_MAX) return false;
  size->width = static_cast<int>(width);
  size->height = static_cast<int>(height);
  return true;
}

// The IHDR size is compared with the expected size (when given) and checked for
// plausibility before decoding, and the chunk structure is checked, so that a small or cut
// PNG claiming 30000x30000 is one clear InputError: no gigabyte buffer and no libpng line
// of its own on stderr.
DepthImage DecodePng16Depth(std::string_view bytes, const DepthSource& src, int expected_width,
                            int expected_height) {
  if (!(src.scale_m_per_unit > 0) || !std::isfinite(src.scale_m_per_unit)) {
    throw InputError(src.path, "depth scale must be a positive number of metres per unit");
  }
  ImageSize declared;
  if (PngSize(bytes, &declared)) {
    CheckDeclaredSize(src.path, declared.width, declared.height, expected_width, expected_height);
    if (!PlausibleSize(declared.width, declared.height)) {
      throw InputError(src.path, "PNG header declares an implausible size " +
                                     std::to_string(declared.width) + "x" +
                                     std::to_string(declared.height));
    }
  }
  // Only PNG and binary/plain PGM.
  static const char kPngSig[] = "\x89PNG\r\n\x1a\n";
  const bool png = bytes.size() >= 8 && bytes.compare(0, 8, std::string_view(kPngSig, 8)) == 0;
  const bool pgm = bytes.size() >= 2 && bytes[0] == 'P' && (bytes[1] == '5' || bytes[1] == '2');
  if (!png && !pgm) throw InputError(src.path, "not a PNG or PGM file (bad signature)");
  const cv::Mat m = DecodeImageBytes(bytes, ChannelOrder::kRgb, src.path);
  if (m.type() != CV_16UC1) {
    throw InputError(src.path, "expected a 16-bit single-channel depth image, got " +
                                   std::to_string(m.channels()) + " channel(s) of " +
                                   (m.depth() == CV_8U ? "8" : "16") + " bits");
  }
  DepthImage d(m.cols, m.rows);
  for (int v = 0; v < m.rows; ++v) {
    const uint16_t* row = m.ptr<uint16_t>(v);
    for (int u = 0; u < m.cols; ++u) {
      const uint16_t raw = row[u];
      d.at(u, v) = (raw == 0 || static_cast<int>(raw) == src.invalid_value)
                       ? 0.0f
                       : Sanitize(raw * src.scale_m_per_unit);
    }
  }
  return d;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The channel for `wanted`: exact name, else the first name ending in "." + wanted; for
// wanted == "": the first channel named (or ending in ".") Z, then Y, then V, else the
// only channel. Empty result: no match.
std::string PickChannel(const std::vector<std::string>& names, const std::string& wanted) {
  auto match = [&](const std::string& w) -> std::string {
    for (const auto& n : names) {
      if (n == w) return n;
    }
    for (const auto& n : names) {
      if (EndsWith(n, "." + w)) return n;
    }
    return "";
  };
  if (!wanted.empty()) return match(wanted);
  for (const char* w : {"Z", "Y", "V"}) {
    const std::string n = match(w);
    if (!n.empty()) return n;
  }
  return names.size() == 1 ? names[0] : "";
}

// An OpenEXR input stream over bytes in memory (the library reads headers, offset tables
// and chunks through it; reading past the end throws, as Imf's own file stream does).
class MemoryIStream : public Imf::IStream {
 public:
  MemoryIStream(std::string_view bytes, const std::string& name)
      : Imf::IStream(name.c_str()), bytes_(bytes) {}
  bool read(char c[], int n) override {
    if (n < 0 || pos_ > bytes_.size() || static_cast<uint64_t>(n) > bytes_.size() - pos_) {
      throw std::runtime_error("unexpected end of file");
    }
    if (n > 0) std::memcpy(c, bytes_.data() + pos_, static_cast<size_t>(n));
    pos_ += static_cast<uint64_t>(n);
    return pos_ < bytes_.size();
  }
  uint64_t tellg() override { return pos_; }
  void seekg(uint64_t pos) override { pos_ = pos; }
  void clear() override {}

 private:
  std::string_view bytes_;
  uint64_t pos_ = 0;
};

uint32_t LittleEndian32(std::string_view b, size_t pos) {
  const auto* p = reinterpret_cast<const unsigned char*>(b.data() + pos);
  return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
}

// Walks the EXR header(s) (magic, version, then per part "name\0type\0" int32 size and
// value, ending with a 0 byte) before OpenEXR sees the bytes: every attribute must fit in
// the file and the data window must be plausible. OpenEXR allocates attribute values and
// offset tables from the sizes a header declares, so a 29-byte corrupt file made it
// allocate hundreds of MiB (found by fuzz_depth_exr). "" when fine, else the problem.
// The first part's data window size goes to *window_width/height (left alone when absent).
std::string ExrHeaderProblem(std::string_view b, int64_t* window_width, int64_t* window_height) {
  if (b.size() < 8 || LittleEndian32(b, 0) != 20000630u) return "not an OpenEXR file (bad magic)";
  const bool multipart = (LittleEndian32(b, 4) & 0x1000u) != 0;
  size_t pos = 8;
  for (int part = 0;; ++part) {
    int attributes = 0;
    while (true) {
      if (pos >= b.size()) return "file ends inside the header";
      if (b[pos] == '\0') {
        ++pos;
        break;
      }
      std::string_view name, type;
      for (std::string_view* field : {&name, &type}) {
        const size_t end = b.find('\0', pos);
        if (end == std::string_view::npos || end - pos > 255) return "malformed header attribute";
        *field = b.substr(pos, end - pos);
        pos = end + 1;
      }
      if (b.size() - pos < 4) return "file ends inside the header";
      const uint32_t size = LittleEndian32(b, pos);
      pos += 4;
      if (size > b.size() - pos) {
        return "header attribute '" + std::string(name) + "' is larger than the file";
      }
      if (name == "dataWindow" && type == "box2i" && size == 16) {
        const auto corner = [&](size_t k) {
          return static_cast<int64_t>(static_cast<int32_t>(LittleEndian32(b, pos + 4 * k)));
        };
        const int64_t width = corner(2) - corner(0) + 1, height = corner(3) - corner(1) + 1;
        if (*window_width < 0) {
          *window_width = width;
          *window_height = height;
        }
        if (!PlausibleSize(width, height)) return "data window has an empty or implausible size";
      }
      pos += size;
      ++attributes;
    }
    if (!multipart || (part > 0 && attributes == 0)) return "";
  }
}

DepthImage DecodeExrDepth(std::string_view bytes, const DepthSource& src, int expected_width,
                          int expected_height) {
  int64_t window_width = -1, window_height = -1;  // of the first part, when declared
  const std::string problem = ExrHeaderProblem(bytes, &window_width, &window_height);
  if (window_width >= 0) {
    CheckDeclaredSize(src.path, window_width, window_height, expected_width, expected_height);
  }
  if (!problem.empty()) throw InputError(src.path, "cannot read EXR: " + problem);
  try {
    MemoryIStream stream(bytes, src.path);
    Imf::InputFile file(stream);
    const Imf::Header& header = file.header();
    std::vector<std::string> names;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
      names.emplace_back(it.name());
    }
    const std::string channel = PickChannel(names, src.exr_channel);
    if (channel.empty()) {
      std::string present;
      for (const auto& n : names) present += (present.empty() ? "" : ", ") + ("'" + n + "'");
      throw InputError(
          src.path, (src.exr_channel.empty() ? std::string("no depth channel (Z, Y or V) found")
                                             : "EXR channel '" + src.exr_channel + "' not found") +
                        "; channels present: " + present);
    }
    const Imath::Box2i dw = header.dataWindow();
    // In 64 bits: the corners are arbitrary ints in a corrupt file.
    const int64_t width64 = int64_t{dw.max.x} - dw.min.x + 1;
    const int64_t height64 = int64_t{dw.max.y} - dw.min.y + 1;
    CheckDeclaredSize(src.path, width64, height64, expected_width, expected_height);
    if (!PlausibleSize(width64, height64)) {
      throw InputError(src.path, "EXR data window has an empty or implausible size");
    }
    const int width = static_cast<int>(width64);
    const int height = static_cast<int>(height64);
    // Not zero-filled: readPixels writes every pixel of the window or throws, and a
    // corrupt file that declares a big window then fails fast instead of first touching
    // up to 512 MiB (found by fuzz_depth_exr: 22 executions/s).
    const size_t npixels = static_cast<size_t>(width) * height;
    const std::unique_ptr<float[]> values(new float[npixels]);
    Imf::FrameBuffer fb;
    // Base pointer offset so that (x, y) in the data window lands at (x - min.x, y - min.y).
    char* base = reinterpret_cast<char*>(values.get()) -
                 (static_cast<ptrdiff_t>(dw.min.x) + static_cast<ptrdiff_t>(dw.min.y) * width) *
                     static_cast<ptrdiff_t>(sizeof(float));
    fb.insert(channel,
              Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * width, 1, 1, 0.0));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    DepthImage d(width, height);
    for (size_t i = 0; i < npixels; ++i) d.values_m[i] = Sanitize(values[i]);
    return d;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(src.path, std::string("cannot read EXR: ") + e.what());
  }
}

// A .sens depth payload: width x height little-endian uint16, zlib-compressed or raw; the
// stream must inflate to exactly that many bytes.
DepthImage DecodeSensDepth(std::string_view bytes, const DepthSource& src) {
  if (!(src.scale_m_per_unit > 0) || !std::isfinite(src.scale_m_per_unit)) {
    throw InputError(src.path, "depth scale must be a positive number of metres per unit");
  }
  if (!PlausibleSize(src.width, src.height)) {
    throw InputError(src.path, "depth payload: implausible size " + std::to_string(src.width) +
                                   "x" + std::to_string(src.height));
  }
  const size_t n = static_cast<size_t>(src.width) * static_cast<size_t>(src.height);
  std::vector<uint16_t> raw(n);
  const std::string where =
      (src.frame_index >= 0 ? ContainerFrameWhere(src.path, src.frame_index) : src.path) +
      " (depth payload at byte " + std::to_string(src.range.offset) + ")";
  if (src.format == DepthFormat::kSensRaw) {
    if (bytes.size() != n * 2) {
      throw InputError(where, "expected " + std::to_string(n * 2) + " bytes of raw uint16, got " +
                                  std::to_string(bytes.size()));
    }
    std::memcpy(raw.data(), bytes.data(), n * 2);
  } else {
    z_stream z{};
    if (inflateInit(&z) != Z_OK) throw InputError(where, "zlib: cannot initialise");
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
    z.avail_in = static_cast<uInt>(std::min<size_t>(bytes.size(), UINT32_MAX));
    z.next_out = reinterpret_cast<Bytef*>(raw.data());
    z.avail_out = static_cast<uInt>(n * 2);
    const int rc = inflate(&z, Z_FINISH);
    const size_t produced = n * 2 - z.avail_out;
    inflateEnd(&z);
    if (rc != Z_STREAM_END || produced != n * 2) {
      throw InputError(where, rc == Z_STREAM_END || rc == Z_BUF_ERROR
                                  ? "zlib depth: expected " + std::to_string(n * 2) + " bytes (" +
                                        std::to_string(src.width) + "x" +
                                        std::to_string(src.height) + " uint16) after inflating"
                                  : "zlib depth: corrupt or cut stream");
    }
  }
  DepthImage d(src.width, src.height);
  // As the 16-bit PNG path: the same metres for the same raw value, whichever container.
  for (size_t i = 0; i < n; ++i) {
    d.values_m[i] = raw[i] == 0 ? 0.0f : Sanitize(raw[i] * src.scale_m_per_unit);
  }
  return d;
}

}  // namespace

void PrefetchDepth(const DepthSource& source) {
  if (source.format == DepthFormat::kSensZlib || source.format == DepthFormat::kSensRaw ||
      source.format == DepthFormat::kIphoneBinRecord) {
    PrefetchFileRange(source.path, source.range.offset, source.range.size);
  } else {
    PrefetchFile(source.path);
  }
}

namespace {

// The distorted pixel whose area holds the ray of undistorted pixel (u, v) of `maps`:
// floor(x + 0.5) (explicit: cv::remap's INTER_NEAREST rounds its fixed-point maps its own
// way); false when it lies outside a width x height distorted image.
bool NearestDistortedPixel(const UndistortMaps& maps, int u, int v, int width, int height, int* x,
                           int* y) {
  const double fx = std::floor(static_cast<double>(maps.map_x(v, u)) + 0.5);
  const double fy = std::floor(static_cast<double>(maps.map_y(v, u)) + 0.5);
  if (!(fx >= 0 && fy >= 0 && fx < width && fy < height)) return false;
  *x = static_cast<int>(fx);
  *y = static_cast<int>(fy);
  return true;
}

}  // namespace

void ApplyFrameMask(const Frame& frame, DepthImage* depth) {
  if (frame.mask_path.empty() && !frame.color_lens) return;
  // The mask's camera: the distorted colour camera, else the colour camera.
  LensCamera lens;
  if (frame.color_lens) {
    lens = *frame.color_lens;
  } else {
    lens.pinhole = frame.color_camera;
  }
  const Camera target = frame.depth_camera.Resized(depth->width, depth->height);
  if (frame.color_lens) {
    // A pixel of the undistorted camera whose ray leaves the distorted image has no image
    // (the undistorted colour there is a reflection of the border): no depth either, whatever
    // its source (a mesh covers it). The sensor depth's lookup rule (ReadFrameDepth).
    const UndistortMaps& maps = GetUndistortMaps(lens, target);
    int x = 0, y = 0;
    for (int v = 0; v < depth->height; ++v) {
      for (int u = 0; u < depth->width; ++u) {
        if (!NearestDistortedPixel(maps, u, v, lens.pinhole.width, lens.pinhole.height, &x, &y)) {
          depth->at(u, v) = 0.0f;
        }
      }
    }
  }
  if (frame.mask_path.empty()) return;
  const cv::Mat m =
      DecodeImageBytes(ReadFileBytes(frame.mask_path), ChannelOrder::kRgb, frame.mask_path);
  if (m.type() != CV_8UC1) {
    throw InputError(frame.mask_path, "mask: expected an 8-bit grey image");
  }
  if (m.cols != lens.pinhole.width || m.rows != lens.pinhole.height) {
    throw InputError(frame.mask_path, "mask is " + std::to_string(m.cols) + "x" +
                                          std::to_string(m.rows) + ", expected " +
                                          std::to_string(lens.pinhole.width) + "x" +
                                          std::to_string(lens.pinhole.height));
  }
  const cv::Mat1b valid = UndistortMask(m, lens, target);
  for (int v = 0; v < depth->height; ++v) {
    const uint8_t* row = valid.ptr<uint8_t>(v);
    for (int u = 0; u < depth->width; ++u) {
      if (row[u] != 255) depth->at(u, v) = 0.0f;
    }
  }
}

namespace {

// A frame without a depth file: what to do instead.
std::string NoDepthFile() {
  return "the frame has no depth file (ScanNet++ DSLR images have no sensor depth: render it "
         "from the scene's mesh with --depth-source mesh, dataset.depth_source: mesh or "
         "depth_source=\"mesh\")";
}

}  // namespace

DepthImage ReadFrameDepth(const Frame& frame) {
  if (frame.depth.path.empty()) throw InputError("frame " + frame.id + ": depth", NoDepthFile());
  if (!frame.depth_lens) {
    DepthImage d = ReadDepth(frame.depth, frame.depth_camera.width, frame.depth_camera.height);
    ApplyFrameMask(frame, &d);
    return d;
  }
  const LensCamera& lens = *frame.depth_lens;
  const DepthImage raw = ReadDepth(frame.depth, lens.pinhole.width, lens.pinhole.height);
  // Nearest neighbour: the distorted pixel whose area holds the ray's point.
  const UndistortMaps& maps = GetUndistortMaps(lens, frame.depth_camera);
  DepthImage d(frame.depth_camera.width, frame.depth_camera.height);
  int x = 0, y = 0;
  for (int v = 0; v < d.height; ++v) {
    for (int u = 0; u < d.width; ++u) {
      if (NearestDistortedPixel(maps, u, v, raw.width, raw.height, &x, &y)) {
        d.at(u, v) = raw.at(x, y);
      }
    }
  }
  ApplyFrameMask(frame, &d);
  return d;
}

DepthImage ReadDepth(const DepthSource& source, int expected_width, int expected_height) {
  if (source.path.empty()) throw InputError("depth", NoDepthFile());
  if (source.format == DepthFormat::kSensZlib || source.format == DepthFormat::kSensRaw ||
      source.format == DepthFormat::kIphoneBinRecord) {
    return DecodeDepth(
        ReadFileRange(source.path, source.range.offset, source.range.size, "depth payload"), source,
        expected_width, expected_height);
  }
  if (source.format == DepthFormat::kHdf5) {
    DepthImage d = ReadHdf5Depth(source.path, expected_width, expected_height);
    for (float& v : d.values_m) v = Sanitize(v);
    return d;
  }
  return DecodeDepth(ReadFileBytes(source.path), source, expected_width, expected_height);
}

DepthImage DecodeDepth(std::string_view bytes, const DepthSource& source, int expected_width,
                       int expected_height) {
  DepthImage d;
  switch (source.format) {
    case DepthFormat::kNpyFloat32:
      d = DecodeNpyDepth(bytes, source);
      break;
    case DepthFormat::kPng16:
      d = DecodePng16Depth(bytes, source, expected_width, expected_height);
      break;
    case DepthFormat::kExr:
      d = DecodeExrDepth(bytes, source, expected_width, expected_height);
      break;
    case DepthFormat::kSensZlib:
    case DepthFormat::kSensRaw:
      if (expected_width > 0 && expected_height > 0) {
        CheckDeclaredSize(source.path, source.width, source.height, expected_width,
                          expected_height);
      }
      d = DecodeSensDepth(bytes, source);
      break;
    case DepthFormat::kHdf5:
      d = DecodeHdf5Depth(bytes, source.path, expected_width, expected_height);
      for (float& v : d.values_m) v = Sanitize(v);
      break;
    case DepthFormat::kIphoneBinDeflate:
    case DepthFormat::kIphoneBinRecord:
      d = DecodeIphoneDepth(bytes, source);
      break;
  }
  if (expected_width > 0 && expected_height > 0 &&
      (d.width != expected_width || d.height != expected_height)) {
    std::ostringstream s;
    s << "depth is " << d.width << "x" << d.height << ", expected " << expected_width << "x"
      << expected_height;
    throw InputError(source.path, s.str());
  }
  return d;
}

namespace {

// JPEG: walk the marker segments to the first start-of-frame (SOF0..SOF15 except
// DHT/JPG/DAC = C4, C8, CC). Seeks past segments, so a file stream reads only the headers.
bool JpegSize(std::istream& in, ImageSize* size) {
  unsigned char b[2];
  if (!in.read(reinterpret_cast<char*>(b), 2) || b[0] != 0xFF || b[1] != 0xD8) return false;
  for (int guard = 0; guard < 10000; ++guard) {
    int c = in.get();
    while (c == 0xFF) c = in.get();  // fill bytes
    if (c == EOF) return false;
    const int marker = c;
    if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) continue;
    if (!in.read(reinterpret_cast<char*>(b), 2)) return false;
    const int len = (b[0] << 8) | b[1];
    if (len < 2) return false;
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      unsigned char sof[5];
      if (!in.read(reinterpret_cast<char*>(sof), 5)) return false;
      size->height = (sof[1] << 8) | sof[2];
      size->width = (sof[3] << 8) | sof[4];
      return size->width > 0 && size->height > 0;
    }
    in.seekg(len - 2, std::ios::cur);
    if (!in) return false;
  }
  return false;
}

// Netpbm (P1..P6): magic, then width and height as decimal tokens, '#' comments allowed.

constexpr size_t kHeadBytes = 512;  // PNG IHDR, a Netpbm header with comments

// The header of `path`'s bytes `head` (its first kHeadBytes or fewer) and, for JPEG, a
// stream over the whole file.
ImageSize ImageSizeOf(const std::string& path, std::string_view head, std::istream& whole) {
  ImageSize size;
  static const char kPngSig[] = "\x89PNG\r\n\x1a\n";
  if (head.size() >= 8 && head.compare(0, 8, std::string_view(kPngSig, 8)) == 0) {
    if (PngSize(head, &size)) return size;
    throw InputError(path, "PNG file without a valid IHDR header (damaged or cut)");
  }
  if (head.size() >= 2 && static_cast<unsigned char>(head[0]) == 0xFF &&
      static_cast<unsigned char>(head[1]) == 0xD8) {
    if (JpegSize(whole, &size)) return size;
    throw InputError(path,
                     "JPEG file without a frame header (SOF) before its end (damaged or cut)");
  }
  if (NetpbmSize(head, &size.width, &size.height)) return size;
  throw InputError(path, "unsupported image format (expected PNG, JPEG or Netpbm)");
}

}  // namespace

ImageSize ReadImageSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::string head(kHeadBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  in.clear();
  in.seekg(0);
  return ImageSizeOf(path, head, in);
}

ImageSize DecodeImageSize(std::string_view bytes, const std::string& path) {
  std::istringstream whole{std::string(bytes)};
  return ImageSizeOf(path, bytes.substr(0, std::min(bytes.size(), kHeadBytes)), whole);
}

}  // namespace gt::io

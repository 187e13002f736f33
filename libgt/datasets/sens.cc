#include "libgt/datasets/sens.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "libgt/core/camera.h"
#include "libgt/core/error.h"
#include "libgt/io/file_read.h"

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the .sens reader assumes a little-endian host (the file's byte order)"
#endif

namespace gt::datasets {
namespace {

// Larger images are refused as implausible (as depth_io.cc does for depth maps).
constexpr int64_t kMaxPixels = int64_t{1} << 27;
constexpr uint64_t kMaxSensorNameBytes = 4096;

// Sequential reads of the header fields, each checked against the file's size first.
class SensCursor {
 public:
  SensCursor(const std::string& path, uint64_t file_size, const SensReadAt& read_at)
      : path_(path), file_size_(file_size), read_at_(read_at) {}

  void Read(void* dst, uint64_t n, const char* field) {
    if (n > file_size_ - offset_) {
      throw InputError(path_, std::string(field) + ": file ends at byte " +
                                  std::to_string(file_size_) + ", expected " + std::to_string(n) +
                                  " bytes at byte " + std::to_string(offset_) +
                                  " (truncated .sens?)");
    }
    read_at_(offset_, static_cast<size_t>(n), dst);
    offset_ += n;
  }
  template <typename T>
  T Get(const char* field) {
    T v;
    Read(&v, sizeof(T), field);
    return v;
  }
  Eigen::Matrix4d Matrix(const char* field) {
    float m[16];
    Read(m, sizeof(m), field);
    Eigen::Matrix4d out;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) out(r, c) = m[r * 4 + c];
    }
    return out;
  }
  void Skip(uint64_t n) { offset_ += n; }  // the caller checked n <= Remaining()
  uint64_t offset() const { return offset_; }
  uint64_t Remaining() const { return file_size_ - offset_; }

 private:
  const std::string& path_;
  uint64_t file_size_;
  const SensReadAt& read_at_;
  uint64_t offset_ = 0;
};

int CheckedSide(uint32_t v, const std::string& path, const char* field) {
  if (v == 0 || v > kMaxImageSidePx) {
    throw InputError(path, std::string(field) + ": " + std::to_string(v) +
                               ", expected an image size in 1.." + std::to_string(kMaxImageSidePx));
  }
  return static_cast<int>(v);
}

void CheckPixels(int w, int h, const std::string& path, const char* what) {
  if (int64_t{w} * h > kMaxPixels) {
    throw InputError(path, std::string(what) + " " + std::to_string(w) + "x" + std::to_string(h) +
                               ": implausible size (at most " + std::to_string(kMaxPixels) +
                               " pixels)");
  }
}

}  // namespace

SensIndex ParseSensIndex(const std::string& path, uint64_t file_size, const SensReadAt& read_at) {
  SensIndex index;
  index.path = path;
  SensCursor in(path, file_size, read_at);
  const auto version = in.Get<uint32_t>("version");
  if (version != kSensVersion) {
    throw InputError(path, "version: " + std::to_string(version) + ", expected " +
                               std::to_string(kSensVersion) + " (a ScanNet .sens file)");
  }
  const auto name_bytes = in.Get<uint64_t>("sensor name length");
  if (name_bytes > kMaxSensorNameBytes || name_bytes > in.Remaining()) {
    throw InputError(path, "sensor name length: " + std::to_string(name_bytes) +
                               ", expected at most " + std::to_string(kMaxSensorNameBytes) +
                               " bytes within the file");
  }
  index.sensor_name.resize(static_cast<size_t>(name_bytes));
  in.Read(index.sensor_name.data(), name_bytes, "sensor name");
  index.color_intrinsic = in.Matrix("colour intrinsic");
  (void)in.Matrix("colour extrinsic");
  index.depth_intrinsic = in.Matrix("depth intrinsic");
  (void)in.Matrix("depth extrinsic");

  const auto color_compression = in.Get<int32_t>("colorCompression");
  if (color_compression < 0 || color_compression > 2) {
    throw InputError(path, "colorCompression: " + std::to_string(color_compression) +
                               " is not supported (expected 0 raw RGB, 1 PNG or 2 JPEG)");
  }
  index.color_compression = static_cast<SensColorCompression>(color_compression);
  const auto depth_compression = in.Get<int32_t>("depthCompression");
  if (depth_compression != 0 && depth_compression != 1) {
    throw InputError(path, "depthCompression: " + std::to_string(depth_compression) +
                               (depth_compression == 2 ? " (OCCI, proprietary)" : "") +
                               " is not supported (expected 0 raw uint16 or 1 zlib uint16)");
  }
  index.depth_compression = static_cast<SensDepthCompression>(depth_compression);
  index.color_width = CheckedSide(in.Get<uint32_t>("colorWidth"), path, "colorWidth");
  index.color_height = CheckedSide(in.Get<uint32_t>("colorHeight"), path, "colorHeight");
  index.depth_width = CheckedSide(in.Get<uint32_t>("depthWidth"), path, "depthWidth");
  index.depth_height = CheckedSide(in.Get<uint32_t>("depthHeight"), path, "depthHeight");
  CheckPixels(index.color_width, index.color_height, path, "colour");
  CheckPixels(index.depth_width, index.depth_height, path, "depth");
  const auto depth_shift = in.Get<float>("depthShift");
  if (!(depth_shift > 0) || !std::isfinite(depth_shift)) {
    throw InputError(path, "depthShift: expected a positive number (1000 for millimetres)");
  }
  index.depth_shift = depth_shift;
  const auto num_frames = in.Get<uint64_t>("numFrames");
  if (num_frames > in.Remaining() / kSensFrameHeaderBytes) {
    throw InputError(path, "numFrames: " + std::to_string(num_frames) + ", but the file holds " +
                               "at most " + std::to_string(in.Remaining() / kSensFrameHeaderBytes) +
                               " frame headers of " + std::to_string(kSensFrameHeaderBytes) +
                               " bytes after the header (truncated .sens?)");
  }
  const uint64_t raw_depth_bytes = uint64_t(index.depth_width) * uint64_t(index.depth_height) * 2;
  const uint64_t raw_color_bytes = uint64_t(index.color_width) * uint64_t(index.color_height) * 3;
  index.frames.reserve(static_cast<size_t>(num_frames));
  for (uint64_t i = 0; i < num_frames; ++i) {
    const std::string frame = "frame " + std::to_string(i);
    const std::string where = io::ContainerFrameWhere(path, static_cast<int64_t>(i));
    SensFrameEntry e;
    e.world_from_cam = in.Matrix((frame + ": cameraToWorld").c_str());
    uint64_t head[4];  // timestampColor, timestampDepth, colorBytes, depthBytes
    in.Read(head, sizeof(head), (frame + ": header").c_str());
    const uint64_t color_bytes = head[2], depth_bytes = head[3];
    if (color_bytes > in.Remaining() || depth_bytes > in.Remaining() - color_bytes) {
      throw InputError(where, "colorBytes " + std::to_string(color_bytes) + " + depthBytes " +
                                  std::to_string(depth_bytes) + " at byte " +
                                  std::to_string(in.offset()) + " run past the end of the file (" +
                                  std::to_string(file_size) + " bytes; truncated .sens?)");
    }
    if (index.depth_compression == SensDepthCompression::kRaw && depth_bytes != 0 &&
        depth_bytes != raw_depth_bytes) {
      throw InputError(where, "depthBytes " + std::to_string(depth_bytes) + ", expected " +
                                  std::to_string(raw_depth_bytes) + " (raw uint16 depth)");
    }
    if (index.color_compression == SensColorCompression::kRaw && color_bytes != 0 &&
        color_bytes != raw_color_bytes) {
      throw InputError(where, "colorBytes " + std::to_string(color_bytes) + ", expected " +
                                  std::to_string(raw_color_bytes) + " (raw RGB colour)");
    }
    e.color = {in.offset(), color_bytes};
    in.Skip(color_bytes);
    e.depth = {in.offset(), depth_bytes};
    in.Skip(depth_bytes);
    index.frames.push_back(e);
  }
  return index;
}

SensIndex ReadSensIndex(const std::string& path) {
  const uint64_t size = io::FileSizeBytes(path);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, "cannot open file (missing or unreadable)");
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  const SensReadAt read_at = [&](uint64_t offset, size_t n, void* dst) {
    auto* out = static_cast<char*>(dst);
    size_t done = 0;
    while (done < n) {
      const ssize_t got = ::pread(fd, out + done, n - done, static_cast<off_t>(offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) throw InputError(path, "read error at byte " + std::to_string(offset + done));
      done += static_cast<size_t>(got);
    }
  };
  return ParseSensIndex(path, size, read_at);
}

}  // namespace gt::datasets

// ScanNet's raw .sens container, read in place (docs/DATASETS.md "ScanNet raw .sens").
// Layout (SensReader's sensorData.h; little-endian struct writes, no padding):
//   uint32 version (4); uint64 n + char[n] sensor name; float32[16] x 4 row-major matrices
//   (colour intrinsic, colour extrinsic, depth intrinsic, depth extrinsic); int32
//   colorCompression (0 raw RGB888, 1 PNG, 2 JPEG), int32 depthCompression (0 raw uint16,
//   1 zlib uint16; 2 OCCI is proprietary and refused); uint32 colorWidth, colorHeight,
//   depthWidth, depthHeight; float32 depthShift (metres = value / shift); uint64 numFrames;
//   then per frame: float32[16] cameraToWorld (row-major; all -inf = lost tracking),
//   uint64 timestampColor, timestampDepth, colorBytes, depthBytes, the colour payload, the
//   depth payload. IMU records after the frames are not read.
// ParseSensIndex makes one pass over the frame headers, seeking past the payloads (no
// payload is read), and gives each payload's byte range: any frame is then read on its own
// (ReadFileRange, pread). Every size and count is checked against the file's size before
// anything is allocated: a damaged file is one InputError naming the file and the field.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "libgt/core/frame.h"

namespace gt::datasets {

inline constexpr uint32_t kSensVersion = 4;
inline constexpr uint64_t kSensFrameHeaderBytes = 16 * 4 + 4 * 8;  // pose + 4 uint64

enum class SensColorCompression : int32_t { kRaw = 0, kPng = 1, kJpeg = 2 };
enum class SensDepthCompression : int32_t { kRaw = 0, kZlib = 1 };

struct SensFrameEntry {
  Eigen::Matrix4d world_from_cam;  // cameraToWorld (float32 in the file), may be -inf
  ByteRange color;                 // size 0: no colour payload
  ByteRange depth;                 // size 0: no depth payload
};

struct SensIndex {
  std::string path;
  std::string sensor_name;
  Eigen::Matrix4d color_intrinsic, depth_intrinsic;  // K is the top-left 3x3
  SensColorCompression color_compression = SensColorCompression::kJpeg;
  SensDepthCompression depth_compression = SensDepthCompression::kZlib;
  int color_width = 0, color_height = 0, depth_width = 0, depth_height = 0;
  double depth_shift = 1000.0;  // raw value / depth_shift = metres
  std::vector<SensFrameEntry> frames;
};

// Reads `size` bytes at `offset` into dst; throws InputError when they cannot be read.
using SensReadAt = std::function<void(uint64_t offset, size_t size, void* dst)>;

// The header and the offset table of a .sens of `file_size` bytes read through read_at
// (`path` names it in messages). The fuzz target calls it on bytes in memory.
SensIndex ParseSensIndex(const std::string& path, uint64_t file_size, const SensReadAt& read_at);
// The same for a file (pread on one descriptor).
SensIndex ReadSensIndex(const std::string& path);

}  // namespace gt::datasets

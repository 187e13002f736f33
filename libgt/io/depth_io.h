// Depth and image files: .npy float32 metres, 16-bit PNG/PGM with a scale, OpenEXR with a
// channel matched by suffix (Blender writes "Depth.Z", "View Layer.Depth.Z",
// "RenderLayer.Depth.Z", "Z", "Y" or "V"). Every invalid marker becomes 0 (depth.h).
#pragma once

#include <string>

#include "libgt/core/depth.h"
#include "libgt/core/frame.h"

namespace gt::io {

// Reads a frame's depth; throws InputError naming the file on any problem, and when the
// size differs from expected_width x expected_height (unless those are 0).
DepthImage ReadDepth(const DepthSource& source, int expected_width = 0, int expected_height = 0);

// Size of an image file (PNG/JPG) without decoding pixels where possible.
struct ImageSize {
  int width = 0;
  int height = 0;
};
ImageSize ReadImageSize(const std::string& path);

}  // namespace gt::io

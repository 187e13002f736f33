// Depth and image files: .npy float32 metres, 16-bit PNG/PGM with a scale, OpenEXR with a
// channel matched by suffix (Blender writes "Depth.Z", "View Layer.Depth.Z",
// "RenderLayer.Depth.Z", "Z", "Y" or "V"). Every invalid marker becomes 0 (depth.h).
#pragma once

#include <string>
#include <string_view>

#include "libgt/core/depth.h"
#include "libgt/core/frame.h"

namespace gt::io {

// Reads a frame's depth; throws InputError naming the file on any problem, and when the
// size differs from expected_width x expected_height (unless those are 0).
// Depth maps are at most 65536 pixels a side and 2^27 pixels in all (checked from the
// header, before any pixel buffer is allocated).
DepthImage ReadDepth(const DepthSource& source, int expected_width = 0, int expected_height = 0);
// A frame's depth in its depth_camera: ReadDepth of frame.depth (at frame.depth_lens's size
// when the map is in a distorted camera, else at depth_camera's), resampled into
// depth_camera (nearest neighbour, 0 outside the distorted image) when depth_lens is set, and
// zeroed where frame.mask_path's mask, remapped into depth_camera, is anonymised.
DepthImage ReadFrameDepth(const Frame& frame);
// Zeroes the depth (in frame.depth_camera, any size: the mask is remapped into that camera
// resized to the depth's size) where the frame has no image: where frame.mask_path is
// anonymised, and, for a distorted colour camera (frame.color_lens), where the undistorted
// pixel's ray leaves the distorted image. Nothing for a frame with neither.
// InputError naming the mask when it is missing, not 8-bit grey or of the wrong size.
void ApplyFrameMask(const Frame& frame, DepthImage* depth);
// Asks the kernel to read a frame's depth file (or its payload inside a container) ahead
// (io::PrefetchFile / PrefetchFileRange); a hint only.
void PrefetchDepth(const DepthSource& source);
// The same from the file's bytes already in memory (source.path names it in messages):
// ReadDepth is ReadFileBytes + DecodeDepth. PNG/PGM go through libgt/io/codec.h (only 16-bit
// grey is depth: an 8-bit or colour file is refused), EXR through
// an in-memory Imf::IStream.
DepthImage DecodeDepth(std::string_view bytes, const DepthSource& source, int expected_width = 0,
                       int expected_height = 0);

// Size of a colour image file from its header, without decoding pixels: PNG (IHDR), JPEG
// (the first start-of-frame segment; only the segment headers are read) or Netpbm
// (P1..P6). Anything else, or a header that is damaged or cut, is an InputError naming the
// file (no decoder is tried on unknown bytes).
struct ImageSize {
  int width = 0;
  int height = 0;
};
ImageSize ReadImageSize(const std::string& path);
// The same from the file's bytes in memory (path names it in messages).
ImageSize DecodeImageSize(std::string_view bytes, const std::string& path);

}  // namespace gt::io

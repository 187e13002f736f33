// Colour images: loading (PNG, JPEG, Netpbm via libgt/io/codec.h) and bilinear resizing to the
// working resolution, with K rescaled by Camera::Resized (camera.h: pixel areas stay aligned, which
// is also what cv::resize with INTER_LINEAR assumes).
//
// Layout: ColorImage::rgb is uint8, row-major [height, width, 3], channels in R, G, B
// order. Grey and 16-bit inputs are converted to 8-bit RGB (16-bit: round(v / 257)); an
// alpha channel is dropped.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/frame.h"

namespace gt::io {

struct ColorImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  // [height, width, 3], R G B

  const uint8_t* pixel(int u, int v) const {
    return &rgb[(static_cast<size_t>(v) * width + u) * 3];
  }
  bool empty() const { return rgb.empty(); }
};

// Decodes an image file; InputError naming the file when missing or undecodable.
ColorImage ReadColor(const std::string& path);

// Bilinear resize (cv::resize, INTER_LINEAR) to new_width x new_height. Same size: a copy.
ColorImage ResizeColorBilinear(const ColorImage& image, int new_width, int new_height);

// Reads `path`, whose intrinsics are `camera` (its size must match the file, else
// InputError naming the file), and resizes it to new_width x new_height; *resized_camera
// (optional) receives camera.Resized(new_width, new_height).
ColorImage ReadColorResized(const std::string& path, const Camera& camera, int new_width,
                            int new_height, Camera* resized_camera = nullptr);

// A frame's colour: the file frame.color_path, or its payload frame.color_range inside a
// container (.sens: JPEG/PNG bytes, or raw RGB888 at color_camera's size with
// color_raw_rgb); with frame.color_lens, the distorted image undistorted into
// frame.color_camera (io/undistort.h). InputError naming the file (and the payload's
// offset) on any problem.
ColorImage ReadFrameColor(const Frame& frame);
// The cheap part of ReadFrameColor, for a scan over many frames: a colour image file
// (frame.color_path without a payload range or a lens) whose header cannot be read or gives
// another size than frame.color_camera is an InputError naming the file. The pixels are not
// decoded (a file cut inside its pixel data still fails when it is read), and payloads
// inside a container are left to the reader. Behind a lens (frame.color_lens) the file is
// the distorted image, of color_lens->pinhole's size.
void CheckFrameColorHeader(const Frame& frame);
// ReadColorResized for a frame's colour (its camera is frame.color_camera).
ColorImage ReadFrameColorResized(const Frame& frame, int new_width, int new_height,
                                 Camera* resized_camera = nullptr);

}  // namespace gt::io

// COLMAP sparse-model bytes -> gt::datasets::ParseColmap{Cameras,Images}{Binary,Text}: the first
// byte picks the parser (0 cameras.bin, 1 images.bin, 2 cameras.txt, 3 images.txt), the
// rest is the file. Counts and sizes are checked against the bytes left before allocating;
// every camera then goes through ColmapPinholeCamera, and through ColmapLensCamera and
// ScanNet++'s undistorted pinhole camera (OpenCV's new-K rules for OPENCV and
// OPENCV_FISHEYE), and every image through the pose conversion (a value or one InputError,
// never a crash; an undistorted camera always passes Camera::Check).
#include <cstdint>
#include <cstdlib>
#include <string>

#include "libgt/core/error.h"
#include "libgt/datasets/colmap.h"
#include "libgt/datasets/undistorted_camera.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const int kind = data[0] % 4;
  const std::string name = kind == 0   ? "cameras.bin"
                           : kind == 1 ? "images.bin"
                           : kind == 2 ? "cameras.txt"
                                       : "images.txt";
  const std::string_view bytes = gt::fuzz::Bytes(data + 1, size - 1);
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    if (kind == 0 || kind == 2) {
      const auto cameras = kind == 0 ? gt::datasets::ParseColmapCamerasBinary(bytes, name)
                                     : gt::datasets::ParseColmapCamerasText(bytes, name);
      for (const auto& entry : cameras) {
        const int64_t id = entry.first;  // named: lambdas cannot capture a structured binding
        const gt::datasets::ColmapCamera& c = entry.second;
        try {
          (void)gt::datasets::ColmapPinholeCamera(c, name);
        } catch (const gt::InputError&) {
        }
        gt::fuzz::ExpectValueOrInputError(name, [&] {
          const gt::Camera undistorted = gt::datasets::ScanNetPPUndistortedCamera(
              gt::datasets::ColmapLensCamera(c, name), name, id);
          std::string error;
          if (!undistorted.Check(&error)) std::abort();
        });
      }
    } else {
      const auto images = kind == 1 ? gt::datasets::ParseColmapImagesBinary(bytes, name)
                                    : gt::datasets::ParseColmapImagesText(bytes, name);
      for (const auto& im : images) {
        if (!gt::datasets::ColmapPoseDefect(im)) (void)gt::datasets::ColmapWorldFromCam(im);
      }
    }
  });
  return 0;
}

// Pinhole camera with K at a stated resolution.
//
// Pixel convention (GROUND_TRUTH.md §1): pixel (u, v) is column u, row v, and its centre is
// the continuous image point (u, v). The pixel area of the image is therefore
// -0.5 <= x < width - 0.5, -0.5 <= y < height - 0.5. Camera axes are OpenCV's
// (x right, y down, z forward); depth is planar z in metres.
//
// Resizing to (width', height') with factors sx = width'/width, sy = height'/height maps
//   fx' = sx * fx,  cx' = sx * (cx + 0.5) - 0.5   (and likewise for y),
// which keeps pixel areas (not pixel centres) aligned.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

namespace gt {

// The largest image side (pixels) that the readers of images, depth maps and camera files
// accept: a larger size in a file is refused before any buffer is allocated.
inline constexpr int64_t kMaxImageSidePx = int64_t{1} << 16;

struct Camera {
  int width = 0;   // pixels
  int height = 0;  // pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;

  static Camera FromK(const Eigen::Matrix3d& K, int width, int height);
  // True when K is finite and of the layout FromK reads, [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]
  // (no skew: a K that is not would lose entries in FromK; the signs of fx, fy are Check's).
  static bool IsPinholeMatrix(const Eigen::Matrix3d& K);
  Eigen::Matrix3d K() const;

  // True when the size is positive, the entries of K finite and the focal lengths > 0.
  bool Check(std::string* error) const;

  // Projection with an explicit cheirality test: nullopt when p_in_cam.z() <= min_z_m.
  // The result may lie outside the image; see InPixelArea.
  std::optional<Eigen::Vector2d> ImgFromCam(const Eigen::Vector3d& p_in_cam,
                                            double min_z_m = 0.0) const;
  // Back-projection of pixel (u, v) at planar depth depth_m.
  Eigen::Vector3d CamFromImg(double u, double v, double depth_m) const;

  // -0.5 <= x < width - 0.5 and the same for y.
  bool InPixelArea(double x, double y) const;

  // The same camera at another resolution (rule above).
  Camera Resized(int new_width, int new_height) const;
  // K_half = diag(1/2, 1/2, 1) K with size (width/2, height/2): rays through full-resolution
  // pixels (2u, 2v). Used for the occupancy frustum (GROUND_TRUTH.md §5).
  Camera HalfGrid() const;
};

}  // namespace gt

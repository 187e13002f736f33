// Depth maps: planar z in metres, float32, row-major [height, width].
// Readers store every invalid marker of their dataset (0, 65535 in 7-Scenes, NaN, inf) as
// 0; IsValidDepth additionally applies the dataset's [min_depth_m, max_depth_m] range
// (TartanAir's sky is ~1e4 m, Blender's background ~1e10 m).
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace gt {

struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> values_m;  // size width * height, row-major: index v * width + u

  DepthImage() = default;
  DepthImage(int w, int h, float fill = 0.0f)
      : width(w), height(h), values_m(static_cast<size_t>(w) * h, fill) {}
  float at(int u, int v) const { return values_m[static_cast<size_t>(v) * width + u]; }
  float& at(int u, int v) { return values_m[static_cast<size_t>(v) * width + u]; }
  bool empty() const { return values_m.empty(); }
};

// The validity range every consumer of depth starts from when no dataset gives one (a
// reader's Scene range, LabelOptions, FusionInput and the frame scan take these): no lower
// limit, and an upper one far beyond any sensor (TartanAir's sky, ~1e4 m, stays invalid).
inline constexpr double kDefaultMinDepthM = 0.0;
inline constexpr double kDefaultMaxDepthM = 1000.0;

// The smallest depth counted as > 0: the smallest normal float (1.18e-38 m). A denormal
// depth is invalid, so that no result depends on the denormals-are-zero / flush-to-zero mode
// of the threads that compute it: torch.set_flush_denormal(True) sets it in a trainer, and
// Embree's BVH builds left it in TBB's workers; under it a denormal threshold compares as 0,
// and `d >= denorm_min` counted depth 0 as valid.
inline constexpr float kMinPositiveDepthM = std::numeric_limits<float>::min();

inline bool IsValidDepth(float d, double min_depth_m, double max_depth_m) {
  return std::isfinite(d) && d >= kMinPositiveDepthM && d >= min_depth_m && d <= max_depth_m;
}

// Nearest-neighbour resampling under the pixel-centre convention of camera.h: target
// pixel u' takes source pixel floor((u' + 0.5) / sx), clamped to the image.
DepthImage ResizeDepthNearest(const DepthImage& depth, int new_width, int new_height);

// Fraction of pixels with IsValidDepth.
double ValidDepthFraction(const DepthImage& depth, double min_depth_m, double max_depth_m);

}  // namespace gt

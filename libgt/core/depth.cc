#include "libgt/core/depth.h"

#include <algorithm>

#include "libgt/core/error.h"

namespace gt {

DepthImage ResizeDepthNearest(const DepthImage& depth, int new_width, int new_height) {
  GT_ASSERT(new_width > 0 && new_height > 0 && !depth.empty());
  if (new_width == depth.width && new_height == depth.height) return depth;
  DepthImage out(new_width, new_height);
  const double inv_sx = static_cast<double>(depth.width) / new_width;
  const double inv_sy = static_cast<double>(depth.height) / new_height;
  std::vector<int> src_u(new_width);
  for (int u = 0; u < new_width; ++u) {
    src_u[u] = std::min(depth.width - 1, static_cast<int>((u + 0.5) * inv_sx));
  }
  for (int v = 0; v < new_height; ++v) {
    const int sv = std::min(depth.height - 1, static_cast<int>((v + 0.5) * inv_sy));
    const float* src_row = &depth.values_m[static_cast<size_t>(sv) * depth.width];
    float* dst_row = &out.values_m[static_cast<size_t>(v) * new_width];
    for (int u = 0; u < new_width; ++u) dst_row[u] = src_row[src_u[u]];
  }
  return out;
}

double ValidDepthFraction(const DepthImage& depth, double min_depth_m, double max_depth_m) {
  if (depth.values_m.empty()) return 0.0;
  size_t n = 0;
  for (float d : depth.values_m) n += IsValidDepth(d, min_depth_m, max_depth_m) ? 1 : 0;
  return static_cast<double>(n) / depth.values_m.size();
}

}  // namespace gt

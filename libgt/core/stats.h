// Order statistics shared by every output that reports them (summary.json's selected_overlap,
// the split and tuple reports), so that "median" means one thing everywhere.
#pragma once

#include <vector>

#include "libgt/core/error.h"

namespace gt {

// The median of sorted values: the middle one, or the mean of the two middle ones for an
// even count (numpy.median's definition). The values must not be empty.
inline double SortedMedian(const std::vector<double>& sorted) {
  GT_ASSERT(!sorted.empty());
  const size_t n = sorted.size();
  return n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

}  // namespace gt

// Everything geometric about one pair of posed depth frames in one call: labels of both
// directions, their metrics at stride 1, and the coarse patch matches (GROUND_TRUTH.md
// §2–4). A thin facade over labels.h and patches.h; depth maps and cameras must already
// be at the working resolution.
#pragma once

#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"

namespace gt {

struct PairLabels {
  Rigid3d cam1_from_cam0 = Rigid3d::Identity();  // b_from_a of direction 0→1
  DirectionLabels l01, l10;                      // image 0 → 1 (grid of 0), 1 → 0 (grid of 1)
  DirectionMetrics m01, m10;                     // MetricsFromLabels(l01 / l10, 1)
  PatchMatches patches;
};

// Throws InputError as LabelDirection / ComputePatchMatches do.
PairLabels LabelPair(const DepthImage& depth0, const Camera& cam0, const Rigid3d& world_from_cam0,
                     const DepthImage& depth1, const Camera& cam1, const Rigid3d& world_from_cam1,
                     const LabelOptions& label_options, const PatchOptions& patch_options);

}  // namespace gt

#include "libgt/geometry/pair.h"

namespace gt {

PairLabels LabelPair(const DepthImage& depth0, const Camera& cam0, const Rigid3d& world_from_cam0,
                     const DepthImage& depth1, const Camera& cam1, const Rigid3d& world_from_cam1,
                     const LabelOptions& label_options, const PatchOptions& patch_options) {
  PairLabels out;
  out.cam1_from_cam0 = RelativePose(world_from_cam0, world_from_cam1);
  const Rigid3d cam0_from_cam1 = out.cam1_from_cam0.inverse(Eigen::Isometry);
  out.l01 = LabelDirection(depth0, cam0, depth1, cam1, out.cam1_from_cam0, label_options);
  out.l10 = LabelDirection(depth1, cam1, depth0, cam0, cam0_from_cam1, label_options);
  out.m01 = MetricsFromLabels(out.l01, 1);
  out.m10 = MetricsFromLabels(out.l10, 1);
  out.patches = ComputePatchMatches(out.l01, out.l10, patch_options);
  return out;
}

}  // namespace gt

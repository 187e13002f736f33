#include "libgt/truth/pair_settings.h"

namespace gt::truth {

namespace {

template <typename T>
void Set(const std::optional<T>& value, T* field) {
  if (value) *field = *value;
}

}  // namespace

std::string OccupancySettingsProblem(const OccupancySettings& settings) {
  if (settings.remove_outliers.value_or(occupancy::FusionOptions().remove_outliers)) return "";
  if (settings.outlier_k) return "outlier_k: used with remove_outliers on only";
  if (settings.outlier_stddev) return "outlier_stddev: used with remove_outliers on only";
  return "";
}

DatasetDepthRange DepthRangeOf(const Scene& scene) {
  DatasetDepthRange r;
  r.min_depth_m = scene.min_depth_m;
  r.max_depth_m = scene.max_depth_m;
  return r;
}

PairTruthOptions ResolvePairTruthOptions(const PairSettings& settings,
                                         const DatasetDepthRange& range) {
  PairTruthOptions o;
  const LabelSettings& ls = settings.labels;
  LabelOptions& lo = o.labels;
  lo = LabelPreset(ls.preset);
  ApplyDatasetDepthRange(range.min_depth_m, range.max_depth_m, &lo);
  Set(range.set_min_depth_m, &lo.min_depth_m);
  Set(range.set_max_depth_m, &lo.max_depth_m);
  Set(ls.min_depth_m, &lo.min_depth_m);
  Set(ls.max_depth_m, &lo.max_depth_m);
  Set(ls.abs_tol_m, &lo.abs_tol_m);
  Set(ls.rel_tol, &lo.rel_tol);
  Set(ls.relative_to, &lo.relative_to);
  Set(ls.bounds, &lo.bounds);
  Set(ls.target_lookup, &lo.target_lookup);
  Set(ls.missing_target, &lo.missing_target);

  o.patches = settings.patches;

  const OccupancySettings& os = settings.occupancy;
  o.occupancy = os.enabled;
  Set(os.mode, &o.mode);
  occupancy::BinOptions& bo = o.bins;
  Set(os.bins, &bo.num_bins);
  Set(os.near_m, &bo.near_m);
  Set(os.far_m, &bo.far_m);
  Set(os.spacing, &bo.spacing);
  Set(os.traversal, &bo.traversal);
  occupancy::FusionOptions& fo = o.fusion;
  Set(os.voxel_m, &fo.voxel_m);
  fo.max_range_m = os.max_range_m.value_or(bo.far_m);
  Set(os.scope, &fo.scope);
  Set(os.window, &fo.window);
  Set(os.scene_stride, &fo.scene_stride);
  Set(os.downsample, &fo.downsample);
  Set(os.remove_outliers, &fo.remove_outliers);
  Set(os.outlier_k, &fo.outlier_k);
  Set(os.outlier_stddev, &fo.outlier_stddev);
  return o;
}

}  // namespace gt::truth

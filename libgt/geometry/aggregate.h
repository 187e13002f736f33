// How a pair's two directional metrics become one number (GROUND_TRUTH.md §3 "Pair
// level"): filters, scores and reports combine the A→B and B→A values with min, mean or
// max; and which occlusion ratio is meant (the paper's OCCLUDED / (W·H), or the released
// code's OCCLUDED / (VISIBLE + OCCLUDED)). One definition for the selection, the LoFTR
// export and the split report.
#pragma once

#include <string>

#include "libgt/geometry/labels.h"

namespace gt {

enum class Aggregate { kMin, kMean, kMax };  // "min" | "mean" | "max"
// Throws InputError(field, ...) on another name.
Aggregate ParseAggregate(const std::string& text, const std::string& field);
const char* AggregateName(Aggregate aggregate);
double Combine(double a, double b, Aggregate aggregate);

enum class OcclusionMetric {
  kImage,    // "image": occlusion_ratio = OCCLUDED / sampled pixels (the paper's)
  kVisible,  // "visible": occlusion_ratio_visible = OCCLUDED / (VISIBLE + OCCLUDED)
};
OcclusionMetric ParseOcclusionMetric(const std::string& text, const std::string& field);
const char* OcclusionMetricName(OcclusionMetric metric);
// The metric's field name in every JSON output ("occlusion_ratio", "occlusion_ratio_visible").
const char* OcclusionMetricField(OcclusionMetric metric);
double OcclusionOf(const DirectionMetrics& m, OcclusionMetric metric);

}  // namespace gt

#include "libgt/geometry/aggregate.h"

#include <algorithm>

#include "libgt/core/error.h"

namespace gt {

Aggregate ParseAggregate(const std::string& text, const std::string& field) {
  if (text == "min") return Aggregate::kMin;
  if (text == "mean") return Aggregate::kMean;
  if (text == "max") return Aggregate::kMax;
  throw InputError(field, "expected one of min, mean, max; got '" + text + "'");
}

const char* AggregateName(Aggregate aggregate) {
  switch (aggregate) {
    case Aggregate::kMin:
      return "min";
    case Aggregate::kMax:
      return "max";
    case Aggregate::kMean:
      break;
  }
  return "mean";
}

double Combine(double a, double b, Aggregate aggregate) {
  switch (aggregate) {
    case Aggregate::kMin:
      return std::min(a, b);
    case Aggregate::kMax:
      return std::max(a, b);
    case Aggregate::kMean:
      break;
  }
  return 0.5 * (a + b);
}

OcclusionMetric ParseOcclusionMetric(const std::string& text, const std::string& field) {
  if (text == "image") return OcclusionMetric::kImage;
  if (text == "visible") return OcclusionMetric::kVisible;
  throw InputError(field, "expected image or visible; got '" + text + "'");
}

const char* OcclusionMetricName(OcclusionMetric metric) {
  return metric == OcclusionMetric::kVisible ? "visible" : "image";
}

const char* OcclusionMetricField(OcclusionMetric metric) {
  return metric == OcclusionMetric::kVisible ? "occlusion_ratio_visible" : "occlusion_ratio";
}

double OcclusionOf(const DirectionMetrics& m, OcclusionMetric metric) {
  return metric == OcclusionMetric::kVisible ? m.occlusion_ratio_visible : m.occlusion_ratio;
}

}  // namespace gt

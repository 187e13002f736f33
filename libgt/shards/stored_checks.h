// Internal to libgt/shards: the pieces the pair and N-view sample checks share
// (sample_check.cc, views_sample_check.cc): array lookup by descr and shape, JSON matrices,
// full-precision numbers, image headers, IsValidDepth's range as float bounds.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/shards/sample_check.h"

namespace gt::shards::detail {

// "[2, 480, 640]".
std::string ShapeText(const std::vector<int64_t>& shape);
// The shortest text (of 15 to 17 significant digits; 6 to 9 for a float) that reads back as
// exactly `v`: every stored value told apart, 0.05 printed as 0.05.
std::string FullPrecision(double v);
std::string FullPrecision(float v);

// arrays[field] when it is stored with this descr and shape (-1: any extent); nullptr when
// absent, or when it differs: then "<field>: expected <descr> <shape> (<shape_words>), got ..."
// is added to `problems`.
const StoredArray* FindArray(const std::map<std::string, StoredArray>& arrays,
                             const std::string& field, const char* descr,
                             const std::vector<int64_t>& shape, const std::string& shape_words,
                             std::vector<std::string>* problems);

// A rows x cols matrix of a JSON array of rows; throws nlohmann::json::type_error otherwise.
Eigen::MatrixXd JsonMatrix(const nlohmann::json& j, int rows, int cols);

// The problem of one image member ("" = none): its format (the member's extension) is
// `format` (the json's image.format; "" = null: no image stored), its bytes complete
// (io::PngDamage / JpegDamage) and its header width x height.
std::string ImageProblem(const std::string& field, std::string_view bytes,
                         const std::string& format, int width, int height);

// label_options' min_depth_m and max_depth_m (null: no upper limit, +infinity, as the
// schemas say); throws nlohmann::json exceptions when they are missing or not numbers.
struct DepthRangeM {
  double min_m = 0, max_m = 0;
};
DepthRangeM LabelDepthRange(const nlohmann::json& label_options);

// Float bounds [lo, hi] such that, for every finite float z >= 0, lo <= z <= hi exactly when
// IsValidDepth(z, min_depth_m, max_depth_m) (core/depth.h), for branch-free passes.
struct FloatDepthBounds {
  float lo = 0, hi = 0;
};
FloatDepthBounds FloatBoundsOf(double min_depth_m, double max_depth_m);

}  // namespace gt::shards::detail

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

#include "libgt/core/camera.h"
#include "libgt/io/npy.h"
#include "libgt/shards/sample_check.h"

namespace gt::shards::detail {

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

// Views of .npy members parsed by io::ParseNpy (not copied; alive while `arrays` is).
std::map<std::string, StoredArray> ArrayViews(const std::map<std::string, io::NpyArray>& arrays);

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

// What a checker of one stored sample keeps: its members, its problems, and the steps every
// such checker takes (sample_check.cc's pair checker, views_sample_check.cc's N-view one).
class StoredSampleChecker {
 protected:
  StoredSampleChecker(const std::map<std::string, StoredArray>& arrays,
                      const std::map<std::string, std::string_view>& images)
      : arrays_(arrays), images_(images) {}

  // check_json(), then, when it returns true, check_rest(); a JSON exception of either (a
  // field missing or of another type) as one "json: expected the fields of schemas/<schema>:
  // ..." problem. Returns the problems.
  template <typename JsonStep, typename RestSteps>
  std::vector<std::string> Run(const char* schema, JsonStep check_json, RestSteps check_rest) {
    try {
      if (check_json()) check_rest();
    } catch (const nlohmann::json::exception& e) {
      Problem("json", std::string("expected the fields of schemas/") + schema + ": " + e.what());
    }
    return problems_;
  }

  void Problem(const std::string& field, const std::string& what) {
    problems_.push_back(field + ": " + what);
  }
  // FindArray over this sample's members, its problems.
  const StoredArray* Array(const std::string& field, const char* descr,
                           const std::vector<int64_t>& shape, const std::string& shape_words) {
    return FindArray(arrays_, field, descr, shape, shape_words, &problems_);
  }
  // The json's resolution [W, H] into *width, *height; false with a problem when a side is
  // outside 1..kMaxImageSidePx.
  bool ReadResolution(const nlohmann::json& meta, int* width, int* height) {
    const nlohmann::json& res = meta.at("resolution");
    *width = res.at(0).get<int>();
    *height = res.at(1).get<int>();
    if (*width >= 1 && *height >= 1 && *width <= kMaxImageSidePx && *height <= kMaxImageSidePx) {
      return true;
    }
    Problem("json", "resolution " + res.dump() + ": expected [W, H] of 1.." +
                        std::to_string(kMaxImageSidePx) + " pixels");
    return false;
  }
  // The json matrix `j` (`name` in problems) as *K: a pinhole K (Camera::IsPinholeMatrix)
  // proper at width x height (Camera::Check); false with a "json: <name>: ..." problem.
  bool JsonCamera(const nlohmann::json& j, const std::string& name, int width, int height,
                  Eigen::Matrix3d* K);
  // The json matrix `j` as *T, a rigid pose (PoseProblem); false with a "json: <name>: ..."
  // problem.
  bool JsonPose(const nlohmann::json& j, const std::string& name, Eigen::Matrix4d* T);
  // ImageProblem of every image member.
  void CheckImages(const std::string& format, int width, int height) {
    for (const auto& [field, bytes] : images_) {
      const std::string p = ImageProblem(field, bytes, format, width, height);
      if (!p.empty()) Problem(field, p);
    }
  }

  const std::map<std::string, StoredArray>& arrays_;
  const std::map<std::string, std::string_view>& images_;
  std::vector<std::string> problems_;
};

// Float bounds [lo, hi] such that, for every finite float z >= 0, lo <= z <= hi exactly when
// IsValidDepth(z, min_depth_m, max_depth_m) (core/depth.h), for branch-free passes.
struct FloatDepthBounds {
  float lo = 0, hi = 0;
};
FloatDepthBounds FloatBoundsOf(double min_depth_m, double max_depth_m);

}  // namespace gt::shards::detail

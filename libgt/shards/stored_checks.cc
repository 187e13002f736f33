#include "libgt/shards/stored_checks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/core/pose.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"

namespace gt::shards::detail {

namespace {

// "[2, 480, 640]".
std::string ShapeText(const std::vector<int64_t>& shape) {
  std::string s = "[";
  for (size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

template <typename T>
std::string ShortestText(T v, int min_digits, int max_digits) {
  std::string text;
  for (int digits = min_digits; digits <= max_digits; ++digits) {
    std::ostringstream o;
    o.precision(digits);
    o << v;
    text = o.str();
    std::istringstream back(text);
    T read{};
    if (!std::isfinite(v) || ((back >> read) && read == v)) break;
  }
  return text;
}

}  // namespace

std::string FullPrecision(double v) { return ShortestText(v, 15, 17); }

std::string FullPrecision(float v) { return ShortestText(v, 6, 9); }

const StoredArray* FindArray(const std::map<std::string, StoredArray>& arrays,
                             const std::string& field, const char* descr,
                             const std::vector<int64_t>& shape, const std::string& shape_words,
                             std::vector<std::string>* problems) {
  const auto it = arrays.find(field);
  if (it == arrays.end()) return nullptr;
  const StoredArray& a = it->second;
  bool ok = a.descr == descr && a.shape.size() == shape.size();
  for (size_t i = 0; ok && i < shape.size(); ++i) ok = shape[i] < 0 || a.shape[i] == shape[i];
  if (ok) return &a;
  std::vector<int64_t> want = shape;
  for (size_t i = 0; i < want.size() && i < a.shape.size(); ++i) {
    if (want[i] < 0) want[i] = a.shape[i];
  }
  problems->push_back(field + ": expected " + descr + " " + ShapeText(want) + " (" + shape_words +
                      "), got " + a.descr + " " + ShapeText(a.shape));
  return nullptr;
}

std::map<std::string, StoredArray> ArrayViews(const std::map<std::string, io::NpyArray>& arrays) {
  std::map<std::string, StoredArray> views;
  for (const auto& [field, a] : arrays) views[field] = StoredArray{a.descr, a.shape, a.data.data()};
  return views;
}

Eigen::MatrixXd JsonMatrix(const nlohmann::json& j, int rows, int cols) {
  const auto fail = [&] {
    return nlohmann::json::type_error::create(
        302, "expected a " + std::to_string(rows) + "x" + std::to_string(cols) + " matrix", &j);
  };
  Eigen::MatrixXd m(rows, cols);
  if (!j.is_array() || static_cast<int>(j.size()) != rows) throw fail();
  for (int r = 0; r < rows; ++r) {
    if (!j[r].is_array() || static_cast<int>(j[r].size()) != cols) throw fail();
    for (int c = 0; c < cols; ++c) m(r, c) = j[r][c].get<double>();
  }
  return m;
}

std::string ImageProblem(const std::string& field, std::string_view bytes,
                         const std::string& format, int width, int height) {
  const std::string extension = field.substr(field.rfind('.') + 1);
  if (format != extension) {
    return "the json's image.format is " +
           (format.empty() ? std::string("null") : "\"" + format + "\"");
  }
  std::string damage = format == "png" ? io::PngDamage(bytes) : io::JpegDamage(bytes);
  if (!damage.empty()) return damage;
  try {
    const io::ImageSize size = io::DecodeImageSize(bytes, field);
    if (size.width != width || size.height != height) {
      return "image is " + std::to_string(size.width) + "x" + std::to_string(size.height) +
             ", expected the json's resolution " + std::to_string(width) + "x" +
             std::to_string(height);
    }
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool StoredSampleChecker::JsonCamera(const nlohmann::json& j, const std::string& name, int width,
                                     int height, Eigen::Matrix3d* K) {
  *K = JsonMatrix(j, 3, 3);
  std::string error;
  if (!Camera::IsPinholeMatrix(*K)) {
    Problem("json", name + ": expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
    return false;
  }
  if (!Camera::FromK(*K, width, height).Check(&error)) {
    Problem("json", name + ": " + error);
    return false;
  }
  return true;
}

bool StoredSampleChecker::JsonPose(const nlohmann::json& j, const std::string& name,
                                   Eigen::Matrix4d* T) {
  *T = JsonMatrix(j, 4, 4);
  if (const auto p = PoseProblem(*T)) {
    Problem("json", name + ": " + *p);
    return false;
  }
  return true;
}

DepthRangeM LabelDepthRange(const nlohmann::json& label_options) {
  const nlohmann::json& max = label_options.at("max_depth_m");
  return {label_options.at("min_depth_m").get<double>(),
          max.is_null() ? std::numeric_limits<double>::infinity() : max.get<double>()};
}

FloatDepthBounds FloatBoundsOf(double min_depth_m, double max_depth_m) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  float lo = static_cast<float>(min_depth_m), hi = static_cast<float>(max_depth_m);
  if (static_cast<double>(lo) < min_depth_m) lo = std::nextafter(lo, kInf);
  if (static_cast<double>(hi) > max_depth_m) hi = std::nextafter(hi, -kInf);
  return {std::max(lo, kMinPositiveDepthM), std::min(hi, std::numeric_limits<float>::max())};
}

}  // namespace gt::shards::detail

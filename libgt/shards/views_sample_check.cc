#include "libgt/shards/views_sample_check.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "libgt/core/bits.h"
#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/shards/stored_checks.h"
#include "libgt/truth/views_truth.h"

namespace gt::shards {

namespace {

using json = nlohmann::json;
using detail::FullPrecision;

std::string Pixel(size_t p, int width) {
  return "pixel (" + std::to_string(p % width) + ", " + std::to_string(p / width) + ")";
}

class ViewsSampleChecker : detail::StoredSampleChecker {
 public:
  ViewsSampleChecker(const json& meta, const std::map<std::string, StoredArray>& arrays,
                     const std::map<std::string, std::string_view>& images,
                     std::vector<uint8_t>* seen_by)
      : StoredSampleChecker(arrays, images), meta_(meta), seen_by_(seen_by) {}

  std::vector<std::string> Run() {
    return StoredSampleChecker::Run(
        "views_sample.schema.json", [&] { return CheckJson(); },
        [&] {
          CheckCameras();
          CheckDepthAndValid();
          CheckBits();
          CheckMetrics();
          CheckQueries();
          CheckTracks();
          CheckImages(image_format_, width_, height_);
        });
  }

 private:
  size_t Plane() const { return static_cast<size_t>(width_) * static_cast<size_t>(height_); }

  bool CheckJson() {
    n_ = meta_.at("num_views").get<int>();
    if (n_ < 1 || n_ > truth::kMaxViews) {
      Problem("json", "num_views " + std::to_string(n_) + ": expected 1.." +
                          std::to_string(truth::kMaxViews));
      return false;
    }
    if (!ReadResolution(meta_, &width_, &height_)) return false;
    const std::string views = " (num_views)";
    const json& frames = meta_.at("frames");
    if (!frames.is_array() || static_cast<int>(frames.size()) != n_) {
      Problem("json", "frames: expected " + std::to_string(n_) + views + " frames");
      return false;
    }
    std::set<std::string> ids;
    for (const json& f : frames) {
      if (!ids.insert(f.at("id").get<std::string>()).second) {
        Problem("json", "frames: frame id " + f.at("id").dump() + " appears twice");
        return false;
      }
    }
    bool ok = true;
    for (const char* name : {"K", "world_from_cam", "covisibility"}) {
      const json& list = meta_.at(name);
      if (!list.is_array() || static_cast<int>(list.size()) != n_) {
        Problem("json", std::string(name) + ": expected " + std::to_string(n_) + views + " " +
                            (name[0] == 'c' ? "rows" : "matrices"));
        return false;
      }
    }
    for (int i = 0; i < n_; ++i) {
      const std::string at = "[" + std::to_string(i) + "]";
      Eigen::Matrix3d K;
      Eigen::Matrix4d T;
      ok &= JsonCamera(meta_["K"][i], "K" + at, width_, height_, &K);
      ok &= JsonPose(meta_["world_from_cam"][i], "world_from_cam" + at, &T);
      K_.push_back(K);
      world_from_cam_.push_back(T);
      const json& row = meta_["covisibility"][i];
      if (!row.is_array() || static_cast<int>(row.size()) != n_) {
        Problem("json",
                "covisibility" + at + ": expected " + std::to_string(n_) + views + " entries");
        ok = false;
      }
    }
    const json& tracks = meta_.at("tracks");
    query_view_ = tracks.at("query_view").get<int>();
    num_tracks_ = tracks.at("num_tracks").get<int64_t>();
    seed_ = tracks.at("seed").get<uint64_t>();
    count_ = tracks.at("count").get<int64_t>();
    if (query_view_ < 0 || query_view_ >= n_ || num_tracks_ < 0 ||
        num_tracks_ > std::numeric_limits<int>::max() || count_ < 0 || count_ > num_tracks_) {
      Problem("json", "tracks " + tracks.dump() + ": expected query_view 0.." +
                          std::to_string(n_ - 1) + " and 0 <= count <= num_tracks");
      return false;
    }
    const detail::DepthRangeM range = detail::LabelDepthRange(meta_.at("label_options"));
    min_depth_m_ = range.min_m;
    max_depth_m_ = range.max_m;
    const json& image = meta_.at("image");
    image_format_ = image.is_null() ? "" : image.at("format").get<std::string>();
    return ok;
  }

  // intrinsics / world_from_cam: the json's matrices, value for value.
  void CheckCameras() {
    const int64_t n = n_;
    const struct {
      const char* field;
      const char* json_name;
      int size;
    } members[2] = {{"intrinsics.npy", "K", 3}, {"world_from_cam.npy", "world_from_cam", 4}};
    for (const auto& m : members) {
      const StoredArray* a = Array(m.field, "<f8", {n, m.size, m.size}, "the json's num_views");
      if (a == nullptr) continue;
      const auto* v = static_cast<const double*>(a->data);
      for (int i = 0; i < n_; ++i) {
        const Eigen::MatrixXd& want =
            m.size == 3 ? Eigen::MatrixXd(K_[i]) : Eigen::MatrixXd(world_from_cam_[i]);
        for (int k = 0; k < m.size * m.size; ++k) {
          const double got = v[static_cast<size_t>(i) * m.size * m.size + k];
          const double stored = want(k / m.size, k % m.size);
          if (got != stored) {
            Problem(m.field, "view " + std::to_string(i) + " (" + std::to_string(k / m.size) +
                                 ", " + std::to_string(k % m.size) + ") holds " +
                                 FullPrecision(got) + ", the json's " + m.json_name + "[" +
                                 std::to_string(i) + "] says " + FullPrecision(stored));
            i = n_;
            break;
          }
        }
      }
    }
  }

  // depth<i>: finite and >= 0; valid: 1 exactly where the depth is valid, 0 elsewhere.
  void CheckDepthAndValid() {
    const StoredArray* v =
        Array("valid.npy", "|u1", {n_, height_, width_}, "the json's num_views and resolution");
    const auto* valid = v ? static_cast<const uint8_t*>(v->data) : nullptr;
    const size_t plane = Plane();
    const auto [lo, hi] = detail::FloatBoundsOf(min_depth_m_, max_depth_m_);
    bool valid_ok = valid != nullptr;
    depths_.assign(n_, nullptr);
    for (int i = 0; i < n_; ++i) {
      const std::string field = "depth" + std::to_string(i) + ".npy";
      const StoredArray* a = Array(field, "<f4", {height_, width_}, "the json's resolution");
      if (a == nullptr) {
        // Without this view's depth, its valid plane still holds only 0 and 1.
        for (size_t p = 0; valid_ok && p < plane; ++p) valid_ok = valid[i * plane + p] <= 1;
        continue;
      }
      const auto* depth = static_cast<const float*>(a->data);
      const uint8_t* mask = valid ? valid + i * plane : nullptr;
      uint8_t any = 0;  // a branch-free pass first; the first pixel at fault only if there is one
      for (size_t p = 0; p < plane; ++p) {
        const float z = depth[p];
        const bool ok = (z >= 0.0f) & (z <= std::numeric_limits<float>::max());
        const uint8_t is_valid = static_cast<uint8_t>((z >= lo) & (z <= hi));
        any |= static_cast<uint8_t>(!ok) | (mask != nullptr ? mask[p] ^ is_valid : 0);
      }
      if (any == 0) {
        depths_[i] = depth;
        continue;
      }
      for (size_t p = 0; p < plane; ++p) {
        const float z = depth[p];
        if (!std::isfinite(z) || z < 0) {
          Problem(field, Pixel(p, width_) + " holds " + FullPrecision(z) +
                             "; expected metres >= 0 (0 = invalid)");
          break;
        }
        const bool is_valid = IsValidDepth(z, min_depth_m_, max_depth_m_);
        if (mask != nullptr && mask[p] != static_cast<uint8_t>(is_valid)) {
          Problem("valid.npy", "view " + std::to_string(i) + " " + Pixel(p, width_) + " holds " +
                                   std::to_string(mask[p]) + "; its depth " + FullPrecision(z) +
                                   " m is " + (is_valid ? "valid" : "invalid") +
                                   " in label_options' range [" + FullPrecision(min_depth_m_) +
                                   ", " + FullPrecision(max_depth_m_) + "] m, expected " +
                                   (is_valid ? "1" : "0"));
          valid_ok = false;
          i = n_;  // one valid.npy problem
          break;
        }
      }
    }
    if (valid_ok) valid_ = valid;
  }

  // visible_in, occluded_in, valid and the tracks: the invariants of every computed result.
  void CheckBits() {
    const std::string words = "the json's num_views and resolution";
    const StoredArray* vis = Array("visible_in.npy", "<u4", {n_, height_, width_}, words);
    const StoredArray* occ = Array("occluded_in.npy", "<u4", {n_, height_, width_}, words);
    const StoredArray* xy =
        Array("track_xy.npy", "<f4", {n_, count_, 2}, "the json's num_views and tracks.count");
    const StoredArray* state =
        Array("track_state.npy", "|u1", {n_, count_}, "the json's num_views and tracks.count");
    if (valid_ == nullptr || vis == nullptr) return;
    visible_in_ = static_cast<const uint32_t*>(vis->data);
    try {
      if (occ == nullptr || xy == nullptr || state == nullptr) {
        truth::SeenBy seen = truth::CountSeenBy(visible_in_, valid_, n_, Plane());
        if (seen_by_ != nullptr) *seen_by_ = std::move(seen.seen_by);
        return;
      }
      truth::SeenBy seen = truth::CheckStoredViewsTruth(
          visible_in_, static_cast<const uint32_t*>(occ->data), valid_, n_, Plane(),
          static_cast<const float*>(xy->data), static_cast<const uint8_t*>(state->data),
          static_cast<size_t>(count_));
      // Row i, column k: view i's valid pixels VISIBLE in k other views (and the invalid
      // ones have no bit): the VISIBLE bits off the diagonal, and the valid pixels.
      for (int i = 0; i < n_; ++i) {
        for (int k = 0; k < n_; ++k) {
          visible_bits_ += k * seen.histogram[static_cast<size_t>(i) * n_ + k];
          valid_pixels_ += seen.histogram[static_cast<size_t>(i) * n_ + k];
        }
      }
      if (seen_by_ != nullptr) *seen_by_ = std::move(seen.seen_by);
      occluded_in_ = static_cast<const uint32_t*>(occ->data);
      track_xy_ = static_cast<const float*>(xy->data);
      track_state_ = static_cast<const uint8_t*>(state->data);
    } catch (const InputError& e) {
      visible_in_ = nullptr;
      // "visible_in: ... at element k" -> "visible_in.npy: ... at element k"
      const std::string what = e.what();
      Problem(e.where() + ".npy", what.substr(e.where().size() + 2));
    }
  }

  // metrics: the bits off the diagonal (CheckBits: occluded_in has none on it), the valid
  // pixels, the ratio.
  void CheckMetrics() {
    if (occluded_in_ == nullptr) return;
    const int64_t valid = valid_pixels_, visible = visible_bits_;
    const int64_t occluded = CountSetBits(occluded_in_, Plane() * n_);
    const double ratio = visible + occluded > 0 ? static_cast<double>(occluded) /
                                                      static_cast<double>(visible + occluded)
                                                : 0.0;
    const json& m = meta_.at("metrics");
    const struct {
      const char* name;
      const char* field;
      const json& stored;
      json counted;
    } values[] = {
        {"counts.VISIBLE", "visible_in.npy", m.at("counts").at("VISIBLE"), visible},
        {"counts.OCCLUDED", "occluded_in.npy", m.at("counts").at("OCCLUDED"), occluded},
        {"valid", "valid.npy", m.at("valid"), valid},
        {"occlusion_ratio_visible", "occluded_in.npy", m.at("occlusion_ratio_visible"), ratio}};
    for (const auto& v : values) {
      if (v.stored.get<double>() != v.counted.get<double>()) {
        return Problem(v.field, std::string("its ") + v.name + " is " + v.counted.dump() +
                                    ", the json's metrics." + v.name + " says " + v.stored.dump());
      }
    }
  }

  // queries: the sampling rule's pixels of view query_view's valid mask.
  void CheckQueries() {
    const StoredArray* a = Array("queries.npy", "<i4", {count_, 2}, "the json's tracks.count");
    if (a == nullptr || valid_ == nullptr) return;
    const auto* uv = static_cast<const int32_t*>(a->data);
    const std::vector<int32_t> want =
        truth::SampleQueries(valid_ + static_cast<size_t>(query_view_) * Plane(), width_, height_,
                             static_cast<int>(num_tracks_), seed_);
    if (static_cast<int64_t>(want.size()) != 2 * count_) {
      return Problem("queries.npy",
                     "holds " + std::to_string(count_) + " queries (the json's tracks.count); " +
                         "view " + std::to_string(query_view_) + " (tracks.query_view) gives " +
                         std::to_string(want.size() / 2) +
                         " = min(tracks.num_tracks, its valid pixels)");
    }
    for (int64_t k = 0; k < count_; ++k) {
      if (uv[2 * k] != want[2 * k] || uv[2 * k + 1] != want[2 * k + 1]) {
        return Problem("queries.npy",
                       "query " + std::to_string(k) + " is (" + std::to_string(uv[2 * k]) + ", " +
                           std::to_string(uv[2 * k + 1]) + "); the sampling of view " +
                           std::to_string(query_view_) + "'s valid pixels with tracks.seed " +
                           std::to_string(seed_) + " gives (" + std::to_string(want[2 * k]) + ", " +
                           std::to_string(want[2 * k + 1]) + ")");
      }
    }
    queries_ = uv;
  }

  // The tracks against the bits at their query pixels, at the query view, and track_depth.
  void CheckTracks() {
    const StoredArray* d =
        Array("track_depth.npy", "<f4", {n_, count_}, "the json's num_views and tracks.count");
    const auto* depth = d ? static_cast<const float*>(d->data) : nullptr;
    if (depth != nullptr && track_xy_ != nullptr) {
      for (size_t k = 0; k < static_cast<size_t>(n_ * count_); ++k) {
        if (std::isnan(depth[k]) != std::isnan(track_xy_[2 * k])) {
          Problem("track_depth.npy", "element " + std::to_string(k) + " is " +
                                         FullPrecision(depth[k]) + " where track_xy is (" +
                                         FullPrecision(track_xy_[2 * k]) + ", " +
                                         FullPrecision(track_xy_[2 * k + 1]) +
                                         "); expected NaN exactly where track_xy is");
          break;
        }
      }
    }
    if (track_state_ == nullptr || queries_ == nullptr) return;
    const size_t plane = Plane();
    const size_t q0 = static_cast<size_t>(query_view_) * plane;
    const float* query_depth = depths_[query_view_];
    for (int64_t k = 0; k < count_; ++k) {
      const int u = queries_[2 * k], v = queries_[2 * k + 1];
      const size_t p = static_cast<size_t>(v) * width_ + u;
      for (int j = 0; j < n_; ++j) {
        const size_t e = static_cast<size_t>(j) * count_ + k;
        const auto state = static_cast<truth::TrackState>(track_state_[e]);
        const bool vis = (visible_in_[q0 + p] >> j) & 1, occ = (occluded_in_[q0 + p] >> j) & 1;
        std::string problem;
        if ((state == truth::TrackState::kVisible) != vis) {
          problem = std::string("is ") + truth::TrackStateName(state) + " while bit " +
                    std::to_string(j) + " of visible_in is " + (vis ? "set" : "not set");
        } else if ((state == truth::TrackState::kOccluded) != occ) {
          problem = std::string("is ") + truth::TrackStateName(state) + " while bit " +
                    std::to_string(j) + " of occluded_in is " + (occ ? "set" : "not set");
        } else if (j == query_view_ &&
                   (track_xy_[2 * e] != static_cast<float>(u) ||
                    track_xy_[2 * e + 1] != static_cast<float>(v) ||
                    (depth != nullptr && query_depth != nullptr && depth[e] != query_depth[p]))) {
          problem = "at its own view is (" + FullPrecision(track_xy_[2 * e]) + ", " +
                    FullPrecision(track_xy_[2 * e + 1]) + ")" +
                    (depth != nullptr ? " at " + FullPrecision(depth[e]) + " m" : "") +
                    "; expected its query pixel" +
                    (depth != nullptr && query_depth != nullptr
                         ? " at its depth " + FullPrecision(query_depth[p]) + " m"
                         : "");
        }
        if (!problem.empty()) {
          return Problem("track_state.npy", "track " + std::to_string(k) + " (query " +
                                                Pixel(p, width_) + " of view " +
                                                std::to_string(query_view_) + ") in view " +
                                                std::to_string(j) + " " + problem);
        }
      }
    }
  }

  const json& meta_;
  std::vector<uint8_t>* seen_by_;
  int n_ = 0, width_ = 0, height_ = 0, query_view_ = 0;
  int64_t num_tracks_ = 0, count_ = 0;
  uint64_t seed_ = 0;
  double min_depth_m_ = 0, max_depth_m_ = 0;
  std::string image_format_;
  std::vector<Eigen::Matrix3d> K_;
  std::vector<Eigen::Matrix4d> world_from_cam_;
  // Set once each has passed its checks; the later checks use only these.
  std::vector<const float*> depths_;
  const uint8_t* valid_ = nullptr;
  const uint32_t *visible_in_ = nullptr, *occluded_in_ = nullptr;
  const float* track_xy_ = nullptr;
  const uint8_t* track_state_ = nullptr;
  const int32_t* queries_ = nullptr;
  int64_t visible_bits_ = 0, valid_pixels_ = 0;  // of seen_by's histogram (CheckBits)
};

}  // namespace

std::vector<std::string> CheckViewsSampleValues(
    const nlohmann::json& meta, const std::map<std::string, StoredArray>& arrays,
    const std::map<std::string, std::string_view>& images, std::vector<uint8_t>* seen_by) {
  if (seen_by != nullptr) seen_by->clear();
  if (!meta.is_object()) return {"json: expected a JSON object"};
  return ViewsSampleChecker(meta, arrays, images, seen_by).Run();
}

std::vector<std::string> CheckViewsSampleValues(
    const nlohmann::json& meta, const std::map<std::string, io::NpyArray>& arrays,
    const std::map<std::string, std::string_view>& images, std::vector<uint8_t>* seen_by) {
  return CheckViewsSampleValues(meta, detail::ArrayViews(arrays), images, seen_by);
}

std::vector<std::string> CheckViewsSampleMembers(const nlohmann::json& meta,
                                                 const std::set<std::string>& fields) {
  std::vector<std::string> problems;
  std::set<std::string> expected = {
      "json",      "intrinsics.npy", "world_from_cam.npy", "visible_in.npy",  "occluded_in.npy",
      "valid.npy", "queries.npy",    "track_xy.npy",       "track_depth.npy", "track_state.npy"};
  int n = 0;
  std::string format;
  try {
    n = meta.at("num_views").get<int>();
    const json& image = meta.at("image");
    if (!image.is_null()) format = image.at("format").get<std::string>();
  } catch (const json::exception& e) {
    problems.push_back(
        std::string("json: expected the fields of schemas/views_sample.schema.json: ") + e.what());
    return problems;
  }
  if (n < 1 || n > truth::kMaxViews) return problems;  // CheckViewsSampleValues says so
  for (const std::string& f : std::set<std::string>(expected)) {
    if (!fields.count(f)) problems.push_back(f + ": missing (every N-view sample holds it)");
  }
  for (int i = 0; i < n; ++i) {
    const std::string views = " (the json's num_views is " + std::to_string(n) + ")";
    const std::string depth = "depth" + std::to_string(i) + ".npy";
    if (!fields.count(depth)) problems.push_back(depth + ": missing" + views);
    expected.insert(depth);
    if (format.empty()) continue;
    const std::string image = "image" + std::to_string(i) + "." + format;
    if (!fields.count(image)) {
      problems.push_back(image + ": missing (the json's image.format is \"" + format + "\")");
    }
    expected.insert(image);
  }
  for (const std::string& f : fields) {
    if (!expected.count(f)) {
      problems.push_back(f + ": not a member of an N-view sample with this json (docs/FORMATS.md)");
    }
  }
  return problems;
}

}  // namespace gt::shards

#include "libgt/shards/sample_check.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "libgt/core/bits.h"
#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/shards/stored_checks.h"

namespace gt::shards {

namespace {

using json = nlohmann::json;

// T_0to1 against cam1_from_cam0 of the two poses: the writer stores the double product, so
// only rounding of the re-computation separates them.
constexpr double kPoseTolerance = 1e-6;

using detail::FullPrecision;

class PairSampleChecker : detail::StoredSampleChecker {
 public:
  PairSampleChecker(const json& meta, const std::map<std::string, StoredArray>& arrays,
                    const std::map<std::string, std::string_view>& images)
      : StoredSampleChecker(arrays, images), meta_(meta) {}

  std::vector<std::string> Run() {
    return StoredSampleChecker::Run(
        "sample.schema.json", [&] { return CheckJson(); },
        [&] {
          CheckLabels();
          CheckDepth();
          CheckCells();
          CheckMatches();
          CheckOccupancy();
          const json& image = meta_.at("image");
          CheckImages(image.is_null() ? "" : image.at("format").get<std::string>(), width_,
                      height_);
        });
  }

 private:
  bool CheckJson() {
    if (!ReadResolution(meta_, &width_, &height_)) return false;
    bool ok = true;
    for (const char* k : {"K0", "K1"}) {
      Eigen::Matrix3d K;
      ok &= JsonCamera(meta_.at(k), k, width_, height_, &K);
    }
    Eigen::Matrix4d pose[3];
    const char* pose_names[3] = {"world_from_cam0", "world_from_cam1", "T_0to1"};
    for (int i = 0; i < 3; ++i) ok &= JsonPose(meta_.at(pose_names[i]), pose_names[i], &pose[i]);
    if (ok) {
      const Eigen::Matrix4d cam1_from_cam0 = pose[1].inverse() * pose[0];
      const double scale = 1 + pose[2].topRightCorner<3, 1>().cwiseAbs().maxCoeff();
      const double off = (cam1_from_cam0 - pose[2]).cwiseAbs().maxCoeff();
      if (!(off <= kPoseTolerance * scale)) {
        Problem("json",
                "T_0to1 differs from cam1_from_cam0 = inverse(world_from_cam1) * "
                "world_from_cam0 by " +
                    FullPrecision(off) + " (expected within " +
                    FullPrecision(kPoseTolerance * scale) + ")");
      }
    }
    const json& po = meta_.at("patch_options");
    stride_ = po.at("stride").get<int>();
    mutual_ = po.at("mutual").get<bool>();
    try {
      anchor_ = ParseAnchor(po.at("anchor").get<std::string>(), "patch_options.anchor");
    } catch (const InputError& e) {
      Problem("json", e.what());
      return false;
    }
    if (stride_ < 1 || stride_ > width_ || stride_ > height_) {
      Problem("json", "patch_options.stride " + std::to_string(stride_) +
                          ": expected 1 .. the image's shorter side");
      return false;
    }
    score_stride_ = meta_.at("score_stride").get<int>();
    if (score_stride_ < 1) {
      Problem("json", "score_stride " + std::to_string(score_stride_) + ": expected >= 1");
      return false;
    }
    const json& m = meta_.at("matches");
    total_ = m.at("total").get<int64_t>();
    for (int t = 0; t < 3; ++t) type_counts_[t] = m.at(kTypeNames[t]).get<int64_t>();
    if (total_ < 0 || type_counts_[0] < 0 || type_counts_[1] < 0 || type_counts_[2] < 0 ||
        type_counts_[0] + type_counts_[1] + type_counts_[2] != total_) {
      Problem("json", "matches " + m.dump() + ": expected counts >= 0 with vv + vo + ov = total");
      return false;
    }
    const detail::DepthRangeM range = detail::LabelDepthRange(meta_.at("label_options"));
    min_depth_m_ = range.min_m;
    max_depth_m_ = range.max_m;
    return ok;
  }

  // label01/label10: codes, then their counts and ratios against metrics and score_metrics.
  void CheckLabels() {
    const char* fields[2] = {"label01.npy", "label10.npy"};
    const char* directions[2] = {"01", "10"};
    for (int d = 0; d < 2; ++d) {
      const StoredArray* a = Array(fields[d], "|u1", {height_, width_}, "the json's resolution");
      if (a == nullptr) continue;
      const auto* codes = static_cast<const uint8_t*>(a->data);
      const size_t n = static_cast<size_t>(width_) * height_;
      DirectionMetrics full;
      try {
        full = MetricsFromLabelCodes(codes, width_, height_, 1);  // throws on a code past 5
      } catch (const InputError&) {
        const size_t p = static_cast<size_t>(
            std::find_if(codes, codes + n, [](uint8_t c) { return c >= kNumPixelLabels; }) - codes);
        Problem(fields[d], "pixel (" + std::to_string(p % width_) + ", " +
                               std::to_string(p / width_) + ") holds " + std::to_string(codes[p]) +
                               "; expected a label code 0.." + std::to_string(kNumPixelLabels - 1));
        continue;
      }
      labels_[d] = codes;
      CompareMetrics(fields[d], "metrics", directions[d], full);
      CompareMetrics(fields[d], "score_metrics", directions[d],
                     MetricsFromLabelCodes(codes, width_, height_, score_stride_));
    }
  }

  void CompareMetrics(const std::string& field, const char* name, const char* direction,
                      const DirectionMetrics& m) {
    const std::string where = std::string(name) + "[\"" + direction + "\"]";
    const json& j = meta_.at(name).at(direction);
    auto differs = [&](const std::string& what, const json& stored, const json& counted) {
      Problem(field, "its " + what + " is " + counted.dump() + ", the json's " + where + " says " +
                         stored.dump());
    };
    if (j.at("sampled").get<int64_t>() != m.sampled) {
      return differs("sampled pixel count", j.at("sampled"), m.sampled);
    }
    for (int k = 0; k < kNumPixelLabels; ++k) {
      const char* label = PixelLabelName(static_cast<PixelLabel>(k));
      if (j.at("counts").at(label).get<int64_t>() != m.counts[k]) {
        return differs(std::string(label) + " count", j.at("counts").at(label), m.counts[k]);
      }
    }
    const std::pair<const char*, double> values[] = {
        {"valid", static_cast<double>(m.valid)},
        {"overlap", m.overlap},
        {"consistent_overlap", m.consistent_overlap},
        {"occlusion_ratio", m.occlusion_ratio},
        {"occlusion_ratio_visible", m.occlusion_ratio_visible}};
    for (const auto& [key, value] : values) {
      if (j.at(key).get<double>() != value) return differs(key, j.at(key), value);
    }
  }

  void CheckDepth() {
    const char* fields[2] = {"depth0.npy", "depth1.npy"};
    for (int d = 0; d < 2; ++d) {
      const StoredArray* a = Array(fields[d], "<f4", {height_, width_}, "the json's resolution");
      if (a == nullptr) continue;
      const auto* depth = static_cast<const float*>(a->data);
      const size_t n = static_cast<size_t>(width_) * height_;
      const uint8_t* labels = labels_[d];
      const auto no_depth_code = static_cast<uint8_t>(PixelLabel::kNoDepth);
      // A branch-free pass (vectorised) first; the first pixel at fault is found only when
      // there is one. Float bounds equal to IsValidDepth's double comparisons.
      const auto [lo, hi] = detail::FloatBoundsOf(min_depth_m_, max_depth_m_);
      uint8_t any = 0;
      for (size_t p = 0; p < n; ++p) {
        const float z = depth[p];
        const bool ok = (z >= 0.0f) & (z <= std::numeric_limits<float>::max());
        const bool valid = (z >= lo) & (z <= hi);
        const bool says_no_depth = labels != nullptr ? labels[p] == no_depth_code : !valid;
        any |= static_cast<uint8_t>(!ok | (says_no_depth == valid));
      }
      if (any == 0) continue;
      for (size_t p = 0; p < n; ++p) {
        const float z = depth[p];
        const bool bad = !std::isfinite(z) || z < 0;
        const bool no_depth = !IsValidDepth(z, min_depth_m_, max_depth_m_);
        if (!bad && (labels == nullptr || (labels[p] == no_depth_code) == no_depth)) continue;
        const std::string at =
            "pixel (" + std::to_string(p % width_) + ", " + std::to_string(p / width_) + ")";
        if (bad) {
          Problem(fields[d],
                  at + " holds " + FullPrecision(z) + "; expected metres >= 0 (0 = invalid)");
        } else {
          Problem(fields[d], at + " holds " + FullPrecision(z) + " m, " +
                                 (no_depth ? "invalid" : "valid") + " in label_options' range [" +
                                 FullPrecision(min_depth_m_) + ", " + FullPrecision(max_depth_m_) +
                                 "] m, while " + (d == 0 ? "label01" : "label10") + " says " +
                                 PixelLabelName(static_cast<PixelLabel>(labels[p])));
        }
        break;
      }
    }
  }

  // cells0/cells1: the labels at the cells' anchor pixels.
  void CheckCells() {
    const char* fields[2] = {"cells0.npy", "cells1.npy"};
    const int cells_w = width_ / stride_, cells_h = height_ / stride_;
    for (int d = 0; d < 2; ++d) {
      const StoredArray* a = Array(fields[d], "|u1", {cells_h, cells_w},
                                   "the json's resolution / patch_options.stride");
      if (a == nullptr) continue;
      const auto* cells = static_cast<const uint8_t*>(a->data);
      for (int r = 0; r < cells_h; ++r) {
        for (int c = 0; c < cells_w; ++c) {
          const uint8_t cell = cells[static_cast<size_t>(r) * cells_w + c];
          const int u = AnchorPixel(c, stride_, anchor_), v = AnchorPixel(r, stride_, anchor_);
          const bool bad_code = cell >= kNumPixelLabels;
          if (!bad_code && labels_[d] == nullptr) continue;
          if (bad_code || labels_[d][static_cast<size_t>(v) * width_ + u] != cell) {
            Problem(fields[d],
                    "cell " + std::to_string(r * cells_w + c) + " holds " + std::to_string(cell) +
                        "; expected " +
                        (bad_code ? std::string("a label code 0..5")
                                  : std::string("the label at its anchor pixel (") +
                                        std::to_string(u) + ", " + std::to_string(v) + "), " +
                                        std::to_string(
                                            labels_[d][static_cast<size_t>(v) * width_ + u])));
            r = cells_h;
            cells = nullptr;  // not used for the matches' rules
            break;
          }
        }
      }
      cells_[d] = cells;
    }
  }

  void CheckMatches() {
    const StoredArray* pairs = Array("matches.npy", "<i4", {total_, 2}, "the json's matches.total");
    const StoredArray* types = Array("match_type.npy", "|u1", {total_}, "the json's matches.total");
    const StoredArray* xy = Array("match_xy.npy", "<f4", {total_, 2}, "the json's matches.total");
    if (pairs == nullptr || types == nullptr) return;
    const auto* ij = static_cast<const int32_t*>(pairs->data);
    const auto* type = static_cast<const uint8_t*>(types->data);
    const auto* pts = xy ? static_cast<const float*>(xy->data) : nullptr;
    const int cells_w = width_ / stride_, cells_h = height_ / stride_;
    const int64_t cells = static_cast<int64_t>(cells_w) * cells_h;
    int64_t counted[3] = {0, 0, 0};
    int64_t previous_type = 0, previous_cell = -1;
    for (int64_t k = 0; k < total_; ++k) {
      const int64_t i = ij[2 * k], j = ij[2 * k + 1];
      auto row = [k] { return "row " + std::to_string(k); };  // for a problem only
      if (type[k] > 2) {
        return Problem("match_type.npy", row() + " is " + std::to_string(type[k]) +
                                             "; expected 0 (vv), 1 (vo) or 2 (ov)");
      }
      for (int side = 0; side < 2; ++side) {
        const int64_t cell = side == 0 ? i : j;
        if (cell < 0 || cell >= cells) {
          return Problem("matches.npy", row() + " names cell " + std::to_string(cell) +
                                            " of image " + std::to_string(side) + ", which has " +
                                            std::to_string(cells) + " cells (" +
                                            std::to_string(width_) + "x" + std::to_string(height_) +
                                            ", stride " + std::to_string(stride_) + ")");
        }
      }
      ++counted[type[k]];
      // The writer's order: vv, then vo (each by cell of image 0), then ov (by cell of 1).
      const int64_t order_cell = type[k] == 2 ? j : i;
      if (type[k] < previous_type || (type[k] == previous_type && order_cell <= previous_cell)) {
        return Problem("matches.npy", row() + " (" + kTypeNames[type[k]] +
                                          ") is out of the order vv, vo by cell of image 0, "
                                          "then ov by cell of image 1, one match per cell");
      }
      previous_type = type[k];
      previous_cell = order_cell;
      // Each match by its rule: its anchor's label, and the target cell of match_xy.
      const uint8_t* anchor_cells = cells_[type[k] == 2 ? 1 : 0];
      const int64_t anchor = type[k] == 2 ? j : i;
      const uint8_t want = type[k] == 0 ? static_cast<uint8_t>(PixelLabel::kVisible)
                                        : static_cast<uint8_t>(PixelLabel::kOccluded);
      if (anchor_cells != nullptr && anchor_cells[anchor] != want) {
        return Problem("matches.npy", row() + " (" + kTypeNames[type[k]] + ") starts from cell " +
                                          std::to_string(anchor) + " of image " +
                                          (type[k] == 2 ? "1" : "0") + ", labelled " +
                                          std::to_string(anchor_cells[anchor]) + " in cells" +
                                          (type[k] == 2 ? "1" : "0") + ".npy; expected " +
                                          PixelLabelName(static_cast<PixelLabel>(want)));
      }
      if (type[k] == 0 && mutual_ && cells_[1] != nullptr &&
          cells_[1][j] != static_cast<uint8_t>(PixelLabel::kVisible)) {
        return Problem("matches.npy", row() + " (vv, mutual) ends in cell " + std::to_string(j) +
                                          " of image 1, labelled " + std::to_string(cells_[1][j]) +
                                          " in cells1.npy; expected VISIBLE");
      }
      if (pts != nullptr) {
        const int64_t target =
            TargetCell(pts[2 * k], pts[2 * k + 1], cells_w, cells_h, stride_, anchor_);
        const int64_t other = type[k] == 2 ? i : j;
        if (target != other) {
          return Problem("match_xy.npy", row() + " (" + FullPrecision(pts[2 * k]) + ", " +
                                             FullPrecision(pts[2 * k + 1]) + ") lies in cell " +
                                             std::to_string(target) + " of image " +
                                             (type[k] == 2 ? "0" : "1") + ", matches.npy says " +
                                             std::to_string(other));
        }
      }
    }
    for (int t = 0; t < 3; ++t) {
      if (counted[t] != type_counts_[t]) {
        return Problem("match_type.npy", "holds " + std::to_string(counted[t]) + " " +
                                             kTypeNames[t] + " matches, the json's matches." +
                                             kTypeNames[t] + " says " +
                                             std::to_string(type_counts_[t]));
      }
    }
  }

  void CheckOccupancy() {
    const json& occ = meta_.at("occupancy");
    if (occ.is_null()) return;
    // The bin edges and the grid [w, h] (samples written before the occupancy renames:
    // "bin_edges_m", no grid: the arrays' own extent, the same for all of them).
    const json& edges = occ.contains("bins") ? occ["bins"].at("edges_m") : occ.at("bin_edges_m");
    int64_t gw = -1, gh = -1;
    if (occ.contains("grid")) {
      gw = occ["grid"].at(0).get<int64_t>();
      gh = occ["grid"].at(1).get<int64_t>();
    }
    if (!edges.is_array() || edges.size() < 2 || edges.size() > 65 ||
        (occ.contains("grid") && (gw < 1 || gh < 1))) {
      return Problem("json", "occupancy: expected a grid [w, h] >= 1 and 2..65 bin edges");
    }
    const int bins = static_cast<int>(edges.size()) - 1;
    const uint64_t mask = bins == 64 ? ~uint64_t{0} : (uint64_t{1} << bins) - 1;
    const std::string grid_words = occ.contains("grid") ? "the json's occupancy.grid"
                                                        : "the shape of the other occupancy arrays";
    for (int c = 0; c < 2; ++c) {
      const std::string n = std::to_string(c);
      if (gw < 0) {  // no grid in the json: the first occupancy array's
        for (const char* f : {"occ0.npy", "occ0_dense.npy", "occ1.npy", "occ1_dense.npy"}) {
          const auto it = arrays_.find(f);
          if (it != arrays_.end() && it->second.shape.size() >= 2) {
            gh = it->second.shape[it->second.shape.size() - 2];
            gw = it->second.shape.back();
            break;
          }
        }
      }
      if (gw < 0) return;  // no occupancy array at all
      const StoredArray* o = Array("occ" + n + ".npy", "<u8", {gh, gw}, grid_words);
      const StoredArray* k = Array("known" + n + ".npy", "<u8", {gh, gw}, grid_words);
      const StoredArray* dense =
          Array("occ" + n + "_dense.npy", "|u1", {bins, gh, gw}, "bins x " + grid_words);
      const size_t plane = static_cast<size_t>(gw) * static_cast<size_t>(gh);
      const auto* ow = o ? static_cast<const uint64_t*>(o->data) : nullptr;
      const auto* kw = k ? static_cast<const uint64_t*>(k->data) : nullptr;
      const auto* dv = dense ? static_cast<const uint8_t*>(dense->data) : nullptr;
      int64_t occupied = 0, known = 0;
      if (ow != nullptr && kw != nullptr) {
        uint64_t stray = 0;  // a branch-free pass first, the cell at fault only when needed
        for (size_t p = 0; p < plane; ++p) stray |= (ow[p] & ~kw[p]) | (kw[p] & ~mask);
        occupied = CountSetBits(ow, plane);
        known = CountSetBits(kw, plane);
        for (size_t p = 0; stray != 0 && p < plane; ++p) {
          if ((ow[p] & ~kw[p]) != 0 || (kw[p] & ~mask) != 0) {
            return Problem("occ" + n + ".npy", "cell " + std::to_string(p) +
                                                   ": expected occupied bins within the known "
                                                   "ones and no bit past bin " +
                                                   std::to_string(bins - 1));
          }
        }
      } else if (dv != nullptr) {
        int64_t odd = 0;  // counted branch-free first (vectorised)
        for (size_t q = 0; q < plane * bins; ++q) {
          odd += (dv[q] != 0) & (dv[q] != 1) & (dv[q] != 255);
          occupied += dv[q] == 1;
          known += dv[q] != 255;
        }
        for (size_t q = 0; odd != 0 && q < plane * bins; ++q) {
          if (dv[q] != 0 && dv[q] != 1 && dv[q] != 255) {
            return Problem("occ" + n + "_dense.npy",
                           "holds " + std::to_string(dv[q]) + " at item " + std::to_string(q) +
                               "; expected 0 (free), 1 (occupied) or 255 (unknown)");
          }
        }
      } else {
        continue;
      }
      if (ow != nullptr && kw != nullptr && dv != nullptr) {
        // The dense value the words give: 255 unknown, else the occupied bit.
        auto word_value = [&](int b, size_t p) {
          const auto k = static_cast<uint8_t>((kw[p] >> b) & 1);
          const auto o = static_cast<uint8_t>((ow[p] >> b) & 1);
          return static_cast<uint8_t>(255 * (1 - k) + (k & o));
        };
        uint8_t differ = 0;  // a branch-free pass first
        for (int b = 0; b < bins; ++b) {
          for (size_t p = 0; p < plane; ++p) differ |= dv[b * plane + p] ^ word_value(b, p);
        }
        for (int b = 0; differ != 0 && b < bins; ++b) {
          for (size_t p = 0; p < plane; ++p) {
            const uint8_t want = word_value(b, p);
            if (dv[b * plane + p] != want) {
              return Problem("occ" + n + "_dense.npy",
                             "bin " + std::to_string(b) + " of cell " + std::to_string(p) +
                                 " holds " + std::to_string(dv[b * plane + p]) + "; the words occ" +
                                 n + "/known" + n + " say " + std::to_string(want));
            }
          }
        }
      }
      if (!occ.contains("counts" + n)) continue;
      const json& counts = occ["counts" + n];
      const int64_t stored[3] = {counts.at("occupied").get<int64_t>(),
                                 counts.at("free").get<int64_t>(),
                                 counts.at("unknown").get<int64_t>()};
      const int64_t found[3] = {occupied, known - occupied,
                                static_cast<int64_t>(plane) * bins - known};
      const char* names[3] = {"occupied", "free", "unknown"};
      for (int i = 0; i < 3; ++i) {
        if (stored[i] != found[i]) {
          return Problem(
              dv != nullptr && ow == nullptr ? "occ" + n + "_dense.npy" : "occ" + n + ".npy",
              "holds " + std::to_string(found[i]) + " " + names[i] +
                  " bins, the json's occupancy.counts" + n + " says " + std::to_string(stored[i]));
        }
      }
    }
  }

  static constexpr const char* kTypeNames[3] = {"vv", "vo", "ov"};

  const json& meta_;
  int width_ = 0, height_ = 0, stride_ = 1, score_stride_ = 1;
  bool mutual_ = true;
  Anchor anchor_ = Anchor::kCenter;
  int64_t total_ = 0;
  int64_t type_counts_[3] = {0, 0, 0};
  double min_depth_m_ = 0, max_depth_m_ = 0;
  const uint8_t* labels_[2] = {nullptr, nullptr};  // when stored and of valid codes
  const uint8_t* cells_[2] = {nullptr, nullptr};   // when stored and of valid shape
};

}  // namespace

std::vector<std::string> CheckPairSampleValues(
    const nlohmann::json& meta, const std::map<std::string, StoredArray>& arrays,
    const std::map<std::string, std::string_view>& images) {
  if (!meta.is_object()) return {"json: expected a JSON object"};
  return PairSampleChecker(meta, arrays, images).Run();
}

std::vector<std::string> CheckPairSampleValues(
    const nlohmann::json& meta, const std::map<std::string, io::NpyArray>& arrays,
    const std::map<std::string, std::string_view>& images) {
  return CheckPairSampleValues(meta, detail::ArrayViews(arrays), images);
}

std::vector<std::string> CheckPairSampleMembers(const nlohmann::json& meta,
                                                const std::set<std::string>& fields) {
  std::vector<std::string> problems;
  std::set<std::string> expected = {"json", "matches.npy", "match_type.npy", "match_xy.npy"};
  auto group = [&](std::vector<std::string> names, const char* what) {
    size_t present = 0;
    for (const std::string& n : names) present += fields.count(n);
    if (present == 0) return;
    for (const std::string& n : names) {
      if (!fields.count(n)) problems.push_back(n + ": missing (the sample holds " + what + ")");
      expected.insert(n);
    }
  };
  group({"label01.npy", "label10.npy", "cells0.npy", "cells1.npy"},
        "other label fields: label01, label10, cells0 and cells1 go together");
  group({"depth0.npy", "depth1.npy"}, "the other depth");
  try {
    const json& image = meta.at("image");
    if (!image.is_null()) {
      const std::string format = image.at("format").get<std::string>();
      for (const char* c : {"0", "1"}) {
        const std::string n = std::string("image") + c + "." + format;
        if (!fields.count(n)) {
          problems.push_back(n + ": missing (the json's image.format is \"" + format + "\")");
        }
        expected.insert(n);
      }
    }
    const json& occ = meta.at("occupancy");
    if (!occ.is_null()) {
      const std::string encoding = occ.at("encoding").get<std::string>();
      std::vector<std::string> names;
      if (encoding != "dense") {
        names.insert(names.end(), {"occ0.npy", "known0.npy", "occ1.npy", "known1.npy"});
      }
      if (encoding != "packed") names.insert(names.end(), {"occ0_dense.npy", "occ1_dense.npy"});
      for (const std::string& n : names) {
        if (!fields.count(n)) {
          problems.push_back(n + ": missing (the json's occupancy.encoding is \"" + encoding +
                             "\")");
        }
        expected.insert(n);
      }
    }
  } catch (const json::exception& e) {
    problems.push_back(std::string("json: expected the fields of schemas/sample.schema.json: ") +
                       e.what());
    return problems;
  }
  for (const char* n : {"json", "matches.npy", "match_type.npy", "match_xy.npy"}) {
    if (!fields.count(n)) problems.push_back(std::string(n) + ": missing (every sample holds it)");
  }
  for (const std::string& f : fields) {
    if (!expected.count(f)) {
      problems.push_back(f + ": not a member of a pair sample with this json (docs/FORMATS.md)");
    }
  }
  return problems;
}

}  // namespace gt::shards

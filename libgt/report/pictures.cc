#include "libgt/report/pictures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "libgt/core/error.h"
#include "libgt/io/codec.h"
#include "libgt/report/canvas.h"
#include "libgt/report/page.h"

namespace gt::report {
namespace {

const char* const kLabelNames[6] = {"NO_DEPTH", "OUT_OF_VIEW",  "VISIBLE",
                                    "OCCLUDED", "INCONSISTENT", "UNKNOWN"};

void CheckBgr(const cv::Mat& image, const std::string& what) {
  if (image.empty() || image.type() != CV_8UC3) {
    throw InputError(what, "expected a non-empty 8-bit BGR image (CV_8UC3)");
  }
}

void CheckVolume(const gt::occupancy::FrustumVolume& v) {
  const size_t n = static_cast<size_t>(std::max(v.width, 0)) * std::max(v.height, 0);
  if (v.width <= 0 || v.height <= 0 || v.occ.size() != n || v.known.size() != n) {
    throw InputError("occupancy", "expected occ and known of size height*width > 0");
  }
  if (v.edges_m.size() < 2 || v.edges_m.size() > 65) {
    throw InputError("occupancy", "expected 2..65 bin edges (1..64 bins)");
  }
}

std::string Metres(double m) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f m", m);
  return buf;
}

// 256 BGR colours of COLORMAP_TURBO, index 0 (dark blue) … 255 (dark red).
std::vector<cv::Vec3b> TurboLut() {
  cv::Mat ramp(256, 1, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<uint8_t>(i, 0) = static_cast<uint8_t>(i);
  cv::Mat colored;
  cv::applyColorMap(ramp, colored, cv::COLORMAP_TURBO);
  std::vector<cv::Vec3b> lut(256);
  for (int i = 0; i < 256; ++i) lut[i] = colored.at<cv::Vec3b>(i, 0);
  return lut;
}

// Colour-map index of bin k of num_bins: near (k = 0) → 255 (red), far → 0 (blue).
int BinLutIndex(int k, int num_bins) {
  if (num_bins <= 1) return 255;
  return static_cast<int>(std::lround(255.0 * (1.0 - static_cast<double>(k) / (num_bins - 1))));
}

int SliceRow(const gt::occupancy::FrustumVolume& v, const OccupancyPictureOptions& o) {
  const int row = o.slice_row < 0 ? v.height / 2 : o.slice_row;
  if (row >= v.height) {
    throw InputError("--slice-row", "expected a row < " + std::to_string(v.height));
  }
  return row;
}

}  // namespace

Rgb MatchTypeColor(uint8_t type) {
  GT_ASSERT(type <= 2);
  return type == 0 ? kMatchColorVv : type == 1 ? kMatchColorVo : kMatchColorOv;
}

cv::Mat PrepareImage(const cv::Mat& image, int width, int height) {
  GT_ASSERT(width > 0 && height > 0);
  if (image.empty()) return cv::Mat(height, width, CV_8UC3, cv::Scalar(128, 128, 128));
  cv::Mat img8;
  if (image.depth() == CV_16U) {
    image.convertTo(img8, CV_8U, 1.0 / 257.0);
  } else if (image.depth() == CV_8U) {
    img8 = image;
  } else {
    throw InputError("image", "expected an 8- or 16-bit image");
  }
  cv::Mat bgr;
  if (img8.channels() == 1) {
    cv::cvtColor(img8, bgr, cv::COLOR_GRAY2BGR);
  } else if (img8.channels() == 4) {
    cv::cvtColor(img8, bgr, cv::COLOR_BGRA2BGR);
  } else if (img8.channels() == 3) {
    bgr = img8;
  } else {
    throw InputError("image", "expected 1, 3 or 4 channels");
  }
  if (bgr.cols == width && bgr.rows == height) return bgr.clone();
  cv::Mat out;
  cv::resize(bgr, out, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
  return out;
}

std::vector<size_t> SelectMatchSubset(const std::vector<uint8_t>& match_type, int max_lines,
                                      uint64_t seed) {
  std::vector<size_t> all(match_type.size());
  std::iota(all.begin(), all.end(), size_t{0});
  if (max_lines < 0) max_lines = 0;
  if (match_type.size() <= static_cast<size_t>(max_lines)) return all;

  std::array<std::vector<size_t>, 256> by_type;
  for (size_t i = 0; i < match_type.size(); ++i) by_type[match_type[i]].push_back(i);
  std::vector<int> present;
  for (int t = 0; t < 256; ++t) {
    if (!by_type[t].empty()) present.push_back(t);
  }
  // Smallest groups first, so that an unused share passes on to the larger ones.
  std::stable_sort(present.begin(), present.end(),
                   [&](int a, int b) { return by_type[a].size() < by_type[b].size(); });
  const uint64_t seed_hash = Mix64(seed);
  std::vector<size_t> chosen;
  size_t remaining = static_cast<size_t>(max_lines);
  for (size_t g = 0; g < present.size(); ++g) {
    std::vector<size_t>& group = by_type[present[g]];
    const size_t share = remaining / (present.size() - g);
    const size_t take = std::min(group.size(), share);
    std::vector<std::pair<uint64_t, size_t>> keyed;
    keyed.reserve(group.size());
    for (size_t idx : group) keyed.emplace_back(Mix64(seed_hash ^ idx), idx);
    std::partial_sort(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(take),
                      keyed.end());
    for (size_t k = 0; k < take; ++k) chosen.push_back(keyed[k].second);
    remaining -= take;
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

bool MatchPictureOptions::Check(std::string* error) const {
  if (!(text_scale >= 0.5 && text_scale <= 4.0)) {
    *error = "text_scale: expected a number in [0.5, 4]";
    return false;
  }
  if (max_lines <= 0) {
    *error = "max_lines: expected > 0";
    return false;
  }
  if (stride < 1) {
    *error = "stride: expected >= 1";
    return false;
  }
  if (thickness < 1 || thickness > 8) {
    *error = "thickness: expected 1..8";
    return false;
  }
  return true;
}

cv::Mat RenderMatches(const cv::Mat& image0, const cv::Mat& image1, const gt::PatchMatches& matches,
                      const MatchPictureOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("match picture options", error);
  CheckBgr(image0, "image0");
  CheckBgr(image1, "image1");
  const size_t n = matches.match_type.size();
  if (matches.matches.size() != 2 * n || matches.match_xy.size() != 2 * n) {
    throw InputError("matches", "expected matches [M, 2], match_type [M] and match_xy [M, 2]");
  }
  const int s = options.stride;
  const int cw0 = matches.cells_w0 > 0 ? matches.cells_w0 : image0.cols / s;
  const int ch0 = matches.cells_h0 > 0 ? matches.cells_h0 : image0.rows / s;
  const int cw1 = matches.cells_w1 > 0 ? matches.cells_w1 : image1.cols / s;
  const int ch1 = matches.cells_h1 > 0 ? matches.cells_h1 : image1.rows / s;
  const int64_t cells0 = static_cast<int64_t>(cw0) * ch0;
  const int64_t cells1 = static_cast<int64_t>(cw1) * ch1;

  std::array<int64_t, 3> counts{};
  for (size_t k = 0; k < n; ++k) {
    const uint8_t t = matches.match_type[k];
    if (t > 2) throw InputError("match_type", "expected codes 0 (vv), 1 (vo), 2 (ov)");
    const int32_t i = matches.matches[2 * k], j = matches.matches[2 * k + 1];
    if (i < 0 || i >= cells0 || j < 0 || j >= cells1) {
      throw InputError("matches", "match " + std::to_string(k) + ": cell outside the " +
                                      std::to_string(cw0) + "x" + std::to_string(ch0) + " / " +
                                      std::to_string(cw1) + "x" + std::to_string(ch1) + " grids");
    }
    if (!std::isfinite(matches.match_xy[2 * k]) || !std::isfinite(matches.match_xy[2 * k + 1])) {
      throw InputError("match_xy", "match " + std::to_string(k) + ": expected finite x, y");
    }
    ++counts[t];
  }

  const int x1 = image0.cols + kPanelGap;
  cv::Mat canvas = SideBySide(image0, image1);
  const std::vector<size_t> subset =
      SelectMatchSubset(matches.match_type, options.max_lines, options.seed);
  auto to_point = [](double x, double y, int dx) {
    return cv::Point(static_cast<int>(std::lround(x)) + dx, static_cast<int>(std::lround(y)));
  };
  for (size_t k : subset) {
    const uint8_t t = matches.match_type[k];
    const int32_t i = matches.matches[2 * k], j = matches.matches[2 * k + 1];
    const double mx = matches.match_xy[2 * k], my = matches.match_xy[2 * k + 1];
    cv::Point p0, p1;
    if (t == 2) {  // ov: warped anchor of image 1 in image 0 → anchor of cell j
      p0 = to_point(mx, my, 0);
      p1 = cv::Point(AnchorPixel(j % cw1, s, options.anchor) + x1,
                     AnchorPixel(j / cw1, s, options.anchor));
    } else {  // vv, vo: anchor of cell i → warped anchor in image 1
      p0 = cv::Point(AnchorPixel(i % cw0, s, options.anchor),
                     AnchorPixel(i / cw0, s, options.anchor));
      p1 = to_point(mx, my, x1);
    }
    const cv::Scalar color = MatchTypeColor(t).Scalar();
    cv::line(canvas, p0, p1, color, options.thickness, cv::LINE_8);
    cv::circle(canvas, p0, 2, color, cv::FILLED, cv::LINE_8);
    cv::circle(canvas, p1, 2, color, cv::FILLED, cv::LINE_8);
  }
  if (!options.legend) return canvas;

  std::vector<LegendEntry> entries = {
      {kMatchColorVv, "vv (visible-visible) " + std::to_string(counts[0])},
      {kMatchColorVo, "vo (visible-occluded) " + std::to_string(counts[1])},
      {kMatchColorOv, "ov (occluded-visible) " + std::to_string(counts[2])},
  };
  std::string shown = "lines: " + std::to_string(subset.size()) + " of " + std::to_string(n);
  return StackVertical({canvas, LegendStrip(entries, canvas.cols, 3, shown, options.text_scale)});
}

bool PredictionPictureOptions::Check(std::string* error) const {
  if (!(text_scale >= 0.5 && text_scale <= 4.0)) {
    *error = "text_scale: expected a number in [0.5, 4]";
    return false;
  }
  if (max_lines <= 0) {
    *error = "max_lines: expected > 0";
    return false;
  }
  if (!(alpha >= 0.0 && alpha <= 1.0)) {
    *error = "alpha: expected a number in [0, 1]";
    return false;
  }
  return true;
}

cv::Mat RenderPredictedMatches(const cv::Mat& image0, const LabelMap& labels01,
                               const cv::Mat& image1, const LabelMap& labels10,
                               const std::vector<float>& kpts0, const std::vector<float>& kpts1,
                               const std::vector<PredictionVerdict>& verdicts,
                               const PredictionPictureOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("prediction picture options", error);
  const size_t n = verdicts.size();
  if (kpts0.size() != 2 * n || kpts1.size() != 2 * n) {
    throw InputError("predictions", "expected kpts0 [N, 2], kpts1 [N, 2] and N verdicts");
  }
  std::vector<uint8_t> groups(n);
  std::array<int64_t, 3> counts{};
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(kpts0[2 * k]) || !std::isfinite(kpts0[2 * k + 1]) ||
        !std::isfinite(kpts1[2 * k]) || !std::isfinite(kpts1[2 * k + 1])) {
      throw InputError("predictions", "match " + std::to_string(k) + ": expected finite x, y");
    }
    groups[k] = static_cast<uint8_t>(verdicts[k]);
    if (groups[k] > 2) throw InputError("predictions", "expected verdicts 0, 1, 2");
    ++counts[groups[k]];
  }
  const cv::Mat over0 = OverlayLabels(image0, labels01, options.alpha);
  const cv::Mat over1 = OverlayLabels(image1, labels10, options.alpha);
  const int x1 = over0.cols + kPanelGap;
  cv::Mat canvas = SideBySide(over0, over1);
  const std::vector<size_t> subset = SelectMatchSubset(groups, options.max_lines, options.seed);
  auto to_point = [](double x, double y, int dx) {
    return cv::Point(static_cast<int>(std::lround(x)) + dx, static_cast<int>(std::lround(y)));
  };
  const std::array<Rgb, 3> colors = {kPredictionCorrectColor, kPredictionWrongColor,
                                     kPredictionUnscoredColor};
  // Wrong matches last, drawn on top.
  for (const uint8_t g : {uint8_t{2}, uint8_t{0}, uint8_t{1}}) {
    for (size_t k : subset) {
      if (groups[k] != g) continue;
      const cv::Point p0 = to_point(kpts0[2 * k], kpts0[2 * k + 1], 0);
      const cv::Point p1 = to_point(kpts1[2 * k], kpts1[2 * k + 1], x1);
      const cv::Scalar color = colors[g].Scalar();
      cv::line(canvas, p0, p1, color, 1, cv::LINE_8);
      cv::circle(canvas, p0, 2, color, cv::FILLED, cv::LINE_8);
      cv::circle(canvas, p1, 2, color, cv::FILLED, cv::LINE_8);
    }
  }
  const std::vector<LegendEntry> entries = {
      {kPredictionCorrectColor, "correct " + std::to_string(counts[0])},
      {kPredictionWrongColor, "wrong " + std::to_string(counts[1])},
      {kPredictionUnscoredColor, "unscored (no target) " + std::to_string(counts[2])},
  };
  std::string shown = "lines: " + std::to_string(subset.size()) + " of " + std::to_string(n) +
                      " (equal share per verdict)";
  if (!options.note.empty()) shown += "; " + options.note;
  return StackVertical({canvas, LegendStrip(entries, canvas.cols, 3, shown, options.text_scale)});
}

bool LabelPictureOptions::Check(std::string* error) const {
  if (!(text_scale >= 0.5 && text_scale <= 4.0)) {
    *error = "text_scale: expected a number in [0.5, 4]";
    return false;
  }
  if (!(alpha >= 0.0 && alpha <= 1.0)) {
    *error = "alpha: expected a number in [0, 1]";
    return false;
  }
  return true;
}

cv::Mat OverlayLabels(const cv::Mat& image, const LabelMap& labels, double alpha) {
  CheckBgr(image, "image");
  if (labels.width != image.cols || labels.height != image.rows ||
      labels.codes.size() != static_cast<size_t>(labels.width) * labels.height) {
    throw InputError("labels", "expected a label map of the image's size " +
                                   std::to_string(image.cols) + "x" + std::to_string(image.rows));
  }
  cv::Mat out(image.rows, image.cols, CV_8UC3);
  for (int v = 0; v < image.rows; ++v) {
    const cv::Vec3b* src = image.ptr<cv::Vec3b>(v);
    cv::Vec3b* dst = out.ptr<cv::Vec3b>(v);
    const uint8_t* codes = labels.codes.data() + static_cast<size_t>(v) * labels.width;
    for (int u = 0; u < image.cols; ++u) {
      if (codes[u] > 5) {
        throw InputError("labels", "pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                                       "): expected a label code 0..5, got " +
                                       std::to_string(codes[u]));
      }
      const cv::Vec3b c = kLabelColors[codes[u]].Bgr();
      for (int ch = 0; ch < 3; ++ch) {
        dst[u][ch] = cv::saturate_cast<uint8_t>((1.0 - alpha) * src[u][ch] + alpha * c[ch]);
      }
    }
  }
  return out;
}

cv::Mat RenderLabels(const cv::Mat& image0, const LabelMap& labels01, const cv::Mat& image1,
                     const LabelMap& labels10, const LabelPictureOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("label picture options", error);
  const cv::Mat over0 = OverlayLabels(image0, labels01, options.alpha);
  const cv::Mat over1 = OverlayLabels(image1, labels10, options.alpha);
  cv::Mat panels = SideBySide(TitleAbove(over0, "image 0: labels 0->1", options.text_scale),
                              TitleAbove(over1, "image 1: labels 1->0", options.text_scale));
  if (!options.legend) return panels;
  std::array<double, 6> share01{}, share10{};
  for (uint8_t c : labels01.codes) share01[c] += 1.0;
  for (uint8_t c : labels10.codes) share10[c] += 1.0;
  std::vector<LegendEntry> entries;
  for (int c = 0; c < 6; ++c) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "%d %s %.1f%% / %.1f%%", c, kLabelNames[c],
                  100.0 * share01[c] / std::max<size_t>(labels01.codes.size(), 1),
                  100.0 * share10[c] / std::max<size_t>(labels10.codes.size(), 1));
    entries.push_back({kLabelColors[c], buf});
  }
  return StackVertical({panels, LegendStrip(entries, panels.cols, 3, "share of pixels: 0->1 / 1->0",
                                            options.text_scale)});
}

bool OccupancyPictureOptions::Check(std::string* error) const {
  if (!(text_scale >= 0.5 && text_scale <= 4.0)) {
    *error = "text_scale: expected a number in [0.5, 4]";
    return false;
  }
  if (scale < 1 || scale > 16) {
    *error = "scale: expected 1..16";
    return false;
  }
  if (slice_row < -1) {
    *error = "slice_row: expected -1 (middle) or a row >= 0";
    return false;
  }
  if (slice_bin_px < 1 || slice_bin_px > 32) {
    *error = "slice_bin_px: expected 1..32";
    return false;
  }
  return true;
}

std::vector<int> FirstOccupiedBins(const gt::occupancy::FrustumVolume& volume) {
  CheckVolume(volume);
  const int num_bins = static_cast<int>(volume.edges_m.size()) - 1;
  std::vector<int> first(volume.occ.size(), -1);
  for (size_t r = 0; r < volume.occ.size(); ++r) {
    for (int k = 0; k < num_bins; ++k) {
      if ((volume.occ[r] >> k) & 1ULL) {
        first[r] = k;
        break;
      }
    }
  }
  return first;
}

cv::Mat RenderFirstOccupied(const gt::occupancy::FrustumVolume& volume,
                            const OccupancyPictureOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("occupancy picture options", error);
  const std::vector<int> first = FirstOccupiedBins(volume);
  const int num_bins = static_cast<int>(volume.edges_m.size()) - 1;
  const std::vector<cv::Vec3b> lut = TurboLut();
  const int sc = options.scale;
  cv::Mat depth(volume.height * sc, volume.width * sc, CV_8UC3);
  for (int v = 0; v < volume.height; ++v) {
    for (int u = 0; u < volume.width; ++u) {
      const size_t r = static_cast<size_t>(v) * volume.width + u;
      cv::Vec3b c;
      if (first[r] >= 0) {
        c = lut[BinLutIndex(first[r], num_bins)];
      } else if (volume.known[r] != 0) {
        c = kNoOccupiedSeenColor.Bgr();
      } else {
        c = kNothingKnownColor.Bgr();
      }
      depth(cv::Rect(u * sc, v * sc, sc, sc)).setTo(cv::Scalar(c[0], c[1], c[2]));
    }
  }
  // Colour bar: near (top) … far (bottom), labelled with the edges in metres.
  const int bar_w = 16, label_w = 72, h = depth.rows;
  cv::Mat bar(h, bar_w + label_w + 6, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int y = 0; y < h; ++y) {
    const int k = std::min(num_bins - 1, y * num_bins / std::max(h, 1));
    bar(cv::Rect(4, y, bar_w, 1))
        .setTo(cv::Scalar(lut[BinLutIndex(k, num_bins)][0], lut[BinLutIndex(k, num_bins)][1],
                          lut[BinLutIndex(k, num_bins)][2]));
  }
  const double mid_m = volume.edges_m[volume.edges_m.size() / 2];
  PutText(bar, Metres(volume.edges_m.front()), bar_w + 8, 12);
  PutText(bar, Metres(mid_m), bar_w + 8, h / 2 + 4);
  PutText(bar, Metres(volume.edges_m.back()), bar_w + 8, h - 4);
  cv::Mat row = SideBySide(depth, bar, 0);
  std::vector<LegendEntry> entries = {
      {kNoOccupiedSeenColor, "no occupied bin, free seen"},
      {kNothingKnownColor, "nothing known"},
  };
  return StackVertical({row, LegendStrip(entries, row.cols, 1, "", options.text_scale)});
}

cv::Mat RenderOccupancySlice(const gt::occupancy::FrustumVolume& volume,
                             const OccupancyPictureOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("occupancy picture options", error);
  CheckVolume(volume);
  const int row = SliceRow(volume, options);
  const int num_bins = static_cast<int>(volume.edges_m.size()) - 1;
  const int sc = options.scale, bp = options.slice_bin_px;
  cv::Mat slice(num_bins * bp, volume.width * sc, CV_8UC3);
  for (int u = 0; u < volume.width; ++u) {
    const size_t r = static_cast<size_t>(row) * volume.width + u;
    for (int k = 0; k < num_bins; ++k) {
      const bool occ = (volume.occ[r] >> k) & 1ULL;
      const bool known = (volume.known[r] >> k) & 1ULL;
      const Rgb c = occ ? kOccupiedColor : known ? kFreeColor : kUnknownColor;
      slice(cv::Rect(u * sc, k * bp, sc, bp)).setTo(c.Scalar());
    }
  }
  const int axis_w = 70;
  cv::Mat axis(slice.rows, axis_w, CV_8UC3, cv::Scalar(255, 255, 255));
  PutText(axis, Metres(volume.edges_m.front()), 2, 12);
  PutText(axis, Metres(volume.edges_m[volume.edges_m.size() / 2]), 2, slice.rows / 2 + 4);
  PutText(axis, Metres(volume.edges_m.back()), 2, slice.rows - 4);
  cv::Mat body = SideBySide(axis, slice, 0);
  body =
      TitleAbove(body, "row v=" + std::to_string(row) + ": depth (down) x u", options.text_scale);
  std::vector<LegendEntry> entries = {
      {kOccupiedColor, "occupied"}, {kFreeColor, "free"}, {kUnknownColor, "unknown"}};
  return StackVertical({body, LegendStrip(entries, body.cols, 3, "", options.text_scale)});
}

cv::Mat RenderOccupancy(const gt::occupancy::FrustumVolume& cam0,
                        const gt::occupancy::FrustumVolume* cam1,
                        const OccupancyPictureOptions& options) {
  cv::Mat top = TitleAbove(RenderFirstOccupied(cam0, options), "camera 0: first occupied bin",
                           options.text_scale);
  cv::Mat bottom =
      TitleAbove(RenderOccupancySlice(cam0, options), "camera 0: slice", options.text_scale);
  if (cam1 != nullptr) {
    top = SideBySide(top, TitleAbove(RenderFirstOccupied(*cam1, options),
                                     "camera 1: first occupied bin", options.text_scale));
    bottom = SideBySide(bottom, TitleAbove(RenderOccupancySlice(*cam1, options), "camera 1: slice",
                                           options.text_scale));
  }
  return StackVertical({top, bottom});
}

gt::occupancy::FrustumVolume VolumeFromDense(const std::vector<uint8_t>& dense, int num_bins,
                                             int height, int width,
                                             const std::vector<double>& edges_m) {
  if (num_bins < 1 || num_bins > 64 || height <= 0 || width <= 0 ||
      dense.size() != static_cast<size_t>(num_bins) * height * width ||
      edges_m.size() != static_cast<size_t>(num_bins) + 1) {
    throw InputError("occupancy",
                     "expected dense uint8 [num_bins <= 64, H, W] and num_bins+1 "
                     "edges");
  }
  gt::occupancy::FrustumVolume v;
  v.width = width;
  v.height = height;
  v.edges_m = edges_m;
  const size_t rays = static_cast<size_t>(height) * width;
  v.occ.assign(rays, 0);
  v.known.assign(rays, 0);
  for (int k = 0; k < num_bins; ++k) {
    for (size_t r = 0; r < rays; ++r) {
      const uint8_t d = dense[k * rays + r];
      if (d == 1) {
        v.occ[r] |= 1ULL << k;
        v.known[r] |= 1ULL << k;
      } else if (d == 0) {
        v.known[r] |= 1ULL << k;
      } else if (d != 255) {
        throw InputError("occupancy",
                         "dense volume: expected 0 (free), 1 (occupied) or 255 "
                         "(unknown), got " +
                             std::to_string(d));
      }
    }
  }
  return v;
}

std::string EncodePng(const cv::Mat& image) {
  return gt::io::EncodePngBytes(image, gt::io::ChannelOrder::kBgr, 6, "png");
}

}  // namespace gt::report

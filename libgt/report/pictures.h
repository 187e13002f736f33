// Pictures of one pair, rendered from plain arrays (no file formats here; pair_source.h
// loads them from shards or `occgt pair` folders).
//
// Images are OpenCV 8-bit 3-channel matrices in BGR order (CV_8UC3), [height, width],
// at the working resolution of the labels (the caller resizes colour images with
// PrepareImage). Colours below are given as (R, G, B) for readers and stored BGR.
//
//  - RenderMatches: images 0 and 1 side by side (image 1 shifted right by width0 +
//    kPanelGap), one straight line per coarse patch match (GROUND_TRUTH.md §4) coloured
//    by type: vv green, vo yellow, ov red. A vv/vo match (i, j) is drawn from the anchor
//    pixel of cell i in image 0 to match_xy in image 1; an ov match from match_xy in
//    image 0 to the anchor of cell j in image 1 (match_xy is always the exact warped
//    anchor, libgt/geometry/patches.h). When there are more than max_lines matches a
//    seeded subset is drawn (SelectMatchSubset).
//  - RenderPredictedMatches: a matcher's predicted matches over the ground truth (the eval
//    section of the split report): the label overlays of both directions (as RenderLabels,
//    weight alpha) side by side, one line per drawn match from its keypoint in image 0 to
//    its keypoint in image 1, coloured by its verdict (libgt/eval/match_quality.h):
//    correct cyan, wrong magenta, unscored (no ground-truth target) white. When there are
//    more than max_lines matches a seeded subset is drawn, an equal share per verdict
//    (SelectMatchSubset over the verdicts).
//  - RenderLabels: the pixel labels of both directions (label01 on image 0, label10 on
//    image 1; codes NO_DEPTH 0 … UNKNOWN 5, GROUND_TRUTH.md §2) blended over the images
//    with weight `alpha`, and a legend with each label's share of the image.
//  - RenderFirstOccupied: per ray of a frustum volume (libgt/occupancy/frustum.h: occ and
//    known bit words, [H/2, W/2]) the first occupied bin as a colour-mapped depth image
//    (near = red … far = blue, COLORMAP_TURBO), with a colour bar in metres; rays with no
//    occupied bin are grey when some bin is known free and black when nothing is known.
//  - RenderOccupancySlice: one row v of the volume as a depth × width picture (bin 0 =
//    near at the top, column u left to right): occupied, free and unknown bins in three
//    distinct colours.
// Every function is deterministic (same inputs and options → identical pixels).
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libgt/geometry/patches.h"
#include "libgt/occupancy/frustum.h"

namespace gt::report {

// (R, G, B) of a colour, as a reader of the docs would write it.
struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  cv::Vec3b Bgr() const { return cv::Vec3b(b, g, r); }
  cv::Scalar Scalar() const { return cv::Scalar(b, g, r); }
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
};

// Match types (MatchType codes 0, 1, 2).
inline constexpr Rgb kMatchColorVv{0, 200, 0};    // visible-visible: green
inline constexpr Rgb kMatchColorVo{255, 220, 0};  // visible-occluded: yellow
inline constexpr Rgb kMatchColorOv{230, 0, 0};    // occluded-visible: red
Rgb MatchTypeColor(uint8_t type);                 // GT_ASSERT(type <= 2)

// Pixel labels, indexed by PixelLabel code 0..5.
inline constexpr std::array<Rgb, 6> kLabelColors = {{
    {40, 40, 40},    // NO_DEPTH: near black
    {60, 110, 255},  // OUT_OF_VIEW: blue
    {0, 200, 70},    // VISIBLE: green
    {235, 30, 30},   // OCCLUDED: red
    {230, 0, 230},   // INCONSISTENT: magenta
    {255, 170, 0},   // UNKNOWN: orange
}};

// Occupancy bins and rays.
inline constexpr Rgb kOccupiedColor{200, 30, 30};          // slice: occupied bin
inline constexpr Rgb kFreeColor{235, 235, 235};            // slice: free bin
inline constexpr Rgb kUnknownColor{70, 90, 150};           // slice: unknown bin
inline constexpr Rgb kNoOccupiedSeenColor{128, 128, 128};  // first-occupied: none, some free
inline constexpr Rgb kNothingKnownColor{0, 0, 0};          // first-occupied: nothing known

// Pixels between the two panels of a side-by-side picture (white).
inline constexpr int kPanelGap = 8;

// A colour image (any size, 1/3/4 channels, 8 or 16 bit) as BGR CV_8UC3 of width x height
// (bilinear resize; 16-bit scaled to 8). An empty image becomes a mid-grey placeholder.
cv::Mat PrepareImage(const cv::Mat& image, int width, int height);

// Indices (increasing) of at most max_lines matches to draw. Each type present gets an
// equal share of max_lines (a type with fewer matches gives its unused share to the
// others), and within a type the matches with the smallest SplitMix64(seed, index) hash
// are taken: same inputs and seed → same subset; all indices when size <= max_lines.
std::vector<size_t> SelectMatchSubset(const std::vector<uint8_t>& match_type, int max_lines,
                                      uint64_t seed);

struct MatchPictureOptions {
  int max_lines = 200;                      // lines drawn at most (> 0)
  uint64_t seed = 0;                        // subset seed (SelectMatchSubset)
  int stride = 8;                           // patch stride of the matches (pixels, >= 1)
  gt::Anchor anchor = gt::Anchor::kCenter;  // anchor rule of the matches
  int thickness = 1;                        // line thickness (pixels, 1..8); 8-connected lines
  bool legend = true;                       // a strip below with the counts per type
  double text_scale = 1.0;  // titles and legends enlarged by this (0.5..4): 1 / display scale
  bool Check(std::string* error) const;
};

// image0/image1: BGR CV_8UC3 at the working resolution (the grids of the matches).
// Throws InputError("matches", ...) when a cell index lies outside its grid or the arrays
// disagree in length. Output: [max(h0, h1) + legend strip, w0 + kPanelGap + w1].
cv::Mat RenderMatches(const cv::Mat& image0, const cv::Mat& image1, const gt::PatchMatches& matches,
                      const MatchPictureOptions& options);

// A label map: PixelLabel codes, row-major [height, width].
struct LabelMap {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> codes;
};

// Predicted matches by verdict.
inline constexpr Rgb kPredictionCorrectColor{0, 235, 255};     // cyan
inline constexpr Rgb kPredictionWrongColor{255, 0, 220};       // magenta
inline constexpr Rgb kPredictionUnscoredColor{255, 255, 255};  // white
enum class PredictionVerdict : uint8_t { kCorrect = 0, kWrong = 1, kUnscored = 2 };

struct PredictionPictureOptions {
  int max_lines = 150;      // lines drawn at most (> 0)
  uint64_t seed = 0;        // subset seed
  double alpha = 0.35;      // label overlay weight, [0, 1]
  std::string note;         // an extra line under the legend (e.g. per-class counts)
  double text_scale = 1.0;  // titles and legends enlarged by this (0.5..4): 1 / display scale
  bool Check(std::string* error) const;
};

// image0/image1: BGR CV_8UC3 of the label maps' sizes; kpts0/kpts1: [N, 2] pixels (x, y);
// verdicts: [N]. Throws InputError("predictions", ...) when the sizes disagree or a point
// is not finite. Output: [max(h0, h1) + legend strip, w0 + kPanelGap + w1].
cv::Mat RenderPredictedMatches(const cv::Mat& image0, const LabelMap& labels01,
                               const cv::Mat& image1, const LabelMap& labels10,
                               const std::vector<float>& kpts0, const std::vector<float>& kpts1,
                               const std::vector<PredictionVerdict>& verdicts,
                               const PredictionPictureOptions& options);

struct LabelPictureOptions {
  double alpha = 0.55;      // weight of the label colour over the image, in [0, 1]
  bool legend = true;       // a strip below with colour, name and share per direction
  double text_scale = 1.0;  // titles and legends enlarged by this (0.5..4): 1 / display scale
  bool Check(std::string* error) const;
};

// One image with its labels blended: pixel = (1 - alpha) * image + alpha * colour.
// Throws InputError("labels", ...) when sizes differ or a code is > 5.
cv::Mat OverlayLabels(const cv::Mat& image, const LabelMap& labels, double alpha);

// Both directions side by side (label01 over image 0, label10 over image 1) with titles
// and legend. Output: [max(h0, h1) + title + legend, w0 + kPanelGap + w1].
cv::Mat RenderLabels(const cv::Mat& image0, const LabelMap& labels01, const cv::Mat& image1,
                     const LabelMap& labels10, const LabelPictureOptions& options);

struct OccupancyPictureOptions {
  int scale = 2;            // pixels per ray in the first-occupied image (2: working size)
  int slice_row = -1;       // row v of the half grid to slice; -1 = the middle row H/2 / 2
  int slice_bin_px = 4;     // picture rows per depth bin in the slice
  double text_scale = 1.0;  // titles and legends enlarged by this (0.5..4): 1 / display scale
  bool Check(std::string* error) const;
};

// First occupied bin per ray, [height * width], -1 when no bin is occupied.
std::vector<int> FirstOccupiedBins(const gt::occupancy::FrustumVolume& volume);

// Throws InputError("occupancy", ...) when occ/known sizes disagree with width*height or
// fewer than 2 edges are given. Output: [height*scale + legend, width*scale + colour bar].
cv::Mat RenderFirstOccupied(const gt::occupancy::FrustumVolume& volume,
                            const OccupancyPictureOptions& options);
// Output: [num_bins*slice_bin_px + legend, width*scale + depth axis]; row v = options'.
cv::Mat RenderOccupancySlice(const gt::occupancy::FrustumVolume& volume,
                             const OccupancyPictureOptions& options);
// The volumes of both cameras: first-occupied images on top, slices below (cam1 may be
// null for a single camera).
cv::Mat RenderOccupancy(const gt::occupancy::FrustumVolume& cam0,
                        const gt::occupancy::FrustumVolume* cam1,
                        const OccupancyPictureOptions& options);

// Dense uint8 [num_bins, height, width] (0 free, 1 occupied, 255 unknown) back to bit words.
// Throws InputError("occupancy", ...) on a size mismatch or another value.
gt::occupancy::FrustumVolume VolumeFromDense(const std::vector<uint8_t>& dense, int num_bins,
                                             int height, int width,
                                             const std::vector<double>& edges_m);

// PNG bytes of an image (deterministic: default compression, no metadata).
std::string EncodePng(const cv::Mat& image);

}  // namespace gt::report

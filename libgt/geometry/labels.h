// Pixel labels and pair metrics for one direction A→B (GROUND_TRUTH.md §2–3).
//
// For each pixel u = (u, v) of image A with planar depth d_A(u) (metres):
//   1. d_A invalid (0, NaN, inf, outside [min_depth_m, max_depth_m])       → kNoDepth
//   2. p_in_a = d_A · K_A⁻¹ [u, v, 1]ᵀ,  p_in_b = b_from_a · p_in_a,  z = p_in_b.z
//   3. cheirality: z <= min_depth_m                                         → kOutOfView
//   4. x = K_B p_in_b / z (compat: / (z + projection_eps_m)); outside bounds → kOutOfView
//   5. d_B = depth of B at the looked-up pixel (nearest: floor(x + 0.5); truncate: the
//      integer part, like torch's .long()); d_B invalid → kUnknown (compat: d_B := 0)
//   6. τ = max(abs_tol_m, rel_tol · z) (or rel_tol · d_B when relative_to = kObserved);
//      |z − d_B| <= τ → kVisible; z > d_B + τ → kOccluded; z < d_B − τ → kInconsistent.
// Codes are stable (uint8, stored in files): see PixelLabel.
//
// Conventions: libgt/core/camera.h (pixel centres at integer coordinates, OpenCV axes),
// libgt/core/pose.h (b_from_a = inverse(world_from_b) * world_from_a). Depth maps and
// cameras are at the working resolution (default 640×480; resize first with
// ResizeDepthNearest and Camera::Resized).
//
// Arithmetic: float32 per pixel, like the tensors of LoFTR / Occ²Net. K_B · R · K_A⁻¹ and
// K_B · t are folded (in double) into one affine map q = d · (a·u + b·v + c) + k, whose
// per-row coefficients are rounded to float once; z = q.z, (x, y) = (q.x, q.y) · r with one
// reciprocal r = 1 / (z + eps). Every threshold (depth range, cheirality, bounds) is
// converted to the float that gives the same decision for float values. The slow
// double-precision reference (tests/geometry/reference.h) agrees label for label except at
// ties, where a compared value is within ~1e-5 (relative) of its threshold: 2 labels of 1.8 M
// in tests/geometry/reference_test.cc. Same inputs → identical labels and positions on any
// machine that implements IEEE-754 float: no fast-math, no FMA contraction
// (-ffp-contract=off), and the SIMD clones of the row kernel (AVX-512, AVX2, baseline
// x86-64, chosen at load time) do the same operations.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/default_init_allocator.h"
#include "libgt/core/depth.h"
#include "libgt/core/pose.h"

namespace gt {

// Stable codes, stored as uint8 in label maps and cell maps (docs/GROUND_TRUTH.md).
enum class PixelLabel : uint8_t {
  kNoDepth = 0,       // source depth invalid
  kOutOfView = 1,     // behind B's camera or projects outside B's image
  kVisible = 2,       // B observes the same surface (within tolerance)
  kOccluded = 3,      // a surface of B lies in front of the point
  kInconsistent = 4,  // B sees past the point (depth/pose error, moving object)
  kUnknown = 5,       // projects into B, but B has no valid depth there
};
inline constexpr int kNumPixelLabels = 6;
// "NO_DEPTH", "OUT_OF_VIEW", "VISIBLE", "OCCLUDED", "INCONSISTENT", "UNKNOWN".
const char* PixelLabelName(PixelLabel label);

// Which depth the relative tolerance multiplies.
enum class RelativeTo { kProjected, kObserved };  // z (projected into B) or d_B (B's depth)
// Which continuous positions count as inside B's image.
enum class Bounds {
  kPixelArea,  // -0.5 <= x < W - 0.5, -0.5 <= y < H - 0.5 (every point a pixel covers)
  kStrict,     // 0 < x < W - 1, 0 < y < H - 1 (LoFTR / Occ²Net code)
};
// How the target pixel is chosen from the continuous position x.
enum class TargetLookup {
  kNearest,   // floor(x + 0.5): the pixel whose area contains x
  kTruncate,  // integer part (toward zero), as torch's .long() in LoFTR / Occ²Net
};
// What an invalid depth of B at the target pixel means.
enum class MissingTarget {
  kUnknown,      // label kUnknown (default)
  kAsZeroDepth,  // compare as d_B = 0 (released Occ²Net code: OCCLUDED when z > tol)
};

// Names used on the command line and in meta.json: "projected"/"observed",
// "pixel-area"/"strict", "nearest"/"truncate", "unknown"/"as-zero-depth".
const char* RelativeToName(RelativeTo v);
const char* BoundsName(Bounds v);
const char* TargetLookupName(TargetLookup v);
const char* MissingTargetName(MissingTarget v);
// Parsers; throw InputError(field, "expected one of ...") on an unknown name.
RelativeTo ParseRelativeTo(const std::string& name, const std::string& field = "--relative-to");
Bounds ParseBounds(const std::string& name, const std::string& field = "--bounds");
TargetLookup ParseTargetLookup(const std::string& name,
                               const std::string& field = "--target-lookup");
MissingTarget ParseMissingTarget(const std::string& name,
                                 const std::string& field = "--missing-target");

struct LabelOptions {
  double min_depth_m =
      kDefaultMinDepthM;  // depths below are invalid (core/depth.h IsValidDepth); also
                          // the cheirality threshold: z <= min_depth_m is OUT_OF_VIEW
  double max_depth_m = kDefaultMaxDepthM;  // depths above are invalid (core/depth.h)
  double abs_tol_m = 0.1;                  // absolute depth tolerance (metres)
  double rel_tol = 0.05;                   // relative tolerance (fraction of z or d_B)
  RelativeTo relative_to = RelativeTo::kProjected;
  Bounds bounds = Bounds::kPixelArea;
  TargetLookup target_lookup = TargetLookup::kNearest;
  MissingTarget missing_target = MissingTarget::kUnknown;
  bool cheirality = true;  // test z > min_depth_m before dividing (off: compat only)
  // The dataset's valid depth range (Scene::min/max_depth_m) replaces min/max_depth_m
  // (ApplyDatasetDepthRange). false: occ2net-compat, which, like the released code, compares
  // every finite depth > 0 (TartanAir's sky too); an explicit range still applies.
  bool dataset_depth_range = true;
  double projection_eps_m = 0.0;  // added to z before the division (compat: 1e-4)

  // min <= max, tolerances finite and >= 0, eps finite and >= 0.
  bool Check(std::string* error) const;
};

// *options's depth range becomes [min_depth_m, max_depth_m] (a dataset's) unless its
// dataset_depth_range is false.
void ApplyDatasetDepthRange(double min_depth_m, double max_depth_m, LabelOptions* options);

// Presets of GROUND_TRUTH.md §2 (options other than those in the table keep their
// defaults: min/max depth come from the dataset, except for occ2net-compat, whose range is
// every finite depth > 0):
//   default         τ = max(0.1 m, 0.05·z), pixel area, nearest, missing → UNKNOWN
//   occ2net         τ = 0.1 m, strict, truncate, missing → UNKNOWN
//   occ2net-compat  as occ2net, missing compared as 0, no cheirality, z + 1e-4, every
//                   finite depth > 0 valid (max_depth_m = FLT_MAX; no dataset range)
//   loftr           τ = 0.2·d_B (observed), strict, truncate, missing → UNKNOWN
//   superglue       τ = 0.1·z (projected), pixel area, nearest, missing → UNKNOWN
//   megadepth       τ = 0.15·z (projected), pixel area, nearest, missing → UNKNOWN (MVS
//                   depth, arbitrary scale: no absolute term)
// Throws InputError("--preset", "expected one of ...") for another name.
LabelOptions LabelPreset(const std::string& name);
std::vector<std::string> PresetNames();

// Labels of every pixel of A, and where each pixel lands in B.
struct DirectionLabels {
  int width = 0;                // of A
  int height = 0;               // of A
  std::vector<uint8_t> labels;  // [height * width], row-major, PixelLabel codes
  // [height * width * 2] float32 (x, y) in B's pixel coordinates (working resolution):
  // the continuous projection of the pixel, computed in float32 (see "Arithmetic"). NaN for
  // kNoDepth and for points that fail the cheirality test; finite (possibly outside B) for every
  // other label.
  // (Its allocator default-initialises: resize() leaves new floats unset.)
  std::vector<float, DefaultInitAllocator<float>> warped_xy;
  // Number of pixels of each PixelLabel code in `labels`, when LabelDirection made them
  // (MetricsFromLabels at stride 1 uses them instead of counting again); nullopt otherwise.
  std::optional<std::array<int64_t, kNumPixelLabels>> counts;

  PixelLabel at(int u, int v) const {
    return static_cast<PixelLabel>(labels[static_cast<size_t>(v) * width + u]);
  }
};

// Labels A→B. depth_a must match cam_a's size and depth_b cam_b's; throws InputError
// ("depth_a"/"depth_b"/"cam_a"/"cam_b"/"options") otherwise.
DirectionLabels LabelDirection(const DepthImage& depth_a, const Camera& cam_a,
                               const DepthImage& depth_b, const Camera& cam_b,
                               const Rigid3d& b_from_a, const LabelOptions& options);

// The N-view form of LabelDirection (views_truth.h): labels A against several targets
// with the same row kernel (so every label equals LabelDirection's) and keeps two bits per
// target. For each target t and each pixel p of rows [row_begin, row_end) of A, bit
// targets[t].bit of visible_bits[p] (occluded_bits[p]) is set when p is kVisible
// (kOccluded) in that target; other bits are left as they are. visible_bits and
// occluded_bits point to A's whole [height, width] row-major array. Targets are labelled
// outer, rows inner (each target's depth read along its memory). Throws InputError as
// LabelDirection, and
// ("bit"/"rows") for a bit outside 0..31 or a row range outside A.
struct BitTarget {
  const DepthImage* depth_b = nullptr;  // [H_B, W_B] of cam_b's size
  const Camera* cam_b = nullptr;
  Rigid3d b_from_a = Rigid3d::Identity();
  int bit = 0;  // 0..31
};
void LabelDirectionBits(const DepthImage& depth_a, const Camera& cam_a,
                        const std::vector<BitTarget>& targets, const LabelOptions& options,
                        int row_begin, int row_end, uint32_t* visible_bits,
                        uint32_t* occluded_bits);

// Labels of single pixels of A in B, with the same kernel (label for label and bit for bit
// LabelDirection's labels and warped_xy at those pixels), and the projected depth.
// pixels_uv: [Q * 2] int32 (u, v), each inside A (InputError("pixels") otherwise).
struct PointLabels {
  std::vector<uint8_t> labels;  // [Q] PixelLabel codes
  std::vector<float> xy;        // [Q * 2] (x, y) in B's pixels; NaN where not projected
  std::vector<float> z_m;       // [Q] z of the point in B's camera (float32 as the kernel
                                // computes it); NaN where not projected
};
PointLabels LabelPoints(const DepthImage& depth_a, const Camera& cam_a, const DepthImage& depth_b,
                        const Camera& cam_b, const Rigid3d& b_from_a, const LabelOptions& options,
                        const std::vector<int32_t>& pixels_uv);

// Metrics of one direction (GROUND_TRUTH.md §3) over the sampled grid: pixels (u, v) with
// u % score_stride == 0 and v % score_stride == 0 (stride 1 = every pixel).
struct DirectionMetrics {
  int64_t sampled = 0;  // pixels of the sampled grid
  int64_t valid = 0;    // sampled pixels with valid depth (sampled - counts[kNoDepth])
  std::array<int64_t, kNumPixelLabels> counts{};  // per PixelLabel code
  double overlap = 0;  // (VISIBLE + OCCLUDED + INCONSISTENT + UNKNOWN) / valid (0 if none)
  double consistent_overlap = 0;       // VISIBLE / sampled
  double occlusion_ratio = 0;          // OCCLUDED / sampled (= W·H at stride 1): the paper's
  double occlusion_ratio_visible = 0;  // OCCLUDED / (VISIBLE + OCCLUDED): the released
                                       // code's (0 when both are 0)
};

// Fast path: labels only the sampled grid, allocates no label maps. Equal, field by
// field, to MetricsFromLabels(LabelDirection(...), score_stride).
DirectionMetrics ScoreDirection(const DepthImage& depth_a, const Camera& cam_a,
                                const DepthImage& depth_b, const Camera& cam_b,
                                const Rigid3d& b_from_a, const LabelOptions& options,
                                int score_stride = 1);
DirectionMetrics MetricsFromLabels(const DirectionLabels& labels, int score_stride = 1);
// The same over a [height, width] row-major map of PixelLabel codes held elsewhere (a stored
// sample's label01.npy); InputError("labels") for a code past kUnknown.
DirectionMetrics MetricsFromLabelCodes(const uint8_t* labels, int width, int height,
                                       int score_stride = 1);
// Fills the ratios from sampled and counts (used by both functions above).
void FinishMetrics(DirectionMetrics* metrics);

}  // namespace gt

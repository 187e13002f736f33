// Coarse patch matches between images 0 and 1 from the pixel labels of both directions
// (GROUND_TRUTH.md §4; the coarse level of LoFTR / Occ²Net, stride 8 → 80×60 cells at
// 640×480).
//
// Cells: cell (c, r) of an image holds pixels s·c … s·c+s−1 × s·r … s·r+s−1; the grid has
// floor(W/s) × floor(H/s) cells (a partial last column/row of pixels has no cell), numbered
// row-major i = r·(W/s) + c.
// Anchor pixel of a cell: kCenter = (s·c + s/2, s·r + s/2) (integer division; the pixel
// nearest the block centre, default), kCorner = (s·c, s·r) (LoFTR's code).
// Target cell of a warped continuous point (x, y) in the other image:
//   kCenter: (floor((x + 0.5)/s), floor((y + 0.5)/s)), the cell whose pixels contain it;
//   kCorner: (floor(x/s + 0.5), floor(y/s + 0.5)), the nearest corner anchor (LoFTR).
// A target outside the grid gives no match (never cell 0).
//
// Match types (uint8): 0 vv — L01(anchor_i) = VISIBLE, j = cell(x01(anchor_i)); with
//   `mutual`, kept only if L10(anchor_j) = VISIBLE and cell(x10(anchor_j)) = i;
// 1 vo — L01(anchor_i) = OCCLUDED, j = cell(x01(anchor_i));
// 2 ov — L10(anchor_j) = OCCLUDED, i = cell(x10(anchor_j)).
// Order (deterministic): all vv by increasing i, then all vo by increasing i, then all ov
// by increasing j. With mutual on, every (i, j) appears at most once; with it off a vv and
// an ov match may share a cell pair.
// match_xy: for vv and vo the warped anchor of image 0 in image 1 (x01(anchor_i)); for ov
// the warped anchor of image 1 in image 0 (x10(anchor_j)), float32 at working resolution.
// LoFTR's fine target is (match_xy − anchor of the target cell) / fine_stride / radius.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libgt/geometry/labels.h"

namespace gt {

enum class Anchor { kCenter, kCorner };
const char* AnchorName(Anchor a);  // "center" / "corner"
Anchor ParseAnchor(const std::string& name, const std::string& field = "--anchor");

enum class MatchType : uint8_t { kVisibleVisible = 0, kVisibleOccluded = 1, kOccludedVisible = 2 };

struct PatchOptions {
  int stride = 8;                   // cell size in pixels at working resolution (>= 1)
  Anchor anchor = Anchor::kCenter;  // anchor pixel and target-cell rule
  bool mutual = true;               // vv: keep only loop-back consistent matches

  bool Check(std::string* error) const;  // stride >= 1
};

struct PatchMatches {
  int cells_w0 = 0, cells_h0 = 0;   // grid of image 0: floor(W0/s) × floor(H0/s)
  int cells_w1 = 0, cells_h1 = 0;   // grid of image 1
  std::vector<int32_t> matches;     // [M * 2]: (cell in image 0, cell in image 1), row-major
  std::vector<uint8_t> match_type;  // [M]: MatchType codes
  std::vector<float> match_xy;      // [M * 2]: (x, y), see the header comment
  std::vector<uint8_t> cells0;      // [cells_h0 * cells_w0]: PixelLabel of each anchor (0→1)
  std::vector<uint8_t> cells1;      // [cells_h1 * cells_w1]: PixelLabel of each anchor (1→0)

  size_t size() const { return match_type.size(); }
};

// Matches of each type (vv, vo, ov).
struct MatchTypeCounts {
  int64_t vv = 0, vo = 0, ov = 0;
};
MatchTypeCounts CountMatchTypes(const PatchMatches& matches);

// l01: labels of image 0 towards 1 (on image 0's grid); l10 the reverse. Throws
// InputError("patch options", ...) when options fail Check or an image is smaller than a
// cell.
PatchMatches ComputePatchMatches(const DirectionLabels& l01, const DirectionLabels& l10,
                                 const PatchOptions& options);

// The target cell (rule above) of the continuous point (x, y) in a cells_w × cells_h grid of
// cells of `stride` pixels, row-major; -1 when the point is not finite or outside the grid.
int32_t TargetCell(float x, float y, int cells_w, int cells_h, int stride, Anchor anchor);

// Anchor pixel coordinate (column or row) of cell index `c` along one axis.
inline int AnchorPixel(int c, int stride, Anchor anchor) {
  return anchor == Anchor::kCenter ? stride * c + stride / 2 : stride * c;
}

}  // namespace gt

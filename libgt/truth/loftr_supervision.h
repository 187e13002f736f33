// LoFTR's coarse supervision of one pair (LoFTR's `spvs_coarse` / `warp_kpts`), with three
// fixes by default and an exact-compatibility option (docs/PYTHON.md, "Supervision").
//
// Grid: image k (its image, not its depth map, of size W_k × H_k) has floor(H_k/s) ×
// floor(W_k/s) coarse cells, numbered row-major i = r·w_c + c; the grid point of cell (c, r)
// is its corner anchor in the pixels of the depth map, (c·σx, r·σy) with σ = s · scale
// (scale: the image's resize factor from the depth map's pixels to the image's, LoFTR's
// data['scale0'], 1 when the image is the depth map's size). σ and the grid points are
// float32 products, as LoFTR's tensors.
// Warp of a grid point g of image A into image B: d = depth_A at the pixel nearest g
// (round half to even, torch's round); p = K_A⁻¹ [g.x·d, g.y·d, d]; q = b_from_a p;
// x = (K_B q).xy / (q.z + 1e-4), rounded to float32 (LoFTR's division, kept by default so
// that the cells no fix touches equal LoFTR's). Target cell of x: round(x / σ_B) per axis,
// in float32 (x and σ_B are float32), half to even.
// Match (i, j): j = target(i) and target(j) = i (LoFTR's mutual loop-back); by increasing i.
//
// Default (three fixes): a grid point without depth (d not finite or d <= 0, or the
// rounded pixel outside the depth map), a point behind B's camera (q.z <= 0) and a point
// whose target is outside B's grid have no target and so no match (LoFTR sends the first
// to the projection of A's centre, mirrors the second into view and sends the third to
// cell 0); cell 0 is then an ordinary cell. Warped points without depth or behind B are
// NaN. With `compat`: LoFTR exactly — no depth or z test, every non-finite or out-of-grid
// target is cell 0, cell 0 of image 0 never matches, and a grid point whose rounded pixel
// lies outside its depth map is an InputError (LoFTR's indexing fails there).
//
// Padded images (LoFTR's MegaDepth batches: image and depth zero-padded to a square, with
// data['mask0'/'mask1'] at the coarse grid, 0 on padding): a view's `cell_mask`. Default: a
// padded cell has no target and its warp is NaN (status kPadded; its grid point stays its
// corner), and a target that lands on a padded cell of the other grid is out of the grid.
// compat: LoFTR's mask_pts_at_padded_regions — the grid point of a padded cell is (0, 0)
// and is warped like any other, and the other grid's padding is ordinary cells.
//
// Numerics in double from the float32/float64 inputs; LoFTR computes in float32, so its
// warped points differ from these by ~1e-4 px and a target may differ where x/σ lies within
// ~1e-5 of a rounding boundary.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "libgt/core/depth.h"

namespace gt::truth {

// Why a grid point has (or has no) target cell (uint8 codes).
enum class WarpStatus : uint8_t {
  kInGrid = 0,     // its warp lands in the other grid: target = that cell
  kNoDepth = 1,    // depth invalid (or its pixel outside the depth map)
  kBehind = 2,     // q.z <= 0: behind (or at) the other camera
  kOutOfGrid = 3,  // the rounded target cell lies outside the other grid (or on its padding)
  kPadded = 4,     // the cell lies in the padding of its own image (cell_mask 0)
};
// "in_grid", "no_depth", "behind", "out_of_grid", "padded"
const char* WarpStatusName(WarpStatus s);

struct LoftrSupervisionOptions {
  int coarse_stride = 8;  // s: coarse cell size in image pixels (LoFTR RESOLUTION[0])
  bool compat = false;    // reproduce LoFTR exactly (header comment) instead of the fixes

  bool Check(std::string* error) const;  // 1 <= coarse_stride <= 1024
};

// One image of the pair. The depth map is not copied: it must outlive the call.
struct LoftrView {
  const float* depth_m = nullptr;         // [depth_height, depth_width] row-major, planar metres
  int depth_width = 0, depth_height = 0;  // in the pixels of K
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // intrinsics of the depth map (invertible)
  int image_width = 0, image_height = 0;            // the image the grid covers (>= coarse_stride)
  double scale_x = 1.0, scale_y = 1.0;  // depth-map pixels per image pixel (> 0, finite)
  // Optional [floor(H/s) · floor(W/s)] row-major over the coarse cells: 0 = padding, else
  // image (LoFTR's coarse data['mask<k>']); null = no padding. Not copied.
  const uint8_t* cell_mask = nullptr;

  void SetDepth(const DepthImage& depth) {
    depth_m = depth.values_m.data();
    depth_width = depth.width;
    depth_height = depth.height;
  }
};

struct LoftrCoarseSupervision {
  int cells_w0 = 0, cells_h0 = 0, cells_w1 = 0, cells_h1 = 0;  // L_k = cells_w_k · cells_h_k
  std::vector<float> grid0, grid1;        // [L_k · 2]: grid points (x, y), depth-map pixels
  std::vector<float> warped0, warped1;    // [L_k · 2]: warp into the other image (its pixels)
  std::vector<int32_t> target0, target1;  // [L_k]: target cell in the other grid; -1 none
                                          // (compat: 0 for every non-target)
  std::vector<uint8_t> status0, status1;  // [L_k]: WarpStatus (also filled with compat)
  std::vector<int32_t> matches;           // [M · 2]: (i, j), increasing i

  size_t size() const { return matches.size() / 2; }
};

// cam1_from_cam0 (LoFTR's T_0to1) warps image 0's grid, cam0_from_cam1 (T_1to0) image 1's;
// only their top 3×4 is used, as given. Throws InputError for options failing Check, a
// missing depth map, a view smaller than one cell, a bad scale, a singular K, and (compat)
// a grid point outside its depth map.
LoftrCoarseSupervision ComputeLoftrSupervision(const LoftrView& view0, const LoftrView& view1,
                                               const Eigen::Matrix4d& cam1_from_cam0,
                                               const Eigen::Matrix4d& cam0_from_cam1,
                                               const LoftrSupervisionOptions& options);

}  // namespace gt::truth

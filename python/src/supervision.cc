// Bindings of libgt/truth/loftr_supervision.h: LoFTR's coarse supervision of one pair
// (truth::ComputeLoftrSupervision) from NumPy arrays. Arguments are converted and checked
// (convert.h), the work runs without the GIL, every output array owns its C++ vector. The
// batched torch function over it is occgt.torch.loftr_supervision (python/occgt/torch).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/core/pose.h"
#include "libgt/geometry/patches.h"
#include "libgt/truth/loftr_supervision.h"
#include "libgt/truth/working_frame.h"
#include "python/src/convert.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

// A relative pose b_from_a [4, 4] (float or integer), rigid (core/pose.h PoseProblem).
Eigen::Matrix4d RelativePoseFromArray(py::handle obj, const std::string& argument) {
  py::array a = AsArray(obj, argument);
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    ThrowValue(argument,
               "expected a float array [4, 4] (rigid [[R, t], [0, 0, 0, 1]], metres), "
               "got dtype " +
                   DtypeText(a));
  }
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    ThrowValue(argument,
               "expected shape (4, 4) (rigid [[R, t], [0, 0, 0, 1]], metres), got " + ShapeText(a));
  }
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!d) throw py::error_already_set();
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = d.at(r, c);
  }
  if (const auto problem = gt::PoseProblem(m)) ThrowValue(argument, *problem);
  return m;
}

// A depth map [H, W] float32 or float64 (planar metres; DepthFromArray's checks and
// messages) as a C-contiguous float32 array: the input itself when it is one (no copy), else
// a converted copy. Kept alive by the caller while the C++ reads it.
py::array_t<float> DepthArray(py::handle obj, const std::string& argument) {
  const py::array a = CheckedDepthArray(obj, argument);
  auto f = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!f) throw py::error_already_set();
  return f;
}

void CheckScale(const std::array<double, 2>& s, const std::string& argument) {
  for (double v : s) {
    if (!(std::isfinite(v) && v > 0)) {
      ThrowValue(argument,
                 "expected (sx, sy), finite and > 0 (depth-map pixels per image "
                 "pixel), got (" +
                     std::to_string(s[0]) + ", " + std::to_string(s[1]) + ")");
    }
  }
}

// A coarse-grid mask [cells_h, cells_w] (bool or integer; 0 = padding) as C-contiguous uint8.
py::array_t<uint8_t> CellMaskArray(py::handle obj, int cells_h, int cells_w,
                                   const std::string& argument) {
  py::array a = AsArray(obj, argument);
  const char kind = a.dtype().kind();
  if (kind != 'b' && kind != 'i' && kind != 'u') {
    ThrowValue(argument,
               "expected a bool or integer array [cells_h, cells_w] (0 = padding), got "
               "dtype " +
                   DtypeText(a));
  }
  if (a.ndim() != 2 || a.shape(0) != cells_h || a.shape(1) != cells_w) {
    ThrowValue(argument,
               "expected shape (" + std::to_string(cells_h) + ", " + std::to_string(cells_w) +
                   ") (the coarse grid of the image: floor(H/s), floor(W/s)), got " + ShapeText(a));
  }
  py::array_t<uint8_t> out({static_cast<py::ssize_t>(cells_h), static_cast<py::ssize_t>(cells_w)});
  auto dst = out.mutable_unchecked<2>();
  const py::array ints = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!ints) throw py::error_already_set();
  const auto src = py::array_t<int64_t>(ints).unchecked<2>();
  for (py::ssize_t r = 0; r < cells_h; ++r) {
    for (py::ssize_t c = 0; c < cells_w; ++c) dst(r, c) = src(r, c) != 0 ? 1 : 0;
  }
  return out;
}

py::dict LoftrCoarseSupervision(py::handle depth0, py::handle depth1, py::handle K0, py::handle K1,
                                py::handle T_0to1, py::handle T_1to0, int coarse_stride,
                                std::array<double, 2> scale0, std::array<double, 2> scale1,
                                std::optional<std::array<int, 2>> image_size0,
                                std::optional<std::array<int, 2>> image_size1, bool compat,
                                py::handle mask0, py::handle mask1) {
  gt::truth::LoftrSupervisionOptions options;
  options.coarse_stride = coarse_stride;
  options.compat = compat;
  std::string error;
  if (!options.Check(&error)) ThrowValue("coarse_stride", error);
  const py::array_t<float> d0 = DepthArray(depth0, "depth0");
  const py::array_t<float> d1 = DepthArray(depth1, "depth1");
  CheckScale(scale0, "scale0");
  CheckScale(scale1, "scale1");
  const auto view = [&](const py::array_t<float>& d, py::handle K,
                        const std::array<double, 2>& scale,
                        const std::optional<std::array<int, 2>>& size, const std::string& index) {
    gt::truth::LoftrView v;
    v.depth_m = d.data();
    v.depth_height = static_cast<int>(d.shape(0));
    v.depth_width = static_cast<int>(d.shape(1));
    v.K = CameraFromArray(K, v.depth_width, v.depth_height, "K" + index).K();
    v.scale_x = scale[0];
    v.scale_y = scale[1];
    v.image_height = size ? (*size)[0] : v.depth_height;
    v.image_width = size ? (*size)[1] : v.depth_width;
    if (v.image_height < coarse_stride || v.image_width < coarse_stride) {
      ThrowValue("image_size" + index, "expected (height, width) of at least one coarse cell (" +
                                           std::to_string(coarse_stride) + " pixels), got (" +
                                           std::to_string(v.image_height) + ", " +
                                           std::to_string(v.image_width) + ")");
    }
    return v;
  };
  gt::truth::LoftrView v0 = view(d0, K0, scale0, image_size0, "0");
  gt::truth::LoftrView v1 = view(d1, K1, scale1, image_size1, "1");
  py::array_t<uint8_t> m0, m1;  // alive while the C++ reads them
  if (!mask0.is_none()) {
    m0 = CellMaskArray(mask0, v0.image_height / coarse_stride, v0.image_width / coarse_stride,
                       "mask0");
    v0.cell_mask = m0.data();
  }
  if (!mask1.is_none()) {
    m1 = CellMaskArray(mask1, v1.image_height / coarse_stride, v1.image_width / coarse_stride,
                       "mask1");
    v1.cell_mask = m1.data();
  }
  const Eigen::Matrix4d cam1_from_cam0 = RelativePoseFromArray(T_0to1, "T_0to1");
  const Eigen::Matrix4d cam0_from_cam1 =
      T_1to0.is_none() ? Eigen::Matrix4d(gt::Rigid3d(cam1_from_cam0).inverse().matrix())
                       : RelativePoseFromArray(T_1to0, "T_1to0");
  // LoFTR's batches carry both: one that is not the other's inverse warped image 1 with
  // another pose (0 matches, silently). The translation is compared relative to its length
  // (float32 poses of MegaDepth's arbitrary scale).
  {
    const Eigen::Matrix4d p = cam0_from_cam1 * cam1_from_cam0;
    const double scale = std::max(1.0, cam1_from_cam0.block<3, 1>(0, 3).norm());
    const double off =
        std::max((p.block<3, 3>(0, 0) - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
                 p.block<3, 1>(0, 3).cwiseAbs().maxCoeff() / scale);
    if (!(off <= gt::kRigidTolerance)) {
      ThrowValue("T_1to0",
                 "expected the inverse of T_0to1 (|T_1to0 T_0to1 - I| = " + std::to_string(off) +
                     " > " + std::to_string(gt::kRigidTolerance) + ", translation relative)");
    }
  }
  gt::truth::LoftrCoarseSupervision s;
  try {
    py::gil_scoped_release no_gil;
    s = gt::truth::ComputeLoftrSupervision(v0, v1, cam1_from_cam0, cam0_from_cam1, options);
  } catch (const gt::InputError& e) {  // "view0: ..." (e.g. compat, a grid point off the map)
    std::string problem = e.what();
    problem.erase(0, e.where().size() + 2);
    ThrowValue(e.where() == "view0"   ? "depth0"
               : e.where() == "view1" ? "depth1"
                                      : e.where(),
               problem);
  }
  const py::ssize_t l0 = static_cast<py::ssize_t>(s.target0.size());
  const py::ssize_t l1 = static_cast<py::ssize_t>(s.target1.size());
  const py::ssize_t m = static_cast<py::ssize_t>(s.size());
  py::dict out;
  out["cells_shape0"] = py::make_tuple(s.cells_h0, s.cells_w0);
  out["cells_shape1"] = py::make_tuple(s.cells_h1, s.cells_w1);
  out["grid0"] = ToArray(std::move(s.grid0), {l0, 2});
  out["grid1"] = ToArray(std::move(s.grid1), {l1, 2});
  out["warped0"] = ToArray(std::move(s.warped0), {l0, 2});
  out["warped1"] = ToArray(std::move(s.warped1), {l1, 2});
  out["target0"] = ToArray(std::move(s.target0), {l0});
  out["target1"] = ToArray(std::move(s.target1), {l1});
  out["status0"] = ToArray(std::move(s.status0), {l0});
  out["status1"] = ToArray(std::move(s.status1), {l1});
  out["matches"] = ToArray(std::move(s.matches), {m, 2});
  return out;
}

// A depth map and its K at the size of LoFTR's resized image (scale = depth-map pixels per
// image pixel): the image covers the top-left round(width * sx) x round(height * sy) pixels
// of the depth map (MegaDepth's depth is padded at the bottom and right), which are resampled
// to width x height with the pixel-centre rules of core/camera.h (ResizeDepthNearest,
// Camera::Resized).
py::tuple DepthAtImageSize(py::handle depth, py::handle K, py::handle scale_arg,
                           py::handle width_arg, py::handle height_arg) {
  const py::array scale_array = AsArray(scale_arg, "scale");
  if (scale_array.size() != 2 ||
      (scale_array.dtype().kind() != 'f' && scale_array.dtype().kind() != 'i' &&
       scale_array.dtype().kind() != 'u')) {
    ThrowValue("scale", "expected (sx, sy), two numbers, got " +
                            std::string(py::repr(scale_arg)).substr(0, 80));
  }
  const py::array_t<double, py::array::forcecast> scale_values(scale_array);
  const std::array<double, 2> scale = {scale_values.data()[0], scale_values.data()[1]};
  const int width = Arg<int>(width_arg, "width"), height = Arg<int>(height_arg, "height");
  CheckScale(scale, "scale");
  if (width < 2 || height < 2) {
    ThrowValue("width/height", "expected an image of at least 2 x 2 pixels, got " +
                                   std::to_string(width) + " x " + std::to_string(height));
  }
  const std::shared_ptr<const gt::DepthImage> full = DepthFromArray(depth, "depth");
  const long cover_w = std::lround(width * scale[0]), cover_h = std::lround(height * scale[1]);
  if (cover_w < 1 || cover_h < 1 || cover_w > full->width || cover_h > full->height) {
    ThrowValue("scale", "the image (" + std::to_string(width) + " x " + std::to_string(height) +
                            ") at this scale covers " + std::to_string(cover_w) + " x " +
                            std::to_string(cover_h) + " depth pixels; the depth map has " +
                            std::to_string(full->width) + " x " + std::to_string(full->height));
  }
  const gt::Camera camera =
      CameraFromArray(K, static_cast<int>(cover_w), static_cast<int>(cover_h), "K");
  gt::DepthImage resized;
  {
    py::gil_scoped_release release;
    gt::DepthImage crop(static_cast<int>(cover_w), static_cast<int>(cover_h));
    for (int v = 0; v < crop.height; ++v) {
      std::copy_n(full->values_m.data() + static_cast<size_t>(v) * full->width, crop.width,
                  crop.values_m.data() + static_cast<size_t>(v) * crop.width);
    }
    resized = gt::ResizeDepthNearest(crop, width, height);
  }
  return py::make_tuple(ToArray(std::move(resized.values_m), {height, width}),
                        MatrixToArray(camera.Resized(width, height).K()));
}

// The target cells (geometry/patches.h TargetCell) of points xy [M, 2] in a cells_w x
// cells_h grid: int32 [M], -1 outside the grid or not finite.
py::array_t<int32_t> TargetCells(py::handle xy_arg, py::handle cells_w_arg, py::handle cells_h_arg,
                                 py::handle stride_arg, py::handle anchor_arg) {
  py::array a = AsArray(xy_arg, "xy");
  if (a.dtype().kind() != 'f' || a.ndim() != 2 || a.shape(1) != 2) {
    ThrowValue("xy", "expected a float array [M, 2], got dtype " + DtypeText(a) + " shape " +
                         ShapeText(a));
  }
  const auto xy = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!xy) throw py::error_already_set();
  const int cells_w = Arg<int>(cells_w_arg, "cells_w"), cells_h = Arg<int>(cells_h_arg, "cells_h");
  const int stride = Arg<int>(stride_arg, "stride");
  if (stride < 1) ThrowValue("stride", "expected an int >= 1, got " + std::to_string(stride));
  const gt::Anchor anchor =
      Named("anchor", [&] { return gt::ParseAnchor(Arg<std::string>(anchor_arg, "anchor")); });
  const py::ssize_t m = xy.shape(0);
  std::vector<int32_t> cells(static_cast<size_t>(m));
  for (py::ssize_t k = 0; k < m; ++k) {
    cells[static_cast<size_t>(k)] =
        gt::TargetCell(xy.at(k, 0), xy.at(k, 1), cells_w, cells_h, stride, anchor);
  }
  return ToArray(std::move(cells), {m});
}

}  // namespace

void BindSupervision(py::module_& m) {
  {
    const gt::truth::LoftrSupervisionOptions options;
    py::dict d;  // occgt.SUPERVISION_DEFAULTS: the signature's defaults, from the C++
    d["coarse_stride"] = options.coarse_stride;
    d["compat"] = options.compat;
    m.attr("SUPERVISION_DEFAULTS") = d;
  }
  m.attr("WARP_STATUS_NAMES") =
      py::make_tuple("in_grid", "no_depth", "behind", "out_of_grid", "padded");
  m.def("loftr_coarse_supervision", &LoftrCoarseSupervision, "depth0"_a, "depth1"_a, "K0"_a, "K1"_a,
        "T_0to1"_a, "T_1to0"_a = py::none(), py::kw_only(),
        "coarse_stride"_a = gt::truth::LoftrSupervisionOptions().coarse_stride,
        "scale0"_a = std::array<double, 2>{1.0, 1.0}, "scale1"_a = std::array<double, 2>{1.0, 1.0},
        "image_size0"_a = py::none(), "image_size1"_a = py::none(),
        "compat"_a = gt::truth::LoftrSupervisionOptions().compat, "mask0"_a = py::none(),
        "mask1"_a = py::none(),
        "LoFTR's coarse supervision of one pair (truth::ComputeLoftrSupervision); see "
        "occgt.torch.loftr_supervision and docs/PYTHON.md, \"Supervision\".");
  m.def("target_cells", &TargetCells, "xy"_a, "cells_w"_a, "cells_h"_a, "stride"_a, "anchor"_a,
        "int32 [M]: the cell of a cells_w x cells_h grid (row-major) each point of xy [M, 2] "
        "falls to by the target-cell rule of the patch matches (geometry/patches.h "
        "TargetCell), -1 outside the grid or not finite.");
  m.def("depth_at_image_size", &DepthAtImageSize, "depth"_a, "K"_a, "scale"_a, "width"_a,
        "height"_a,
        "(depth, K) at the size of LoFTR's resized image: the top-left round(width * sx) x "
        "round(height * sy) pixels of depth (scale = depth-map pixels per image pixel) "
        "resampled nearest to width x height, and K for it (pixel-centre rules, "
        "docs/GROUND_TRUTH.md §1).");
}

}  // namespace occgt_py

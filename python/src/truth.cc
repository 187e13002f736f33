// Bindings of libgt/truth: one pair's ground truth (truth::ComputePairTruth) from NumPy
// arrays, and the dense form of the occupancy words (occupancy::DenseVolume). Arguments are
// converted and checked (convert.h), the Options struct is filled like `occgt pair` /
// `occgt occupancy` fill it, the work runs without the GIL, and every output array owns its
// C++ vector. The documented signatures are those of python/occgt/__init__.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/pair_truth.h"
#include "python/src/convert.h"
#include "python/src/scope_map.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

struct PairArguments {
  std::string preset;
  std::optional<double> abs_tol_m, rel_tol, min_depth_m, max_depth_m;
  std::optional<std::string> relative_to, bounds, target_lookup, missing_target;
  int stride;
  std::string anchor;
  bool mutual, occupancy;
  double voxel_m;
  std::optional<double> max_range_m;  // none: far_m (as a recipe and `occgt occupancy`)
  double near_m, far_m;
  int bins;
  std::string spacing, traversal, occupancy_mode;
  const PyScopeMap* scope_map = nullptr;  // Scene.fuse's map, or none (fuse the pair here)
};

gt::truth::PairTruthOptions MakeOptions(const PairArguments& a) {
  gt::truth::PairTruthOptions o;
  gt::LabelOptions& lo = o.labels;
  lo = Named("preset", [&] { return gt::LabelPreset(a.preset); });
  if (a.abs_tol_m) lo.abs_tol_m = *a.abs_tol_m;
  if (a.rel_tol) lo.rel_tol = *a.rel_tol;
  if (a.min_depth_m) lo.min_depth_m = *a.min_depth_m;
  if (a.max_depth_m) lo.max_depth_m = *a.max_depth_m;
  if (a.relative_to) lo.relative_to = gt::ParseRelativeTo(*a.relative_to, "relative_to");
  if (a.bounds) lo.bounds = gt::ParseBounds(*a.bounds, "bounds");
  if (a.target_lookup) lo.target_lookup = gt::ParseTargetLookup(*a.target_lookup, "target_lookup");
  if (a.missing_target) {
    lo.missing_target = gt::ParseMissingTarget(*a.missing_target, "missing_target");
  }
  o.patches.stride = a.stride;
  o.patches.anchor = gt::ParseAnchor(a.anchor, "anchor");
  o.patches.mutual = a.mutual;
  o.occupancy = a.occupancy;
  o.fusion.voxel_size_m = a.voxel_m;
  o.fusion.max_range_m = a.max_range_m.value_or(a.far_m);
  o.bins.num_bins = a.bins;
  o.bins.near_m = a.near_m;
  o.bins.far_m = a.far_m;
  o.bins.spacing = Named("spacing", [&] { return gt::occupancy::ParseBinSpacing(a.spacing); });
  o.bins.traversal = Named("traversal", [&] { return gt::occupancy::ParseTraversal(a.traversal); });
  o.mode =
      Named("occupancy_mode", [&] { return gt::occupancy::ParseOccupancyMode(a.occupancy_mode); });
  std::string error;
  if (!o.Check(&error)) ThrowValue("options", error);
  return o;
}

gt::truth::WorkingFrame MakeFrame(py::handle depth, py::handle K, py::handle world_from_cam,
                                  const std::string& index) {
  gt::truth::WorkingFrame f;
  f.depth = DepthFromArray(depth, "depth" + index);
  f.camera = CameraFromArray(K, f.depth->width, f.depth->height, "K" + index);
  f.world_from_cam = PoseFromArray(world_from_cam, "world_from_cam" + index);
  return f;
}

py::dict PairGroundTruth(py::handle depth0, py::handle depth1, py::handle K0, py::handle K1,
                         py::handle world_from_cam0, py::handle world_from_cam1,
                         const PairArguments& args) {
  const gt::truth::PairTruthOptions options = MakeOptions(args);
  const gt::truth::WorkingFrame f0 = MakeFrame(depth0, K0, world_from_cam0, "0");
  const gt::truth::WorkingFrame f1 = MakeFrame(depth1, K1, world_from_cam1, "1");
  const PyScopeMap* scope = args.scope_map;
  if (scope) {
    std::ostringstream problem;
    if (!options.occupancy) problem << "given without occupancy=True";
    else if (options.mode != gt::occupancy::OccupancyMode::kOctomap)
      problem << "used by occupancy_mode 'octomap' only";
    else if (scope->voxel_m != options.fusion.voxel_size_m ||
             scope->max_range_m != options.fusion.max_range_m)
      problem << "fused with voxel_m " << scope->voxel_m << ", max_range_m " << scope->max_range_m
              << "; expected the same here, got voxel_m " << options.fusion.voxel_size_m
              << ", max_range_m " << options.fusion.max_range_m;
    if (!problem.str().empty()) ThrowValue("scope_map", problem.str());
  }
  gt::truth::PairTruth truth;
  {
    py::gil_scoped_release no_gil;
    truth = gt::truth::ComputePairTruth(f0, f1, options, scope ? &scope->fused->map : nullptr);
  }
  gt::PairLabels& p = truth.labels;
  gt::PatchMatches& pm = p.patches;
  const py::ssize_t m = static_cast<py::ssize_t>(pm.size());
  py::dict out;
  out["label01"] = ToArray(std::move(p.l01.labels), {p.l01.height, p.l01.width});
  out["label10"] = ToArray(std::move(p.l10.labels), {p.l10.height, p.l10.width});
  out["matches"] = ToArray(std::move(pm.matches), {m, 2});
  out["match_type"] = ToArray(std::move(pm.match_type), {m});
  out["match_xy"] = ToArray(std::move(pm.match_xy), {m, 2});
  out["cells0"] = ToArray(std::move(pm.cells0), {pm.cells_h0, pm.cells_w0});
  out["cells1"] = ToArray(std::move(pm.cells1), {pm.cells_h1, pm.cells_w1});
  out["T_0to1"] = MatrixToArray(p.cam1_from_cam0.matrix());
  out["metrics01"] = JsonToPython(gt::truth::MetricsJson<nlohmann::ordered_json>(p.m01));
  out["metrics10"] = JsonToPython(gt::truth::MetricsJson<nlohmann::ordered_json>(p.m10));
  if (truth.occupancy) {
    gt::occupancy::FrustumVolume& v0 = truth.occupancy->cam0;
    gt::occupancy::FrustumVolume& v1 = truth.occupancy->cam1;
    const py::ssize_t n = static_cast<py::ssize_t>(v0.edges_m.size());
    out["occ0"] = ToArray(std::move(v0.occ), {v0.height, v0.width});
    out["known0"] = ToArray(std::move(v0.known), {v0.height, v0.width});
    out["occ1"] = ToArray(std::move(v1.occ), {v1.height, v1.width});
    out["known1"] = ToArray(std::move(v1.known), {v1.height, v1.width});
    out["bin_edges_m"] = ToArray(std::move(v0.edges_m), {n});
  }
  return out;
}

py::array_t<uint8_t> DenseVolume(py::handle occ, py::handle known, int bins) {
  gt::occupancy::FrustumVolume v;
  std::vector<py::ssize_t> shape_occ, shape_known;
  v.occ = WordsFromArray(occ, "occ", &shape_occ);
  v.known = WordsFromArray(known, "known", &shape_known);
  if (shape_occ != shape_known) {
    ThrowValue("known", "expected the shape of occ " + ShapeText(AsArray(occ, "occ")) + ", got " +
                            ShapeText(AsArray(known, "known")));
  }
  gt::occupancy::BinOptions b;
  b.num_bins = bins;
  std::string error;
  if (!b.Check(&error)) ThrowValue("bins", error);
  v.height = static_cast<int>(shape_occ[0]);
  v.width = static_cast<int>(shape_occ[1]);
  v.edges_m = gt::occupancy::BinEdges(b);  // only their number matters here
  std::vector<uint8_t> dense;
  {
    py::gil_scoped_release no_gil;
    dense = gt::occupancy::DenseVolume(v);
  }
  return ToArray(std::move(dense), {bins, v.height, v.width});
}

}  // namespace

void BindTruth(py::module_& m) {
  py::class_<PyScopeMap>(m, "ScopeMap",
                         "An occupancy map fused over a scope of a scene (Scene.fuse), for "
                         "pair_ground_truth(..., occupancy=True, scope_map=...).")
      .def_property_readonly(
          "scene", [](const PyScopeMap& s) { return s.scene; }, "scene name")
      .def_property_readonly(
          "scope", [](const PyScopeMap& s) { return s.scope; }, "'pair', 'window:N' or 'scene:S'")
      .def_property_readonly(
          "fused_ids", [](const PyScopeMap& s) { return s.fused->fused_ids; },
          "ids of the frames fused, in fusion order")
      .def_property_readonly(
          "skipped",
          [](const PyScopeMap& s) {
            py::list out;
            for (const auto& k : s.fused->skipped) out.append(py::make_tuple(k.frame_id, k.reason));
            return out;
          },
          "[(frame id, reason)] of the scope's frames that could not be read (not fused)")
      .def_property_readonly(
          "voxel_m", [](const PyScopeMap& s) { return s.voxel_m; }, "voxel size (metres)")
      .def_property_readonly(
          "max_range_m", [](const PyScopeMap& s) { return s.max_range_m; },
          "ray truncation (metres)")
      .def("__repr__", [](const PyScopeMap& s) {
        return "<occgt.ScopeMap " + s.scene + " " + s.scope + " (" +
               std::to_string(s.fused->fused_ids.size()) + " frames)>";
      });
  m.def(
      "pair_ground_truth",
      [](py::handle depth0, py::handle depth1, py::handle K0, py::handle K1,
         py::handle world_from_cam0, py::handle world_from_cam1, std::string preset,
         std::optional<double> abs_tol_m, std::optional<double> rel_tol,
         std::optional<double> min_depth_m, std::optional<double> max_depth_m,
         std::optional<std::string> relative_to, std::optional<std::string> bounds,
         std::optional<std::string> target_lookup, std::optional<std::string> missing_target,
         int stride, std::string anchor, bool mutual, bool occupancy, double voxel_m,
         std::optional<double> max_range_m, double near_m, double far_m, int bins, std::string spacing,
         std::string traversal, std::string occupancy_mode, const PyScopeMap* scope_map) {
        const PairArguments args{std::move(preset),
                                 abs_tol_m,
                                 rel_tol,
                                 min_depth_m,
                                 max_depth_m,
                                 relative_to,
                                 bounds,
                                 target_lookup,
                                 missing_target,
                                 stride,
                                 std::move(anchor),
                                 mutual,
                                 occupancy,
                                 voxel_m,
                                 max_range_m,
                                 near_m,
                                 far_m,
                                 bins,
                                 std::move(spacing),
                                 std::move(traversal),
                                 std::move(occupancy_mode),
                                 scope_map};
        return PairGroundTruth(depth0, depth1, K0, K1, world_from_cam0, world_from_cam1, args);
      },
      "depth0"_a, "depth1"_a, "K0"_a, "K1"_a, "world_from_cam0"_a, "world_from_cam1"_a,
      "preset"_a = "default", py::kw_only(), "abs_tol_m"_a = py::none(), "rel_tol"_a = py::none(),
      "min_depth_m"_a = py::none(), "max_depth_m"_a = py::none(), "relative_to"_a = py::none(),
      "bounds"_a = py::none(), "target_lookup"_a = py::none(), "missing_target"_a = py::none(),
      "stride"_a = 8, "anchor"_a = "center", "mutual"_a = true, "occupancy"_a = false,
      "voxel_m"_a = 0.05, "max_range_m"_a = py::none(), "near_m"_a = 0.1, "far_m"_a = 10.0, "bins"_a = 64,
      "spacing"_a = "linear", "traversal"_a = "exact", "occupancy_mode"_a = "octomap",
      "scope_map"_a = py::none(),
      "The ground truth of one pair (truth::ComputePairTruth); see occgt.pair_ground_truth.");
  m.def("dense_volume", &DenseVolume, "occ"_a, "known"_a, "bins"_a = 64,
        "uint8 [bins, H/2, W/2] (0 free, 1 occupied, 255 unknown) of occupancy words "
        "(occupancy::DenseVolume); see occgt.dense_volume.");
}

}  // namespace occgt_py

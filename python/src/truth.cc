// Bindings of libgt/truth: one pair's ground truth (truth::ComputePairTruth) from NumPy
// arrays, and the dense form of the occupancy words (occupancy::DenseVolume). Arguments are
// converted and checked (convert.h), the Options struct is filled like `occgt pair` /
// `occgt occupancy` fill it, the work runs without the GIL, and every output array owns its
// C++ vector. The documented signatures are those of python/occgt/__init__.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/core/pose.h"
#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/pair_truth.h"
#include "libgt/truth/views_truth.h"
#include "libgt/truth/working_frame.h"
#include "python/src/convert.h"
#include "python/src/scope_map.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

// The keyword arguments of pair_ground_truth and pair_options (python/occgt/__init__.py
// documents them): None keeps the C++ default, and truth::ResolvePairTruthOptions resolves
// them like every other entry point. An unknown keyword is a TypeError, as in Python.
struct PairArguments {
  gt::truth::PairSettings settings;
  gt::truth::DatasetDepthRange range;
  const PyScopeMap* scope_map = nullptr;  // Scene.fuse's map, or none (fuse the pair here)
};

template <typename T>
const char* Expected() {
  if constexpr (std::is_same_v<T, bool>) return "a bool";
  if constexpr (std::is_same_v<T, int>) return "an int";
  if constexpr (std::is_same_v<T, double>) return "a float";
  if constexpr (std::is_same_v<T, std::string>) return "a str";
  return "(min, max) floats";
}

// kwargs[name] (removed from kwargs), None when absent or None; a value of the wrong Python
// type is a TypeError naming the argument, as pybind11's own conversions are.
template <typename T>
std::optional<T> Take(py::dict* kwargs, const char* name) {
  if (!kwargs->contains(name)) return std::nullopt;
  const py::object value = (*kwargs)[name];
  PyDict_DelItemString(kwargs->ptr(), name);
  if (value.is_none()) return std::nullopt;
  if constexpr (std::is_same_v<T, int> || std::is_same_v<T, std::string> ||
                std::is_same_v<T, double> || std::is_same_v<T, bool>) {
    return Arg<T>(value, name);  // an int out of range is a ValueError, not "got int"; a bool
                                 // is not a number (abs_tol_m=True was 1.0), nor 0 a bool
  }
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw py::type_error(std::string(name) + ": expected " + Expected<T>() + ", got " +
                         std::string(py::str(value.get_type().attr("__name__"))));
  }
}

// The label keywords (and the dataset's depth range) of kw into *a, removed from kw: shared
// by pair_ground_truth, pair_options and views_ground_truth.
void TakeLabelArguments(const std::string& preset, py::dict* kw_ptr, PairArguments* a_ptr) {
  py::dict& kw = *kw_ptr;
  PairArguments& a = *a_ptr;
  gt::truth::LabelSettings& ls = a.settings.labels;
  Named("preset", [&] { gt::LabelPreset(preset); });  // a bad name names the argument
  ls.preset = preset;
  ls.abs_tol_m = Take<double>(&kw, "abs_tol_m");
  ls.rel_tol = Take<double>(&kw, "rel_tol");
  ls.min_depth_m = Take<double>(&kw, "min_depth_m");
  ls.max_depth_m = Take<double>(&kw, "max_depth_m");
  if (auto v = Take<std::string>(&kw, "relative_to"))
    ls.relative_to = gt::ParseRelativeTo(*v, "relative_to");
  if (auto v = Take<std::string>(&kw, "bounds")) ls.bounds = gt::ParseBounds(*v, "bounds");
  if (auto v = Take<std::string>(&kw, "target_lookup")) {
    ls.target_lookup = gt::ParseTargetLookup(*v, "target_lookup");
  }
  if (auto v = Take<std::string>(&kw, "missing_target")) {
    ls.missing_target = gt::ParseMissingTarget(*v, "missing_target");
  }
  if (auto v = Take<std::pair<double, double>>(&kw, "dataset_depth_range")) {
    a.range.min_depth_m = v->first;
    a.range.max_depth_m = v->second;
  }
  a.range.set_min_depth_m = Take<double>(&kw, "dataset_min_depth_m");
  a.range.set_max_depth_m = Take<double>(&kw, "dataset_max_depth_m");
}

// The point filters of a fusion, as a ScopeMap check compares them.
std::string FiltersText(const gt::occupancy::FusionOptions& f) {
  std::ostringstream s;
  s << "downsample " << (f.downsample ? "on" : "off") << ", remove_outliers ";
  if (f.remove_outliers)
    s << "on (outlier_k " << f.outlier_k << ", outlier_stddev " << f.outlier_stddev << ")";
  else
    s << "off";
  return s.str();
}

void RejectUnknownKeywords(const py::dict& kw) {
  for (const auto& item : kw) {
    throw py::type_error("got an unexpected keyword argument '" + std::string(py::str(item.first)) +
                         "'");
  }
}

PairArguments ArgumentsFromKwargs(const std::string& preset, const py::kwargs& given) {
  py::dict kw(given);  // a copy: keys are removed as they are read
  PairArguments a;
  gt::truth::PairSettings& st = a.settings;
  TakeLabelArguments(preset, &kw, &a);
  if (auto v = Take<int>(&kw, "stride")) st.patches.stride = *v;
  if (auto v = Take<std::string>(&kw, "anchor")) st.patches.anchor = gt::ParseAnchor(*v, "anchor");
  if (auto v = Take<bool>(&kw, "mutual")) st.patches.mutual = *v;
  gt::truth::OccupancySettings& os = st.occupancy;
  os.enabled = Take<bool>(&kw, "occupancy").value_or(false);
  os.voxel_m = Take<double>(&kw, "voxel_m");
  os.max_range_m = Take<double>(&kw, "max_range_m");
  os.bins = Take<int>(&kw, "bins");
  os.near_m = Take<double>(&kw, "near_m");
  os.far_m = Take<double>(&kw, "far_m");
  if (auto v = Take<std::string>(&kw, "spacing")) {
    os.spacing = Named("spacing", [&] { return gt::occupancy::ParseBinSpacing(*v); });
  }
  if (auto v = Take<std::string>(&kw, "traversal")) {
    os.traversal = Named("traversal", [&] { return gt::occupancy::ParseTraversal(*v); });
  }
  if (auto v = Take<std::string>(&kw, "occupancy_mode")) {
    os.mode = Named("occupancy_mode", [&] { return gt::occupancy::ParseOccupancyMode(*v); });
  }
  os.downsample = Take<bool>(&kw, "downsample");
  os.remove_outliers = Take<bool>(&kw, "remove_outliers");
  os.outlier_k = Take<int>(&kw, "outlier_k");
  os.outlier_stddev = Take<double>(&kw, "outlier_stddev");
  if (std::string why = gt::truth::OccupancySettingsProblem(os); !why.empty()) {
    ThrowValue(why.substr(0, why.find(':')), why.substr(why.find(':') + 2));
  }
  if (kw.contains("scope_map")) {
    const py::object m = kw["scope_map"];
    PyDict_DelItemString(kw.ptr(), "scope_map");
    if (!m.is_none()) {
      if (!py::isinstance<PyScopeMap>(m)) {
        throw py::type_error("scope_map: expected a ScopeMap (Scene.fuse), got " +
                             std::string(py::str(m.get_type().attr("__name__"))));
      }
      a.scope_map = m.cast<const PyScopeMap*>();
    }
  }
  RejectUnknownKeywords(kw);
  return a;
}

gt::truth::PairTruthOptions MakeOptions(const PairArguments& a) {
  const gt::truth::PairTruthOptions o = gt::truth::ResolvePairTruthOptions(a.settings, a.range);
  std::string error;
  if (!o.Check(&error)) {
    ThrowOptionsValue(error, a.settings.occupancy.max_range_m, a.settings.occupancy.far_m);
  }
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

// The resolved options as the outputs record them (label_options, patch_options,
// occupancy_options: pair_files.h), so that a caller can compare them with a shard's.
py::dict OptionsDict(const gt::truth::PairTruthOptions& o) {
  py::dict d;
  d["label_options"] = JsonToPython(gt::truth::LabelOptionsJson(o.labels));
  d["patch_options"] = JsonToPython(gt::truth::PatchOptionsJson(o.patches));
  d["occupancy_options"] =
      o.occupancy ? JsonToPython(gt::truth::OccupancyOptionsJson(o)) : py::object(py::none());
  return d;
}

py::dict PairGroundTruth(py::handle depth0, py::handle depth1, py::handle K0, py::handle K1,
                         py::handle world_from_cam0, py::handle world_from_cam1,
                         const PairArguments& args) {
  const gt::truth::PairTruthOptions options = MakeOptions(args);
  const gt::truth::WorkingFrame f0 = MakeFrame(depth0, K0, world_from_cam0, "0");
  const gt::truth::WorkingFrame f1 = MakeFrame(depth1, K1, world_from_cam1, "1");
  // One patch cell must fit the image (the labels failed later without naming stride).
  const int stride = options.patches.stride;
  for (const gt::truth::WorkingFrame* f : {&f0, &f1}) {
    if (options.labels_and_matches && (f->depth->width < stride || f->depth->height < stride)) {
      ThrowValue("stride", "stride " + std::to_string(stride) + " is larger than the " +
                               std::to_string(f->depth->width) + "x" +
                               std::to_string(f->depth->height) +
                               " depth map (one patch cell must fit)");
    }
  }
  const PyScopeMap* scope = args.scope_map;
  if (scope) {
    std::ostringstream problem;
    if (!options.occupancy)
      problem << "given without occupancy=True";
    else if (options.mode != gt::occupancy::OccupancyMode::kOctomap)
      problem << "used by occupancy_mode 'octomap' only";
    else if (FiltersText(scope->fusion) != FiltersText(options.fusion))
      problem << "fused with " << FiltersText(scope->fusion) << "; expected the same here, got "
              << FiltersText(options.fusion);
    else if (scope->voxel_m != options.fusion.voxel_m ||
             scope->max_range_m != options.fusion.max_range_m)
      problem << "fused with voxel_m " << scope->voxel_m << ", max_range_m " << scope->max_range_m
              << "; expected the same here, got voxel_m " << options.fusion.voxel_m
              << ", max_range_m " << options.fusion.max_range_m;
    // The depth maps it fused were of this size and depth range (a map of other frames' size
    // or range was used silently).
    else if (scope->width != f0.depth->width || scope->height != f0.depth->height)
      problem << "fused at " << scope->width << "x" << scope->height
              << "; expected the size of depth0 here, " << f0.depth->width << "x"
              << f0.depth->height;
    else if (scope->min_depth_m != options.labels.min_depth_m ||
             scope->max_depth_m != options.labels.max_depth_m)
      problem << "fused with depth range [" << scope->min_depth_m << ", " << scope->max_depth_m
              << "] m; expected the same here, got [" << options.labels.min_depth_m << ", "
              << options.labels.max_depth_m << "] m";
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
  if (scope) {  // the options as a sample's json records them: the scope the map was fused over
    gt::truth::PairTruthOptions shown = options;
    gt::occupancy::ParseFusionScope(scope->scope, &shown.fusion);
    out["options"] = OptionsDict(shown);
  } else {
    out["options"] = OptionsDict(options);
  }
  if (truth.occupancy) {
    gt::occupancy::FrustumVolume& v0 = truth.occupancy->cam0;
    gt::occupancy::FrustumVolume& v1 = truth.occupancy->cam1;
    const py::ssize_t n = static_cast<py::ssize_t>(v0.edges_m.size());
    out["occ0"] = ToArray(std::move(v0.occ), {v0.height, v0.width});
    out["known0"] = ToArray(std::move(v0.known), {v0.height, v0.width});
    out["occ1"] = ToArray(std::move(v1.occ), {v1.height, v1.width});
    out["known1"] = ToArray(std::move(v1.known), {v1.height, v1.width});
    out["bin_edges_m"] = ToArray(std::move(v0.edges_m), {n});
    const std::optional<gt::occupancy::FusionStats>& stats = truth.occupancy->fusion_stats;
    out["fusion_stats"] =
        stats ? JsonToPython(gt::truth::FusionStatsJson(*stats)) : py::object(py::none());
  }
  return out;
}

// A list/tuple of arrays, or one array stacked on its first axis, as a list of items named
// "<argument>[i]" (item_ndim: the dimensions of one item).
std::vector<py::object> Items(py::handle obj, const std::string& argument, int item_ndim) {
  std::vector<py::object> items;
  if (py::isinstance<py::list>(obj) || py::isinstance<py::tuple>(obj)) {
    for (py::handle h : obj) items.push_back(py::reinterpret_borrow<py::object>(h));
    return items;
  }
  const py::array a = AsArray(obj, argument);
  if (a.ndim() != item_ndim + 1) {
    // numpy.asarray of a generator, dict or None is a 0-d object array: name the type.
    const std::string got =
        a.ndim() == 0 && a.dtype().kind() == 'O' ? TypeName(obj) : "shape " + ShapeText(a);
    ThrowValue(argument, "expected a list of arrays or one array of " +
                             std::to_string(item_ndim + 1) + " dimensions, got " + got);
  }
  for (py::ssize_t i = 0; i < a.shape(0); ++i) items.push_back(a[py::int_(i)]);
  return items;
}

// views_ground_truth's options from its arguments, checked before any array is looked at.
gt::truth::ViewsTruthOptions ViewsOptions(const std::string& preset, int num_tracks, int query_view,
                                          uint64_t seed, const py::kwargs& given) {
  py::dict kw(given);
  PairArguments a;
  TakeLabelArguments(preset, &kw, &a);
  RejectUnknownKeywords(kw);
  gt::truth::ViewsTruthOptions options;
  options.labels = MakeOptions(a).labels;
  options.num_tracks = num_tracks;
  options.query_view = query_view;
  options.seed = seed;
  if (num_tracks < 0) ThrowValue("num_tracks", "expected >= 0, got " + std::to_string(num_tracks));
  if (query_view < 0) ThrowValue("query_view", "expected >= 0, got " + std::to_string(query_view));
  return options;
}

py::dict ViewsGroundTruth(py::handle depths, py::handle Ks, py::handle world_from_cams,
                          const std::string& preset, py::handle queries, int num_tracks,
                          int query_view, uint64_t seed, const py::kwargs& given) {
  const gt::truth::ViewsTruthOptions options =
      ViewsOptions(preset, num_tracks, query_view, seed, given);
  const std::vector<py::object> d = Items(depths, "depths", 2);
  const std::vector<py::object> k = Items(Ks, "Ks", 2);
  const std::vector<py::object> p = Items(world_from_cams, "world_from_cams", 2);
  const size_t n = d.size();
  if (n < 1 || n > static_cast<size_t>(gt::truth::kMaxViews)) {
    ThrowValue("depths", "expected 1.." + std::to_string(gt::truth::kMaxViews) +
                             " depth maps, got " + std::to_string(n));
  }
  if (k.size() != n) {
    ThrowValue("Ks", "expected " + std::to_string(n) + " matrices (one per depth map), got " +
                         std::to_string(k.size()));
  }
  if (p.size() != n) {
    ThrowValue("world_from_cams", "expected " + std::to_string(n) +
                                      " poses (one per depth map), got " +
                                      std::to_string(p.size()));
  }
  if (query_view < 0 || static_cast<size_t>(query_view) >= n) {
    ThrowValue("query_view",
               "expected 0.." + std::to_string(n - 1) + ", got " + std::to_string(query_view));
  }
  std::vector<gt::truth::WorkingFrame> views(n);
  for (size_t i = 0; i < n; ++i) {
    const std::string index = "[" + std::to_string(i) + "]";
    views[i].depth = DepthFromArray(d[i], "depths" + index);
    views[i].camera =
        CameraFromArray(k[i], views[i].depth->width, views[i].depth->height, "Ks" + index);
    views[i].world_from_cam = PoseFromArray(p[i], "world_from_cams" + index);
    const gt::DepthImage& di = *views[i].depth;
    const gt::DepthImage& d0 = *views[0].depth;
    if (di.width != d0.width || di.height != d0.height) {
      ThrowValue("depths" + index,
                 "expected (" + std::to_string(d0.height) + ", " + std::to_string(d0.width) +
                     ") (the shape of depths[0]), got (" + std::to_string(di.height) + ", " +
                     std::to_string(di.width) + ")");
    }
  }
  std::optional<std::vector<int32_t>> query_uv;
  if (!queries.is_none()) {
    const py::array q = AsArray(queries, "queries");
    if (q.ndim() != 2 || q.shape(1) != 2 || q.dtype().kind() == 'f' ||
        (q.dtype().kind() != 'i' && q.dtype().kind() != 'u')) {
      ThrowValue("queries", "expected an integer array [Q, 2] of (u, v) pixels, got " +
                                DtypeText(q) + " " + ShapeText(q));
    }
    // uint64 values above 2^63 - 1 clipped to it (still outside the image), not wrapped
    // to negative ones; the message shows the value given.
    const bool u64 = q.dtype().kind() == 'u' && q.itemsize() == 8;
    const py::array_t<int64_t, py::array::c_style | py::array::forcecast> q64(
        u64 ? py::array(q.attr("clip")(0, std::numeric_limits<int64_t>::max())) : q);
    query_uv.emplace(static_cast<size_t>(q64.size()));
    const int64_t* src = q64.data();
    for (py::ssize_t i = 0; i < q64.size(); ++i) {
      const int64_t lim = i % 2 == 0 ? views[0].depth->width : views[0].depth->height;
      if (src[i] < 0 || src[i] >= lim) {
        ThrowValue("queries", "expected pixels (u, v) inside the " +
                                  std::to_string(views[0].depth->width) + "x" +
                                  std::to_string(views[0].depth->height) + " image, got " +
                                  std::string(py::str(q[py::make_tuple(i / 2, i % 2)])) +
                                  " at row " + std::to_string(i / 2));
      }
      (*query_uv)[static_cast<size_t>(i)] = static_cast<int32_t>(src[i]);
    }
  }
  gt::truth::ViewsTruth t;
  {
    py::gil_scoped_release no_gil;
    t = gt::truth::ComputeViewsTruth(views, options, query_uv);
  }
  const py::ssize_t nv = t.num_views, h = t.height, w = t.width;
  const py::ssize_t nq = static_cast<py::ssize_t>(t.num_queries());
  py::dict out;
  out["visible_in"] = ToArray(std::move(t.visible_in), {nv, h, w});
  out["occluded_in"] = ToArray(std::move(t.occluded_in), {nv, h, w});
  out["valid"] = ToArray(std::move(t.valid), {nv, h, w});
  out["seen_by"] = ToArray(std::move(t.seen_by), {nv, h, w});
  out["seen_by_histogram"] = ToArray(std::move(t.seen_by_histogram), {nv, nv});
  out["query_view"] = t.query_view;
  out["queries"] = ToArray(std::move(t.queries), {nq, 2});
  out["track_xy"] = ToArray(std::move(t.track_xy), {nv, nq, 2});
  out["track_depth"] = ToArray(std::move(t.track_depth), {nv, nq});
  out["track_state"] = ToArray(std::move(t.track_state), {nv, nq});
  out["label_options"] = JsonToPython(gt::truth::LabelOptionsJson(options.labels));
  return out;
}

py::array_t<uint8_t> DenseVolume(py::handle occ, py::handle known, py::handle bins_arg) {
  const int bins = Arg<int>(bins_arg, "bins");
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
  // A bit at or past `bins` is of another bin count (it was ignored).
  if (bins < 64) {
    for (const auto& [name, words] :
         {std::pair<const char*, const std::vector<uint64_t>*>{"occ", &v.occ},
          std::pair<const char*, const std::vector<uint64_t>*>{"known", &v.known}}) {
      for (size_t i = 0; i < words->size(); ++i) {
        if ((*words)[i] >> bins) {
          ThrowValue(name, "element " + std::to_string(i) + " has a bit at or past bins=" +
                               std::to_string(bins) + " (words of another bin count?)");
        }
      }
    }
  }
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

// seen_by and seen_by_histogram of stored bitmasks (truth::CountSeenBy).
py::dict ViewsSeenBy(py::handle visible_in, py::handle valid) {
  const py::array v = AsArray(visible_in, "visible_in");
  const py::array m = AsArray(valid, "valid");
  if (v.dtype().kind() != 'u' || v.itemsize() != 4 || v.ndim() != 3) {
    ThrowValue("visible_in", "expected uint32 [N, H, W] (views_ground_truth's visible_in), got " +
                                 DtypeText(v) + " " + ShapeText(v));
  }
  if (m.dtype().kind() != 'u' || m.itemsize() != 1 || m.ndim() != 3 || m.shape(0) != v.shape(0) ||
      m.shape(1) != v.shape(1) || m.shape(2) != v.shape(2)) {
    ThrowValue("valid", "expected uint8 of visible_in's shape " + ShapeText(v) + ", got " +
                            DtypeText(m) + " " + ShapeText(m));
  }
  const auto vc = py::array_t<uint32_t, py::array::c_style | py::array::forcecast>::ensure(v);
  const auto mc = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(m);
  if (!vc || !mc) throw py::error_already_set();
  const py::ssize_t n = v.shape(0), h = v.shape(1), w = v.shape(2);
  if (n < 1 || n > gt::truth::kMaxViews) {
    ThrowValue("visible_in", "expected 1.." + std::to_string(gt::truth::kMaxViews) +
                                 " views, got " + std::to_string(n));
  }
  gt::truth::SeenBy s;
  {
    py::gil_scoped_release no_gil;
    s = gt::truth::CountSeenBy(vc.data(), mc.data(), static_cast<int>(n),
                               static_cast<size_t>(h) * static_cast<size_t>(w));
  }
  py::dict out;
  out["seen_by"] = ToArray(std::move(s.seen_by), {n, h, w});
  out["seen_by_histogram"] = ToArray(std::move(s.histogram), {n, n});
  return out;
}

// The value every keyword argument of pair_ground_truth takes when None: the defaults of the
// C++ Options structs as truth::ResolvePairTruthOptions gives them (the Python signatures
// show these values; none is written in Python).
py::dict PairDefaults() {
  const gt::truth::PairSettings settings;
  const gt::truth::PairTruthOptions o = gt::truth::ResolvePairTruthOptions(settings);
  py::dict d;
  d["preset"] = settings.labels.preset;
  d["stride"] = o.patches.stride;
  d["anchor"] = gt::AnchorName(o.patches.anchor);
  d["mutual"] = o.patches.mutual;
  d["voxel_m"] = o.fusion.voxel_m;
  d["near_m"] = o.bins.near_m;
  d["far_m"] = o.bins.far_m;
  d["bins"] = o.bins.num_bins;
  d["spacing"] = gt::occupancy::BinSpacingName(o.bins.spacing);
  d["traversal"] = gt::occupancy::TraversalName(o.bins.traversal);
  d["occupancy_mode"] = gt::occupancy::OccupancyModeName(o.mode);
  d["downsample"] = o.fusion.downsample;
  d["remove_outliers"] = o.fusion.remove_outliers;
  d["outlier_k"] = o.fusion.outlier_k;
  d["outlier_stddev"] = o.fusion.outlier_stddev;
  d["min_depth_m"] = gt::kDefaultMinDepthM;
  d["max_depth_m"] = gt::kDefaultMaxDepthM;
  const gt::truth::Resolution resolution;
  d["width"] = resolution.width;
  d["height"] = resolution.height;
  return d;
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
          "[(frame id, reason)] of the scope's frames left out of the fusion, in scene order: "
          "those the reader marks unusable (reason 'unusable: ...') and those whose depth could "
          "not be read")
      .def_property_readonly(
          "fusion_stats",
          [](const PyScopeMap& s) {
            return JsonToPython(gt::truth::FusionStatsJson(s.fused->map.stats()));
          },
          "what happened to the points of the fused frames (pair_ground_truth's fusion_stats)")
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
         py::handle world_from_cam0, py::handle world_from_cam1, py::handle preset,
         const py::kwargs& kwargs) {
        return PairGroundTruth(depth0, depth1, K0, K1, world_from_cam0, world_from_cam1,
                               ArgumentsFromKwargs(Arg<std::string>(preset, "preset"), kwargs));
      },
      "depth0"_a, "depth1"_a, "K0"_a, "K1"_a, "world_from_cam0"_a, "world_from_cam1"_a,
      "preset"_a = gt::truth::LabelSettings().preset,
      "The ground truth of one pair (truth::ComputePairTruth); see occgt.pair_ground_truth. "
      "A keyword argument that is None keeps the C++ default (PAIR_DEFAULTS).");
  m.def(
      "pair_options",
      [](py::handle preset, const py::kwargs& kwargs) {
        return OptionsDict(
            MakeOptions(ArgumentsFromKwargs(Arg<std::string>(preset, "preset"), kwargs)));
      },
      "preset"_a = gt::truth::LabelSettings().preset,
      "The options pair_ground_truth resolves from the same arguments (its 'options' entry), "
      "without computing anything; see occgt.pair_options.");
  m.def(
      "scope_name",
      [](const std::string& scope) {
        gt::occupancy::FusionOptions o;
        try {
          gt::occupancy::ParseFusionScope(scope, &o);
        } catch (const gt::InputError& e) {  // "--scope: ...": the argument is `scope` here
          ThrowValue("scope", std::string(e.what()).substr(e.where().size() + 2));
        }
        return gt::occupancy::FusionScopeName(o);
      },
      "scope"_a,
      "The name ScopeMap.scope gives a fusion scope ('pair', 'window:N', 'scene:S'; leading "
      "zeros dropped), by occupancy::ParseFusionScope; ValueError naming `scope` otherwise.");
  m.attr("PAIR_DEFAULTS") = PairDefaults();
  {
    const gt::truth::ViewsTruthOptions views;
    py::dict d;
    d["num_tracks"] = views.num_tracks;
    d["query_view"] = views.query_view;
    d["seed"] = views.seed;
    m.attr("VIEWS_DEFAULTS") = d;
  }
  m.def(
      "views_ground_truth",
      [](py::handle depths, py::handle Ks, py::handle world_from_cams, py::handle preset,
         py::handle queries, py::handle num_tracks, py::handle query_view, py::handle seed,
         const py::kwargs& kwargs) {
        return ViewsGroundTruth(depths, Ks, world_from_cams, Arg<std::string>(preset, "preset"),
                                queries, Arg<int>(num_tracks, "num_tracks"),
                                Arg<int>(query_view, "query_view"), Arg<uint64_t>(seed, "seed"),
                                kwargs);
      },
      "depths"_a, "Ks"_a, "world_from_cams"_a, py::kw_only(),
      "preset"_a = gt::truth::LabelSettings().preset, "queries"_a = py::none(),
      "num_tracks"_a = gt::truth::ViewsTruthOptions().num_tracks,
      "query_view"_a = gt::truth::ViewsTruthOptions().query_view,
      "seed"_a = gt::truth::ViewsTruthOptions().seed,
      "The dense ground truth of N views (truth::ComputeViewsTruth); see "
      "occgt.views_ground_truth.");
  {
    py::tuple names(gt::truth::kNumTrackStates);
    for (int s = 0; s < gt::truth::kNumTrackStates; ++s) {
      names[s] = gt::truth::TrackStateName(static_cast<gt::truth::TrackState>(s));
    }
    m.attr("TRACK_STATE_NAMES") = names;
  }

  m.def(
      "check_resolution",
      [](py::handle width, py::handle height) {
        const gt::truth::Resolution r{Arg<int>(width, "width"), Arg<int>(height, "height")};
        if (std::string error; !r.Check(&error)) ThrowValue("width, height", error);
      },
      "width"_a, "height"_a,
      "None for a working resolution the datasets accept (truth::Resolution), else TypeError "
      "(not an int) or ValueError.");
  m.def(
      "views_options",
      [](py::handle preset, py::handle num_tracks, py::handle query_view, py::handle seed,
         const py::kwargs& kwargs) {
        const gt::truth::ViewsTruthOptions options =
            ViewsOptions(Arg<std::string>(preset, "preset"), Arg<int>(num_tracks, "num_tracks"),
                         Arg<int>(query_view, "query_view"), Arg<uint64_t>(seed, "seed"), kwargs);
        return JsonToPython(gt::truth::LabelOptionsJson(options.labels));
      },
      "preset"_a = gt::truth::LabelSettings().preset,
      "num_tracks"_a = gt::truth::ViewsTruthOptions().num_tracks,
      "query_view"_a = gt::truth::ViewsTruthOptions().query_view,
      "seed"_a = gt::truth::ViewsTruthOptions().seed,
      "The label options views_ground_truth resolves from the same arguments (its "
      "'label_options' entry), checked, without computing anything (TupleIndexDataset).");
  m.def("views_seen_by", &ViewsSeenBy, "visible_in"_a, "valid"_a,
        "seen_by uint8 [N, H, W] and seen_by_histogram int64 [N, N] of stored N-view bitmasks "
        "(truth::CountSeenBy), as views_ground_truth returns them; see occgt.views_seen_by.");
  m.def("dense_volume", &DenseVolume, "occ"_a, "known"_a,
        "bins"_a = gt::occupancy::BinOptions().num_bins,
        "uint8 [bins, H/2, W/2] (0 free, 1 occupied, 255 unknown) of occupancy words "
        "(occupancy::DenseVolume); see occgt.dense_volume.");
}

}  // namespace occgt_py

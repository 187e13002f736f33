// Bindings of libgt/io (the dataset readers) and of the working-frame loading of libgt/truth:
// open_dataset(root, format) -> Dataset; Dataset.scenes(), Dataset.scene(name) -> Scene;
// Scene.frames (gt::Frame metadata), Scene.load(frame_id, width, height) -> (depth, K,
// world_from_cam) at the working resolution (truth::LoadWorkingDepth / WorkingCamera, the
// two halves of truth::LoadWorkingFrame), Scene.load_color(frame_id, width, height) -> RGB
// at the working resolution (io::ReadColorResized, the image of a shard sample). Files are
// read without the GIL. For occgt.torch.ShardDataset: gunzip (a .npy.gz member) and
// npy_header (a .npy member's header, io::ParseNpyHeader).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/core/frame.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/gzip.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"
#include "libgt/occupancy/fusion.h"
#include "libgt/render/frame_depth.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/pair_truth.h"
#include "libgt/truth/working_frame.h"
#include "python/src/convert.h"
#include "python/src/scope_map.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

// A recipe's dataset.fused_depth block from Python: None (render::FusedDepthOptions'
// defaults, occgt.DATASET_DEFAULTS["fused_depth"]) or a dict with abs_tol_m and/or rel_tol.
gt::render::FusedDepthOptions FusedDepthFrom(const py::object& value) {
  gt::render::FusedDepthOptions fused;
  if (value.is_none()) return fused;
  if (!py::isinstance<py::dict>(value)) {
    throw py::type_error("fused_depth: expected None or a dict {abs_tol_m, rel_tol}, got " +
                         std::string(py::str(py::type::of(value).attr("__name__"))));
  }
  for (const auto& [k, v] : value.cast<py::dict>()) {
    const std::string key = py::str(k);
    double* field = key == "abs_tol_m" ? &fused.abs_tol_m
                    : key == "rel_tol" ? &fused.rel_tol
                                       : nullptr;
    if (field == nullptr) {
      ThrowValue("fused_depth", "unknown key '" + key + "' (expected abs_tol_m, rel_tol)");
    }
    if (!py::isinstance<py::float_>(v) && !py::isinstance<py::int_>(v)) {
      throw py::type_error("fused_depth: " + key + ": expected a number, got " +
                           std::string(py::str(py::type::of(v).attr("__name__"))));
    }
    *field = v.cast<double>();
  }
  std::string error;
  if (!fused.Check(&error)) ThrowValue("fused_depth", error);
  return fused;
}

class PyScene {
 public:
  explicit PyScene(gt::Scene scene) : scene_(std::make_shared<const gt::Scene>(std::move(scene))) {}

  const gt::Scene& scene() const { return *scene_; }

  // Scene::mesh_path (a copy of the scene: the frames are shared by value, once).
  // A str or os.PathLike; anything else is one TypeError line (pybind11's own was a list
  // of the accepted signatures).
  void SetMeshPath(py::handle value) {
    py::object path = py::reinterpret_borrow<py::object>(value);
    if (!py::isinstance<py::str>(path) && py::hasattr(path, "__fspath__")) {
      path = py::module_::import("os").attr("fspath")(path);
    }
    if (!py::isinstance<py::str>(path)) {
      throw py::type_error("mesh_path: expected a path (str or os.PathLike), got " +
                           TypeName(value));
    }
    auto copy = std::make_shared<gt::Scene>(*scene_);
    copy->mesh_path = path.cast<std::string>();
    scene_ = std::move(copy);
  }

  py::tuple Load(py::handle frame_id_arg, py::handle width, py::handle height,
                 py::handle depth_source_arg, const py::object& fused_depth) const {
    const std::string frame_id = Arg<std::string>(frame_id_arg, "frame_id");
    const std::string depth_source = Arg<std::string>(depth_source_arg, "depth_source");
    const gt::truth::Resolution resolution{Arg<int>(width, "width"), Arg<int>(height, "height")};
    std::string error;
    if (!resolution.Check(&error)) ThrowValue("width, height", error);
    gt::render::FrameDepthOptions depth_options;
    depth_options.source = Named("depth_source", [&] {
      return gt::render::ParseDepthSourceMode(depth_source, "depth_source");
    });
    depth_options.fused = FusedDepthFrom(fused_depth);
    gt::DepthImage depth;
    gt::Camera camera;
    gt::Rigid3d world_from_cam;
    {
      py::gil_scoped_release no_gil;
      const gt::Frame& frame = scene_->frames[gt::truth::FindFrame(*scene_, frame_id, "frame_id")];
      // Its InputError names the file (an unreadable depth file or mesh) or the scene (no
      // mesh): passed on as it is, a ValueError "<file>: <problem>".
      depth = gt::truth::LoadWorkingDepth(*scene_, frame, resolution, depth_options);
      camera = gt::truth::WorkingCamera(frame, resolution);
      world_from_cam = frame.world_from_cam;
    }
    const int h = depth.height, w = depth.width;
    return py::make_tuple(ToArray(std::move(depth.values_m), {h, w}), MatrixToArray(camera.K()),
                          MatrixToArray(world_from_cam.matrix()));
  }

  py::array_t<uint8_t> LoadColor(py::handle frame_id_arg, py::handle width_arg,
                                 py::handle height_arg) const {
    const std::string frame_id = Arg<std::string>(frame_id_arg, "frame_id");
    const int width = Arg<int>(width_arg, "width"), height = Arg<int>(height_arg, "height");
    const gt::truth::Resolution resolution{width, height};
    std::string error;
    if (!resolution.Check(&error)) ThrowValue("width, height", error);
    gt::io::ColorImage image;
    {
      py::gil_scoped_release no_gil;
      const gt::Frame& frame = scene_->frames[gt::truth::FindFrame(*scene_, frame_id, "frame_id")];
      if (frame.color_path.empty()) {
        throw gt::InputError(
            "frame_id", "frame " + frame.id + " of scene " + scene_->name + " has no colour image");
      }
      image = gt::io::ReadFrameColorResized(frame, width, height);
    }
    const int h = image.height, w = image.width;
    return ToArray(std::move(image.rgb), {h, w, 3});
  }

  PyScopeMap Fuse(py::handle id0_arg, py::handle id1_arg, py::handle width_arg,
                  py::handle height_arg, py::handle scope_arg, py::handle voxel_arg,
                  py::handle max_range_arg, py::handle far_arg, py::handle min_depth_arg,
                  py::handle max_depth_arg, py::handle preset_arg, py::handle dataset_min_depth_arg,
                  py::handle dataset_max_depth_arg, py::handle downsample_arg,
                  py::handle remove_outliers_arg, py::handle outlier_k_arg,
                  py::handle outlier_stddev_arg) const {
    const std::optional<double> voxel_m = OptionalArg<double>(voxel_arg, "voxel_m");
    const std::optional<double> max_range_m = OptionalArg<double>(max_range_arg, "max_range_m");
    const std::optional<double> far_m = OptionalArg<double>(far_arg, "far_m");
    const std::optional<double> min_depth_m = OptionalArg<double>(min_depth_arg, "min_depth_m");
    const std::optional<double> max_depth_m = OptionalArg<double>(max_depth_arg, "max_depth_m");
    const std::optional<double> dataset_min_depth_m =
        OptionalArg<double>(dataset_min_depth_arg, "dataset_min_depth_m");
    const std::optional<double> dataset_max_depth_m =
        OptionalArg<double>(dataset_max_depth_arg, "dataset_max_depth_m");
    const std::string id0 = Arg<std::string>(id0_arg, "id0");
    const std::string id1 = Arg<std::string>(id1_arg, "id1");
    const std::string scope = Arg<std::string>(scope_arg, "scope");
    const std::string preset = Arg<std::string>(preset_arg, "preset");
    const int width = Arg<int>(width_arg, "width"), height = Arg<int>(height_arg, "height");
    const gt::truth::Resolution resolution{width, height};
    std::string error;
    if (!resolution.Check(&error)) ThrowValue("width, height", error);
    gt::truth::PairSettings settings;
    Named("preset", [&] { gt::LabelPreset(preset); });
    settings.labels.preset = preset;
    settings.labels.min_depth_m = min_depth_m;  // the fusion's validity range: the labels'
    settings.labels.max_depth_m = max_depth_m;
    settings.occupancy.voxel_m = voxel_m;
    settings.occupancy.max_range_m = max_range_m;
    settings.occupancy.far_m = far_m;
    gt::truth::OccupancySettings& os = settings.occupancy;
    os.downsample = OptionalArg<bool>(downsample_arg, "downsample");
    os.remove_outliers = OptionalArg<bool>(remove_outliers_arg, "remove_outliers");
    os.outlier_k = OptionalArg<int>(outlier_k_arg, "outlier_k");
    os.outlier_stddev = OptionalArg<double>(outlier_stddev_arg, "outlier_stddev");
    if (std::string why = gt::truth::OccupancySettingsProblem(os); !why.empty()) {
      ThrowValue(why.substr(0, why.find(':')), why.substr(why.find(':') + 2));
    }
    gt::occupancy::FusionOptions parsed;
    Named("scope", [&] { gt::occupancy::ParseFusionScope(scope, &parsed); });
    settings.occupancy.scope = parsed.scope;
    settings.occupancy.window = parsed.window;
    settings.occupancy.scene_stride = parsed.scene_stride;
    gt::truth::DatasetDepthRange range = gt::truth::DepthRangeOf(*scene_);
    range.set_min_depth_m = dataset_min_depth_m;
    range.set_max_depth_m = dataset_max_depth_m;
    gt::truth::PairTruthOptions o = gt::truth::ResolvePairTruthOptions(settings, range);
    o.labels_and_matches = false;
    if (!o.Check(&error)) ThrowOptionsValue(error, max_range_m, far_m);
    PyScopeMap out;
    {
      py::gil_scoped_release no_gil;
      const size_t i0 = gt::truth::FindFrame(*scene_, id0, "id0");
      const size_t i1 = gt::truth::FindFrame(*scene_, id1, "id1");
      const gt::Scene& scene = *scene_;
      out.fused = std::make_shared<const gt::truth::ScopeMap>(gt::truth::FuseScope(
          scene, i0, i1, o,
          [&](size_t i) { return gt::truth::LoadWorkingFrame(scene.frames[i], resolution); }));
    }
    out.scene = scene_->name;
    out.scope = gt::occupancy::FusionScopeName(o.fusion);
    out.voxel_m = o.fusion.voxel_m;
    out.max_range_m = o.fusion.max_range_m;
    out.fusion = o.fusion;
    out.min_depth_m = o.labels.min_depth_m;
    out.max_depth_m = o.labels.max_depth_m;
    out.width = width;
    out.height = height;
    return out;
  }

 private:
  std::shared_ptr<const gt::Scene> scene_;
};

class PyDataset {
 public:
  PyDataset(py::handle root, py::handle format, py::handle device, py::handle tum_max_dt_s)
      : root_(Arg<std::string>(root, "root")), format_(Arg<std::string>(format, "format")) {
    gt::datasets::ReaderOptions options;
    const std::string device_name = Arg<std::string>(device, "device");
    options.scannetpp_device =
        Named("device", [&] { return gt::datasets::ParseScanNetPPDevice(device_name, "device"); });
    // tum: the association tolerance (a recipe's dataset.tum_max_dt_s; None: the default).
    if (const std::optional<double> dt = OptionalArg<double>(tum_max_dt_s, "tum_max_dt_s")) {
      if (!std::isfinite(*dt) || *dt < 0) {
        ThrowValue("tum_max_dt_s", "expected a finite number of seconds >= 0");
      }
      options.tum_max_dt_s = *dt;
    }
    reader_ = Named("format", [&] {
      return gt::datasets::MakeReader(gt::ParseDatasetFormat(format_, "format"), options);
    });
  }

  const std::string& root() const { return root_; }
  const std::string& format() const { return format_; }

  std::vector<std::string> Scenes() const {
    py::gil_scoped_release no_gil;
    return gt::datasets::ListSceneNames(*reader_, root_);
  }
  PyScene Scene(py::handle name_arg) const {
    const std::string name = Arg<std::string>(name_arg, "name");
    py::gil_scoped_release no_gil;
    return PyScene(reader_->ReadScene(root_, name));
  }

 private:
  std::string root_, format_;
  std::shared_ptr<const gt::datasets::DatasetReader> reader_;
};

// The defaults of the keyword arguments below, from the C++ Options structs.
std::string DefaultDepthSource() {
  return gt::render::DepthSourceModeName(gt::render::FrameDepthOptions().source);
}
std::string DefaultDevice() {
  return gt::datasets::ScanNetPPDeviceName(gt::datasets::ReaderOptions().scannetpp_device);
}

}  // namespace

void BindIo(py::module_& m) {
  m.attr("FORMATS") = py::tuple(py::cast(gt::datasets::KnownFormats()));
  {
    py::dict d;  // occgt.DATASET_DEFAULTS
    d["device"] = DefaultDevice();
    d["tum_max_dt_s"] = gt::datasets::ReaderOptions().tum_max_dt_s;
    d["depth_source"] = DefaultDepthSource();
    const gt::render::FusedDepthOptions fused;  // a recipe's dataset.fused_depth
    py::dict f;
    f["abs_tol_m"] = fused.abs_tol_m;
    f["rel_tol"] = fused.rel_tol;
    d["fused_depth"] = f;
    m.attr("DATASET_DEFAULTS") = d;
  }

  // A compressed .npy shard member (sample.compression: deflate) inflated into a new
  // bytearray (occgt.torch.ShardDataset parses it in place): sized by the .npy header inside
  // (io::GzippedNpyPlainSize, so a crafted member cannot inflate beyond the array it
  // declares), filled by io::GunzipInto (libdeflate) without the GIL.
  m.def(
      "gunzip_npy",
      [](py::buffer gz, const std::string& what) {
        const py::buffer_info in = gz.request();
        if (in.ndim != 1 || in.itemsize != 1 || in.strides[0] != 1) {
          throw gt::InputError(what, "gunzip_npy: expected a contiguous byte buffer");
        }
        const std::string_view bytes(static_cast<const char*>(in.ptr),
                                     static_cast<size_t>(in.size));
        const size_t size = gt::io::GzippedNpyPlainSize(bytes, what);
        auto out = py::reinterpret_steal<py::bytearray>(
            PyByteArray_FromStringAndSize(nullptr, static_cast<Py_ssize_t>(size)));
        if (!out) throw py::error_already_set();
        char* dst = PyByteArray_AsString(out.ptr());
        {
          py::gil_scoped_release release;
          gt::io::GunzipInto(bytes, dst, size, what);
        }
        return out;
      },
      "gz"_a, "what"_a,
      "The plain bytes of the gzip'd .npy member `gz` as a bytearray (ValueError naming "
      "`what` on bad data or another size than its header declares)");

  // The header of a .npy shard member in place (io::ParseNpyHeader: no copy of the data);
  // occgt.torch.ShardDataset maps descr with numpy and views the data with np.frombuffer.
  m.def(
      "npy_header",
      [](py::buffer buf, py::ssize_t offset, py::ssize_t size, const std::string& what) {
        const py::buffer_info in = buf.request();
        if (in.ndim != 1 || in.itemsize != 1 || in.strides[0] != 1) {
          throw gt::InputError(what, "npy_header: expected a contiguous byte buffer");
        }
        if (offset < 0 || size < 0 || offset > in.size || size > in.size - offset) {
          throw gt::InputError(what, "npy_header: bytes [" + std::to_string(offset) + ", +" +
                                         std::to_string(size) + ") outside the buffer of " +
                                         std::to_string(in.size));
        }
        const gt::io::NpyHeader h = gt::io::ParseNpyHeader(
            std::string_view(static_cast<const char*>(in.ptr) + offset, static_cast<size_t>(size)),
            what);
        py::tuple shape(h.shape.size());
        for (size_t i = 0; i < h.shape.size(); ++i) shape[i] = py::int_(h.shape[i]);
        return py::make_tuple(h.descr, h.fortran_order, std::move(shape), h.data_offset);
      },
      "buf"_a, "offset"_a, "size"_a, "what"_a,
      "(descr, fortran_order, shape, data_offset) of the .npy bytes buf[offset:offset + size] "
      "(io::ParseNpyHeader: magic, version, header dict; descr as written, e.g. '<f4', not "
      "checked against a dtype list; data_offset from the member's start). ValueError naming "
      "`what` and the header field on a bad header.");

  py::class_<gt::Frame>(m, "Frame",
                        "One frame of a scene as its reader lists it (metadata only; "
                        "Scene.load reads the depth).")
      .def_property_readonly(
          "id", [](const gt::Frame& f) { return f.id; }, "stable id within the scene")
      .def_property_readonly(
          "number", [](const gt::Frame& f) { return f.number; }, "numeric order in the scene")
      .def_property_readonly(
          "usable", [](const gt::Frame& f) { return f.usable; },
          "False when the frame must not be used (lost tracking, non-rigid pose, no depth)")
      .def_property_readonly(
          "reason", [](const gt::Frame& f) { return f.unusable_reason; },
          "why the frame is unusable: a stable category ('' when usable)")
      .def_property_readonly(
          "detail", [](const gt::Frame& f) { return f.unusable_detail; },
          "where in the input the reason was found and what, e.g. "
          "'.../pose_left.txt:11: non-finite value' ('' when none)")
      .def_property_readonly(
          "width", [](const gt::Frame& f) { return f.depth_camera.width; },
          "width of the depth map (pixels)")
      .def_property_readonly(
          "height", [](const gt::Frame& f) { return f.depth_camera.height; },
          "height of the depth map (pixels)")
      .def_property_readonly(
          "K", [](const gt::Frame& f) { return MatrixToArray(f.depth_camera.K()); },
          "float64 [3, 3] intrinsics at the depth map's resolution (width x height), pixels")
      .def_property_readonly(
          "world_from_cam",
          [](const gt::Frame& f) { return MatrixToArray(f.world_from_cam.matrix()); },
          "float64 [4, 4] camera-to-world pose, OpenCV camera axes, metres")
      .def_property_readonly(
          "depth_path", [](const gt::Frame& f) { return f.depth.path; }, "depth file")
      .def_property_readonly(
          "color_path", [](const gt::Frame& f) { return f.color_path; },
          "colour image ('' when the dataset has none)")
      .def("__repr__", [](const gt::Frame& f) {
        return "<occgt.Frame " + f.id + (f.usable ? "" : " unusable: " + f.UnusableMessage()) + ">";
      });

  py::class_<PyScene>(m, "Scene", "One scene of a dataset: its frames and how to load them.")
      .def_property_readonly(
          "name", [](const PyScene& s) { return s.scene().name; }, "scene name")
      .def_property_readonly(
          "format", [](const PyScene& s) { return gt::DatasetFormatName(s.scene().format); },
          "reader format")
      .def_property_readonly(
          "path", [](const PyScene& s) { return s.scene().path; }, "folder or manifest read")
      .def_property_readonly(
          "min_depth_m", [](const PyScene& s) { return s.scene().min_depth_m; },
          "the dataset's minimum valid depth (metres; `occgt pair` uses it unless overridden)")
      .def_property_readonly(
          "max_depth_m", [](const PyScene& s) { return s.scene().max_depth_m; },
          "the dataset's maximum valid depth (metres)")
      .def_property_readonly(
          "frames", [](const PyScene& s) { return s.scene().frames; },
          "list[Frame], sorted by number (usable or not)")
      .def_property(
          "mesh_path", [](const PyScene& s) { return s.scene().mesh_path; }, &PyScene::SetMeshPath,
          "the scene's mesh (PLY, in the frames' world frame) that depth_source 'mesh' and "
          "'fused' render; '' when none (the reader's: ScanNet's <scene>_vh_clean_2.ply)")
      .def("load", &PyScene::Load, "frame_id"_a, "width"_a = gt::truth::Resolution().width,
           "height"_a = gt::truth::Resolution().height, py::kw_only(),
           "depth_source"_a = DefaultDepthSource(), "fused_depth"_a = py::none(),
           "(depth float32 [height, width] planar metres (0 = invalid), K float64 [3, 3] at "
           "width x height, world_from_cam float64 [4, 4]) of a usable frame at the working "
           "resolution: depth resized with nearest neighbour, K rescaled with the pixel-area "
           "rule (truth::LoadWorkingFrame); depth_source 'mesh' renders mesh_path at that size, "
           "'fused' combines both (docs/GROUND_TRUTH.md 'Depth sources') with the tolerances "
           "fused_depth {abs_tol_m, rel_tol} (None: DATASET_DEFAULTS['fused_depth'], a recipe's "
           "dataset.fused_depth). ValueError for an "
           "unknown or unusable frame_id, an unreadable depth file or mesh, or a scene without "
           "a mesh.")
      .def("fuse", &PyScene::Fuse, "id0"_a, "id1"_a, "width"_a = gt::truth::Resolution().width,
           "height"_a = gt::truth::Resolution().height, py::kw_only(), "scope"_a = "pair",
           "voxel_m"_a = py::none(), "max_range_m"_a = py::none(), "far_m"_a = py::none(),
           "min_depth_m"_a = py::none(), "max_depth_m"_a = py::none(),
           "preset"_a = gt::truth::LabelSettings().preset, "dataset_min_depth_m"_a = py::none(),
           "dataset_max_depth_m"_a = py::none(), "downsample"_a = py::none(),
           "remove_outliers"_a = py::none(), "outlier_k"_a = py::none(),
           "outlier_stddev"_a = py::none(),
           "ScopeMap: the occupancy map of the pair (id0, id1) fused over a scope (truth::"
           "FuseScope, `occgt occupancy --scope`): 'pair', 'window:N' (the usable frames within "
           "N positions of either frame) or 'scene:S' (every S-th usable frame: one map for all "
           "pairs of the scene), depth at width x height, voxel_m and max_range_m in metres, "
           "the depth range the scene's (as `preset` takes it) unless given; None: the defaults of "
           "pair_ground_truth (PAIR_DEFAULTS; max_range_m: far_m), and so are the point filters "
           "(downsample, remove_outliers, outlier_k, outlier_stddev). Frames of the scope that "
           "cannot "
           "be read "
           "are skipped and listed in ScopeMap.skipped. Pass it to "
           "pair_ground_truth(..., occupancy=True, scope_map=...).")
      .def("load_color", &PyScene::LoadColor, "frame_id"_a,
           "width"_a = gt::truth::Resolution().width, "height"_a = gt::truth::Resolution().height,
           "colour of a frame at the working resolution: uint8 [height, width, 3], channels R, "
           "G, B, resized bilinearly from the colour camera's size (io::ReadColorResized: the "
           "pixels of a shard's image0/image1). ValueError when the frame has no colour image "
           "or it cannot be read.")
      .def("__repr__", [](const PyScene& s) {
        return "<occgt.Scene " + s.scene().name + " (" + gt::DatasetFormatName(s.scene().format) +
               ", " + std::to_string(s.scene().frames.size()) + " frames)>";
      });

  py::class_<PyDataset>(m, "Dataset", "A dataset root read by one of occgt's readers.")
      .def(py::init<py::handle, py::handle, py::handle, py::handle>(), "root"_a, "format"_a,
           py::kw_only(), "device"_a = DefaultDevice(), "tum_max_dt_s"_a = py::none())
      .def_property_readonly("root", &PyDataset::root, "dataset root folder")
      .def_property_readonly("format", &PyDataset::format, "reader format")
      .def("scenes", &PyDataset::Scenes, "scene names under the root, sorted")
      .def("scene", &PyDataset::Scene, "name"_a,
           "the scene's frames (ValueError naming the file for a bad or missing one)")
      .def("__repr__", [](const PyDataset& d) {
        return "<occgt.Dataset " + d.format() + " " + d.root() + ">";
      });
}

}  // namespace occgt_py

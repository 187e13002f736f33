// Bindings of libgt/render: load_mesh(path) -> Mesh (the mesh's BVH, built once, shared by
// every call and thread), render_depth(mesh, K, world_from_cam, width, height, *, model,
// dist, near_m, far_m) -> planar depth float32 [H, W] (render/mesh_renderer.h). The mesh is
// read and the BVH built, and every render cast, without the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/core/lens.h"
#include "libgt/render/mesh.h"
#include "libgt/render/mesh_renderer.h"
#include "libgt/truth/working_frame.h"
#include "python/src/convert.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

namespace {

class PyMesh {
 public:
  PyMesh(std::string path, size_t num_vertices,
         std::shared_ptr<const gt::render::MeshRenderer> renderer)
      : path_(std::move(path)), num_vertices_(num_vertices), renderer_(std::move(renderer)) {}
  const std::string& path() const { return path_; }
  size_t num_vertices() const { return num_vertices_; }
  size_t num_triangles() const { return renderer_->NumTriangles(); }
  const gt::render::MeshRenderer& renderer() const { return *renderer_; }

 private:
  std::string path_;
  size_t num_vertices_;
  std::shared_ptr<const gt::render::MeshRenderer> renderer_;
};

PyMesh LoadMesh(const std::string& path) {
  py::gil_scoped_release no_gil;
  gt::render::TriangleMesh mesh = gt::render::ReadPlyMesh(path);
  const size_t num_vertices = mesh.NumVertices();
  auto renderer = std::make_shared<const gt::render::MeshRenderer>(mesh);
  return PyMesh(path, num_vertices, std::move(renderer));
}

gt::LensModel ParseModel(const std::string& model) {
  for (gt::LensModel m :
       {gt::LensModel::kPinhole, gt::LensModel::kOpenCv, gt::LensModel::kOpenCvFisheye}) {
    if (model == gt::LensModelName(m)) return m;
  }
  ThrowValue("model", "expected 'pinhole', 'opencv' or 'opencv_fisheye', got '" + model + "'");
}

py::array_t<float> RenderDepth(py::handle mesh_arg, py::handle K, py::handle world_from_cam,
                               py::handle width_arg, py::handle height_arg, py::handle model_arg,
                               py::handle dist, py::handle near_arg, py::handle far_arg) {
  if (!py::isinstance<PyMesh>(mesh_arg)) {
    throw py::type_error("mesh: expected an occgt.Mesh (occgt.load_mesh), got " +
                         TypeName(mesh_arg));
  }
  const PyMesh& mesh = mesh_arg.cast<const PyMesh&>();
  const int width = Arg<int>(width_arg, "width"), height = Arg<int>(height_arg, "height");
  const std::string model = Arg<std::string>(model_arg, "model");
  const double near_m = Arg<double>(near_arg, "near_m"), far_m = Arg<double>(far_arg, "far_m");
  const gt::truth::Resolution resolution{width, height};
  std::string error;
  if (!resolution.Check(&error)) ThrowValue("width, height", error);
  gt::LensCamera lens;
  lens.pinhole = CameraFromArray(K, width, height, "K");
  lens.model = ParseModel(model);
  const gt::Rigid3d pose = PoseFromArray(world_from_cam, "world_from_cam");
  if (!dist.is_none()) {
    if (lens.model == gt::LensModel::kPinhole)
      ThrowValue("dist", "must be None for model 'pinhole'");
    const py::array a = AsArray(dist, "dist");
    const size_t expected_max = lens.model == gt::LensModel::kOpenCv ? 5 : 4;
    if (a.ndim() != 1 || a.size() < 4 || static_cast<size_t>(a.size()) > expected_max) {
      ThrowValue("dist", std::string("expected ") +
                             (lens.model == gt::LensModel::kOpenCv
                                  ? "[k1, k2, p1, p2] or [k1, k2, p1, p2, k3]"
                                  : "[k1, k2, k3, k4]") +
                             ", got shape " + ShapeText(a));
    }
    const py::array_t<double, py::array::forcecast> values(a);
    for (py::ssize_t i = 0; i < values.size(); ++i) lens.coeffs[i] = values.at(i);
  } else if (lens.model != gt::LensModel::kPinhole) {
    ThrowValue("dist", "required for model '" + model + "'");
  }
  if (!lens.Check(&error)) ThrowValue("dist", error);
  gt::render::RenderOptions options;
  options.near_m = near_m;
  options.far_m = far_m;
  if (!options.Check(&error)) ThrowValue("near_m, far_m", error);
  std::vector<float> depth;
  {
    py::gil_scoped_release no_gil;
    gt::render::RenderedDepth rendered = mesh.renderer().Render(lens, pose, options);
    depth.assign(rendered.depth_m.begin(), rendered.depth_m.end());
  }
  return ToArray(std::move(depth), {height, width});
}

}  // namespace

void BindRender(py::module_& m) {
  py::class_<PyMesh>(m, "Mesh", "A triangle mesh and its ray-casting BVH (occgt.load_mesh)")
      .def_property_readonly("path", &PyMesh::path)
      .def_property_readonly("num_vertices", &PyMesh::num_vertices)
      .def_property_readonly("num_triangles", &PyMesh::num_triangles)
      .def("__repr__", [](const PyMesh& mesh) {
        return "occgt.Mesh('" + mesh.path() + "', " + std::to_string(mesh.num_triangles()) +
               " triangles)";
      });
  m.def("load_mesh", &LoadMesh, "path"_a);
  const gt::render::RenderOptions render;
  const std::string model = gt::LensModelName(gt::LensCamera().model);
  py::dict defaults;  // occgt.RENDER_DEFAULTS: the signature's defaults, from the C++
  defaults["model"] = model;
  defaults["near_m"] = render.near_m;
  defaults["far_m"] = render.far_m;
  m.attr("RENDER_DEFAULTS") = defaults;
  m.def("render_depth", &RenderDepth, "mesh"_a, "K"_a, "world_from_cam"_a, "width"_a, "height"_a,
        py::kw_only(), "model"_a = model, "dist"_a = py::none(), "near_m"_a = render.near_m,
        "far_m"_a = render.far_m);
}

}  // namespace occgt_py

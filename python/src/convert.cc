#include "python/src/convert.h"

#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "libgt/truth/working_frame.h"

namespace occgt_py {

using namespace pybind11::literals;

void ThrowValue(const std::string& argument, const std::string& problem) {
  throw py::value_error(argument + ": " + problem);
}

void ThrowOptionsValue(std::string error, const std::optional<double>& max_range_m,
                       const std::optional<double>& far_m) {
  if (!max_range_m && far_m && error.find("max_range_m") != std::string::npos) {
    error += " (max_range_m is far_m when not given: far_m=" + std::to_string(*far_m) + ")";
  }
  ThrowValue("options", error);
}

std::string TypeName(py::handle value) { return py::str(py::type::of(value).attr("__name__")); }

namespace {

// value as a Python int (operator.index), or TypeError naming the argument.
py::int_ IndexArg(py::handle value, const std::string& argument) {
  if (PyBool_Check(value.ptr()) || PyFloat_Check(value.ptr()) || !PyIndex_Check(value.ptr())) {
    throw py::type_error(argument + ": expected an int, got " + TypeName(value));
  }
  PyObject* i = PyNumber_Index(value.ptr());
  if (i == nullptr) throw py::error_already_set();
  return py::reinterpret_steal<py::int_>(i);
}

}  // namespace

template <>
int Arg<int>(py::handle value, const std::string& argument) {
  const py::int_ i = IndexArg(value, argument);
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
  if (overflow != 0 || v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    ThrowValue(argument, "expected an int in " + std::to_string(std::numeric_limits<int>::min()) +
                             ".." + std::to_string(std::numeric_limits<int>::max()) + ", got " +
                             std::string(py::repr(i)));
  }
  return static_cast<int>(v);
}

template <>
uint64_t Arg<uint64_t>(py::handle value, const std::string& argument) {
  const py::int_ i = IndexArg(value, argument);
  const unsigned long long v = PyLong_AsUnsignedLongLong(i.ptr());
  if (PyErr_Occurred()) {  // negative or >= 2^64
    PyErr_Clear();
    ThrowValue(argument, "expected an int in 0.." +
                             std::to_string(std::numeric_limits<uint64_t>::max()) + ", got " +
                             std::string(py::repr(i)));
  }
  return static_cast<uint64_t>(v);
}

template <>
std::string Arg<std::string>(py::handle value, const std::string& argument) {
  if (!PyUnicode_Check(value.ptr())) {
    throw py::type_error(argument + ": expected a str, got " + TypeName(value));
  }
  return value.cast<std::string>();
}

template <>
bool Arg<bool>(py::handle value, const std::string& argument) {
  // True/False or numpy.bool_, not 0/1 (mutual=0 passed as False).
  if (!PyBool_Check(value.ptr()) && TypeName(value) != "bool_") {
    throw py::type_error(argument + ": expected a bool, got " + TypeName(value));
  }
  return PyObject_IsTrue(value.ptr()) == 1;
}

template <>
double Arg<double>(py::handle value, const std::string& argument) {
  PyObject* v = value.ptr();
  const bool number =
      PyFloat_Check(v) || PyLong_Check(v) || PyIndex_Check(v) ||
      (Py_TYPE(v)->tp_as_number != nullptr && Py_TYPE(v)->tp_as_number->nb_float != nullptr);
  // numpy.bool_ is not a number either (looked up only for objects that are not a Python
  // float or int, so that the common case costs no type-name string).
  if (PyBool_Check(v) || PyUnicode_Check(v) || PyBytes_Check(v) || !number ||
      (!PyFloat_Check(v) && !PyLong_Check(v) && TypeName(value) == "bool_")) {
    throw py::type_error(argument + ": expected a number, got " + TypeName(value));
  }
  const double d = PyFloat_AsDouble(v);
  if (d == -1.0 && PyErr_Occurred()) {  // e.g. an array of 2 elements
    PyErr_Clear();
    throw py::type_error(argument + ": expected a number, got " + TypeName(value));
  }
  return d;
}

py::array AsArray(py::handle obj, const std::string& argument) {
  if (py::isinstance<py::array>(obj)) return py::reinterpret_borrow<py::array>(obj);
  try {
    return py::module_::import("numpy").attr("asarray")(obj);
  } catch (py::error_already_set& e) {
    // numpy's reason, e.g. torch's "Can't call numpy() on Tensor that requires grad. Use
    // tensor.detach().numpy() instead." or a ragged list's "inhomogeneous shape".
    std::string why = py::str(e.value());
    ThrowValue(argument,
               "expected a NumPy array or array-like (a CPU torch tensor without "
               "grad, nested lists of numbers), got " +
                   TypeName(obj) + " (numpy.asarray: " + why + ")");
  }
}

std::string ShapeText(const py::array& a) { return py::str(a.attr("shape")); }
std::string DtypeText(const py::array& a) { return py::str(a.dtype()); }

namespace {

// dtype kind 'f' (floating, not complex) of 4 or 8 bytes.
bool IsFloat32Or64(const py::array& a) {
  const char kind = a.dtype().kind();
  return kind == 'f' && (a.itemsize() == 4 || a.itemsize() == 8);
}

// Real numbers: floating or integer (not bool, complex, object, strings).
bool IsRealNumber(const py::array& a) {
  const char kind = a.dtype().kind();
  return kind == 'f' || kind == 'i' || kind == 'u';
}

// A [rows, cols] real array as float64, row-major.
Eigen::MatrixXd RealMatrix(py::handle obj, int rows, int cols, const std::string& argument,
                           const std::string& expected) {
  py::array a = AsArray(obj, argument);
  if (!IsRealNumber(a)) {
    ThrowValue(argument, "expected a float array " + expected + ", got dtype " + DtypeText(a));
  }
  if (a.ndim() != 2 || a.shape(0) != rows || a.shape(1) != cols) {
    ThrowValue(argument, "expected shape (" + std::to_string(rows) + ", " + std::to_string(cols) +
                             ") " + expected + ", got " + ShapeText(a));
  }
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!d) throw py::error_already_set();
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m(r, c) = d.at(r, c);
  }
  return m;
}

}  // namespace

py::array CheckedDepthArray(py::handle obj, const std::string& argument) {
  // numpy.asarray drops a masked array's mask: its masked pixels would count as valid depth.
  if (py::isinstance(obj, py::module_::import("numpy.ma").attr("MaskedArray"))) {
    ThrowValue(argument,
               "a masked array (numpy.ma) would lose its mask: pass depth.filled(0) (0 = invalid)");
  }
  py::array a = AsArray(obj, argument);
  if (!IsFloat32Or64(a)) {
    ThrowValue(argument,
               "expected a depth map of dtype float32 or float64 (planar metres), got dtype " +
                   DtypeText(a));
  }
  if (a.ndim() != 2) {
    ThrowValue(argument, "expected a depth map of shape (H, W), got shape " + ShapeText(a));
  }
  gt::truth::Resolution size;
  size.width = static_cast<int>(std::min<py::ssize_t>(a.shape(1), gt::truth::kMaxResolution + 1));
  size.height = static_cast<int>(std::min<py::ssize_t>(a.shape(0), gt::truth::kMaxResolution + 1));
  std::string error;
  if (!size.Check(&error)) ThrowValue(argument, error + " (shape " + ShapeText(a) + ")");
  return a;
}

std::shared_ptr<const gt::DepthImage> DepthFromArray(py::handle obj, const std::string& argument) {
  const py::array a = CheckedDepthArray(obj, argument);
  auto depth = std::make_shared<gt::DepthImage>();
  depth->width = static_cast<int>(a.shape(1));
  depth->height = static_cast<int>(a.shape(0));
  const size_t n = static_cast<size_t>(depth->width) * depth->height;
  const auto native_float32 = py::array::c_style | py::array::forcecast;
  if (py::isinstance<py::array_t<float, native_float32>>(a)) {
    // float32, C order, native byte order: one copy of the buffer (no zeroing first).
    const float* p = static_cast<const float*>(a.data());
    depth->values_m.assign(p, p + n);
    return depth;
  }
  depth->values_m.resize(n);
  // Any other layout: one copy (and the float64 -> float32 rounding, as a C cast) straight
  // into the image: numpy.copyto into a view of its buffer, whatever the strides of the input.
  py::capsule no_owner(depth.get(), [](void*) {});
  py::array_t<float> view({a.shape(0), a.shape(1)}, depth->values_m.data(), no_owner);
  py::module_::import("numpy").attr("copyto")(view, a, "casting"_a = "same_kind");
  return depth;
}

gt::Camera CameraFromArray(py::handle obj, int width, int height, const std::string& argument) {
  const char* expected = "[[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (pixels)";
  const Eigen::MatrixXd K = RealMatrix(obj, 3, 3, argument, expected);
  if (!K.allFinite()) {  // before the layout test, which NaN entries would fail misleadingly
    std::ostringstream got;
    got << "K must be finite, got [[" << K(0, 0) << ", " << K(0, 1) << ", " << K(0, 2) << "], ["
        << K(1, 0) << ", " << K(1, 1) << ", " << K(1, 2) << "], [" << K(2, 0) << ", " << K(2, 1)
        << ", " << K(2, 2) << "]]";
    ThrowValue(argument, got.str());
  }
  if (!gt::Camera::IsPinholeMatrix(K)) {
    std::ostringstream got;
    got << "expected " << expected << " (no skew, last row 0 0 1), got [[" << K(0, 0) << ", "
        << K(0, 1) << ", " << K(0, 2) << "], [" << K(1, 0) << ", " << K(1, 1) << ", " << K(1, 2)
        << "], [" << K(2, 0) << ", " << K(2, 1) << ", " << K(2, 2) << "]]";
    ThrowValue(argument, got.str());
  }
  const gt::Camera camera = gt::Camera::FromK(K, width, height);
  std::string error;
  if (!camera.Check(&error)) ThrowValue(argument, error);
  return camera;
}

gt::Rigid3d PoseFromArray(py::handle obj, const std::string& argument) {
  const Eigen::Matrix4d m =
      RealMatrix(obj, 4, 4, argument, "(rigid world_from_cam: [[R, t], [0, 0, 0, 1]], metres)");
  if (const auto problem = gt::PoseProblem(m)) ThrowValue(argument, *problem);
  gt::Rigid3d pose = gt::Rigid3d::Identity();
  pose.linear() = m.topLeftCorner<3, 3>();
  pose.translation() = m.topRightCorner<3, 1>();
  return pose;
}

std::vector<uint64_t> WordsFromArray(py::handle obj, const std::string& argument,
                                     std::vector<py::ssize_t>* shape) {
  py::array a = AsArray(obj, argument);
  // int64: the same bits as torch holds them (torch has no uint64; occgt.torch's words).
  if ((a.dtype().kind() != 'u' && a.dtype().kind() != 'i') || a.itemsize() != 8) {
    ThrowValue(argument,
               "expected dtype uint64 or int64 (one bit per depth bin), got dtype " + DtypeText(a));
  }
  if (a.ndim() != 2) ThrowValue(argument, "expected shape (H/2, W/2), got shape " + ShapeText(a));
  *shape = {a.shape(0), a.shape(1)};
  if (a.dtype().kind() == 'i') a = a.attr("view")(py::dtype::of<uint64_t>());  // same bits
  auto c = py::array_t<uint64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!c) throw py::error_already_set();
  return std::vector<uint64_t>(c.data(), c.data() + c.size());
}

py::array_t<double> MatrixToArray(const Eigen::MatrixXd& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto w = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) w(r, c) = m(r, c);
  }
  return out;
}

py::object JsonToPython(const nlohmann::ordered_json& j) {
  switch (j.type()) {
    case nlohmann::ordered_json::value_t::object: {
      py::dict d;
      for (const auto& [key, value] : j.items()) d[py::str(key)] = JsonToPython(value);
      return std::move(d);
    }
    case nlohmann::ordered_json::value_t::array: {
      py::list l;
      for (const auto& value : j) l.append(JsonToPython(value));
      return std::move(l);
    }
    case nlohmann::ordered_json::value_t::string:
      return py::str(j.get<std::string>());
    case nlohmann::ordered_json::value_t::boolean:
      return py::bool_(j.get<bool>());
    case nlohmann::ordered_json::value_t::number_integer:
      return py::int_(j.get<int64_t>());
    case nlohmann::ordered_json::value_t::number_unsigned:
      return py::int_(j.get<uint64_t>());
    case nlohmann::ordered_json::value_t::number_float: {
      // JSON has no infinity or NaN: the files hold null for them (max_depth_m of a range
      // without upper limit), and so does Python, so that a dict equals its file's.
      const double v = j.get<double>();
      return std::isfinite(v) ? py::object(py::float_(v)) : py::object(py::none());
    }
    default:
      return py::none();
  }
}

}  // namespace occgt_py

// Conversions between NumPy arrays and the plain types of libgt, shared by the binding files
// of the module `occgt._occgt` (docs/PYTHON.md). Every input is checked here, at the
// boundary: a wrong dtype, shape or value raises ValueError("<argument>: <what was expected>,
// got ..."), never a crash. Outputs take ownership of the C++ vectors (no copy).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/core/pose.h"

namespace occgt_py {

namespace py = pybind11;

// ValueError("<argument>: <problem>").
[[noreturn]] void ThrowValue(const std::string& argument, const std::string& problem);
// ValueError("options: <error>") for options that failed their Check; when the error is
// about max_range_m and only far_m was given (far_m is then the ray range), it says so.
[[noreturn]] void ThrowOptionsValue(std::string error, const std::optional<double>& max_range_m,
                                    const std::optional<double>& far_m);

// Runs f; an InputError of a parser (whose field is a CLI flag such as "--preset") becomes
// ValueError("<argument>: <problem>").
template <typename F>
auto Named(const std::string& argument, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const gt::InputError& e) {
    std::string problem = e.what();
    const std::string prefix = e.where() + ": ";
    if (problem.compare(0, prefix.size(), prefix) == 0) problem.erase(0, prefix.size());
    ThrowValue(argument, problem);
  }
}

// A scalar argument of Python type int, str (or a uint64 seed) as its C++ type: a value of
// another Python type is TypeError("<argument>: expected an int, got float"; bool is not an
// int here), an int outside the C++ type's range ValueError("<argument>: expected an int in
// A..B, got N"). Any object with __index__ (numpy integers) is an int.
template <typename T>
T Arg(py::handle value, const std::string& argument);
template <>
int Arg<int>(py::handle value, const std::string& argument);
template <>
uint64_t Arg<uint64_t>(py::handle value, const std::string& argument);
template <>
std::string Arg<std::string>(py::handle value, const std::string& argument);
// True/False or numpy.bool_ (not 0/1): TypeError("<argument>: expected a bool, got int").
template <>
bool Arg<bool>(py::handle value, const std::string& argument);
// A real number: a Python int or float, a NumPy or 0-d torch scalar (anything with
// __float__ but str, bytes, bool and numpy.bool_): TypeError("<argument>: expected a number, got
// str").
template <>
double Arg<double>(py::handle value, const std::string& argument);
// Arg<T> of a value that may be None (nullopt).
template <typename T>
std::optional<T> OptionalArg(py::handle value, const std::string& argument) {
  if (value.is_none()) return std::nullopt;
  return Arg<T>(value, argument);
}
// The name of value's Python type ("str", "Tensor") for messages.
std::string TypeName(py::handle value);

// An array-like as a NumPy array (numpy.asarray), or ValueError naming the argument and why
// numpy refused it (a torch tensor that requires grad or lives on a GPU, a ragged list).
py::array AsArray(py::handle obj, const std::string& argument);
// "(480, 640)" / "float64" for messages.
std::string ShapeText(const py::array& a);
std::string DtypeText(const py::array& a);

// Depth map [H, W] float32 or float64 (any strides; float64 is rounded to float32), planar
// metres; 2 <= H, W <= 8192 (truth::Resolution). One copy into the DepthImage.
// A depth map argument as a NumPy array, checked: dtype float32 or float64 (planar metres),
// shape (H, W) with 2 <= H, W <= 8192, not a numpy.ma masked array (its mask would be
// dropped); ValueError naming the argument otherwise.
py::array CheckedDepthArray(py::handle obj, const std::string& argument);
std::shared_ptr<const gt::DepthImage> DepthFromArray(py::handle obj, const std::string& argument);
// K [3, 3] (float or integer) = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] for an image of
// width x height; fx, fy > 0 and finite (Camera::Check).
gt::Camera CameraFromArray(py::handle obj, int width, int height, const std::string& argument);
// world_from_cam [4, 4] (float or integer), rigid (core/pose.h PoseProblem: finite, last row
// 0 0 0 1, |R^T R - I| <= 1e-3, det R > 0). Used as given (R is not re-orthonormalised), so a
// pose from Scene.load gives the same bits as the CLI.
gt::Rigid3d PoseFromArray(py::handle obj, const std::string& argument);
// A uint64 (or int64, the same bits: occgt.torch's words) array of shape [H, W] (occupancy
// words), copied into a vector.
std::vector<uint64_t> WordsFromArray(py::handle obj, const std::string& argument,
                                     std::vector<py::ssize_t>* shape);

// The vector as an array of the given shape, owning it through a capsule (no copy).
template <typename T, typename A>
py::array_t<T> ToArray(std::vector<T, A>&& values, const std::vector<py::ssize_t>& shape) {
  size_t n = 1;
  for (py::ssize_t s : shape) n *= static_cast<size_t>(s);
  if (n != values.size()) throw std::logic_error("occgt: array size does not match its shape");
  auto owned = std::make_unique<std::vector<T, A>>(std::move(values));
  T* data = owned->data();
  py::capsule base(owned.get(), [](void* p) { delete static_cast<std::vector<T, A>*>(p); });
  owned.release();  // the capsule owns it now
  return py::array_t<T>(shape, data, base);
}

py::array_t<double> MatrixToArray(const Eigen::MatrixXd& m);  // [rows, cols] float64 (a copy)

// A JSON value as Python objects (objects → dict in their order, arrays → list; a number
// that is not finite → None, as the JSON text writes it: null).
py::object JsonToPython(const nlohmann::ordered_json& j);

}  // namespace occgt_py

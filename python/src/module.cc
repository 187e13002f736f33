// The extension module `occgt._occgt` (docs/PYTHON.md): one thin binding file per domain
// (geometry.cc: label codes and presets; truth.cc: the per-pair ground truth; io.cc: the
// dataset readers), the array conversions in convert.h. gt::InputError (bad input at a
// boundary) becomes ValueError with the C++ message ("<field>: <what was expected>").
#include <pybind11/pybind11.h>

#include "gt/core/version.h"
#include "libgt/core/error.h"

namespace occgt_py {
namespace py = pybind11;
void BindGeometry(py::module_& m);
void BindTruth(py::module_& m);
void BindIo(py::module_& m);
}  // namespace occgt_py

PYBIND11_MODULE(_occgt, m) {
  namespace py = pybind11;
  m.doc() =
      "occgt: ground truth for occlusion-aware image matching (C++ core). Use the package "
      "`occgt`, which re-exports these functions with type hints (docs/PYTHON.md).";
  m.attr("__version__") = gt::kVersion;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const gt::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  occgt_py::BindGeometry(m);
  occgt_py::BindTruth(m);
  occgt_py::BindIo(m);
}

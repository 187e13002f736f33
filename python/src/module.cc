// The extension module `occgt._occgt` (docs/PYTHON.md): one thin binding file per domain
// (geometry.cc: label codes and presets; truth.cc: the per-pair ground truth; io.cc: the
// dataset readers; shards.cc: where a tar shard's members are; render.cc: meshes and rendered depth), the array conversions in
// convert.h. gt::InputError (bad input at a boundary) becomes ValueError with the C++
// message ("<field>: <what was expected>").
#include <pybind11/pybind11.h>

#if defined(__GLIBC__)
#include <malloc.h>

#include <cstdlib>
#include <cstring>
#endif

#include "gt/core/version.h"
#include "libgt/core/error.h"

namespace occgt_py {
namespace py = pybind11;
void BindGeometry(py::module_& m);
void BindTruth(py::module_& m);
void BindIo(py::module_& m);
void BindSupervision(py::module_& m);
void BindShards(py::module_& m);
void BindRender(py::module_& m);

// One pair's ground truth allocates ~8 MB at 640x480 (depth copies, label and warp maps) and
// frees it on return. With glibc's dynamic thresholds that memory goes back to the kernel
// after every call and is faulted in again on the next: 3.5 of 6.5 ms per pair on one core
// (docs/PERFORMANCE.md). The process keeps freed memory instead, as the occgt binary does
// (apps/main.cc): mmap only above 32 MiB, trim the heap only above 256 MiB free. A user's
// GLIBC_TUNABLES for malloc wins.
void KeepFreedMemory() {
#if defined(__GLIBC__)
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.") != nullptr) return;
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
}

}  // namespace occgt_py

PYBIND11_MODULE(_occgt, m) {
  namespace py = pybind11;
  m.doc() =
      "occgt: ground truth for occlusion-aware image matching (C++ core). Use the package "
      "`occgt`, which re-exports these functions with type hints (docs/PYTHON.md).";
  m.attr("__version__") = gt::kVersion;
  occgt_py::KeepFreedMemory();
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
  occgt_py::BindSupervision(m);
  occgt_py::BindShards(m);
  occgt_py::BindRender(m);
}

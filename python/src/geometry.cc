// Bindings of libgt/geometry: the stable label codes and match types, the preset names.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "libgt/geometry/labels.h"
#include "libgt/geometry/patches.h"
#include "python/src/convert.h"

namespace occgt_py {

namespace py = pybind11;
using namespace pybind11::literals;

void BindGeometry(py::module_& m) {
  py::tuple names(gt::kNumPixelLabels);
  for (int k = 0; k < gt::kNumPixelLabels; ++k) {
    names[k] = gt::PixelLabelName(static_cast<gt::PixelLabel>(k));
  }
  m.attr("LABEL_NAMES") = names;  // index = uint8 code of label01/label10/cells0/cells1
  m.attr("MATCH_TYPE_NAMES") = py::make_tuple("vv", "vo", "ov");  // index = match_type code
  m.attr("PRESETS") = py::tuple(py::cast(gt::PresetNames()));
}

}  // namespace occgt_py

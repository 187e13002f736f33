// Python values written as a pickle (protocol 2), and read back from pickles of plain values
// and NumPy arrays: the index files of LoFTR's MegaDepth loader are pickled dicts read with
// np.load(path, allow_pickle=True) (docs/EXPORTS.md).
//
// Only plain Python values are written (None, bool, int, float, str, list, tuple, dict with
// str keys), with these opcodes of the protocol (Python's Lib/pickletools.py documents them):
// PROTO 2, NONE, NEWTRUE/NEWFALSE, BININT (int32) or LONG1 (wider ints, little-endian two's
// complement), BINFLOAT (IEEE 754 double, big-endian), BINUNICODE (UTF-8, uint32 length),
// EMPTY_LIST/EMPTY_TUPLE/EMPTY_DICT, MARK + APPENDS / TUPLE / SETITEMS, TUPLE1..3, STOP. No
// memo and no globals: the bytes name no callable, and the same value always gives the same
// bytes.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gt::io {

struct PyValue {
  enum class Kind { kNone, kBool, kInt, kFloat, kStr, kList, kTuple, kDict };
  Kind kind = Kind::kNone;
  int64_t int_value = 0;  // kBool (0/1) and kInt
  double float_value = 0;
  std::string str;                // kStr (UTF-8)
  std::vector<PyValue> items;     // kList, kTuple; kDict: values, in key order of `keys`
  std::vector<std::string> keys;  // kDict

  static PyValue None() { return PyValue(); }
  static PyValue Bool(bool b);
  static PyValue Int(int64_t v);
  static PyValue Float(double v);
  static PyValue Str(std::string s);
  static PyValue List(std::vector<PyValue> items);
  static PyValue Tuple(std::vector<PyValue> items);
  // Entries written in the given order (a Python dict keeps it).
  static PyValue Dict(std::vector<std::pair<std::string, PyValue>> entries);
};

// The pickle of `value`, protocol 2, ending with STOP.
std::string PickleBytes(const PyValue& value);

// Reads a pickle (protocols 0-5 as Python 3 writes them: memo, frames, short and long
// forms) of plain values and NumPy data, without running anything: the only globals
// accepted are NumPy's array reconstruction (numpy.core.multiarray._reconstruct or
// numpy._core.multiarray._reconstruct with numpy.ndarray), numpy.dtype and
// numpy.core.multiarray.scalar (any other global is an InputError naming it). A NumPy
// array becomes nested lists by its shape (C or Fortran order, numeric, bool, unicode or
// object dtype); a NumPy scalar its Python value; bytes a kStr of the raw bytes; dict keys
// must be str. Every malformed input (truncation, unknown opcode, stack underflow, sizes
// beyond the bytes) is an InputError(what, ...) checked before allocating.
PyValue ReadPickle(std::string_view bytes, const std::string& what);

}  // namespace gt::io

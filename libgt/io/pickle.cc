#include "libgt/io/pickle.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>

#include "libgt/core/error.h"

namespace gt::io {

PyValue PyValue::Bool(bool b) {
  PyValue v;
  v.kind = Kind::kBool;
  v.int_value = b ? 1 : 0;
  return v;
}

PyValue PyValue::Int(int64_t i) {
  PyValue v;
  v.kind = Kind::kInt;
  v.int_value = i;
  return v;
}

PyValue PyValue::Float(double f) {
  PyValue v;
  v.kind = Kind::kFloat;
  v.float_value = f;
  return v;
}

PyValue PyValue::Str(std::string s) {
  PyValue v;
  v.kind = Kind::kStr;
  v.str = std::move(s);
  return v;
}

PyValue PyValue::List(std::vector<PyValue> items) {
  PyValue v;
  v.kind = Kind::kList;
  v.items = std::move(items);
  return v;
}

PyValue PyValue::Tuple(std::vector<PyValue> items) {
  PyValue v;
  v.kind = Kind::kTuple;
  v.items = std::move(items);
  return v;
}

PyValue PyValue::Dict(std::vector<std::pair<std::string, PyValue>> entries) {
  PyValue v;
  v.kind = Kind::kDict;
  for (auto& [key, value] : entries) {
    v.keys.push_back(key);
    v.items.push_back(std::move(value));
  }
  return v;
}

namespace {

void PutLittle(std::string* out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

void PutStr(std::string* out, const std::string& s) {
  out->push_back('X');  // BINUNICODE
  PutLittle(out, s.size(), 4);
  out->append(s);
}

void Put(std::string* out, const PyValue& v) {
  switch (v.kind) {
    case PyValue::Kind::kNone:
      out->push_back('N');
      return;
    case PyValue::Kind::kBool:
      out->push_back(v.int_value ? '\x88' : '\x89');
      return;
    case PyValue::Kind::kInt:
      if (v.int_value >= INT32_MIN && v.int_value <= INT32_MAX) {
        out->push_back('J');  // BININT
        PutLittle(out, static_cast<uint32_t>(static_cast<int32_t>(v.int_value)), 4);
      } else {
        out->push_back('\x8a');  // LONG1: 8 bytes of two's complement
        out->push_back('\x08');
        PutLittle(out, static_cast<uint64_t>(v.int_value), 8);
      }
      return;
    case PyValue::Kind::kFloat: {
      out->push_back('G');  // BINFLOAT, big-endian
      uint64_t bits;
      std::memcpy(&bits, &v.float_value, 8);
      for (int i = 7; i >= 0; --i) out->push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
      return;
    }
    case PyValue::Kind::kStr:
      PutStr(out, v.str);
      return;
    case PyValue::Kind::kList:
      out->push_back(']');  // EMPTY_LIST
      if (v.items.empty()) return;
      out->push_back('(');  // MARK
      for (const PyValue& x : v.items) Put(out, x);
      out->push_back('e');  // APPENDS
      return;
    case PyValue::Kind::kTuple:
      if (v.items.empty()) {
        out->push_back(')');  // EMPTY_TUPLE
        return;
      }
      if (v.items.size() > 3) out->push_back('(');
      for (const PyValue& x : v.items) Put(out, x);
      out->push_back(v.items.size() == 1   ? '\x85'
                     : v.items.size() == 2 ? '\x86'
                     : v.items.size() == 3 ? '\x87'
                                           : 't');
      return;
    case PyValue::Kind::kDict:
      out->push_back('}');  // EMPTY_DICT
      if (v.items.empty()) return;
      out->push_back('(');
      for (size_t i = 0; i < v.items.size(); ++i) {
        PutStr(out, v.keys[i]);
        Put(out, v.items[i]);
      }
      out->push_back('u');  // SETITEMS
      return;
  }
}

}  // namespace

std::string PickleBytes(const PyValue& value) {
  std::string out = "\x80\x02";  // PROTO 2
  Put(&out, value);
  out.push_back('.');  // STOP
  return out;
}

}  // namespace gt::io

// ---------------------------------------------------------------------------------------
// Reading.

namespace gt::io {
namespace {

// An object on the unpickler's stack or in its memo (shared: BUILD and APPEND change the
// object every reference sees, as in Python).
struct Obj {
  enum class Tag { kValue, kMark, kGlobal, kDtype, kArray, kTuple };
  Tag tag = Tag::kValue;
  PyValue value;       // kValue (and kArray once built)
  std::string global;  // kGlobal: "module.name"
  char kind = 0;       // kDtype: 'f', 'i', 'u', 'b', 'O', 'U', 'S', 'c'
  int itemsize = 0;    // kDtype: bytes per item (U: 4 per character)
  bool big_endian = false;
  bool built = false;                       // kArray
  std::vector<std::shared_ptr<Obj>> items;  // kTuple: its members as they are
  int depth = 0;  // containers nested in it (lists, dicts, tuples, arrays)
};

// Deeper nesting is refused (the reader and the conversion recurse on it).
constexpr int kMaxDepth = 200;
using ObjPtr = std::shared_ptr<Obj>;

ObjPtr Mark() {
  auto o = std::make_shared<Obj>();
  o->tag = Obj::Tag::kMark;
  return o;
}

ObjPtr Value(PyValue v) {
  auto o = std::make_shared<Obj>();
  o->value = std::move(v);
  return o;
}

class Unpickler {
 public:
  Unpickler(std::string_view bytes, const std::string& what) : b_(bytes), what_(what) {}

  PyValue Run() {
    while (true) {
      const unsigned char op = Byte();
      switch (op) {
        case 0x80:  // PROTO
          Byte();
          break;
        case 0x95:  // FRAME
          Take(8);
          break;
        case '.':  // STOP
          if (stack_.size() != 1) Fail("STOP with " + std::to_string(stack_.size()) + " items");
          return Final(stack_.back());
        case '(':
          stack_.push_back(Mark());
          break;
        case 'N':
          stack_.push_back(Value(PyValue::None()));
          break;
        case 0x88:
        case 0x89:
          stack_.push_back(Value(PyValue::Bool(op == 0x88)));
          break;
        case 'J':
          stack_.push_back(Value(PyValue::Int(static_cast<int32_t>(Little(4)))));
          break;
        case 'K':
          stack_.push_back(Value(PyValue::Int(Byte())));
          break;
        case 'M':
          stack_.push_back(Value(PyValue::Int(static_cast<int64_t>(Little(2)))));
          break;
        case 0x8a:    // LONG1
        case 0x8b: {  // LONG4
          const uint64_t n = op == 0x8a ? Byte() : Little(4);
          stack_.push_back(Value(PyValue::Int(SignedLittle(Take(n)))));
          break;
        }
        case 'G': {
          const std::string_view raw = Take(8);
          uint64_t bits = 0;
          for (char c : raw) bits = (bits << 8) | static_cast<unsigned char>(c);
          double d;
          std::memcpy(&d, &bits, 8);
          stack_.push_back(Value(PyValue::Float(d)));
          break;
        }
        case 'X':  // BINUNICODE
        case 'B':  // BINBYTES
        case 'T':  // BINSTRING (Python 2)
          stack_.push_back(Value(PyValue::Str(std::string(Take(Little(4))))));
          break;
        case 0x8c:  // SHORT_BINUNICODE
        case 'C':   // SHORT_BINBYTES
        case 'U':   // SHORT_BINSTRING
          stack_.push_back(Value(PyValue::Str(std::string(Take(Byte())))));
          break;
        case 0x8d:  // BINUNICODE8
        case 0x8e:  // BINBYTES8
        case 0x96:  // BYTEARRAY8
          stack_.push_back(Value(PyValue::Str(std::string(Take(Little(8))))));
          break;
        case ']':
          stack_.push_back(Value(PyValue::List({})));
          break;
        case ')':
          stack_.push_back(Tuple({}));
          break;
        case '}':
          stack_.push_back(Value(PyValue::Dict({})));
          break;
        case 't':
          stack_.push_back(Tuple(PopRawToMark()));
          break;
        case 0x85:
        case 0x86:
        case 0x87: {
          const size_t n = op - 0x84u;
          std::vector<ObjPtr> items(n);
          for (size_t i = n; i-- > 0;) items[i] = Pop();
          stack_.push_back(Tuple(std::move(items)));
          break;
        }
        case 'a':
        case 'e': {
          std::vector<ObjPtr> items;
          if (op == 'a') {
            items.push_back(Pop());
          } else {
            items = PopRawToMark();
          }
          Obj& list = Top();
          if (list.tag != Obj::Tag::kValue || list.value.kind != PyValue::Kind::kList) {
            Fail("APPEND to something that is not a list");
          }
          for (const ObjPtr& x : items) {
            Deepen(&list, *x);
            list.value.items.push_back(Final(x));
          }
          break;
        }
        case 's':
        case 'u': {
          std::vector<ObjPtr> kv;
          if (op == 's') {
            ObjPtr v = Pop();
            kv.push_back(Pop());
            kv.push_back(std::move(v));
          } else {
            kv = PopRawToMark();
          }
          if (kv.size() % 2) Fail("SETITEMS with an odd number of items");
          Obj& dict = Top();
          if (dict.tag != Obj::Tag::kValue || dict.value.kind != PyValue::Kind::kDict) {
            Fail("SETITEM on something that is not a dict");
          }
          for (size_t i = 0; i < kv.size(); i += 2) {
            const PyValue key = Final(kv[i]);
            if (key.kind != PyValue::Kind::kStr) Fail("a dict key that is not a str");
            Deepen(&dict, *kv[i + 1]);
            dict.value.keys.push_back(key.str);
            dict.value.items.push_back(Final(kv[i + 1]));
          }
          break;
        }
        case 'q':
          memo_[Byte()] = Top_();
          break;
        case 'r':
          memo_[Little(4)] = Top_();
          break;
        case 0x94:
          memo_[memo_.size()] = Top_();
          break;
        case 'h':
        case 'j': {
          const uint64_t k = op == 'h' ? Byte() : Little(4);
          auto it = memo_.find(k);
          if (it == memo_.end()) Fail("memo key " + std::to_string(k) + " not set");
          stack_.push_back(it->second);
          break;
        }
        case 'c': {  // GLOBAL "module\nname\n"
          const std::string module = Line(), name = Line();
          stack_.push_back(Global(module + "." + name));
          break;
        }
        case 0x93: {  // STACK_GLOBAL
          const PyValue name = PopValue(), module = PopValue();
          if (name.kind != PyValue::Kind::kStr || module.kind != PyValue::Kind::kStr) {
            Fail("STACK_GLOBAL without two str");
          }
          stack_.push_back(Global(module.str + "." + name.str));
          break;
        }
        case 'R':
          Reduce();
          break;
        case 'b':
          Build();
          break;
        default:
          Fail("unsupported opcode 0x" + Hex(op));
      }
    }
  }

 private:
  [[noreturn]] void Fail(const std::string& why) const {
    throw InputError(what_, "pickle: " + why + " (at byte " + std::to_string(pos_) + ")");
  }
  static std::string Hex(unsigned v) {
    const char* d = "0123456789abcdef";
    return std::string{d[(v >> 4) & 15], d[v & 15]};
  }
  std::string_view Take(uint64_t n) {
    if (n > b_.size() - pos_) Fail("truncated (" + std::to_string(n) + " bytes wanted)");
    const std::string_view s = b_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  unsigned char Byte() { return static_cast<unsigned char>(Take(1)[0]); }
  uint64_t Little(int n) {
    const std::string_view s = Take(n);
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(s[i]);
    return v;
  }
  int64_t SignedLittle(std::string_view s) {
    if (s.size() > 8) Fail("an integer wider than 64 bits");
    if (s.empty()) return 0;
    uint64_t v = 0;
    for (size_t i = s.size(); i-- > 0;) v = (v << 8) | static_cast<unsigned char>(s[i]);
    if (s.size() < 8 && (static_cast<unsigned char>(s.back()) & 0x80)) {
      v |= ~uint64_t{0} << (8 * s.size());
    }
    return static_cast<int64_t>(v);
  }
  std::string Line() {
    const size_t end = b_.find('\n', pos_);
    if (end == std::string_view::npos) Fail("truncated GLOBAL");
    std::string s(b_.substr(pos_, end - pos_));
    pos_ = end + 1;
    return s;
  }
  ObjPtr Top_() {
    if (stack_.empty()) Fail("empty stack");
    return stack_.back();
  }
  Obj& Top() { return *Top_(); }
  ObjPtr Pop() {
    ObjPtr o = Top_();
    stack_.pop_back();
    return o;
  }
  PyValue PopValue() {
    ObjPtr o = Pop();
    return Final(o);
  }
  std::vector<ObjPtr> PopRawToMark() {
    std::vector<ObjPtr> items;
    while (true) {
      if (stack_.empty()) Fail("no MARK");
      ObjPtr o = Pop();
      if (o->tag == Obj::Tag::kMark) break;
      items.push_back(o);
    }
    std::reverse(items.begin(), items.end());
    return items;
  }
  // `container` now holds `item`: its depth grows to item's + 1, within kMaxDepth.
  void Deepen(Obj* container, const Obj& item) const {
    container->depth = std::max(container->depth, item.depth + 1);
    if (container->depth > kMaxDepth) {
      Fail("containers nested deeper than " + std::to_string(kMaxDepth));
    }
  }
  ObjPtr Tuple(std::vector<ObjPtr> items) const {
    auto o = std::make_shared<Obj>();
    o->tag = Obj::Tag::kTuple;
    for (const ObjPtr& x : items) Deepen(o.get(), *x);
    o->items = std::move(items);
    return o;
  }
  PyValue Final(const ObjPtr& o) const {
    if (o->tag == Obj::Tag::kValue) return o->value;
    if (o->tag == Obj::Tag::kArray && o->built) return o->value;
    if (o->tag == Obj::Tag::kTuple) {
      std::vector<PyValue> items;
      for (const ObjPtr& x : o->items) items.push_back(Final(x));
      return PyValue::Tuple(std::move(items));
    }
    Fail(o->tag == Obj::Tag::kMark ? "a MARK where a value belongs"
                                   : "an object that is not a value (" + o->global + ")");
  }
  ObjPtr Global(const std::string& name) {
    static const char* const kAllowed[] = {
        "numpy.core.multiarray._reconstruct", "numpy._core.multiarray._reconstruct",
        "numpy.ndarray", "numpy.dtype", "numpy.core.multiarray.scalar",
        "numpy._core.multiarray.scalar",
        // Protocol 2 has no bytes opcode: Python writes bytes as _codecs.encode(str,
        // 'latin1') and b'' as bytes() (both pure conversions).
        "_codecs.encode", "__builtin__.bytes", "builtins.bytes",
        // Protocol 5: arrays as _frombuffer(buffer, dtype, shape, order).
        "numpy.core.numeric._frombuffer", "numpy._core.numeric._frombuffer"};
    for (const char* a : kAllowed) {
      if (name == a) {
        auto o = std::make_shared<Obj>();
        o->tag = Obj::Tag::kGlobal;
        o->global = name;
        return o;
      }
    }
    Fail("global " + name + " is not allowed (only NumPy arrays and plain values are read)");
  }
  void Reduce() {
    const ObjPtr args = Pop();
    const ObjPtr fn = Pop();
    if (fn->tag != Obj::Tag::kGlobal || args->tag != Obj::Tag::kTuple) {
      Fail("REDUCE without a global and an argument tuple");
    }
    const std::string& g = fn->global;
    const std::vector<ObjPtr>& a = args->items;
    auto ends_with = [&](const char* tail) {
      const size_t n = std::strlen(tail);
      return g.size() >= n && g.compare(g.size() - n, n, tail) == 0;
    };
    if (ends_with("._reconstruct")) {
      auto o = std::make_shared<Obj>();
      o->tag = Obj::Tag::kArray;
      stack_.push_back(o);
    } else if (g == "numpy.dtype") {
      if (a.empty() || a[0]->tag != Obj::Tag::kValue || a[0]->value.kind != PyValue::Kind::kStr) {
        Fail("numpy.dtype() without a type code");
      }
      stack_.push_back(Dtype(a[0]->value.str));
    } else if (ends_with(".scalar")) {  // scalar(dtype, bytes)
      if (a.size() != 2 || a[0]->tag != Obj::Tag::kDtype || a[1]->tag != Obj::Tag::kValue ||
          a[1]->value.kind != PyValue::Kind::kStr ||
          a[1]->value.str.size() != static_cast<size_t>(a[0]->itemsize) || a[0]->kind == 'O') {
        Fail("numpy scalar(dtype, bytes)");
      }
      stack_.push_back(Value(Element(*a[0], a[1]->value.str)));
    } else if (ends_with("._frombuffer")) {
      if (a.size() != 4 || a[1]->tag != Obj::Tag::kDtype)
        Fail("_frombuffer(data, dtype, shape, order)");
      const PyValue order = Final(a[3]);
      auto o = std::make_shared<Obj>();
      o->tag = Obj::Tag::kArray;
      o->value = MakeArray(Final(a[2]), *a[1],
                           order.kind == PyValue::Kind::kStr && order.str == "F", Final(a[0]));
      o->depth = 32;
      o->built = true;
      stack_.push_back(o);
    } else if (g == "_codecs.encode") {
      if (a.size() != 2 || a[0]->tag != Obj::Tag::kValue || a[1]->tag != Obj::Tag::kValue ||
          a[0]->value.kind != PyValue::Kind::kStr || a[1]->value.str != "latin1") {
        Fail("_codecs.encode(str, 'latin1')");
      }
      stack_.push_back(Value(PyValue::Str(Latin1(a[0]->value.str))));
    } else if (ends_with(".bytes")) {
      if (!a.empty()) Fail("bytes() with arguments");
      stack_.push_back(Value(PyValue::Str("")));
    } else {
      Fail("REDUCE of " + g);
    }
  }
  // The code points (all < 256) of a UTF-8 string as bytes.
  std::string Latin1(const std::string& utf8) const {
    std::string out;
    for (size_t i = 0; i < utf8.size(); ++i) {
      const auto c = static_cast<unsigned char>(utf8[i]);
      if (c < 0x80) {
        out += static_cast<char>(c);
      } else if ((c & 0xE0) == 0xC0 && c <= 0xC3 && i + 1 < utf8.size()) {
        out +=
            static_cast<char>(((c & 0x1F) << 6) | (static_cast<unsigned char>(utf8[++i]) & 0x3F));
      } else {
        Fail("_codecs.encode of a character beyond latin-1");
      }
    }
    return out;
  }
  ObjPtr Dtype(const std::string& code) {
    auto o = std::make_shared<Obj>();
    o->tag = Obj::Tag::kDtype;
    if (code.size() < 2) Fail("numpy dtype '" + code + "'");
    o->kind = code[0];
    o->itemsize = std::atoi(code.c_str() + 1);
    if (o->kind == 'U') o->itemsize *= 4;
    if (std::string("fiubOUS").find(o->kind) == std::string::npos || o->itemsize <= 0 ||
        o->itemsize > (1 << 20)) {
      Fail("numpy dtype '" + code + "'");
    }
    return o;
  }
  void Build() {
    const ObjPtr state_obj = Pop();
    Obj& target = Top();
    if (target.tag == Obj::Tag::kDtype) {
      // (version, byteorder, ...): '>' big-endian, '<', '|' or '=' otherwise.
      const std::vector<ObjPtr>& st = state_obj->items;
      if (state_obj->tag == Obj::Tag::kTuple && st.size() > 1 && st[1]->tag == Obj::Tag::kValue &&
          st[1]->value.kind == PyValue::Kind::kStr) {
        target.big_endian = st[1]->value.str == ">";
      }
      return;
    }
    if (target.tag != Obj::Tag::kArray) Fail("BUILD of something that is not an array");
    // The array's state: (version, shape, dtype, is_fortran, data). The dtype is an object
    // of this reader, so the tuple is taken from the stack's raw objects.
    if (state_obj->tag != Obj::Tag::kTuple) Fail("array state");
    const std::vector<ObjPtr>& st = state_obj->items;
    if (st.size() != 5) Fail("array state of " + std::to_string(st.size()) + " items");
    if (st[2]->tag != Obj::Tag::kDtype) Fail("array dtype");
    const PyValue fortran_flag = Final(st[3]);
    target.value = MakeArray(Final(st[1]), *st[2],
                             fortran_flag.kind == PyValue::Kind::kBool && fortran_flag.int_value,
                             Final(st[4]));
    target.depth = st[4]->depth + 32;  // the data's nesting and up to 32 dimensions
    if (target.depth > kMaxDepth) Fail("containers nested too deep");
    target.built = true;
  }
  // Nested lists of an array's elements: `data` raw bytes (or, for object dtype, the list of
  // elements), in C or Fortran order.
  PyValue MakeArray(const PyValue& shape, const Obj& dt, bool fortran, const PyValue& data) const {
    if (shape.kind != PyValue::Kind::kTuple) Fail("array shape");
    std::vector<int64_t> dims;
    uint64_t count = 1;
    if (shape.items.size() > 32) Fail("an array of more than 32 dimensions");
    for (const PyValue& d : shape.items) {
      if (d.kind != PyValue::Kind::kInt || d.int_value < 0) Fail("array shape");
      dims.push_back(d.int_value);
      if (d.int_value > 0 && count > (uint64_t{1} << 40) / static_cast<uint64_t>(d.int_value)) {
        Fail("array too large");
      }
      count *= static_cast<uint64_t>(d.int_value);
    }
    std::vector<PyValue> flat;
    if (dt.kind == 'O') {
      if (data.kind != PyValue::Kind::kList || data.items.size() != count) {
        Fail("object array data");
      }
      flat = data.items;
    } else {
      if (data.kind != PyValue::Kind::kStr || data.str.size() != count * dt.itemsize) {
        Fail("array data of " +
             std::to_string(data.kind == PyValue::Kind::kStr ? data.str.size() : 0) +
             " bytes, expected " + std::to_string(count * dt.itemsize));
      }
      for (uint64_t i = 0; i < count; ++i) {
        flat.push_back(
            Element(dt, std::string_view(data.str).substr(i * dt.itemsize, dt.itemsize)));
      }
    }
    if (fortran && dims.size() > 1) {  // to C order
      std::vector<PyValue> c(flat.size());
      std::vector<int64_t> idx(dims.size(), 0);
      for (uint64_t k = 0; k < count; ++k) {
        uint64_t f = 0, stride = 1;
        for (size_t d = 0; d < dims.size(); ++d) {
          f += static_cast<uint64_t>(idx[d]) * stride;
          stride *= static_cast<uint64_t>(dims[d]);
        }
        c[k] = flat[f];
        for (size_t d = dims.size(); d-- > 0;) {
          if (++idx[d] < dims[d]) break;
          idx[d] = 0;
        }
      }
      flat.swap(c);
    }
    return Nest(flat, dims, 0, 0);
  }
  PyValue Nest(const std::vector<PyValue>& flat, const std::vector<int64_t>& dims, size_t d,
               uint64_t offset) const {
    if (dims.empty()) return flat.empty() ? PyValue::None() : flat[0];
    uint64_t inner = 1;
    for (size_t k = d + 1; k < dims.size(); ++k) inner *= static_cast<uint64_t>(dims[k]);
    std::vector<PyValue> out;
    for (int64_t i = 0; i < dims[d]; ++i) {
      out.push_back(d + 1 == dims.size() ? flat[offset + i]
                                         : Nest(flat, dims, d + 1, offset + i * inner));
    }
    return PyValue::List(std::move(out));
  }
  PyValue Element(const Obj& dt, std::string_view raw) const {
    std::string b(raw);
    if (dt.big_endian && dt.kind != 'U' && dt.kind != 'S') std::reverse(b.begin(), b.end());
    auto uns = [&] {
      uint64_t v = 0;
      for (size_t i = b.size(); i-- > 0;) v = (v << 8) | static_cast<unsigned char>(b[i]);
      return v;
    };
    switch (dt.kind) {
      case 'b':
        return PyValue::Bool(b[0] != 0);
      case 'u':
        return PyValue::Int(static_cast<int64_t>(uns()));
      case 'i': {
        uint64_t v = uns();
        if (b.size() < 8 && (v >> (8 * b.size() - 1)) & 1) v |= ~uint64_t{0} << (8 * b.size());
        return PyValue::Int(static_cast<int64_t>(v));
      }
      case 'f':
        if (b.size() == 8) {
          double d;
          std::memcpy(&d, b.data(), 8);
          return PyValue::Float(d);
        }
        if (b.size() == 4) {
          float f;
          std::memcpy(&f, b.data(), 4);
          return PyValue::Float(f);
        }
        Fail("float of " + std::to_string(b.size()) + " bytes");
      case 'S':
        return PyValue::Str(b.substr(0, b.find('\0')));
      case 'U': {  // UCS-4 to UTF-8, trailing NULs dropped
        std::string out;
        for (size_t i = 0; i + 4 <= b.size(); i += 4) {
          uint32_t c = 0;
          for (int k = dt.big_endian ? 0 : 3; dt.big_endian ? k < 4 : k >= 0;
               dt.big_endian ? ++k : --k) {
            c = (c << 8) | static_cast<unsigned char>(b[i + k]);
          }
          if (c == 0) break;
          if (c < 0x80) {
            out += static_cast<char>(c);
          } else if (c < 0x800) {
            out += static_cast<char>(0xC0 | (c >> 6));
            out += static_cast<char>(0x80 | (c & 0x3F));
          } else if (c < 0x10000) {
            out += static_cast<char>(0xE0 | (c >> 12));
            out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (c & 0x3F));
          } else {
            out += static_cast<char>(0xF0 | (c >> 18));
            out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
            out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (c & 0x3F));
          }
        }
        return PyValue::Str(out);
      }
      default:
        Fail(std::string("array of dtype kind '") + dt.kind + "'");
    }
  }

  std::string_view b_;
  std::string what_;
  size_t pos_ = 0;
  std::vector<ObjPtr> stack_;
  std::map<uint64_t, ObjPtr> memo_;
};

}  // namespace

PyValue ReadPickle(std::string_view bytes, const std::string& what) {
  return Unpickler(bytes, what).Run();
}

}  // namespace gt::io

#include "libgt/io/pickle.h"

#include <cstring>

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

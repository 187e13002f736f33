#include "libgt/render/mesh.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/file_read.h"

namespace gt::render {
namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool ParsePlyType(const std::string& name, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [n, t] : kNames) {
    if (name == n) {
      *type = t;
      return true;
    }
  }
  return false;
}

size_t TypeSize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool IsFloat(PlyType t) { return t == PlyType::kFloat32 || t == PlyType::kFloat64; }

struct Property {
  std::string name;
  bool is_list = false;
  PlyType type = PlyType::kFloat32;      // the value type (a list's item type)
  PlyType count_type = PlyType::kUint8;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { kAscii, kBinaryLittle, kBinaryBig };

struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  size_t data_offset = 0;  // first byte after "end_header\n"
};

Header ParseHeader(std::string_view bytes, const std::string& where) {
  constexpr size_t kMaxHeaderBytes = 1 << 20;
  if (bytes.substr(0, 3) != "ply" || bytes.size() < 4 || (bytes[3] != '\n' && bytes[3] != '\r')) {
    throw InputError(where, "not a PLY file (expected 'ply' on the first line)");
  }
  Header header;
  size_t pos = 0;
  bool have_format = false;
  int line_number = 0;
  while (true) {
    const size_t eol = bytes.find('\n', pos);
    if (eol == std::string_view::npos || eol > kMaxHeaderBytes) {
      throw InputError(where, "PLY header without 'end_header' (truncated file?)");
    }
    std::string line(bytes.substr(pos, eol - pos));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    ++line_number;
    const std::string at = "header line " + std::to_string(line_number) + ": ";
    std::istringstream in(line);
    std::string keyword;
    in >> keyword;
    if (line_number == 1) continue;  // "ply"
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      std::string name, version;
      in >> name >> version;
      if (name == "ascii") {
        header.encoding = Encoding::kAscii;
      } else if (name == "binary_little_endian") {
        header.encoding = Encoding::kBinaryLittle;
      } else if (name == "binary_big_endian") {
        header.encoding = Encoding::kBinaryBig;
      } else {
        throw InputError(where,
                         at + "unknown format '" + name +
                             "' (expected ascii, binary_little_endian or binary_big_endian)");
      }
      if (version != "1.0")
        throw InputError(where, at + "unsupported PLY version '" + version + "' (expected 1.0)");
      have_format = true;
    } else if (keyword == "element") {
      Element element;
      std::string count;
      in >> element.name >> count;
      const auto [end, ec] =
          std::from_chars(count.data(), count.data() + count.size(), element.count);
      if (element.name.empty() || count.empty() || ec != std::errc() ||
          end != count.data() + count.size()) {
        throw InputError(
            where, at + "bad element line '" + line + "' (expected 'element <name> <count>')");
      }
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) throw InputError(where, at + "property before any element");
      Property property;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type >> property.name;
        property.is_list = true;
        if (!ParsePlyType(count_type, &property.count_type) || IsFloat(property.count_type) ||
            !ParsePlyType(item_type, &property.type)) {
          throw InputError(where, at + "bad list property '" + line +
                                      "' (expected 'property list <integer type> <type> <name>')");
        }
      } else {
        in >> property.name;
        if (!ParsePlyType(type, &property.type)) {
          throw InputError(where, at + "unknown property type '" + type + "'");
        }
      }
      if (property.name.empty()) throw InputError(where, at + "property without a name");
      header.elements.back().properties.push_back(std::move(property));
    } else {
      throw InputError(where, at + "unknown header keyword '" + keyword + "'");
    }
  }
  if (!have_format) throw InputError(where, "PLY header without a 'format' line");
  header.data_offset = pos;
  return header;
}

// The roles of one element's properties in the mesh.
struct Roles {
  int x = -1, y = -1, z = -1;  // vertex
  int indices = -1;            // face
};

Roles FindRoles(const Element& element, const std::string& where) {
  Roles roles;
  for (size_t i = 0; i < element.properties.size(); ++i) {
    const Property& p = element.properties[i];
    if (element.name == "vertex" && (p.name == "x" || p.name == "y" || p.name == "z")) {
      if (p.is_list || !IsFloat(p.type)) {
        throw InputError(where, "vertex property '" + p.name + "' must be float or double");
      }
      (p.name == "x" ? roles.x : p.name == "y" ? roles.y : roles.z) = static_cast<int>(i);
    }
    if (element.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index")) {
      if (!p.is_list || (p.type != PlyType::kInt32 && p.type != PlyType::kUint32)) {
        throw InputError(where,
                         "face property '" + p.name +
                             "' must be a list of int or uint (e.g. 'property list uchar int "
                             "vertex_indices')");
      }
      roles.indices = static_cast<int>(i);
    }
  }
  if (element.name == "vertex" && (roles.x < 0 || roles.y < 0 || roles.z < 0)) {
    throw InputError(where, "element vertex without x, y and z properties");
  }
  if (element.name == "face" && roles.indices < 0) {
    throw InputError(where, "element face without a vertex_indices list");
  }
  return roles;
}

// Reads values from the data section, binary or ASCII, bounds-checked.
class Cursor {
 public:
  Cursor(std::string_view data, Encoding encoding, const std::string& where)
      : data_(data), encoding_(encoding), where_(where) {}

  double ReadNumber(PlyType type) {
    if (encoding_ == Encoding::kAscii) return ReadAscii(type);
    const size_t size = TypeSize(type);
    if (data_.size() - pos_ < size) Truncated();
    unsigned char raw[8];
    std::memcpy(raw, data_.data() + pos_, size);
    pos_ += size;
    if (encoding_ == Encoding::kBinaryBig) std::reverse(raw, raw + size);
    switch (type) {
      case PlyType::kInt8:
        return static_cast<int8_t>(raw[0]);
      case PlyType::kUint8:
        return raw[0];
      case PlyType::kInt16: {
        int16_t v;
        std::memcpy(&v, raw, 2);
        return v;
      }
      case PlyType::kUint16: {
        uint16_t v;
        std::memcpy(&v, raw, 2);
        return v;
      }
      case PlyType::kInt32: {
        int32_t v;
        std::memcpy(&v, raw, 4);
        return v;
      }
      case PlyType::kUint32: {
        uint32_t v;
        std::memcpy(&v, raw, 4);
        return v;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, raw, 4);
        return v;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, raw, 8);
        return v;
      }
    }
    return 0;
  }

  // Skips one property value (a whole list for list properties).
  void Skip(const Property& p) {
    if (!p.is_list) {
      if (encoding_ == Encoding::kAscii) {
        ReadNumber(p.type);
      } else {
        const size_t size = TypeSize(p.type);
        if (data_.size() - pos_ < size) Truncated();
        pos_ += size;
      }
      return;
    }
    const uint64_t n = ReadCount(p.count_type);
    if (encoding_ == Encoding::kAscii) {
      for (uint64_t i = 0; i < n; ++i) ReadNumber(p.type);
    } else {
      const uint64_t bytes = n * TypeSize(p.type);
      if (data_.size() - pos_ < bytes) Truncated();
      pos_ += bytes;
    }
  }

  uint64_t ReadCount(PlyType type) {
    const double v = ReadNumber(type);
    if (!(v >= 0)) throw InputError(where_, "negative list length in the PLY data");
    return static_cast<uint64_t>(v);
  }

  size_t position() const { return pos_; }

  // ASCII: the row of `element` just read must end its line (PLY writes one row per line).
  // A header count larger than the file's rows otherwise read the next element's first line
  // as this row, and failed later naming something else ("face 0 has 2 vertices").
  void EndAsciiRow(const std::string& element, uint64_t row) {
    if (encoding_ != Encoding::kAscii) return;
    while (pos_ < data_.size() &&
           (data_[pos_] == ' ' || data_[pos_] == '\t' || data_[pos_] == '\r'))
      ++pos_;
    if (pos_ == data_.size() || data_[pos_] == '\n') return;
    throw InputError(where_, element + " " + std::to_string(row) +
                                 ": more values on its line than the header's properties (a " +
                                 element + " count in the header larger than the file's " +
                                 element + " rows?)");
  }

 private:
  [[noreturn]] void Truncated() const {
    throw InputError(where_,
                     "PLY data ends early (truncated file, or counts larger than the data)");
  }

  double ReadAscii(PlyType type) {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (pos_ == data_.size()) Truncated();
    const char* begin = data_.data() + pos_;
    const char* end = data_.data() + data_.size();
    double value = 0;
    std::from_chars_result r{};
    if (IsFloat(type)) {
      r = std::from_chars(begin, end, value);
    } else {
      int64_t i = 0;
      r = std::from_chars(begin, end, i);
      value = static_cast<double>(i);
    }
    if (r.ec != std::errc() ||
        (r.ptr != end && !std::isspace(static_cast<unsigned char>(*r.ptr)))) {
      throw InputError(where_, "bad number in the ASCII PLY data at byte " + std::to_string(pos_) +
                                   " of the data");
    }
    pos_ = static_cast<size_t>(r.ptr - data_.data());
    return value;
  }

  std::string_view data_;
  Encoding encoding_;
  const std::string& where_;
  size_t pos_ = 0;
};

// Least bytes one row of the element takes (lists: their count, plus three items for the
// face list, whose faces need at least three vertices).
uint64_t MinRowBytes(const Element& element, const Roles& roles, Encoding encoding) {
  uint64_t bytes = 0;
  for (size_t i = 0; i < element.properties.size(); ++i) {
    const Property& p = element.properties[i];
    const uint64_t items = static_cast<int>(i) == roles.indices ? 3 : 0;
    if (encoding == Encoding::kAscii) {
      bytes += 2 * (1 + items);  // a digit and a separator per value (a list: its count)
    } else {
      bytes += p.is_list ? TypeSize(p.count_type) + items * TypeSize(p.type) : TypeSize(p.type);
    }
  }
  return bytes;
}

}  // namespace

TriangleMesh ParsePlyMesh(std::string_view bytes, const std::string& where) {
  const Header header = ParseHeader(bytes, where);
  const std::string_view data = bytes.substr(header.data_offset);

  // Counts against the bytes, before any allocation.
  std::vector<Roles> roles;
  uint64_t least_bytes = 0;
  int vertex_element = -1, face_element = -1;
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const Element& element = header.elements[e];
    roles.push_back(FindRoles(element, where));
    if (element.name == "vertex") {
      if (vertex_element >= 0) throw InputError(where, "two vertex elements");
      vertex_element = static_cast<int>(e);
    }
    if (element.name == "face") {
      if (face_element >= 0) throw InputError(where, "two face elements");
      face_element = static_cast<int>(e);
    }
    const uint64_t row = MinRowBytes(element, roles.back(), header.encoding);
    if (element.count > 0 && row == 0) {
      throw InputError(where, "element " + element.name + " has rows but no properties");
    }
    const uint64_t available = data.size() + 1 - std::min<uint64_t>(least_bytes, data.size() + 1);
    if (row > 0 && element.count > available / row) {
      throw InputError(where, "element " + element.name + " claims " +
                                  std::to_string(element.count) + " rows, more than the file's " +
                                  std::to_string(data.size()) +
                                  " data bytes can hold (truncated or corrupt file)");
    }
    least_bytes += element.count * row;
  }
  if (vertex_element < 0) throw InputError(where, "PLY without a vertex element");
  if (face_element < 0)
    throw InputError(where, "PLY without a face element (a point cloud, not a mesh)");

  TriangleMesh mesh;
  const uint64_t num_vertices = header.elements[vertex_element].count;
  if (num_vertices > std::numeric_limits<uint32_t>::max()) {
    throw InputError(where, "more than 2^32 - 1 vertices");
  }
  mesh.vertices_m.resize(num_vertices * 3);
  mesh.triangles.reserve(header.elements[face_element].count * 3);

  Cursor cursor(data, header.encoding, where);
  for (size_t e = 0; e < header.elements.size(); ++e) {
    const Element& element = header.elements[e];
    const Roles& r = roles[e];
    const bool is_vertex = static_cast<int>(e) == vertex_element;
    const bool is_face = static_cast<int>(e) == face_element;
    for (uint64_t row = 0; row < element.count; ++row) {
      for (size_t i = 0; i < element.properties.size(); ++i) {
        const int pi = static_cast<int>(i);
        const Property& p = element.properties[i];
        if (is_vertex && (pi == r.x || pi == r.y || pi == r.z)) {
          const double v = cursor.ReadNumber(p.type);
          if (!std::isfinite(v) || std::abs(v) > std::numeric_limits<float>::max()) {
            throw InputError(where, "vertex " + std::to_string(row) + ": non-finite coordinate");
          }
          mesh.vertices_m[row * 3 + (pi == r.x ? 0 : pi == r.y ? 1 : 2)] = static_cast<float>(v);
        } else if (is_face && pi == r.indices) {
          const uint64_t n = cursor.ReadCount(p.count_type);
          if (n < 3) {
            throw InputError(where, "face " + std::to_string(row) + " has " + std::to_string(n) +
                                        " vertices (expected at least 3)");
          }
          uint32_t first = 0, previous = 0;
          for (uint64_t k = 0; k < n; ++k) {
            const double v = cursor.ReadNumber(p.type);
            if (!(v >= 0) || v >= static_cast<double>(num_vertices)) {
              throw InputError(where, "face " + std::to_string(row) + ": vertex index " +
                                          std::to_string(static_cast<int64_t>(v)) +
                                          " outside [0, " + std::to_string(num_vertices) + ")");
            }
            const uint32_t index = static_cast<uint32_t>(v);
            if (k == 0) first = index;
            if (k >= 2) {
              mesh.triangles.push_back(first);
              mesh.triangles.push_back(previous);
              mesh.triangles.push_back(index);
            }
            previous = index;
          }
        } else {
          cursor.Skip(p);
        }
      }
      cursor.EndAsciiRow(element.name, row);
    }
  }
  // Data after the last element: a header count too small (the rows past it would be
  // dropped without a word) or a damaged file. ASCII may end with white space.
  size_t rest = cursor.position();
  if (header.encoding == Encoding::kAscii) {
    while (rest < data.size() && std::isspace(static_cast<unsigned char>(data[rest]))) ++rest;
  }
  if (rest < data.size()) {
    throw InputError(where, std::to_string(data.size() - rest) +
                                " bytes of data after the last element (a count in the header "
                                "smaller than the file's rows, or a damaged file)");
  }
  // Nothing to render ("element face 0"): as the scene's mesh it would make every rendered
  // pixel "no depth" without a word.
  if (mesh.triangles.empty()) {
    throw InputError(where, "no triangles (" + std::to_string(mesh.NumVertices()) +
                                " vertices, no face): expected a triangle mesh");
  }
  return mesh;
}

TriangleMesh ReadPlyMesh(const std::string& path) {
  const std::string bytes = io::ReadFileBytes(path);
  return ParsePlyMesh(bytes, path);
}

std::string EncodePlyMesh(const TriangleMesh& mesh) {
  std::string out = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                    std::to_string(mesh.NumVertices()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(mesh.NumTriangles()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
  const size_t header = out.size();
  out.resize(header + mesh.vertices_m.size() * 4 + mesh.NumTriangles() * 13);
  char* p = out.data() + header;
  if (!mesh.vertices_m.empty()) std::memcpy(p, mesh.vertices_m.data(), mesh.vertices_m.size() * 4);
  p += mesh.vertices_m.size() * 4;
  for (size_t t = 0; t < mesh.NumTriangles(); ++t) {
    *p++ = 3;
    std::memcpy(p, &mesh.triangles[3 * t], 12);
    p += 12;
  }
  return out;
}

}  // namespace gt::render

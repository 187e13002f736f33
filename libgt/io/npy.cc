// NumPy .npy / .npz reading and writing (rules in npy.h and SHARDS.md).
#include "libgt/io/npy.h"

#include <zip.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/core/utf8.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/gzip.h"
#include "libgt/io/npz_members.h"

namespace gt::io {
namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr size_t kMagicLen = 6;
constexpr size_t kMaxHeaderBytes = 10000;  // reader limit (numpy's own default)
constexpr size_t kAlign = 64;

// Item size of a supported little-endian (or byte-order-free) descr, 0 when unsupported.
// The type codes are numpy's: b bool, i signed, u unsigned, f float.
size_t SupportedItemSize(const std::string& descr) {
  static const char* const kOneByte[] = {"|b1", "|i1", "|u1"};
  for (const char* d : kOneByte) {
    if (descr == d) return 1;
  }
  static const struct {
    const char* descr;
    size_t size;
  } kMulti[] = {{"<i2", 2}, {"<u2", 2}, {"<f2", 2}, {"<i4", 4}, {"<u4", 4},
                {"<f4", 4}, {"<i8", 8}, {"<u8", 8}, {"<f8", 8}};
  for (const auto& d : kMulti) {
    if (descr == d.descr) return d.size;
  }
  return 0;
}

// A minimal reader of the Python dict literal numpy writes as the header:
// {'descr': '<f4', 'fortran_order': False, 'shape': (480, 640), }
// Keys may come in any order with any spacing; strings use ' or ".
class HeaderParser {
 public:
  HeaderParser(std::string_view text, const std::string& name) : s_(text), name_(name) {}

  void Parse(std::string* descr, bool* fortran_order, std::vector<int64_t>* shape) {
    bool have_descr = false, have_fortran = false, have_shape = false;
    Expect('{', "header");
    SkipSpace();
    while (Peek() != '}') {
      const std::string key = ParseString("header key");
      Expect(':', "header");
      if (key == "descr") {
        SkipSpace();
        if (Peek() == '[') Fail("descr", "structured (record) dtypes are not supported");
        *descr = ParseString("descr");
        have_descr = true;
      } else if (key == "fortran_order") {
        *fortran_order = ParseBool("fortran_order");
        have_fortran = true;
      } else if (key == "shape") {
        *shape = ParseShape();
        have_shape = true;
      } else {
        Fail("header", "unexpected key '" + key + "' (expected descr, fortran_order, shape)");
      }
      SkipSpace();
      if (Peek() == ',') {
        ++pos_;
        SkipSpace();
      } else if (Peek() != '}') {
        Fail("header", "expected ',' or '}' at offset " + std::to_string(pos_));
      }
    }
    ++pos_;
    SkipSpace();
    if (pos_ != s_.size()) Fail("header", "unexpected text after the closing '}'");
    if (!have_descr) Fail("descr", "missing key");
    if (!have_fortran) Fail("fortran_order", "missing key");
    if (!have_shape) Fail("shape", "missing key");
  }

 private:
  [[noreturn]] void Fail(const std::string& field, const std::string& what) const {
    throw InputError(name_ + ": header field '" + field + "'", what);
  }
  char Peek() const { return pos_ < s_.size() ? s_[pos_] : '\0'; }
  void SkipSpace() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  void Expect(char c, const std::string& field) {
    SkipSpace();
    if (Peek() != c) {
      Fail(field, std::string("expected '") + c + "' at offset " + std::to_string(pos_));
    }
    ++pos_;
  }
  std::string ParseString(const std::string& field) {
    SkipSpace();
    const char quote = Peek();
    if (quote != '\'' && quote != '"') Fail(field, "expected a quoted string");
    const size_t end = s_.find(quote, pos_ + 1);
    if (end == std::string_view::npos) Fail(field, "unterminated string");
    std::string out(s_.substr(pos_ + 1, end - pos_ - 1));
    pos_ = end + 1;
    return out;
  }
  bool ParseBool(const std::string& field) {
    SkipSpace();
    if (s_.substr(pos_, 4) == "True") {
      pos_ += 4;
      return true;
    }
    if (s_.substr(pos_, 5) == "False") {
      pos_ += 5;
      return false;
    }
    Fail(field, "expected True or False");
  }
  std::vector<int64_t> ParseShape() {
    std::vector<int64_t> shape;
    Expect('(', "shape");
    SkipSpace();
    while (Peek() != ')') {
      bool negative = false;
      if (Peek() == '-') {
        negative = true;
        ++pos_;
      }
      if (!std::isdigit(static_cast<unsigned char>(Peek()))) {
        Fail("shape", "expected a non-negative integer at offset " + std::to_string(pos_));
      }
      int64_t value = 0;
      while (std::isdigit(static_cast<unsigned char>(Peek()))) {
        const int digit = Peek() - '0';
        if (value > (std::numeric_limits<int64_t>::max() - digit) / 10) {
          Fail("shape", "dimension does not fit in int64");
        }
        value = value * 10 + digit;
        ++pos_;
      }
      if (Peek() == 'L') ++pos_;  // Python 2 long suffix
      if (negative) Fail("shape", "negative dimension -" + std::to_string(value));
      shape.push_back(value);
      SkipSpace();
      if (Peek() == ',') {
        ++pos_;
        SkipSpace();
      } else if (Peek() != ')') {
        Fail("shape", "expected ',' or ')' at offset " + std::to_string(pos_));
      }
    }
    ++pos_;
    return shape;
  }

  std::string_view s_;
  const std::string& name_;
  size_t pos_ = 0;
};

std::string ShapeText(const std::vector<int64_t>& shape) {
  std::string out = "(";
  for (size_t i = 0; i < shape.size(); ++i) {
    if (i > 0) out += ", ";
    out += std::to_string(shape[i]);
  }
  if (shape.size() == 1) out += ",";
  out += ")";
  return out;
}

uint32_t ReadLe(std::string_view bytes, size_t offset, int nbytes) {
  uint32_t v = 0;
  for (int i = nbytes - 1; i >= 0; --i) {
    v = (v << 8) | static_cast<unsigned char>(bytes[offset + i]);
  }
  return v;
}

struct ZipCloser {
  void operator()(zip_t* z) const {
    if (z != nullptr) zip_discard(z);
  }
};
struct ZipFileCloser {
  void operator()(zip_file_t* f) const {
    if (f != nullptr) zip_fclose(f);
  }
};

std::string ZipErrorText(int code) {
  zip_error_t error;
  zip_error_init_with_code(&error, code);
  std::string text = zip_error_strerror(&error);
  zip_error_fini(&error);
  return text;
}

}  // namespace

int64_t NpyArray::NumElements() const {
  int64_t n = 1;
  for (int64_t d : shape) n *= d;
  return n;
}

size_t NpyArray::ItemSize() const { return SupportedItemSize(descr); }

template <typename T>
const T* NpyArray::As(const std::string& name_for_errors) const {
  if (descr != NpyDescr<T>()) {
    throw InputError(name_for_errors, "dtype is '" + descr + "', expected '" + NpyDescr<T>() + "'");
  }
  GT_ASSERT(data.size() == static_cast<size_t>(NumElements()) * sizeof(T));
  return reinterpret_cast<const T*>(data.data());
}

template <>
const char* NpyDescr<float>() {
  return "<f4";
}
template <>
const char* NpyDescr<double>() {
  return "<f8";
}
template <>
const char* NpyDescr<int32_t>() {
  return "<i4";
}
template <>
const char* NpyDescr<int64_t>() {
  return "<i8";
}
template <>
const char* NpyDescr<uint8_t>() {
  return "|u1";
}
template <>
const char* NpyDescr<uint16_t>() {
  return "<u2";
}
template <>
const char* NpyDescr<uint32_t>() {
  return "<u4";
}
template <>
const char* NpyDescr<uint64_t>() {
  return "<u8";
}

NpyHeader ParseNpyHeader(std::string_view bytes, const std::string& name) {
  if (bytes.size() < kMagicLen + 4 || std::memcmp(bytes.data(), kMagic, kMagicLen) != 0) {
    throw InputError(name, "not a .npy file (bad magic, expected \\x93NUMPY)");
  }
  const int major = static_cast<unsigned char>(bytes[6]);
  const int minor = static_cast<unsigned char>(bytes[7]);
  if ((major != 1 && major != 2 && major != 3) || minor != 0) {
    throw InputError(name + ": version", "unsupported .npy format version " +
                                             std::to_string(major) + "." + std::to_string(minor) +
                                             " (expected 1.0, 2.0 or 3.0)");
  }
  const size_t length_bytes = major == 1 ? 2 : 4;
  if (bytes.size() < kMagicLen + 2 + length_bytes) {
    throw InputError(name + ": header", "file ends inside the header length");
  }
  const size_t header_len = ReadLe(bytes, kMagicLen + 2, static_cast<int>(length_bytes));
  const size_t header_start = kMagicLen + 2 + length_bytes;
  if (header_len > kMaxHeaderBytes) {
    throw InputError(name + ": header", "header of " + std::to_string(header_len) +
                                            " bytes exceeds the limit of " +
                                            std::to_string(kMaxHeaderBytes));
  }
  if (bytes.size() < header_start + header_len) {
    throw InputError(name + ": header", "file ends inside the header");
  }

  NpyHeader header;
  HeaderParser parser(bytes.substr(header_start, header_len), name);
  parser.Parse(&header.descr, &header.fortran_order, &header.shape);
  header.data_offset = header_start + header_len;
  return header;
}

size_t GzippedNpyPlainSize(std::string_view gz, const std::string& name) {
  // The header: a short prefix holds it for every array occgt writes (128 bytes); a longer
  // header, as its length field gives it, up to the longest the reader accepts. Inflating
  // the reader's maximum every time cost ~20 us a member on the read path.
  constexpr size_t kShortPrefix = 256;
  std::string head = GunzipPrefix(gz, kShortPrefix, name);
  if (head.size() == kShortPrefix && std::memcmp(head.data(), kMagic, kMagicLen) == 0) {
    const size_t length_bytes = head[6] == 1 ? 2 : 4;
    const size_t needed =
        kMagicLen + 2 + length_bytes + ReadLe(head, kMagicLen + 2, static_cast<int>(length_bytes));
    if (needed > kShortPrefix) {
      head = GunzipPrefix(gz, std::min(needed, kMagicLen + 2 + 4 + kMaxHeaderBytes), name);
    }
  }
  const NpyHeader header = ParseNpyHeader(head, name);
  // The item size of "<f4", "|u1", "<U7" (4 bytes a code unit), "|S5", "<M8[ns]": the
  // digits after the type code.
  const std::string& d = header.descr;
  size_t pos = d.empty() || std::isalpha(static_cast<unsigned char>(d[0])) ? 0 : 1;
  const bool utf32 = pos < d.size() && d[pos] == 'U';
  ++pos;
  size_t item = 0;
  for (; pos < d.size() && std::isdigit(static_cast<unsigned char>(d[pos])) && item < 1000000;
       ++pos) {
    item = item * 10 + static_cast<size_t>(d[pos] - '0');
  }
  if (item == 0) return GzipPlainSize(gz, name);
  if (utf32) item *= 4;
  constexpr size_t kMaxPlain = size_t{1} << 31;
  size_t bytes = header.data_offset;
  size_t count = 1;
  bool over = false;
  for (const int64_t n : header.shape) {
    if (n < 0) throw InputError(name + ": header field 'shape'", "negative dimension");
    if (n != 0 && count > kMaxPlain / static_cast<size_t>(n)) over = true;
    count = over ? count : count * static_cast<size_t>(n);
  }
  over = over || (count != 0 && item > kMaxPlain / count);
  if (!over) bytes += count * item;
  if (over || bytes > kMaxPlain || bytes > gz.size() * 1032 + 64) {
    throw InputError(
        name + ": header field 'shape'",
        "the header declares an array larger than " +
            std::string(over || bytes > kMaxPlain
                            ? "2 GiB"
                            : "these " + std::to_string(gz.size()) + " gzip bytes can hold"));
  }
  return bytes;
}

std::string GunzipNpy(std::string_view gz, const std::string& name) {
  std::string out(GzippedNpyPlainSize(gz, name), '\0');
  GunzipInto(gz, out.data(), out.size(), name);
  return out;
}

NpyArray ParseNpy(std::string_view bytes, const std::string& name) {
  NpyHeader header = ParseNpyHeader(bytes, name);
  NpyArray array;
  array.descr = std::move(header.descr);
  array.shape = std::move(header.shape);
  array.fortran_order = header.fortran_order;

  const std::string& d = array.descr;
  if (d.find('O') != std::string::npos) {
    throw InputError(name + ": header field 'descr'",
                     "object dtype '" + d + "' (pickled Python objects) is not supported");
  }
  if (d.size() >= 2 && d[0] == '>' && SupportedItemSize("<" + d.substr(1)) > 0) {
    throw InputError(name + ": header field 'descr'",
                     "big-endian dtype '" + d +
                         "' is not supported; save little-endian (arr.astype('<" + d.substr(1) +
                         "'))");
  }
  if (d.size() == 3 && (d[0] == '<' || d[0] == '>' || d[0] == '=') && d[2] == '1' &&
      SupportedItemSize("|" + d.substr(1)) == 1) {
    array.descr = "|" + d.substr(1);  // one-byte types have no byte order
  } else if (d.size() >= 2 && d[0] == '=') {
    throw InputError(name + ": header field 'descr'",
                     "native-order dtype '" + d + "' is ambiguous; expected '<' or '|'");
  }
  const size_t item_size = SupportedItemSize(array.descr);
  if (item_size == 0) {
    throw InputError(name + ": header field 'descr'",
                     "unsupported dtype '" + d +
                         "' (expected one of |b1 |i1 |u1 <i2 <u2 <f2 <i4 <u4 <f4 <i8 <u8 <f8)");
  }
  if (array.fortran_order) {
    throw InputError(name + ": header field 'fortran_order'",
                     "True is not supported (save with np.ascontiguousarray)");
  }

  // Byte size, checked for overflow and against the file before allocating.
  const size_t data_start = header.data_offset;
  const uint64_t available = bytes.size() - data_start;
  uint64_t nbytes = item_size;
  constexpr uint64_t kMax = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  for (int64_t dim : array.shape) {
    if (dim != 0 && nbytes > kMax / static_cast<uint64_t>(dim)) {
      throw InputError(name + ": header field 'shape'",
                       ShapeText(array.shape) + " has a byte size that overflows int64");
    }
    nbytes *= static_cast<uint64_t>(dim);
  }
  if (nbytes > available) {
    throw InputError(name + ": header field 'shape'",
                     ShapeText(array.shape) + " of '" + array.descr + "' needs " +
                         std::to_string(nbytes) + " data bytes, the file has " +
                         std::to_string(available));
  }
  array.data.assign(bytes.data() + data_start, nbytes);
  return array;
}

NpyArray ReadNpy(const std::string& path) { return ParseNpy(ReadFileBytes(path), path); }

namespace {

// The .npy bytes of an array of `item_size`-byte elements of dtype `descr` (not checked).
std::string EncodeNpyOf(const std::string& descr, size_t item_size,
                        const std::vector<int64_t>& shape, const void* data, size_t nbytes) {
  uint64_t expected = item_size;
  for (int64_t dim : shape) {
    GT_ASSERT(dim >= 0);
    expected *= static_cast<uint64_t>(dim);
  }
  GT_ASSERT_MSG(expected == nbytes, "EncodeNpy: shape " + ShapeText(shape) + " needs " +
                                        std::to_string(expected) + " bytes, got " +
                                        std::to_string(nbytes));

  std::string dict =
      "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + ShapeText(shape) + ", }";
  // Version 1.0: 6 magic + 2 version + 2 length bytes; 2.0: a 4-byte length.
  int major = 1;
  size_t prefix = kMagicLen + 2 + 2;
  size_t padded = ((prefix + dict.size() + 1 + kAlign - 1) / kAlign) * kAlign - prefix;
  if (padded > 65535) {
    major = 2;
    prefix = kMagicLen + 2 + 4;
    padded = ((prefix + dict.size() + 1 + kAlign - 1) / kAlign) * kAlign - prefix;
  }
  std::string out;
  out.reserve(prefix + padded + nbytes);
  out.append(kMagic, kMagicLen);
  out.push_back(static_cast<char>(major));
  out.push_back('\0');
  const size_t length_bytes = major == 1 ? 2 : 4;
  for (size_t i = 0; i < length_bytes; ++i) {
    out.push_back(static_cast<char>((padded >> (8 * i)) & 0xff));
  }
  out += dict;
  out.append(padded - dict.size() - 1, ' ');
  out.push_back('\n');
  GT_ASSERT(out.size() % kAlign == 0);
  if (nbytes > 0) out.append(static_cast<const char*>(data), nbytes);
  return out;
}

void AppendUtf8(uint32_t code, std::string* out) {
  if (code < 0x80) {
    out->push_back(static_cast<char>(code));
  } else if (code < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (code >> 6)));
    out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
  } else if (code < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (code >> 12)));
    out->push_back(static_cast<char>(0x80 | ((code >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (code >> 18)));
    out->push_back(static_cast<char>(0x80 | ((code >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((code >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
  }
}

}  // namespace

std::string EncodeNpy(const std::string& descr, const std::vector<int64_t>& shape, const void* data,
                      size_t nbytes) {
  const size_t item_size = SupportedItemSize(descr);
  GT_ASSERT_MSG(item_size > 0, "EncodeNpy: unsupported descr " + descr);
  return EncodeNpyOf(descr, item_size, shape, data, nbytes);
}

std::string EncodeStringsNpy(const std::vector<std::string>& values, const std::string& what) {
  std::vector<std::vector<uint32_t>> codes(values.size());
  size_t n = 1;
  for (size_t k = 0; k < values.size(); ++k) {
    if (!Utf8CodePoints(values[k], &codes[k])) {
      throw InputError(what,
                       "string " + std::to_string(k) + " is not UTF-8 text: " + Quoted(values[k]));
    }
    n = std::max(n, codes[k].size());
  }
  std::string data(values.size() * n * 4, '\0');
  for (size_t k = 0; k < codes.size(); ++k) {
    for (size_t c = 0; c < codes[k].size(); ++c) {
      for (int b = 0; b < 4; ++b) {
        data[(k * n + c) * 4 + b] = static_cast<char>((codes[k][c] >> (8 * b)) & 0xff);
      }
    }
  }
  return EncodeNpyOf("<U" + std::to_string(n), n * 4, {static_cast<int64_t>(values.size())},
                     data.data(), data.size());
}

std::vector<std::string> DecodeStringsNpy(std::string_view bytes, const std::string& name) {
  const NpyHeader h = ParseNpyHeader(bytes, name);
  if (h.descr.size() < 3 || h.descr.compare(0, 2, "<U") != 0 || h.shape.size() != 1 ||
      h.fortran_order) {
    throw InputError(name, "expected a 1-D '<U' string array, got " + h.descr);
  }
  // n code units a string: digits only, bounded (no std::stoul exception, no overflow of
  // count * n * 4 below).
  const std::string units = h.descr.substr(2);
  if (units.size() > 4 || units.find_first_not_of("0123456789") != std::string::npos ||
      std::stoul(units) == 0) {
    throw InputError(name,
                     "expected a 1-D '<U' string array of 1..9999 characters, got " + h.descr);
  }
  const size_t n = std::stoul(units);
  const size_t count = static_cast<size_t>(h.shape[0]);
  const size_t data_bytes = bytes.size() > h.data_offset ? bytes.size() - h.data_offset : 0;
  if (count > data_bytes / (n * 4)) throw InputError(name, "truncated");
  std::vector<std::string> out(count);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + h.data_offset);
  for (size_t k = 0; k < count; ++k) {
    for (size_t c = 0; c < n; ++c) {
      const unsigned char* u = data + (k * n + c) * 4;
      const uint32_t code = u[0] | (u[1] << 8) | (u[2] << 16) | (static_cast<uint32_t>(u[3]) << 24);
      if (code == 0) break;  // numpy pads shorter strings with NULs
      if (code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) {
        throw InputError(name, "string " + std::to_string(k) + ": code unit " +
                                   std::to_string(code) + " is not a Unicode character");
      }
      AppendUtf8(code, &out[k]);
    }
  }
  return out;
}

template <typename T>
void WriteNpy(const std::string& path, const std::vector<int64_t>& shape,
              const std::vector<T>& values) {
  WriteFileAtomic(path, EncodeNpy(shape, values));
}

namespace {

// The members of an open archive as .npy bytes; `path` names it in messages.
std::map<std::string, std::string> ReadNpzMemberBytes(zip_t* archive, const std::string& path);

std::map<std::string, NpyArray> ReadNpzMembers(zip_t* archive, const std::string& path) {
  std::map<std::string, NpyArray> out;
  for (auto& [key, bytes] : ReadNpzMemberBytes(archive, path)) {
    out.emplace(key, ParseNpy(bytes, path + ":" + key + ".npy"));
  }
  return out;
}

std::unique_ptr<zip_t, ZipCloser> OpenNpz(const std::string& path) {
  int code = 0;
  std::unique_ptr<zip_t, ZipCloser> archive(zip_open(path.c_str(), ZIP_RDONLY, &code));
  if (!archive) {
    if (!FileExists(path)) throw InputError(path, "cannot open (no such file)");
    throw InputError(path, "not a readable .npz (zip) archive: " + ZipErrorText(code));
  }
  return archive;
}

}  // namespace

std::map<std::string, NpyArray> ReadNpz(const std::string& path) {
  return ReadNpzMembers(OpenNpz(path).get(), path);
}

std::map<std::string, std::string> ReadNpzBytes(const std::string& path) {
  return ReadNpzMemberBytes(OpenNpz(path).get(), path);
}

std::map<std::string, NpyArray> ParseNpz(std::string_view bytes, const std::string& name) {
  zip_error_t error;
  zip_error_init(&error);
  // The source does not own the bytes (freep = 0); zip_open_from_source takes the source.
  zip_source_t* source = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &error);
  if (source == nullptr) {
    const std::string why = zip_error_strerror(&error);
    zip_error_fini(&error);
    throw InputError(name, "cannot read .npz bytes: " + why);
  }
  std::unique_ptr<zip_t, ZipCloser> archive(zip_open_from_source(source, ZIP_RDONLY, &error));
  if (!archive) {
    zip_source_free(source);
    const std::string why = zip_error_strerror(&error);
    zip_error_fini(&error);
    throw InputError(name, "not a readable .npz (zip) archive: " + why);
  }
  zip_error_fini(&error);
  return ReadNpzMembers(archive.get(), name);
}

namespace {

std::map<std::string, std::string> ReadNpzMemberBytes(zip_t* archive, const std::string& path) {
  std::map<std::string, std::string> out;
  const zip_int64_t count = zip_get_num_entries(archive, 0);
  for (zip_int64_t i = 0; i < count; ++i) {
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(archive, i, 0, &st) != 0 || !(st.valid & ZIP_STAT_NAME) ||
        !(st.valid & ZIP_STAT_SIZE)) {
      throw InputError(path, "cannot read zip entry " + std::to_string(i));
    }
    const std::string member = st.name;
    const std::string where = path + ":" + member;
    const std::string suffix = ".npy";
    if (member.size() <= suffix.size() ||
        member.compare(member.size() - suffix.size(), suffix.size(), suffix) != 0) {
      throw InputError(where, "expected only '<name>.npy' members in a .npz");
    }
    if (st.valid & ZIP_STAT_COMP_METHOD) {
      if (st.comp_method != ZIP_CM_STORE && st.comp_method != ZIP_CM_DEFLATE) {
        throw InputError(where, "compression method " + std::to_string(st.comp_method) +
                                    " (expected stored or deflated)");
      }
    }
    std::unique_ptr<zip_file_t, ZipFileCloser> file(zip_fopen_index(archive, i, 0));
    if (!file) {
      throw InputError(where, std::string("cannot open member: ") + zip_strerror(archive));
    }
    // Read in chunks rather than trusting the declared size for one big allocation.
    std::string bytes;
    char buffer[1 << 16];
    while (true) {
      const zip_int64_t n = zip_fread(file.get(), buffer, sizeof(buffer));
      if (n < 0) {
        throw InputError(where,
                         std::string("cannot read member: ") + zip_file_strerror(file.get()));
      }
      if (n == 0) break;
      bytes.append(buffer, static_cast<size_t>(n));
      if (bytes.size() > st.size) throw InputError(where, "member larger than declared");
    }
    if (bytes.size() != st.size) throw InputError(where, "member shorter than declared");
    std::string key = member.substr(0, member.size() - suffix.size());
    if (out.count(key) != 0) throw InputError(where, "duplicate member");
    out.emplace(std::move(key), std::move(bytes));
  }
  return out;
}

}  // namespace

void WriteNpz(const std::string& path, const std::map<std::string, std::string>& npy_members) {
  if (npy_members.empty()) {
    // libzip's zip_close removes an archive without entries instead of writing it. An empty
    // .npz (np.savez with no arrays) is a zip of one end-of-central-directory record: the
    // signature and 18 zero bytes.
    WriteFileAtomic(path, std::string("PK\x05\x06", 4) + std::string(18, '\0'));
    return;
  }
  // libzip writes to a file; write it beside the target, then publish its bytes atomically.
  const std::string staging = path + ".zip.tmp";
  std::error_code ec;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  std::filesystem::remove(staging, ec);
  int code = 0;
  std::unique_ptr<zip_t, ZipCloser> archive(
      zip_open(staging.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code));
  if (!archive) throw InputError(path, "cannot create .npz: " + ZipErrorText(code));
  // 1980-01-01 00:00:00, the DOS epoch: fixed so that equal inputs give equal bytes.
  constexpr zip_uint16_t kDosTime = 0;
  constexpr zip_uint16_t kDosDate = (0 << 9) | (1 << 5) | 1;
  for (const auto& [name, bytes] : npy_members) {
    const std::string member = name + ".npy";
    zip_source_t* source = zip_source_buffer(archive.get(), bytes.data(), bytes.size(), 0);
    if (source == nullptr) throw InputError(path + ":" + member, zip_strerror(archive.get()));
    const zip_int64_t index = zip_file_add(archive.get(), member.c_str(), source, ZIP_FL_ENC_UTF_8);
    if (index < 0) {
      zip_source_free(source);
      throw InputError(path + ":" + member,
                       std::string("cannot add: ") + zip_strerror(archive.get()));
    }
    if (zip_set_file_compression(archive.get(), index, ZIP_CM_STORE, 0) != 0 ||
        zip_file_set_dostime(archive.get(), index, kDosTime, kDosDate, 0) != 0) {
      throw InputError(path + ":" + member, zip_strerror(archive.get()));
    }
  }
  zip_t* raw = archive.release();
  if (zip_close(raw) != 0) {
    const std::string why = zip_strerror(raw);
    zip_discard(raw);
    std::filesystem::remove(staging, ec);
    throw InputError(path, "cannot write .npz: " + why);
  }
  std::string bytes;
  try {
    bytes = ReadFileBytes(staging);
  } catch (...) {
    std::filesystem::remove(staging, ec);
    throw;
  }
  std::filesystem::remove(staging, ec);
  WriteFileAtomic(path, bytes);
}

#define GT_NPY_INSTANTIATE(T)                                  \
  template const T* NpyArray::As<T>(const std::string&) const; \
  template void WriteNpy<T>(const std::string&, const std::vector<int64_t>&, const std::vector<T>&);
GT_NPY_INSTANTIATE(float)
GT_NPY_INSTANTIATE(double)
GT_NPY_INSTANTIATE(int32_t)
GT_NPY_INSTANTIATE(int64_t)
GT_NPY_INSTANTIATE(uint8_t)
GT_NPY_INSTANTIATE(uint16_t)
GT_NPY_INSTANTIATE(uint32_t)
GT_NPY_INSTANTIATE(uint64_t)
#undef GT_NPY_INSTANTIATE

}  // namespace gt::io

// NumPy .npy and .npz, the exchange format of every array occgt writes (docs/FORMATS.md).
//
// Writer: format version 1.0 (2.0 only when the header exceeds 65535 bytes), little-endian
// descr ('<f4', '<i4', '<u8', '|u1', ...), C order, header padded with spaces and ending in
// '\n' so that the data starts at a multiple of 64 bytes.
// Reader: rejects bad magic, unsupported versions, headers over 10000 bytes, object or
// unknown dtypes, big-endian data, and shapes whose byte size overflows or exceeds the
// file; every error names the file (or npz member) and the field.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace gt::io {

struct NpyArray {
  std::string descr;           // e.g. "<f4" (always little-endian or '|')
  std::vector<int64_t> shape;  // C order
  bool fortran_order = false;
  std::string data;  // raw bytes, size = product(shape) * item size

  int64_t NumElements() const;
  size_t ItemSize() const;
  // Typed view; throws InputError when T does not match descr.
  template <typename T>
  const T* As(const std::string& name_for_errors) const;
};

// descr of a C++ type: float "<f4", double "<f8", int32_t "<i4", int64_t "<i8",
// uint8_t "|u1", uint16_t "<u2", uint32_t "<u4", uint64_t "<u8".
template <typename T>
const char* NpyDescr();
template <>
const char* NpyDescr<float>();
template <>
const char* NpyDescr<double>();
template <>
const char* NpyDescr<int32_t>();
template <>
const char* NpyDescr<int64_t>();
template <>
const char* NpyDescr<uint8_t>();
template <>
const char* NpyDescr<uint16_t>();
template <>
const char* NpyDescr<uint32_t>();
template <>
const char* NpyDescr<uint64_t>();

// The header of .npy bytes as written: magic, version (1.0, 2.0 or 3.0), header length (at
// most 10000 bytes) and the dict, checked for syntax only (a structured descr, a list, is
// refused). descr, fortran_order and the data size are not checked against the reader
// rules above: ParseNpy does that; a caller that maps descr with numpy
// (occgt.torch.ShardDataset) applies numpy's. Throws InputError naming `name` (and the
// header field) otherwise, with ParseNpy's messages.
struct NpyHeader {
  std::string descr;  // as written: "<f4", ">f4", "|O8", ...
  std::vector<int64_t> shape;
  bool fortran_order = false;
  size_t data_offset = 0;  // bytes from the start of the .npy to the array data
};
NpyHeader ParseNpyHeader(std::string_view bytes, const std::string& name);

// The plain size of a gzip'd .npy (a shard's `<field>.npy.gz`) as its own header gives it:
// only the header is inflated to find it, so that a caller inflating exactly this many
// bytes (GunzipInto) never inflates more than the array the header declares, whatever the
// gzip trailer says. Throws InputError naming `name` for bad gzip data, a bad header, or a
// size over 2 GiB or beyond what DEFLATE reaches from these bytes (~1032:1). A descr
// without an item size (none of occgt's) falls back to the trailer's size.
size_t GzippedNpyPlainSize(std::string_view gz, const std::string& name);
// The plain bytes of a gzip'd .npy, inflated into exactly that size: InputError naming
// `name` when the data inflates to another size.
std::string GunzipNpy(std::string_view gz, const std::string& name);

// Parse .npy bytes; `name` is used in error messages (a path or "file.npz:member").
NpyArray ParseNpy(std::string_view bytes, const std::string& name);
NpyArray ReadNpy(const std::string& path);

// Encode an array as .npy bytes (see rules above).
std::string EncodeNpy(const std::string& descr, const std::vector<int64_t>& shape, const void* data,
                      size_t nbytes);
template <typename T, typename A = std::allocator<T>>
std::string EncodeNpy(const std::vector<int64_t>& shape, const std::vector<T, A>& values) {
  return EncodeNpy(NpyDescr<T>(), shape, values.data(), values.size() * sizeof(T));
}
// Strings as a 1-D NumPy unicode array (descr '<U<n>': n UTF-32LE code units a string, n the
// longest and at least 1), as np.save writes a list of str; the strings are UTF-8 text.
// Throws InputError(what, ...) for one that is not UTF-8.
std::string EncodeStringsNpy(const std::vector<std::string>& values, const std::string& what);
// The strings of such an array, as UTF-8 (numpy's NUL padding dropped). Throws InputError
// naming `name` for another dtype or rank, n outside 1..9999, a truncated array or a code
// unit that is not a Unicode scalar value.
std::vector<std::string> DecodeStringsNpy(std::string_view bytes, const std::string& name);
// Atomic write (atomic_file.h WriteFileAtomic) of EncodeNpy.
template <typename T>
void WriteNpy(const std::string& path, const std::vector<int64_t>& shape,
              const std::vector<T>& values);

// .npz: a zip of "<name>.npy" members (stored or deflated). Keys are member names without
// the ".npy" suffix.
std::map<std::string, NpyArray> ReadNpz(const std::string& path);
// The same from the archive's bytes in memory; `name` is used in error messages.
std::map<std::string, NpyArray> ParseNpz(std::string_view bytes, const std::string& name);
// Writes a stored (uncompressed) .npz atomically; members in the map's (sorted) order,
// fixed timestamps, so equal inputs give identical bytes.
void WriteNpz(const std::string& path, const std::map<std::string, std::string>& npy_members);

}  // namespace gt::io

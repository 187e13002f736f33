#include "libgt/io/gzip.h"

#include <zlib.h>

#include <cstring>

#include "libgt/core/error.h"

namespace gt::io {

std::string GzipBytes(std::string_view data, int level) {
  GT_ASSERT(level >= 1 && level <= 9);
  z_stream z;
  std::memset(&z, 0, sizeof z);
  // windowBits 15 + 16: a gzip wrapper with zlib's default header (no name, mtime 0).
  GT_ASSERT(deflateInit2(&z, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) == Z_OK);
  std::string out(deflateBound(&z, static_cast<uLong>(data.size())) + 32, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&z, Z_FINISH);
  const size_t n = z.total_out;
  deflateEnd(&z);
  GT_ASSERT(rc == Z_STREAM_END);
  out.resize(n);
  return out;
}

std::string GunzipBytes(std::string_view gz, const std::string& what, size_t max_bytes) {
  if (gz.size() < 18 || static_cast<unsigned char>(gz[0]) != 0x1f ||
      static_cast<unsigned char>(gz[1]) != 0x8b) {
    throw InputError(what, "not gzip data (expected the 1f 8b signature)");
  }
  z_stream z;
  std::memset(&z, 0, sizeof z);
  if (inflateInit2(&z, 15 + 16) != Z_OK) throw InputError(what, "zlib inflateInit2 failed");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  z.avail_in = static_cast<uInt>(gz.size());
  std::string out;
  char buf[1 << 16];
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    z.next_out = reinterpret_cast<Bytef*>(buf);
    z.avail_out = sizeof buf;
    rc = inflate(&z, Z_NO_FLUSH);
    if (rc != Z_OK && rc != Z_STREAM_END) {
      const std::string msg = z.msg ? z.msg : (rc == Z_BUF_ERROR ? "truncated" : "corrupt");
      inflateEnd(&z);
      throw InputError(what, "bad gzip data: " + msg);
    }
    const size_t produced = sizeof buf - z.avail_out;
    if (out.size() + produced > max_bytes) {
      inflateEnd(&z);
      throw InputError(what,
                       "gzip data inflates to more than " + std::to_string(max_bytes) + " bytes");
    }
    out.append(buf, produced);
    if (rc != Z_STREAM_END && produced == 0 && z.avail_in == 0) {
      inflateEnd(&z);
      throw InputError(what, "bad gzip data: truncated");
    }
  }
  const bool trailing = z.avail_in != 0;
  inflateEnd(&z);
  if (trailing) throw InputError(what, "bad gzip data: trailing bytes after the stream");
  return out;
}

}  // namespace gt::io

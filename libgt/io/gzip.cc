#include "libgt/io/gzip.h"

#include <libdeflate.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <new>

#include "libgt/core/error.h"

namespace gt::io {

namespace {

// One compressor per thread and level, one decompressor per thread: libdeflate allocates a
// few hundred kB for a compressor, which a build would otherwise fault in for every member.
libdeflate_compressor* Compressor(int level) {
  struct Cached {
    libdeflate_compressor* c = nullptr;
    int level = 0;
    ~Cached() { libdeflate_free_compressor(c); }
  };
  thread_local Cached cached;
  if (cached.c == nullptr || cached.level != level) {
    libdeflate_free_compressor(cached.c);
    cached.c = libdeflate_alloc_compressor(level);
    cached.level = level;
    if (cached.c == nullptr) throw std::bad_alloc();
  }
  return cached.c;
}

libdeflate_decompressor* Decompressor() {
  struct Cached {
    libdeflate_decompressor* d = libdeflate_alloc_decompressor();
    ~Cached() { libdeflate_free_decompressor(d); }
  };
  thread_local Cached cached;
  if (cached.d == nullptr) throw std::bad_alloc();
  return cached.d;
}

}  // namespace

std::string GzipBytes(std::string_view data, int level) {
  GT_ASSERT(level >= 1 && level <= 12);
  libdeflate_compressor* c = Compressor(level);
  std::string out(libdeflate_gzip_compress_bound(c, data.size()), '\0');
  const size_t n = libdeflate_gzip_compress(c, data.data(), data.size(), out.data(), out.size());
  GT_ASSERT(n > 0);  // the bound always fits
  out.resize(n);
  return out;
}

namespace {

// zlib's streaming inflate: the slow path, whose errors say what is wrong with the data.
std::string GunzipWithZlib(std::string_view gz, const std::string& what, size_t max_bytes) {
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

// libdeflate's whole-buffer inflate into exactly `size` bytes: true when `gz` is one gzip
// member of exactly that plain size, with nothing after it.
bool InflateExactly(std::string_view gz, char* out, size_t size) {
  size_t in_used = 0;
  size_t out_size = 0;
  return libdeflate_gzip_decompress_ex(Decompressor(), gz.data(), gz.size(), out, size, &in_used,
                                       &out_size) == LIBDEFLATE_SUCCESS &&
         in_used == gz.size() && out_size == size;
}

// DEFLATE expands at most ~1032:1: a larger trailer size is a lie.
bool PlausiblePlainSize(std::string_view gz, uint32_t isize) {
  return isize <= gz.size() * 1032 + 64;
}

void CheckGzipSignature(std::string_view gz, const std::string& what) {
  if (gz.size() < 18 || static_cast<unsigned char>(gz[0]) != 0x1f ||
      static_cast<unsigned char>(gz[1]) != 0x8b) {
    throw InputError(what, "not gzip data (expected the 1f 8b signature)");
  }
}

}  // namespace

std::string GunzipBytes(std::string_view gz, const std::string& what, size_t max_bytes) {
  CheckGzipSignature(gz, what);
  // Fast path: libdeflate into a buffer of the trailer's size, when that size is possible
  // and within max_bytes, so that a lying trailer never makes a large allocation. A failure
  // goes to zlib's streaming inflate, which gives the result or the precise error.
  const uint32_t isize = GzipTrailerSize(gz);
  if (isize <= max_bytes && PlausiblePlainSize(gz, isize)) {
    std::string out(isize, '\0');
    if (InflateExactly(gz, out.data(), out.size())) return out;
  }
  return GunzipWithZlib(gz, what, max_bytes);
}

std::string GunzipPrefix(std::string_view gz, size_t max_bytes, const std::string& what) {
  CheckGzipSignature(gz, what);
  z_stream z;
  std::memset(&z, 0, sizeof z);
  if (inflateInit2(&z, 15 + 16) != Z_OK) throw InputError(what, "zlib inflateInit2 failed");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  z.avail_in = static_cast<uInt>(gz.size());
  std::string out(max_bytes, '\0');
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(max_bytes);
  int rc = Z_OK;
  while (rc == Z_OK && z.avail_out > 0) {
    const uInt before = z.avail_out;
    rc = inflate(&z, Z_NO_FLUSH);
    if (rc == Z_OK && z.avail_out == before && z.avail_in == 0) rc = Z_BUF_ERROR;
  }
  const size_t produced = max_bytes - z.avail_out;
  const std::string msg = z.msg ? z.msg : (rc == Z_BUF_ERROR ? "truncated" : "corrupt");
  inflateEnd(&z);
  if (rc != Z_OK && rc != Z_STREAM_END) throw InputError(what, "bad gzip data: " + msg);
  out.resize(produced);
  return out;
}

void GunzipInto(std::string_view gz, char* out, size_t size, const std::string& what) {
  CheckGzipSignature(gz, what);
  if (InflateExactly(gz, out, size)) return;
  const std::string plain = GunzipWithZlib(gz, what, size);
  if (plain.size() != size) {
    throw InputError(what, "gzip data inflates to " + std::to_string(plain.size()) +
                               " bytes, expected " + std::to_string(size));
  }
  std::memcpy(out, plain.data(), size);
}

size_t GzipPlainSize(std::string_view gz, const std::string& what) {
  CheckGzipSignature(gz, what);
  const uint32_t isize = GzipTrailerSize(gz);
  if (!PlausiblePlainSize(gz, isize)) {
    throw InputError(what, "bad gzip data: its trailer claims " + std::to_string(isize) +
                               " bytes from " + std::to_string(gz.size()) + " compressed");
  }
  return isize;
}

uint32_t GzipTrailerSize(std::string_view gz) {
  if (gz.size() < 4) return 0;
  uint32_t isize = 0;
  for (size_t k = 0; k < 4; ++k) {
    isize |= static_cast<uint32_t>(static_cast<unsigned char>(gz[gz.size() - 4 + k])) << (8 * k);
  }
  return isize;
}

}  // namespace gt::io

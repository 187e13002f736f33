#include "libgt/io/files.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "libgt/core/error.h"

namespace gt::io {
namespace fs = std::filesystem;

std::string ReadFileBytes(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path, "expected a file, found a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, "read error");
  return ss.str();
}

bool FileExists(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

namespace {

// Writes all bytes to fd; false on error.
bool WriteAll(int fd, std::string_view bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

void WriteFileAtomic(const std::string& path, std::string_view bytes) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw InputError(path, "cannot create the parent folder: " + ec.message());
  }
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    throw InputError(path, std::string("cannot create ") + tmp + ": " + std::strerror(errno));
  const bool wrote = WriteAll(fd, bytes);
  const int write_errno = errno;
  const bool synced = wrote && ::fsync(fd) == 0;
  const int sync_errno = errno;
  const bool closed = ::close(fd) == 0;
  if (!wrote || !synced || !closed) {
    ::unlink(tmp.c_str());
    const int e = !wrote ? write_errno : (!synced ? sync_errno : errno);
    throw InputError(path, std::string("write failed: ") + std::strerror(e));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw InputError(path, std::string("cannot rename the temporary file: ") + std::strerror(e));
  }
  // Make the rename durable: fsync the folder (best effort).
  const std::string dir = target.has_parent_path() ? target.parent_path().string() : ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

namespace {

bool EqualsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

// One token as a double: decimal/scientific notation, or inf/-inf/+inf/infinity/nan.
bool ParseToken(std::string_view tok, double* value) {
  std::string_view body = tok;
  double sign = 1.0;
  if (!body.empty() && (body[0] == '-' || body[0] == '+')) {
    sign = body[0] == '-' ? -1.0 : 1.0;
    body.remove_prefix(1);
  }
  if (EqualsNoCase(body, "inf") || EqualsNoCase(body, "infinity")) {
    *value = sign * std::numeric_limits<double>::infinity();
    return true;
  }
  if (EqualsNoCase(body, "nan")) {
    *value = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  // strtod also accepts hex floats and "nan(...)": only allow plain decimal characters.
  for (char c : body) {
    if (!((c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '-' || c == '+')) {
      return false;
    }
  }
  if (body.empty()) return false;
  const std::string s(tok);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return false;
  *value = v;  // overflow gives +-HUGE_VAL (inf), which callers treat as non-finite
  return true;
}

}  // namespace

std::vector<double> ParseNumbers(std::string_view line, const std::string& path, int line_no) {
  std::vector<double> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r' ||
                               line[i] == '\n' || line[i] == ',')) {
      ++i;
    }
    if (i >= line.size()) break;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r' &&
           line[j] != '\n' && line[j] != ',') {
      ++j;
    }
    const std::string_view tok = line.substr(i, j - i);
    double v = 0;
    if (!ParseToken(tok, &v)) {
      throw InputError(path + ":" + std::to_string(line_no),
                       "expected a number, found '" + std::string(tok) + "'");
    }
    out.push_back(v);
    i = j;
  }
  return out;
}

std::vector<std::string> ReadLines(const std::string& path) {
  return SplitLines(ReadFileBytes(path));
}

std::vector<std::string> SplitLines(std::string_view bytes) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < bytes.size()) {
    size_t end = bytes.find('\n', start);
    if (end == std::string::npos) end = bytes.size();
    std::string line(bytes.substr(start, end - start));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
    start = end + 1;
  }
  return lines;
}

// ---------------------------------------------------------------------------------------
// MD5 (RFC 1321), written from the RFC's description.
Md5::Md5() { state_ = {0x67452301u, 0xefcdab89u, 0x98badcfeu, 0x10325476u}; }

void Md5::Update(const void* data_in, size_t n) {
  if (n == 0) return;
  const auto* data = static_cast<const unsigned char*>(data_in);
  total_bytes_ += n;
  if (buffer_len_ > 0) {  // complete the partial block first
    const size_t take = std::min(n, 64 - buffer_len_);
    std::memcpy(buffer_.data() + buffer_len_, data, take);
    buffer_len_ += take;
    data += take;
    n -= take;
    if (buffer_len_ < 64) return;
    Transform(buffer_.data());
    buffer_len_ = 0;
  }
  for (; n >= 64; data += 64, n -= 64) Transform(data);  // whole blocks straight from input
  std::memcpy(buffer_.data(), data, n);
  buffer_len_ = n;
}

std::string Md5::HexDigest() {
  const uint64_t bit_len = total_bytes_ * 8;
  unsigned char pad[72] = {0x80};
  const size_t pad_len = (buffer_len_ < 56 ? 56 : 120) - buffer_len_;
  for (int i = 0; i < 8; ++i) pad[pad_len + i] = static_cast<unsigned char>(bit_len >> (8 * i));
  Update(pad, pad_len + 8);
  static const char* kHex = "0123456789abcdef";
  std::string out;
  out.reserve(32);
  for (uint32_t word : state_) {
    for (int i = 0; i < 4; ++i) {
      const unsigned b = (word >> (8 * i)) & 0xffu;
      out.push_back(kHex[b >> 4]);
      out.push_back(kHex[b & 15]);
    }
  }
  return out;
}

// The 64 steps unrolled (round functions F, G, H, I of RFC 1321 3.4, constants
// floor(|sin(i + 1)| * 2^32) of its table T).
#define OCCGT_MD5_STEP(f, a, b, c, d, x, t, s) \
  (a) += f((b), (c), (d)) + (x) + (t);         \
  (a) = ((a) << (s)) | ((a) >> (32 - (s)));    \
  (a) += (b)
#define OCCGT_MD5_F(x, y, z) ((z) ^ ((x) & ((y) ^ (z))))
#define OCCGT_MD5_G(x, y, z) ((y) ^ ((z) & ((x) ^ (y))))
#define OCCGT_MD5_H(x, y, z) ((x) ^ (y) ^ (z))
#define OCCGT_MD5_I(x, y, z) ((y) ^ ((x) | ~(z)))

void Md5::Transform(const unsigned char* block) {
  uint32_t m[16];
  for (int i = 0; i < 16; ++i) {
    m[i] = static_cast<uint32_t>(block[4 * i]) | (static_cast<uint32_t>(block[4 * i + 1]) << 8) |
           (static_cast<uint32_t>(block[4 * i + 2]) << 16) |
           (static_cast<uint32_t>(block[4 * i + 3]) << 24);
  }
  uint32_t a = state_[0], b = state_[1], c = state_[2], d = state_[3];
  // clang-format off
  OCCGT_MD5_STEP(OCCGT_MD5_F, a, b, c, d, m[0], 0xd76aa478u, 7);
  OCCGT_MD5_STEP(OCCGT_MD5_F, d, a, b, c, m[1], 0xe8c7b756u, 12);
  OCCGT_MD5_STEP(OCCGT_MD5_F, c, d, a, b, m[2], 0x242070dbu, 17);
  OCCGT_MD5_STEP(OCCGT_MD5_F, b, c, d, a, m[3], 0xc1bdceeeu, 22);
  OCCGT_MD5_STEP(OCCGT_MD5_F, a, b, c, d, m[4], 0xf57c0fafu, 7);
  OCCGT_MD5_STEP(OCCGT_MD5_F, d, a, b, c, m[5], 0x4787c62au, 12);
  OCCGT_MD5_STEP(OCCGT_MD5_F, c, d, a, b, m[6], 0xa8304613u, 17);
  OCCGT_MD5_STEP(OCCGT_MD5_F, b, c, d, a, m[7], 0xfd469501u, 22);
  OCCGT_MD5_STEP(OCCGT_MD5_F, a, b, c, d, m[8], 0x698098d8u, 7);
  OCCGT_MD5_STEP(OCCGT_MD5_F, d, a, b, c, m[9], 0x8b44f7afu, 12);
  OCCGT_MD5_STEP(OCCGT_MD5_F, c, d, a, b, m[10], 0xffff5bb1u, 17);
  OCCGT_MD5_STEP(OCCGT_MD5_F, b, c, d, a, m[11], 0x895cd7beu, 22);
  OCCGT_MD5_STEP(OCCGT_MD5_F, a, b, c, d, m[12], 0x6b901122u, 7);
  OCCGT_MD5_STEP(OCCGT_MD5_F, d, a, b, c, m[13], 0xfd987193u, 12);
  OCCGT_MD5_STEP(OCCGT_MD5_F, c, d, a, b, m[14], 0xa679438eu, 17);
  OCCGT_MD5_STEP(OCCGT_MD5_F, b, c, d, a, m[15], 0x49b40821u, 22);
  OCCGT_MD5_STEP(OCCGT_MD5_G, a, b, c, d, m[1], 0xf61e2562u, 5);
  OCCGT_MD5_STEP(OCCGT_MD5_G, d, a, b, c, m[6], 0xc040b340u, 9);
  OCCGT_MD5_STEP(OCCGT_MD5_G, c, d, a, b, m[11], 0x265e5a51u, 14);
  OCCGT_MD5_STEP(OCCGT_MD5_G, b, c, d, a, m[0], 0xe9b6c7aau, 20);
  OCCGT_MD5_STEP(OCCGT_MD5_G, a, b, c, d, m[5], 0xd62f105du, 5);
  OCCGT_MD5_STEP(OCCGT_MD5_G, d, a, b, c, m[10], 0x02441453u, 9);
  OCCGT_MD5_STEP(OCCGT_MD5_G, c, d, a, b, m[15], 0xd8a1e681u, 14);
  OCCGT_MD5_STEP(OCCGT_MD5_G, b, c, d, a, m[4], 0xe7d3fbc8u, 20);
  OCCGT_MD5_STEP(OCCGT_MD5_G, a, b, c, d, m[9], 0x21e1cde6u, 5);
  OCCGT_MD5_STEP(OCCGT_MD5_G, d, a, b, c, m[14], 0xc33707d6u, 9);
  OCCGT_MD5_STEP(OCCGT_MD5_G, c, d, a, b, m[3], 0xf4d50d87u, 14);
  OCCGT_MD5_STEP(OCCGT_MD5_G, b, c, d, a, m[8], 0x455a14edu, 20);
  OCCGT_MD5_STEP(OCCGT_MD5_G, a, b, c, d, m[13], 0xa9e3e905u, 5);
  OCCGT_MD5_STEP(OCCGT_MD5_G, d, a, b, c, m[2], 0xfcefa3f8u, 9);
  OCCGT_MD5_STEP(OCCGT_MD5_G, c, d, a, b, m[7], 0x676f02d9u, 14);
  OCCGT_MD5_STEP(OCCGT_MD5_G, b, c, d, a, m[12], 0x8d2a4c8au, 20);
  OCCGT_MD5_STEP(OCCGT_MD5_H, a, b, c, d, m[5], 0xfffa3942u, 4);
  OCCGT_MD5_STEP(OCCGT_MD5_H, d, a, b, c, m[8], 0x8771f681u, 11);
  OCCGT_MD5_STEP(OCCGT_MD5_H, c, d, a, b, m[11], 0x6d9d6122u, 16);
  OCCGT_MD5_STEP(OCCGT_MD5_H, b, c, d, a, m[14], 0xfde5380cu, 23);
  OCCGT_MD5_STEP(OCCGT_MD5_H, a, b, c, d, m[1], 0xa4beea44u, 4);
  OCCGT_MD5_STEP(OCCGT_MD5_H, d, a, b, c, m[4], 0x4bdecfa9u, 11);
  OCCGT_MD5_STEP(OCCGT_MD5_H, c, d, a, b, m[7], 0xf6bb4b60u, 16);
  OCCGT_MD5_STEP(OCCGT_MD5_H, b, c, d, a, m[10], 0xbebfbc70u, 23);
  OCCGT_MD5_STEP(OCCGT_MD5_H, a, b, c, d, m[13], 0x289b7ec6u, 4);
  OCCGT_MD5_STEP(OCCGT_MD5_H, d, a, b, c, m[0], 0xeaa127fau, 11);
  OCCGT_MD5_STEP(OCCGT_MD5_H, c, d, a, b, m[3], 0xd4ef3085u, 16);
  OCCGT_MD5_STEP(OCCGT_MD5_H, b, c, d, a, m[6], 0x04881d05u, 23);
  OCCGT_MD5_STEP(OCCGT_MD5_H, a, b, c, d, m[9], 0xd9d4d039u, 4);
  OCCGT_MD5_STEP(OCCGT_MD5_H, d, a, b, c, m[12], 0xe6db99e5u, 11);
  OCCGT_MD5_STEP(OCCGT_MD5_H, c, d, a, b, m[15], 0x1fa27cf8u, 16);
  OCCGT_MD5_STEP(OCCGT_MD5_H, b, c, d, a, m[2], 0xc4ac5665u, 23);
  OCCGT_MD5_STEP(OCCGT_MD5_I, a, b, c, d, m[0], 0xf4292244u, 6);
  OCCGT_MD5_STEP(OCCGT_MD5_I, d, a, b, c, m[7], 0x432aff97u, 10);
  OCCGT_MD5_STEP(OCCGT_MD5_I, c, d, a, b, m[14], 0xab9423a7u, 15);
  OCCGT_MD5_STEP(OCCGT_MD5_I, b, c, d, a, m[5], 0xfc93a039u, 21);
  OCCGT_MD5_STEP(OCCGT_MD5_I, a, b, c, d, m[12], 0x655b59c3u, 6);
  OCCGT_MD5_STEP(OCCGT_MD5_I, d, a, b, c, m[3], 0x8f0ccc92u, 10);
  OCCGT_MD5_STEP(OCCGT_MD5_I, c, d, a, b, m[10], 0xffeff47du, 15);
  OCCGT_MD5_STEP(OCCGT_MD5_I, b, c, d, a, m[1], 0x85845dd1u, 21);
  OCCGT_MD5_STEP(OCCGT_MD5_I, a, b, c, d, m[8], 0x6fa87e4fu, 6);
  OCCGT_MD5_STEP(OCCGT_MD5_I, d, a, b, c, m[15], 0xfe2ce6e0u, 10);
  OCCGT_MD5_STEP(OCCGT_MD5_I, c, d, a, b, m[6], 0xa3014314u, 15);
  OCCGT_MD5_STEP(OCCGT_MD5_I, b, c, d, a, m[13], 0x4e0811a1u, 21);
  OCCGT_MD5_STEP(OCCGT_MD5_I, a, b, c, d, m[4], 0xf7537e82u, 6);
  OCCGT_MD5_STEP(OCCGT_MD5_I, d, a, b, c, m[11], 0xbd3af235u, 10);
  OCCGT_MD5_STEP(OCCGT_MD5_I, c, d, a, b, m[2], 0x2ad7d2bbu, 15);
  OCCGT_MD5_STEP(OCCGT_MD5_I, b, c, d, a, m[9], 0xeb86d391u, 21);
  // clang-format on
  state_[0] += a;
  state_[1] += b;
  state_[2] += c;
  state_[3] += d;
}
#undef OCCGT_MD5_STEP
#undef OCCGT_MD5_F
#undef OCCGT_MD5_G
#undef OCCGT_MD5_H
#undef OCCGT_MD5_I

std::string Md5Hex(std::string_view bytes) {
  Md5 md5;
  md5.Update(bytes.data(), bytes.size());
  return md5.HexDigest();
}

std::string Md5HexOfFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  Md5 md5;
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const std::streamsize n = in.gcount();
    if (n > 0) md5.Update(buf.data(), static_cast<size_t>(n));
  }
  if (in.bad()) throw InputError(path, "read error");
  return md5.HexDigest();
}

}  // namespace gt::io

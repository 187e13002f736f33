#include "libgt/io/files.h"

#include <fcntl.h>
#include <unistd.h>

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
namespace {

class Md5 {
 public:
  Md5() { state_ = {0x67452301u, 0xefcdab89u, 0x98badcfeu, 0x10325476u}; }

  void Update(const unsigned char* data, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      buffer_[buffer_len_++] = data[i];
      if (buffer_len_ == 64) {
        Transform(buffer_.data());
        buffer_len_ = 0;
      }
    }
    total_bytes_ += n;
  }

  std::string HexDigest() {
    const uint64_t bit_len = total_bytes_ * 8;
    const unsigned char pad_start = 0x80;
    Update(&pad_start, 1);
    const unsigned char zero = 0;
    while (buffer_len_ != 56) Update(&zero, 1);
    unsigned char len_le[8];
    for (int i = 0; i < 8; ++i) len_le[i] = static_cast<unsigned char>(bit_len >> (8 * i));
    Update(len_le, 8);
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

 private:
  static uint32_t Rotl(uint32_t x, int c) { return (x << c) | (x >> (32 - c)); }

  void Transform(const unsigned char* block) {
    static const uint32_t kShift[64] = {7, 12, 17, 22, 7, 12, 17, 22, 7, 12, 17, 22, 7, 12, 17, 22,
                                        5, 9,  14, 20, 5, 9,  14, 20, 5, 9,  14, 20, 5, 9,  14, 20,
                                        4, 11, 16, 23, 4, 11, 16, 23, 4, 11, 16, 23, 4, 11, 16, 23,
                                        6, 10, 15, 21, 6, 10, 15, 21, 6, 10, 15, 21, 6, 10, 15, 21};
    static const std::array<uint32_t, 64> kSine = [] {
      std::array<uint32_t, 64> t{};
      for (int i = 0; i < 64; ++i) {
        t[i] = static_cast<uint32_t>(std::floor(std::fabs(std::sin(i + 1.0)) * 4294967296.0));
      }
      return t;
    }();
    uint32_t m[16];
    for (int i = 0; i < 16; ++i) {
      m[i] = static_cast<uint32_t>(block[4 * i]) | (static_cast<uint32_t>(block[4 * i + 1]) << 8) |
             (static_cast<uint32_t>(block[4 * i + 2]) << 16) |
             (static_cast<uint32_t>(block[4 * i + 3]) << 24);
    }
    uint32_t a = state_[0], b = state_[1], c = state_[2], d = state_[3];
    for (int i = 0; i < 64; ++i) {
      uint32_t f;
      int g;
      if (i < 16) {
        f = (b & c) | (~b & d);
        g = i;
      } else if (i < 32) {
        f = (d & b) | (~d & c);
        g = (5 * i + 1) % 16;
      } else if (i < 48) {
        f = b ^ c ^ d;
        g = (3 * i + 5) % 16;
      } else {
        f = c ^ (b | ~d);
        g = (7 * i) % 16;
      }
      const uint32_t next_d = d;
      d = c;
      c = b;
      b = b + Rotl(a + f + kSine[i] + m[g], kShift[i]);
      a = next_d;
    }
    state_[0] += a;
    state_[1] += b;
    state_[2] += c;
    state_[3] += d;
  }

  std::array<uint32_t, 4> state_;
  std::array<unsigned char, 64> buffer_{};
  size_t buffer_len_ = 0;
  uint64_t total_bytes_ = 0;
};

}  // namespace

std::string Md5Hex(std::string_view bytes) {
  Md5 md5;
  md5.Update(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
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
    if (n > 0)
      md5.Update(reinterpret_cast<const unsigned char*>(buf.data()), static_cast<size_t>(n));
  }
  if (in.bad()) throw InputError(path, "read error");
  return md5.HexDigest();
}

}  // namespace gt::io

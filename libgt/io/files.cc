#include "libgt/io/files.h"

#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <sys/stat.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "libgt/core/error.h"

namespace gt::io {
namespace fs = std::filesystem;

void PrefetchFile(const std::string& path) {
  if (path.empty()) return;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_WILLNEED);
  ::close(fd);
}

std::string ReadFileBytes(const std::string& path) {
  // One buffer of the file's size, filled by read(2): no growing copies through a
  // stringstream (those were most of the page faults of reading depth maps).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw InputError(path, "expected a file, found a folder");
    throw InputError(path, "cannot open file (missing or unreadable)");
  }
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw InputError(path, "read error");
  if (S_ISDIR(st.st_mode)) throw InputError(path, "expected a file, found a folder");
  std::string bytes;
  // The size is a hint (a file may grow, and /proc files report 0): read to the end.
  bytes.resize(S_ISREG(st.st_mode) && st.st_size > 0 ? static_cast<size_t>(st.st_size) + 1
                                                     : size_t{1} << 16);
  size_t done = 0;
  while (true) {
    if (done == bytes.size()) bytes.resize(bytes.size() * 2);
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path, "read error");
    }
    if (n == 0) break;
    done += static_cast<size_t>(n);
  }
  bytes.resize(done);
  return bytes;
}

bool FileExists(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

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

namespace {

// Writes `bytes` to path + ".tmp" (creating missing parent folders) and fsyncs it. Returns
// "" on success, else the problem, the temporary removed.
std::string StageTemporary(const std::string& path, std::string_view bytes) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    if (ec) return "cannot create the parent folder: " + ec.message();
  }
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return "cannot create " + tmp + ": " + std::strerror(errno);
  const bool wrote = WriteAll(fd, bytes);
  const int write_errno = errno;
  const bool synced = wrote && ::fsync(fd) == 0;
  const int sync_errno = errno;
  const bool closed = ::close(fd) == 0;
  if (!wrote || !synced || !closed) {
    const int e = !wrote ? write_errno : (!synced ? sync_errno : errno);
    ::unlink(tmp.c_str());
    return std::string("write failed: ") + std::strerror(e);
  }
  return "";
}

// Renames path + ".tmp" onto path; throws InputError naming path (temporary removed).
void PublishTemporary(const std::string& path) {
  const std::string tmp = path + ".tmp";
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw InputError(path, std::string("cannot rename the temporary file: ") + std::strerror(e));
  }
}

std::string ParentFolder(const std::string& path) {
  const fs::path target(path);
  return target.has_parent_path() ? target.parent_path().string() : ".";
}

// Makes renames in `dir` durable (best effort).
void SyncFolder(const std::string& dir) {
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace

void WriteFileAtomic(const std::string& path, std::string_view bytes) {
  if (std::string problem = StageTemporary(path, bytes); !problem.empty()) {
    throw InputError(path, problem);
  }
  PublishTemporary(path);
  SyncFolder(ParentFolder(path));
}

void RunConcurrently(const std::vector<std::function<void()>>& functions) {
  std::vector<std::exception_ptr> errors(functions.size());
  tbb::parallel_for(size_t{0}, functions.size(), size_t{1}, [&](size_t i) {
    try {
      functions[i]();
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

void WriteFilesAtomic(const std::vector<FileToWrite>& files) {
  // 1. every temporary written and fsynced, concurrently.
  std::vector<std::string> problem(files.size());  // empty: staged
  tbb::parallel_for(size_t{0}, files.size(), size_t{1},
                    [&](size_t i) { problem[i] = StageTemporary(files[i].path, files[i].bytes); });
  auto remove_temporaries = [&](size_t from) {
    for (size_t i = from; i < files.size(); ++i) ::unlink((files[i].path + ".tmp").c_str());
  };
  for (size_t i = 0; i < files.size(); ++i) {
    if (!problem[i].empty()) {
      remove_temporaries(0);
      throw InputError(files[i].path, problem[i]);
    }
  }
  // 2. published in order, then each folder made durable once.
  std::set<std::string> folders;
  for (size_t i = 0; i < files.size(); ++i) {
    try {
      PublishTemporary(files[i].path);
    } catch (const InputError&) {
      remove_temporaries(i + 1);
      throw;
    }
    folders.insert(ParentFolder(files[i].path));
  }
  for (const std::string& dir : folders) SyncFolder(dir);
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
// MD5 through OpenSSL's EVP interface.
namespace {
// OpenSSL's MD5 implementation, fetched once for the process (EVP_md5() is fetched again at
// every digest's start). The machine's openssl.cnf is not loaded: a digest must not depend
// on it, and reading it (~0.5 ms, more when the file has left the page cache) was on the
// serial start of every build.
const EVP_MD* Md5Method() {
  static const EVP_MD* const md = [] {
    OPENSSL_init_crypto(OPENSSL_INIT_NO_LOAD_CONFIG, nullptr);
    return EVP_MD_fetch(nullptr, "MD5", nullptr);
  }();
  return md;
}
}  // namespace

Md5::Md5() : ctx_(EVP_MD_CTX_new()) {
  const EVP_MD* md = Md5Method();
  if (ctx_ == nullptr || md == nullptr || EVP_DigestInit_ex(ctx_, md, nullptr) != 1) {
    throw std::runtime_error("OpenSSL: cannot start an MD5 digest");
  }
}
Md5::~Md5() { EVP_MD_CTX_free(ctx_); }
Md5::Md5(Md5&& other) noexcept : ctx_(other.ctx_) { other.ctx_ = nullptr; }
Md5& Md5::operator=(Md5&& other) noexcept {
  std::swap(ctx_, other.ctx_);
  return *this;
}

void Md5::Update(const void* data, size_t n) {
  if (n > 0 && EVP_DigestUpdate(ctx_, data, n) != 1) {
    throw std::runtime_error("OpenSSL: MD5 update failed");
  }
}

std::string Md5::HexDigest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(ctx_, digest, &length) != 1 || length != 16) {
    throw std::runtime_error("OpenSSL: MD5 final failed");
  }
  static const char* kHex = "0123456789abcdef";
  std::string out;
  out.reserve(32);
  for (unsigned int i = 0; i < length; ++i) {
    out.push_back(kHex[digest[i] >> 4]);
    out.push_back(kHex[digest[i] & 15]);
  }
  return out;
}

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

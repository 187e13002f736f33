#include "libgt/io/file_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

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

void PrefetchFileRange(const std::string& path, uint64_t offset, uint64_t size) {
  if (path.empty() || size == 0) return;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  ::posix_fadvise(fd, static_cast<off_t>(offset), static_cast<off_t>(size), POSIX_FADV_WILLNEED);
  ::close(fd);
}

namespace {

// One open descriptor per container file, shared by every thread reading it (pread has no
// file position); closed when the last reader holding it is done after its eviction.
struct SharedFd {
  int fd = -1;
  uint64_t size = 0;
  dev_t dev = 0;  // identity of the file opened: a file replaced since is opened again
  ino_t ino = 0;
  int64_t mtime_ns = 0;
  ~SharedFd() {
    if (fd >= 0) ::close(fd);
  }
};

std::shared_ptr<const SharedFd> OpenShared(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const SharedFd>> open_files;
  static std::vector<std::string> order;  // opening order, for eviction
  constexpr size_t kMaxOpen = 64;
  auto mtime_ns = [](const struct stat& st) {
    return int64_t{st.st_mtim.tv_sec} * 1000000000 + st.st_mtim.tv_nsec;
  };
  std::lock_guard<std::mutex> lock(mutex);
  const auto it = open_files.find(path);
  if (it != open_files.end()) {
    struct stat now {};
    const SharedFd& f = *it->second;
    if (::stat(path.c_str(), &now) == 0 && now.st_dev == f.dev && now.st_ino == f.ino &&
        static_cast<uint64_t>(now.st_size) == f.size && mtime_ns(now) == f.mtime_ns) {
      return it->second;
    }
    open_files.erase(it);
    order.erase(std::find(order.begin(), order.end(), path));
  }
  auto f = std::make_shared<SharedFd>();
  f->fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f->fd < 0) throw InputError(path, "cannot open file (missing or unreadable)");
  struct stat st {};
  if (::fstat(f->fd, &st) != 0) throw InputError(path, "read error");
  if (!S_ISREG(st.st_mode)) throw InputError(path, "expected a regular file");
  f->size = static_cast<uint64_t>(st.st_size);
  f->dev = st.st_dev;
  f->ino = st.st_ino;
  f->mtime_ns = mtime_ns(st);
  if (order.size() >= kMaxOpen) {
    open_files.erase(order.front());
    order.erase(order.begin());
  }
  order.push_back(path);
  open_files[path] = f;
  return f;
}

}  // namespace

std::string ReadFileRange(const std::string& path, uint64_t offset, uint64_t size,
                          const std::string& what) {
  const std::shared_ptr<const SharedFd> f = OpenShared(path);
  if (offset > f->size || size > f->size - offset) {
    throw InputError(path, what + ": bytes [" + std::to_string(offset) + ", +" +
                               std::to_string(size) + ") past the end of the file (" +
                               std::to_string(f->size) + " bytes)");
  }
  std::string bytes(static_cast<size_t>(size), '\0');
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n =
        ::pread(f->fd, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path, what + ": read error");
    }
    if (n == 0) throw InputError(path, what + ": file ends before the payload does");
    done += static_cast<size_t>(n);
  }
  return bytes;
}

std::string ContainerFrameWhere(const std::string& path, int64_t index) {
  return path + ": frame " + std::to_string(index);
}

uint64_t FileSizeBytes(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw InputError(path, "cannot open file (missing or unreadable)");
  }
  if (S_ISDIR(st.st_mode)) throw InputError(path, "expected a file, found a folder");
  return static_cast<uint64_t>(st.st_size);
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

}  // namespace gt::io

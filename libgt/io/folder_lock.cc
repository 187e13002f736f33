#include "libgt/io/folder_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "libgt/core/error.h"

namespace gt::io {

FolderLock::FolderLock(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir, "cannot create the output folder: " + ec.message());
  const std::string path = dir + "/.lock";
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  while (::flock(fd_, LOCK_EX) != 0) {
    if (errno == EINTR) continue;
    const int e = errno;
    ::close(fd_);
    throw InputError(path, std::string("cannot lock: ") + std::strerror(e));
  }
}

FolderLock::~FolderLock() { ::close(fd_); }  // releases the lock

std::unique_ptr<FileLock> FileLock::TryAcquire(const std::string& path, int64_t slot) {
  int64_t busy = 0;
  return TryAcquire(path, std::vector<int64_t>{slot}, &busy);
}

std::unique_ptr<FileLock> FileLock::TryAcquire(const std::string& path,
                                               const std::vector<int64_t>& slots, int64_t* busy) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  for (const int64_t slot : slots) {
    struct flock range {};
    range.l_type = F_WRLCK;
    range.l_whence = SEEK_SET;
    range.l_start = static_cast<off_t>(slot);
    range.l_len = 1;
    while (::fcntl(fd, F_SETLK, &range) != 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      ::close(fd);  // releases the bytes taken so far
      if (e == EAGAIN || e == EACCES) {
        *busy = slot;
        return nullptr;
      }
      throw InputError(path, std::string("cannot lock: ") + std::strerror(e));
    }
  }
  return std::unique_ptr<FileLock>(new FileLock(fd));
}

FileLock::~FileLock() { ::close(fd_); }

}  // namespace gt::io

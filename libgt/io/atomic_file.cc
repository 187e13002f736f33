#include "libgt/io/atomic_file.h"

#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>

#include "libgt/core/error.h"

namespace gt::io {
namespace fs = std::filesystem;

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

std::string OutputFileProblem(const std::string& path) {
  if (path.empty()) return "expected a file path, got ''";
  if (path.back() == '/') return "names a folder (it ends with '/'): expected a file path";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);  // follows symbolic links
  if (ec || !fs::exists(status) || fs::is_regular_file(status)) return "";
  if (fs::is_directory(status)) return "is a folder: expected a file path";
  return "exists and is not a regular file (a device, FIFO or socket), which writing a new file "
         "onto its path would replace";
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
  if (std::string problem = OutputFileProblem(path); !problem.empty()) {
    throw InputError(path, problem);
  }
  std::error_code ec;
  // A link is written through: its target is the file replaced (the link stays), also a
  // target that does not exist yet (weakly_canonical leaves a dangling link unresolved, so
  // the link itself was replaced). Links to links are followed, up to 40 as the kernel does.
  fs::path target = path;
  for (int hops = 0; fs::is_symlink(fs::symlink_status(target, ec)); ++hops) {
    if (hops == 40) throw InputError(path, "cannot resolve the symbolic link: too many levels");
    const fs::path next = fs::read_symlink(target, ec);
    if (ec) throw InputError(path, "cannot resolve the symbolic link: " + ec.message());
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  if (target != fs::path(path)) {
    target = fs::weakly_canonical(target, ec);
    if (ec) throw InputError(path, "cannot resolve the symbolic link: " + ec.message());
  }
  if (std::string problem = StageTemporary(target.string(), bytes); !problem.empty()) {
    throw InputError(path, problem);
  }
  PublishTemporary(target.string());
  SyncFolder(ParentFolder(target.string()));
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

}  // namespace gt::io

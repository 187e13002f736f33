// An exclusive advisory lock (flock) on DIR/.lock, held while a task writes one of the files
// that every task of a split may write at the same moment (recipe.json, the synthetic
// dataset, the shard plan, the indices and summary): WriteFileAtomic's fixed `X.tmp` name
// is safe for one writer only. The lock file is empty and never removed; the lock is
// released when the object is destroyed (or the process ends).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace gt::io {

// An exclusive advisory lock (POSIX record lock, fcntl F_SETLK) on byte `slot` of one file,
// taken without waiting: TryAcquire returns null when another process holds that byte. One
// file serves many independent locks (one per build task). The file is created when missing
// and never removed; the lock is released when the object is destroyed or the process ends.
class FileLock {
 public:
  // Throws InputError naming the file when it cannot be created or opened.
  static std::unique_ptr<FileLock> TryAcquire(const std::string& path, int64_t slot);
  // Every byte of `slots` at once, on one descriptor (one per byte would run out of file
  // descriptors for a task of thousands of shards): null, *busy = the first byte another
  // process holds, when any is held (none is then kept). POSIX record locks belong to the
  // process: closing any other descriptor of the same file in this process releases them,
  // so a file locked this way is opened nowhere else.
  static std::unique_ptr<FileLock> TryAcquire(const std::string& path,
                                              const std::vector<int64_t>& slots, int64_t* busy);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  explicit FileLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

class FolderLock {
 public:
  // Creates DIR when missing and blocks until the lock is held; throws InputError naming
  // the folder or the lock file.
  explicit FolderLock(const std::string& dir);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace gt::io

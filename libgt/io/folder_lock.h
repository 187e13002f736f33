// An exclusive advisory lock (flock) on DIR/.lock, held while a task writes one of the files
// that every task of a split may write at the same moment (recipe.json, the synthetic
// dataset, the shard plan, the indices and summary): WriteFileAtomic's fixed `X.tmp` name
// is safe for one writer only. The lock file is empty and never removed; the lock is
// released when the object is destroyed (or the process ends).
#pragma once

#include <string>

namespace gt::io {

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

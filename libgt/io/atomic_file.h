// Publishing files atomically: every output of occgt is written to "<path>.tmp", fsynced
// and renamed onto its path, so that a reader never sees a half-written file and a crash
// leaves at most a temporary behind (docs/RELIABILITY.md).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace gt::io {

// Why `path` cannot take a new file, or "": empty, ending with '/', an existing folder, or an
// existing file that is not a regular one (a device such as /dev/null, a FIFO, a socket:
// renaming onto it would replace the node). A symbolic link counts as its target.
std::string OutputFileProblem(const std::string& path);

// Writes `bytes` to path + ".tmp", fsyncs, renames onto `path`. Creates missing parent
// folders. A symbolic link is written through: the file replaces its target (the link
// stays). Throws InputError naming the path on any failure (OutputFileProblem, disk full,
// permissions) and removes the temporary file, so a reader never sees a half-written output.
void WriteFileAtomic(const std::string& path, std::string_view bytes);

// write(2) of all bytes to fd, retrying on EINTR; false on error (errno set).
bool WriteAll(int fd, std::string_view bytes);

// Several files at once, for the small indices a run ends with: each is written to
// "<path>.tmp" and fsynced, all concurrently (their fsyncs overlap); then, when every one
// of them succeeded, they are renamed onto their paths in the order given (a later file
// may be the completion marker of an earlier one) and each parent folder is fsynced once.
// When a file cannot be written, none of the batch is published, every temporary is
// removed, and the InputError of the first failing file in the list's order is thrown. When
// a rename fails (the target is a folder, say), the files before it stay published and
// the temporaries of the rest are removed.
struct FileToWrite {
  std::string path;
  std::string bytes;
};
void WriteFilesAtomic(const std::vector<FileToWrite>& files);

}  // namespace gt::io

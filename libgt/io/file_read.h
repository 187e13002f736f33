// Reading files: whole-file reads with errors that name the file, text lines, and a
// read-ahead hint for the frame scan.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace gt::io {

// Whole file as bytes; throws InputError("<path>", "cannot open ...") when unreadable.
std::string ReadFileBytes(const std::string& path);
bool FileExists(const std::string& path);

// Bytes [offset, offset + size) of a file (a payload inside a container such as a ScanNet
// .sens), read with pread(2) from one descriptor per file that every thread shares (kept
// open for the process; at most 64 files, the least recently opened closed first). A range
// past the end of the file is an InputError naming the file, the offset and the size, checked
// before allocating. `what` names the payload in messages ("frame 12 depth").
std::string ReadFileRange(const std::string& path, uint64_t offset, uint64_t size,
                          const std::string& what);
// "<path>: frame <index>": where a message about one frame of a container file (a ScanNet
// .sens) points, in the reader's errors and unusable-frame details and in payload reads.
std::string ContainerFrameWhere(const std::string& path, int64_t index);
// Size of a file in bytes; InputError naming it when it cannot be opened.
uint64_t FileSizeBytes(const std::string& path);

// Lines of a text file (without '\n', '\r' stripped).
std::vector<std::string> ReadLines(const std::string& path);
// The same split of text already in memory.
std::vector<std::string> SplitLines(std::string_view text);

// Asks the kernel to start reading the whole file into the page cache in the background
// (posix_fadvise POSIX_FADV_WILLNEED) and returns without waiting, so that a later read of
// it does not stall a compute thread on the disk (the frame scan reads ahead with it). A
// hint only: a file that cannot be opened is skipped (its reader reports the error when it
// reads it), and a cached file costs an open/close.
void PrefetchFile(const std::string& path);
// The same for bytes [offset, offset + size) only (a payload inside a container).
void PrefetchFileRange(const std::string& path, uint64_t offset, uint64_t size);

}  // namespace gt::io

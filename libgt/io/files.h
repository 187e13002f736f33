// File helpers shared by every reader and writer: whole-file reads with errors that name
// the file, numbered text lines, and atomic publication (write X.tmp, fsync, rename).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace gt::io {

// Whole file as bytes; throws InputError("<path>", "cannot open ...") when unreadable.
std::string ReadFileBytes(const std::string& path);
bool FileExists(const std::string& path);

// Writes `bytes` to path + ".tmp", fsyncs, renames onto `path`. Creates missing parent
// folders. Throws InputError naming the path on any failure (disk full, permissions) and
// removes the temporary file, so a reader never sees a half-written output.
void WriteFileAtomic(const std::string& path, std::string_view bytes);

// Whitespace-separated doubles of one text line; accepts "inf", "-inf", "nan" (any case),
// which ScanNet writes for lost tracking. Throws InputError("<path>:<line>", ...) on a
// token that is not a number.
std::vector<double> ParseNumbers(std::string_view line, const std::string& path, int line_no);

// Lines of a text file (without '\n', '\r' stripped).
std::vector<std::string> ReadLines(const std::string& path);
// The same split of text already in memory.
std::vector<std::string> SplitLines(std::string_view text);

// Lower-case hex MD5 of bytes / of a file.
std::string Md5Hex(std::string_view bytes);
// The same, incrementally: Update any number of times, then HexDigest once.
class Md5 {
 public:
  Md5();
  void Update(const void* data, size_t n);
  std::string HexDigest();

 private:
  void Transform(const unsigned char* block);
  std::array<uint32_t, 4> state_;
  std::array<unsigned char, 64> buffer_{};
  size_t buffer_len_ = 0;
  uint64_t total_bytes_ = 0;
};
std::string Md5HexOfFile(const std::string& path);

}  // namespace gt::io

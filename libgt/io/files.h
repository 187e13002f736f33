// File helpers shared by every reader and writer: whole-file reads with errors that name
// the file, numbered text lines, and atomic publication (write X.tmp, fsync, rename).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

struct evp_md_ctx_st;  // OpenSSL (openssl/evp.h), kept out of this header

namespace gt::io {

// Whole file as bytes; throws InputError("<path>", "cannot open ...") when unreadable.
std::string ReadFileBytes(const std::string& path);
bool FileExists(const std::string& path);

// Asks the kernel to start reading the whole file into the page cache in the background
// (posix_fadvise POSIX_FADV_WILLNEED) and returns without waiting, so that a later read of
// it does not stall a compute thread on the disk. A hint only: a file that cannot be opened
// is skipped (its reader reports the error when it reads it), and a cached file costs an
// open/close.
void PrefetchFile(const std::string& path);

// Writes `bytes` to path + ".tmp", fsyncs, renames onto `path`. Creates missing parent
// folders. Throws InputError naming the path on any failure (disk full, permissions) and
// removes the temporary file, so a reader never sees a half-written output.
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

// Runs the functions concurrently (TBB tasks) and returns when all have finished; if some
// threw, rethrows the exception of the first of them in the list's order (so the error
// reported does not depend on timing).
void RunConcurrently(const std::vector<std::function<void()>>& functions);

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
// OpenSSL's MD5 (libcrypto, ~1.3x the speed of the RFC 1321 code occgt had; a shard's
// digest is computed in the serial stage of the write pipeline). Movable, not copyable.
class Md5 {
 public:
  Md5();
  ~Md5();
  Md5(Md5&&) noexcept;
  Md5& operator=(Md5&&) noexcept;
  Md5(const Md5&) = delete;
  Md5& operator=(const Md5&) = delete;
  void Update(const void* data, size_t n);
  std::string HexDigest();

 private:
  evp_md_ctx_st* ctx_ = nullptr;  // OpenSSL's EVP_MD_CTX
};
std::string Md5HexOfFile(const std::string& path);

}  // namespace gt::io

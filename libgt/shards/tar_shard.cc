#include "libgt/shards/tar_shard.h"

#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <unordered_set>
#include <utility>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/md5.h"

namespace gt::shards {
namespace {

struct ArchiveWriteDeleter {
  void operator()(archive* a) const { archive_write_free(a); }
};
struct ArchiveReadDeleter {
  void operator()(archive* a) const { archive_read_free(a); }
};
struct EntryDeleter {
  void operator()(archive_entry* e) const { archive_entry_free(e); }
};

// libarchive's client for a tar file: reads of `block` bytes with pread(2) at the position
// libarchive has reached, skips without a system call (the position moves; a skip stops at
// the end of the file, so that libarchive sees the truncation). A header-only pass costs
// one small read per member: archive_read_open_filename reads at least 64 KiB at each header
// of a regular file (and seeks twice), which made listing a shard's headers 1.6x slower
// than a Python loop of one 512-byte pread per header (docs/PERFORMANCE.md).
struct PreadClient {
  int fd = -1;
  int64_t offset = 0;      // next byte libarchive gets
  int64_t file_bytes = 0;  // size of the file
  std::vector<char> buffer;

  PreadClient() = default;
  PreadClient(const PreadClient&) = delete;
  PreadClient& operator=(const PreadClient&) = delete;
  ~PreadClient() {
    if (fd >= 0) ::close(fd);
  }

  static la_ssize_t Read(archive* a, void* client, const void** out) {
    auto* self = static_cast<PreadClient*>(client);
    ssize_t n = 0;
    do {
      n = ::pread(self->fd, self->buffer.data(), self->buffer.size(), self->offset);
    } while (n < 0 && errno == EINTR);
    if (n < 0) {
      archive_set_error(a, errno, "read failed: %s", std::strerror(errno));
      return -1;
    }
    self->offset += n;
    *out = self->buffer.data();
    return n;
  }
  static la_int64_t Skip(archive* /*a*/, void* client, la_int64_t request) {
    auto* self = static_cast<PreadClient*>(client);
    const int64_t skip =
        std::max<int64_t>(0, std::min<int64_t>(request, self->file_bytes - self->offset));
    self->offset += skip;
    return skip;
  }
};

std::string ArchiveMessage(archive* a) {
  const char* s = archive_error_string(a);
  return s != nullptr ? s : "unknown libarchive error";
}

}  // namespace

struct TarShardWriter::Impl {
  std::string path;
  std::string tmp_path;
  int fd = -1;
  std::unique_ptr<archive, ArchiveWriteDeleter> ar;
  bool dead = false;      // a write failed: nothing more may be written or published
  bool finished = false;  // published
  int write_errno = 0;    // errno of the first failed write(2)
  int64_t nsamples = 0;
  int64_t bytes = 0;
  int64_t writeback_from = 0;  // bytes before this offset have been handed to writeback
  io::Md5 md5;                 // of the bytes digested so far (the published file's digest)
  std::set<std::string> keys;

  // libarchive write callback: writes the whole block. A failed write(2) is recorded in
  // write_errno and the block (and every later one) is reported as written: returning an
  // error would put the archive into libarchive's fatal state, from which
  // archive_write_free no longer releases the client buffers of archive_write_open2 (a
  // leak LeakSanitizer showed on the disk-full path). Callers call CheckWrites() after
  // every libarchive call instead.
  //
  // The archive is unblocked (bytes_per_block 0), so a member's data arrives here in one
  // piece: one write(2) for the whole buffer instead of one per 10240-byte block, and no
  // copy into libarchive's block buffer. The bytes are then digested (the MD5 of the file
  // is the digest of every block, in order).
  static la_ssize_t Write(archive* /*a*/, void* client, const void* buf, size_t n) {
    auto* self = static_cast<Impl*>(client);
    if (self->write_errno != 0) return static_cast<la_ssize_t>(n);
    self->WriteAll(buf, n);
    self->md5.Update(buf, n);
    if (self->write_errno == 0) self->bytes += static_cast<int64_t>(n);
    return static_cast<la_ssize_t>(n);
  }

  // Starts the writeback of the bytes written so far (asynchronous, no wait) once at least
  // kWritebackBytes of whole pages are pending, so that the fsync of Finish, which
  // publication waits for, has little left to flush. Whole pages only (the partial last
  // page would be written twice). Advisory: an error here is ignored (fsync reports any
  // real one).
  void StartWriteback() {
#ifdef __linux__
    const int64_t upto = bytes & ~int64_t{4095};
    if (upto - writeback_from < kWritebackBytes) return;
    (void)::sync_file_range(fd, writeback_from, upto - writeback_from, SYNC_FILE_RANGE_WRITE);
    writeback_from = upto;
#endif
  }
  static constexpr int64_t kWritebackBytes = int64_t{1} << 20;

  // write(2) of the whole buffer; a failure is recorded in write_errno (see Write).
  void WriteAll(const void* buf, size_t n) {
    if (!io::WriteAll(fd, std::string_view(static_cast<const char*>(buf), n))) write_errno = errno;
  }

  void CheckAdd(const Sample& sample);      // throws (and abandons) on a bad sample
  void WriteMembers(const Sample& sample);  // the sample's members through libarchive

  // Fails (abandoning the shard) when a write(2) of the archive has failed.
  void CheckWrites(const std::string& member) {
    if (write_errno != 0) Fail(member, std::string("write failed: ") + std::strerror(write_errno));
  }

  void Fail(const std::string& member, const std::string& problem) {
    Abandon();
    throw InputError(path + (member.empty() ? "" : ": " + member), problem);
  }

  // Drops the archive and removes the temporary file (idempotent).
  void Abandon() {
    dead = true;
    ar.reset();
    if (fd >= 0) {
      ::close(fd);
      fd = -1;
    }
    if (!tmp_path.empty()) ::unlink(tmp_path.c_str());
  }
};

TarShardWriter::TarShardWriter(std::string path) : impl_(std::make_unique<Impl>()) {
  impl_->path = std::move(path);
  impl_->tmp_path = impl_->path + ".tmp";
  const std::filesystem::path parent = std::filesystem::path(impl_->path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
    if (ec) throw InputError(impl_->path, "cannot create folder: " + ec.message());
  }
  impl_->fd = ::open(impl_->tmp_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (impl_->fd < 0) {
    const std::string reason = std::strerror(errno);
    impl_->tmp_path.clear();  // not ours to remove
    throw InputError(impl_->path, "cannot open temporary shard for writing: " + reason);
  }
  impl_->ar.reset(archive_write_new());
  archive* a = impl_->ar.get();
  if (a == nullptr || archive_write_set_format_ustar(a) != ARCHIVE_OK ||
      archive_write_add_filter_none(a) != ARCHIVE_OK ||
      archive_write_set_bytes_per_block(a, 0) != ARCHIVE_OK ||
      archive_write_open2(a, impl_.get(), nullptr, &Impl::Write, nullptr, nullptr) != ARCHIVE_OK) {
    impl_->Fail("", "cannot start a ustar archive: " +
                        (a != nullptr ? ArchiveMessage(a) : std::string("out of memory")));
  }
}

TarShardWriter::~TarShardWriter() {
  if (impl_ && !impl_->finished) impl_->Abandon();
}

void TarShardWriter::Add(const Sample& sample) {
  impl_->CheckAdd(sample);
  impl_->WriteMembers(sample);
}

void TarShardWriter::Add(Sample&& sample) {
  const Sample taken = std::move(sample);  // released on return
  Add(taken);
}

void TarShardWriter::Impl::CheckAdd(const Sample& sample) {
  if (dead || finished) {
    throw InputError(path, "writer is closed (an earlier write failed or Finish() ran)");
  }
  if (std::string e = CheckSample(sample); !e.empty()) Fail(sample.key, e);
  if (!keys.insert(sample.key).second) Fail(sample.key, "sample key repeats in the shard");
}

void TarShardWriter::Impl::WriteMembers(const Sample& sample) {
  Impl& s = *this;
  std::unique_ptr<archive_entry, EntryDeleter> entry(archive_entry_new());
  for (const SampleField& field : sample.fields) {
    const std::string member = sample.key + "." + field.name;
    archive_entry_clear(entry.get());
    archive_entry_copy_pathname(entry.get(), member.c_str());
    archive_entry_set_size(entry.get(), static_cast<la_int64_t>(field.bytes.size()));
    archive_entry_set_filetype(entry.get(), AE_IFREG);
    archive_entry_set_perm(entry.get(), 0644);
    archive_entry_set_mtime(entry.get(), 0, 0);
    archive_entry_set_uid(entry.get(), 0);
    archive_entry_set_gid(entry.get(), 0);
    archive* a = s.ar.get();
    if (archive_write_header(a, entry.get()) != ARCHIVE_OK) {
      s.CheckWrites(member);
      s.Fail(member, "cannot write tar header: " + ArchiveMessage(a));
    }
    size_t done = 0;
    while (done < field.bytes.size()) {
      const la_ssize_t w =
          archive_write_data(a, field.bytes.data() + done, field.bytes.size() - done);
      s.CheckWrites(member);
      if (w <= 0) s.Fail(member, "cannot write member data: " + ArchiveMessage(a));
      done += static_cast<size_t>(w);
    }
    if (archive_write_finish_entry(a) != ARCHIVE_OK) {
      s.CheckWrites(member);
      s.Fail(member, "cannot finish member: " + ArchiveMessage(a));
    }
    s.CheckWrites(member);
    s.StartWriteback();
  }
  ++s.nsamples;
}

ShardInfo TarShardWriter::Finish() {
  Impl& s = *impl_;
  if (s.dead || s.finished) {
    throw InputError(s.path, "writer is closed (an earlier write failed or Finish() ran)");
  }
  if (archive_write_close(s.ar.get()) != ARCHIVE_OK) {
    s.CheckWrites("");
    s.Fail("", "cannot close the archive: " + ArchiveMessage(s.ar.get()));
  }
  s.CheckWrites("");
  s.ar.reset();
  if (::fsync(s.fd) != 0) s.Fail("", std::string("fsync failed: ") + std::strerror(errno));
  if (::close(s.fd) != 0) {
    s.fd = -1;
    s.Fail("", std::string("close failed: ") + std::strerror(errno));
  }
  s.fd = -1;
  if (::rename(s.tmp_path.c_str(), s.path.c_str()) != 0) {
    s.Fail("", std::string("cannot rename the temporary shard: ") + std::strerror(errno));
  }
  s.finished = true;
  ShardInfo info;
  info.path = s.path;
  info.nsamples = s.nsamples;
  info.filesize = s.bytes;
  info.md5sum = s.md5.HexDigest();  // computed while writing, not by reading the file back
  struct stat st {};
  if (::stat(s.path.c_str(), &st) != 0 || st.st_size != info.filesize) {
    throw InputError(s.path, "published shard size differs from the bytes written");
  }
  return info;
}

int64_t TarShardWriter::num_samples() const { return impl_->nsamples; }
int64_t TarShardWriter::bytes_written() const { return impl_->bytes; }

namespace {

// Why the 512-byte header at `offset` could not be read, said from the block itself:
// libarchive's own words are "Damaged tar archive" (or, for the first header, "Unrecognized
// archive format") for a header whose checksum does not match. libarchive parses; this only
// chooses the message. "" when the block looks like a header.
std::string HeaderProblem(int fd, int64_t offset, int64_t file_bytes) {
  if (file_bytes - offset < 512) {
    return "the file ends inside the 512-byte header, at byte " + std::to_string(file_bytes) +
           " (truncated)";
  }
  unsigned char block[512];
  if (::pread(fd, block, sizeof(block), offset) != static_cast<ssize_t>(sizeof(block))) return "";
  int64_t sum = 0, stored = 0;
  for (int i = 0; i < 512; ++i) sum += (i >= 148 && i < 156) ? ' ' : block[i];
  for (int i = 148; i < 156 && block[i] >= '0' && block[i] <= '7'; ++i) {
    stored = stored * 8 + (block[i] - '0');
  }
  if (sum != stored) return "checksum mismatch: not a POSIX ustar header (damaged, or not a tar)";
  return "";
}

// The one reading loop of ForEachTarMember (read_data) and ForEachTarHeader (the data is
// skipped, not read; `block` is the size of each read: 512 bytes, one header, for a
// header-only pass).
void ReadTar(const std::string& tar_path, bool read_data, size_t block,
             const std::function<void(const TarMemberInfo&, std::string_view data)>& visit) {
  PreadClient client;
  client.fd = ::open(tar_path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (client.fd < 0 || ::fstat(client.fd, &st) != 0) {
    throw InputError(tar_path, std::string("cannot open the tar archive: ") + std::strerror(errno));
  }
  const int64_t file_bytes = static_cast<int64_t>(st.st_size);
  client.file_bytes = file_bytes;
  client.buffer.resize(block);
  int64_t next_header = 0;  // where the next header starts: after the last member's padded data
  std::string last_member;
  // A header libarchive refused (it reads the first one when the archive is opened).
  const auto header_error = [&](const std::string& libarchive_message) {
    std::string problem = HeaderProblem(client.fd, next_header, file_bytes);
    return InputError(tar_path + ": tar header at byte " + std::to_string(next_header) +
                          (last_member.empty() ? "" : " (after member " + last_member + ")"),
                      (problem.empty() ? "bad tar header" : problem) +
                          " (libarchive: " + libarchive_message + ")");
  };
  // Declared after the client: freed (and so done with it) first.
  std::unique_ptr<archive, ArchiveReadDeleter> ar(archive_read_new());
  archive* a = ar.get();
  archive_read_support_format_tar(a);
  if (archive_read_open2(a, &client, nullptr, &PreadClient::Read, &PreadClient::Skip, nullptr) !=
      ARCHIVE_OK) {
    throw header_error(ArchiveMessage(a));
  }
  std::string data;
  while (true) {
    archive_entry* entry = nullptr;
    const int r = archive_read_next_header(a, &entry);
    if (r == ARCHIVE_EOF) break;
    if (r != ARCHIVE_OK) throw header_error(ArchiveMessage(a));
    TarMemberInfo info;
    const char* name = archive_entry_pathname(entry);
    info.path = name != nullptr ? name : "";
    info.size = archive_entry_size(entry);
    // The bytes libarchive has consumed: the header and any pax / GNU long-name record.
    info.data_offset = archive_filter_bytes(a, 0);
    info.mtime = archive_entry_mtime(entry);
    info.uid = archive_entry_uid(entry);
    info.gid = archive_entry_gid(entry);
    info.mode = static_cast<int>(archive_entry_perm(entry));
    // A hard link entry is a regular file to libarchive, with no data of its own.
    info.regular_file =
        archive_entry_filetype(entry) == AE_IFREG && archive_entry_hardlink(entry) == nullptr;
    info.sparse = archive_entry_sparse_count(entry) > 0;
    const std::string where = tar_path + ": " + info.path;
    if (info.size < 0) throw InputError(where, "negative member size");
    if (info.size > file_bytes - info.data_offset) {  // before allocating the member's buffer
      throw InputError(where, "member of " + std::to_string(info.size) + " bytes at byte " +
                                  std::to_string(info.data_offset) +
                                  " runs past the end of the file (" + std::to_string(file_bytes) +
                                  " bytes: truncated)");
    }
    next_header = info.data_offset + (info.size + 511) / 512 * 512;
    last_member = info.path;
    if (read_data) {
      data.resize(static_cast<size_t>(info.size));
      size_t done = 0;
      while (done < data.size()) {
        const la_ssize_t n = archive_read_data(a, data.data() + done, data.size() - done);
        if (n < 0) throw InputError(where, "cannot read data: " + ArchiveMessage(a));
        if (n == 0) throw InputError(where, "truncated member data");
        done += static_cast<size_t>(n);
      }
    }
    visit(info, read_data ? std::string_view(data) : std::string_view());
  }
  // libarchive takes an archive that just stops after a member as ended; a tar ends with
  // zero blocks (occgt writes two), so one that has none was cut at a member boundary.
  if (archive_filter_bytes(a, 0) < next_header + 512) {
    throw InputError(tar_path, "ends at byte " + std::to_string(next_header) +
                                   (last_member.empty() ? "" : ", after member " + last_member) +
                                   ", without the zero end-of-archive blocks (truncated)");
  }
}

}  // namespace

void ForEachTarMember(
    const std::string& tar_path,
    const std::function<void(const TarMemberInfo&, std::string_view data)>& visit) {
  ReadTar(tar_path, true, size_t{1} << 16, visit);
}

void ForEachTarHeader(const std::string& tar_path,
                      const std::function<void(const TarMemberInfo&)>& visit) {
  ReadTar(tar_path, false, 512,
          [&](const TarMemberInfo& info, std::string_view /*data*/) { visit(info); });
}

std::vector<ShardSampleRange> ListShardSamples(const std::string& tar_path) {
  std::vector<ShardSampleRange> samples;
  std::unordered_set<std::string> seen;
  std::string key, field;
  ForEachTarHeader(tar_path, [&](const TarMemberInfo& info) {
    if (!info.regular_file || !SplitMemberPath(info.path, &key, &field)) return;
    const size_t slash = key.rfind('/');
    if (key.compare(slash == std::string::npos ? 0 : slash + 1, 2, "__") == 0) return;
    const std::string where = tar_path + ": " + info.path;
    if (info.sparse) throw InputError(where, "sparse member (shard members are plain files)");
    if (samples.empty() || samples.back().key != key) {
      if (!seen.insert(key).second) {
        throw InputError(where, "members of sample " + key + " are not consecutive");
      }
      samples.push_back(ShardSampleRange{key, info.data_offset, 0, {}});
    }
    ShardSampleRange& sample = samples.back();
    for (const ShardMemberRange& m : sample.members) {
      if (m.field == field) {
        throw InputError(where, "sample " + key + " has two " + field + " members");
      }
    }
    sample.members.push_back(ShardMemberRange{field, info.data_offset - sample.start, info.size});
    sample.length = info.data_offset + info.size - sample.start;
  });
  return samples;
}

std::vector<Sample> ReadShardSamples(const std::string& tar_path) {
  std::vector<Sample> samples;
  ForEachTarMember(tar_path, [&](const TarMemberInfo& info, std::string_view data) {
    std::string key, field;
    if (!SplitMemberPath(info.path, &key, &field)) {
      throw InputError(tar_path + ": " + info.path, "member name has no '.<field>' suffix");
    }
    if (samples.empty() || samples.back().key != key) samples.push_back(Sample{key, {}});
    std::string bytes = DecodeMember(&field, data, tar_path + ": " + info.path);
    samples.back().fields.push_back(SampleField{field, std::move(bytes)});
  });
  return samples;
}

Sample ReadShardSample(const std::string& tar_path, const std::string& key) {
  Sample out{key, {}};
  ForEachTarMember(tar_path, [&](const TarMemberInfo& info, std::string_view data) {
    std::string k, field;
    if (SplitMemberPath(info.path, &k, &field) && k == key) {
      std::string bytes = DecodeMember(&field, data, tar_path + ": " + info.path);
      out.fields.push_back(SampleField{field, std::move(bytes)});
    }
  });
  if (out.fields.empty()) throw InputError(tar_path, "no sample " + key);
  return out;
}

}  // namespace gt::shards

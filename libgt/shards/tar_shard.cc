#include "libgt/shards/tar_shard.h"

#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <utility>

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

void ForEachTarMember(
    const std::string& tar_path,
    const std::function<void(const TarMemberInfo&, std::string_view data)>& visit) {
  std::unique_ptr<archive, ArchiveReadDeleter> ar(archive_read_new());
  archive* a = ar.get();
  archive_read_support_format_tar(a);
  if (archive_read_open_filename(a, tar_path.c_str(), 1 << 16) != ARCHIVE_OK) {
    throw InputError(tar_path, "cannot open as a tar archive: " + ArchiveMessage(a));
  }
  struct stat archive_st {};
  const int64_t archive_bytes =
      ::stat(tar_path.c_str(), &archive_st) == 0 ? static_cast<int64_t>(archive_st.st_size) : 0;
  std::string data;
  std::string last_member = "(start)";
  while (true) {
    archive_entry* entry = nullptr;
    const int r = archive_read_next_header(a, &entry);
    if (r == ARCHIVE_EOF) break;
    if (r != ARCHIVE_OK) {
      throw InputError(tar_path,
                       "bad tar header after member " + last_member + ": " + ArchiveMessage(a));
    }
    TarMemberInfo info;
    const char* name = archive_entry_pathname(entry);
    info.path = name != nullptr ? name : "";
    last_member = info.path;
    info.size = archive_entry_size(entry);
    info.data_offset = archive_read_header_position(a) + 512;
    info.mtime = archive_entry_mtime(entry);
    info.uid = archive_entry_uid(entry);
    info.gid = archive_entry_gid(entry);
    info.mode = static_cast<int>(archive_entry_perm(entry));
    info.regular_file = archive_entry_filetype(entry) == AE_IFREG;
    if (info.size < 0) throw InputError(tar_path + ": " + info.path, "negative member size");
    if (info.size > archive_bytes) {  // checked before allocating the member's buffer
      throw InputError(tar_path + ": " + info.path, "member size " + std::to_string(info.size) +
                                                        " exceeds the archive's " +
                                                        std::to_string(archive_bytes) + " bytes");
    }
    data.resize(static_cast<size_t>(info.size));
    size_t done = 0;
    while (done < data.size()) {
      const la_ssize_t n = archive_read_data(a, data.data() + done, data.size() - done);
      if (n < 0) {
        throw InputError(tar_path + ": " + info.path, "cannot read data: " + ArchiveMessage(a));
      }
      if (n == 0) throw InputError(tar_path + ": " + info.path, "truncated member data");
      done += static_cast<size_t>(n);
    }
    visit(info, std::string_view(data));
  }
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

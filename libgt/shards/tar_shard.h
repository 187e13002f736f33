// Deterministic WebDataset tar shards, written and read with libarchive (SHARDS.md).
//
// Format: POSIX ustar, one regular-file member per sample field, named "<key>.<field>",
// in the order the samples and their fields are given (files of one sample contiguous).
// Every header has mode 0644, mtime 0, uid/gid 0 and empty uname/gname, and the archive
// ends right after the two zero end blocks (the archive is written unblocked: libarchive's
// bytes_per_block = 0), so the file size is a multiple of 512, not of 10240. Same samples
// in, same bytes out.
// Member data starts on a 512-byte boundary; .npy fields whose header pads the data to a
// multiple of 64 bytes (gt::io::EncodeNpy does) therefore have 64-byte aligned array data
// inside the uncompressed shard.
//
// Publication is atomic: data goes to "<path>.tmp"; Finish() fsyncs and renames it onto
// <path>. A writer destroyed without Finish(), or one whose write failed, removes the
// temporary file, so a reader never sees a partial shard. Errors (disk full, bad key,
// over-long member path) throw gt::InputError naming the shard and the member.
// A writer starts no thread or task of its own and is used by one thread at a time;
// writers of different shards may run on different threads.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/shards/sample.h"

namespace gt::shards {

// What a finished shard is, as index.json lists it.
struct ShardInfo {
  std::string path;      // file written (as given to the writer)
  int64_t nsamples = 0;  // samples (keys) in the shard
  std::string md5sum;    // lower-case hex MD5 of the whole file
  int64_t filesize = 0;  // bytes
};

class TarShardWriter {
 public:
  // Opens "<path>.tmp" for writing (creating missing parent folders); throws InputError
  // naming the shard when it cannot.
  explicit TarShardWriter(std::string path);
  ~TarShardWriter();  // without Finish(): closes and removes "<path>.tmp"
  TarShardWriter(const TarShardWriter&) = delete;
  TarShardWriter& operator=(const TarShardWriter&) = delete;

  // Appends the sample's fields in order: each member is written and then MD5-digested,
  // in that order, on the calling thread. Throws InputError("<path>: <key>...") when the
  // sample fails CheckSample, when a key repeats within the shard, or when the write
  // fails; after a throw the writer is dead (further calls throw) and nothing is published.
  void Add(const Sample& sample);
  // The same, taking the sample: its buffers are released when Add returns (same bytes).
  void Add(Sample&& sample);
  // Closes the archive, fsyncs, renames onto the final path; returns its size and the MD5
  // of the bytes written (computed while writing, not by reading the file back).
  ShardInfo Finish();

  int64_t num_samples() const;
  int64_t bytes_written() const;  // tar bytes so far (headers + padded data)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Header fields of one tar member as read back.
struct TarMemberInfo {
  std::string path;         // member path
  int64_t size = 0;         // data bytes
  int64_t data_offset = 0;  // offset of the data in the tar file (multiple of 512; after any
                            // pax / GNU long-name record of the member)
  int64_t mtime = 0;
  int64_t uid = 0, gid = 0;
  int mode = 0;  // permission bits, e.g. 0644
  bool regular_file = false;
  bool sparse = false;  // a GNU / pax sparse member: its bytes in the file are not its data
};

// Calls `visit` for every member in file order with its header and data (libarchive).
// Throws InputError naming the tar and what was expected when it cannot be read: a header
// libarchive refuses is "<tar>: tar header at byte <n> (after member <m>): <why>" (checksum
// mismatch, the file ends inside it, ...: said from the block, libarchive's words follow),
// a member whose data runs past the end of the file "<tar>: <member>: ...", an archive that
// ends without a zero end block "<tar>: ends at byte <n>, ..." (cut at a member boundary).
void ForEachTarMember(
    const std::string& tar_path,
    const std::function<void(const TarMemberInfo&, std::string_view data)>& visit);
// The same reading, header by header, without reading the data (libarchive skips it with a
// seek): for an index of where the members are (ListShardSamples). The same errors.
void ForEachTarHeader(const std::string& tar_path,
                      const std::function<void(const TarMemberInfo&)>& visit);

// Where a sample's members are in its shard file, for random access without reading the
// shard (occgt.torch.ShardDataset reads a sample with one pread of [start, start + length)).
struct ShardMemberRange {
  std::string field;   // "label01.npy", "label01.npy.gz", "json", ...
  int64_t offset = 0;  // of the member's data, from the sample's start
  int64_t size = 0;    // data bytes
};
struct ShardSampleRange {
  std::string key;
  int64_t start = 0;   // offset of the first member's data in the file
  int64_t length = 0;  // bytes from start to the end of the last member's data (the headers
                       // of the members in between included)
  std::vector<ShardMemberRange> members;  // in file order
};
// The samples of a shard from one pass over its headers (ForEachTarHeader: the data is not
// read), grouped the WebDataset way: the regular-file members, each split by
// SplitMemberPath; members without a dot in the basename, or whose basename starts with
// "__" (__meta__.json), are not sample members and are left out; consecutive members with
// the same key form one sample. Throws ForEachTarHeader's InputErrors, and
// InputError("<tar>: <member>", ...) for a sparse member, for a sample whose members are
// not consecutive and for a field that repeats within a sample.
std::vector<ShardSampleRange> ListShardSamples(const std::string& tar_path);

// All samples of a shard, grouped by key the WebDataset way (consecutive members with the
// same key form one sample; fields in member order). Reads the whole shard into memory.
std::vector<Sample> ReadShardSamples(const std::string& tar_path);
// One sample by key; throws InputError("<tar>", "no sample <key>") when absent.
Sample ReadShardSample(const std::string& tar_path, const std::string& key);

}  // namespace gt::shards

// Tar shards: written with TarShardWriter, read back both with libarchive
// (ForEachTarMember) and with a small independent ustar parser below, which checks the
// raw header bytes (magic, modes, owners, mtime, checksums, offsets) that readers such as
// wids, DALI and Python's tarfile rely on.
#include "libgt/shards/tar_shard.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/gzip.h"
#include "libgt/io/md5.h"
#include "libgt/io/npy.h"
#include "libgt/shards/sample.h"
#include "tests/support/test_support.h"

namespace gt::shards {
namespace {

namespace fs = std::filesystem;

// ---- reference ustar parser (POSIX.1-1988 header layout) ------------------------------
struct RawMember {
  std::string name;
  int64_t size = 0;
  int64_t header_offset = 0;
  int64_t data_offset = 0;
  std::string mode, uid, gid, mtime, magic, version, uname, gname;
  char typeflag = 0;
  bool checksum_ok = false;
};

int64_t ParseOctal(const std::string& field) {
  int64_t v = 0;
  for (char c : field) {
    if (c == '\0' || c == ' ') break;
    EXPECT_TRUE(c >= '0' && c <= '7') << "non-octal digit in " << field;
    v = v * 8 + (c - '0');
  }
  return v;
}

std::string Field(const std::string& block, size_t off, size_t len) {
  std::string s = block.substr(off, len);
  const size_t nul = s.find('\0');
  return nul == std::string::npos ? s : s.substr(0, nul);
}

// Parses all members; sets *end_offset to the offset of the first zero block.
std::vector<RawMember> ParseUstar(const std::string& tar, int64_t* end_offset) {
  std::vector<RawMember> members;
  size_t off = 0;
  while (off + 512 <= tar.size()) {
    const std::string block = tar.substr(off, 512);
    if (block == std::string(512, '\0')) break;
    RawMember m;
    m.header_offset = static_cast<int64_t>(off);
    m.name = Field(block, 0, 100);
    m.mode = Field(block, 100, 8);
    m.uid = Field(block, 108, 8);
    m.gid = Field(block, 116, 8);
    m.size = ParseOctal(Field(block, 124, 12));
    m.mtime = Field(block, 136, 12);
    m.typeflag = block[156];
    m.magic = block.substr(257, 6);
    m.version = block.substr(263, 2);
    m.uname = Field(block, 265, 32);
    m.gname = Field(block, 297, 32);
    int64_t sum = 0;
    for (size_t i = 0; i < 512; ++i) {
      sum += (i >= 148 && i < 156) ? ' ' : static_cast<unsigned char>(block[i]);
    }
    m.checksum_ok = sum == ParseOctal(Field(block, 148, 8));
    m.data_offset = static_cast<int64_t>(off) + 512;
    members.push_back(m);
    off += 512 + static_cast<size_t>((m.size + 511) / 512 * 512);
  }
  *end_offset = static_cast<int64_t>(off);
  return members;
}

// A hand-made ustar member (header + data + padding), for archives the writer refuses to
// make (a repeated key or field, other member types).
std::string UstarMember(const std::string& name, const std::string& data, char type = '0',
                        const std::string& link = "") {
  std::string h(512, '\0');
  h.replace(0, name.size(), name);
  h.replace(157, link.size(), link);
  h.replace(100, 7, "0000644");
  h.replace(108, 7, "0000000");
  h.replace(116, 7, "0000000");
  char field[16];
  std::snprintf(field, sizeof(field), "%011llo", static_cast<unsigned long long>(data.size()));
  h.replace(124, 11, field);
  h.replace(136, 11, "00000000000");
  h.replace(148, 8, "        ");
  h[156] = type;
  h.replace(257, 6, std::string("ustar\0", 6));
  h.replace(263, 2, "00");
  unsigned sum = 0;
  for (char c : h) sum += static_cast<unsigned char>(c);
  std::snprintf(field, sizeof(field), "%06o", sum);
  h.replace(148, 7, std::string(field, 6) + '\0');
  return h + data + std::string((512 - data.size() % 512) % 512, '\0');
}

// The error message of f(), which must throw an InputError.
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

// ---- sample fixtures ---------------------------------------------------------------------
Sample MakeSample(const std::string& key, int seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> labels(37 * 23);
  for (auto& v : labels) v = static_cast<uint8_t>(rng() % 6);
  std::vector<float> depth(13 * 7);
  for (auto& v : depth) v = static_cast<float>(rng() % 1000) / 100.0f;
  Sample s;
  s.key = key;
  s.fields.push_back({"json", "{\"seed\": " + std::to_string(seed) + "}"});
  s.fields.push_back({"label01.npy", io::EncodeNpy<uint8_t>({37, 23}, labels)});
  s.fields.push_back({"depth0.npy", io::EncodeNpy<float>({13, 7}, depth)});
  s.fields.push_back({"txt", std::string(static_cast<size_t>(seed % 700), 'x')});
  return s;
}

std::vector<Sample> MakeSamples() {
  return {MakeSample("scene0707_00/000015_000585", 1), MakeSample("scene0707_00/000045_000105", 2),
          MakeSample("hospital/Easy/P036/000010_000020", 3)};
}

ShardInfo WriteShard(const std::string& path, const std::vector<Sample>& samples) {
  TarShardWriter writer(path);
  for (const auto& s : samples) writer.Add(s);
  return writer.Finish();
}

TEST(TarShard, LargeMembersReadBackIntactAndTheDigestIsTheFiles) {
  // Members of several MiB reach the writer's write callback in one piece (unblocked
  // archive): the MD5 computed while writing must be that of the published bytes, and
  // the members must read back intact, whatever their size mod 512.
  const std::string dir = test::ScratchDir("shards_tar_large");
  std::mt19937 rng(7);
  std::vector<Sample> samples;
  for (int k = 0; k < 3; ++k) {
    Sample s;
    s.key = "scene/large_" + std::to_string(k);
    for (const size_t n : {size_t{256} << 10, (size_t{256} << 10) - 1, size_t{1} << 20,
                           (size_t{3} << 20) + 333, size_t{77}}) {
      std::string bytes(n + static_cast<size_t>(k), '\0');
      for (char& c : bytes) c = static_cast<char>(rng());
      s.fields.push_back({"f" + std::to_string(s.fields.size()) + ".bin", std::move(bytes)});
    }
    samples.push_back(std::move(s));
  }
  const std::string path = dir + "/large-000000.tar";
  const ShardInfo info = WriteShard(path, samples);
  const std::string tar = io::ReadFileBytes(path);
  EXPECT_EQ(info.filesize, static_cast<int64_t>(tar.size()));
  EXPECT_EQ(info.md5sum, io::Md5Hex(tar));
  const std::vector<Sample> back = ReadShardSamples(path);
  ASSERT_EQ(back.size(), samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    ASSERT_EQ(back[k].fields.size(), samples[k].fields.size());
    for (size_t f = 0; f < samples[k].fields.size(); ++f) {
      EXPECT_TRUE(back[k].fields[f].bytes == samples[k].fields[f].bytes) << k << " " << f;
    }
  }
}

// "<path>.tmp" is a symlink to /dev/full, so every write(2) fails with ENOSPC: `add` and
// Finish must throw an InputError naming the shard, and nothing may be left published.
void ExpectDiskFullFailsAndPublishesNothing(const std::string& path,
                                            const std::function<void(TarShardWriter&)>& add) {
  ASSERT_TRUE(fs::exists("/dev/full"));
  fs::create_symlink("/dev/full", path + ".tmp");
  bool threw = false;
  try {
    TarShardWriter writer(path);
    add(writer);
    writer.Finish();
  } catch (const InputError& e) {
    threw = true;
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_TRUE(threw);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::is_symlink(path + ".tmp"));
}

// Samples with small and large members (up to 1 MiB + 4097 bytes, past the writeback step).
std::vector<Sample> LargeSamples(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Sample> samples;
  for (int k = 0; k < count; ++k) {
    Sample s;
    s.key = "scene/large_sample_" + std::to_string(k);
    s.fields.push_back({"json", "{\"k\": " + std::to_string(k) + "}"});
    for (const size_t n : {size_t{256} << 10, size_t{5}, (size_t{1} << 20) + 4097,
                           static_cast<size_t>(rng() % 3000)}) {
      std::string bytes(n, '\0');
      for (char& c : bytes) c = static_cast<char>(rng());
      s.fields.push_back({"f" + std::to_string(s.fields.size()) + ".bin", std::move(bytes)});
    }
    samples.push_back(std::move(s));
  }
  return samples;
}

TEST(TarShard, MovedAndCopiedSamplesGiveTheSameBytesAndMd5) {
  // Add(const Sample&) and Add(Sample&&), in any mix: the file and its MD5 must not depend
  // on which samples were handed over.
  const std::string dir = test::ScratchDir("shards_tar_moved");
  const std::vector<Sample> samples = LargeSamples(4, 11);
  const ShardInfo plain = WriteShard(dir + "/plain-000000.tar", samples);
  const std::string plain_bytes = io::ReadFileBytes(dir + "/plain-000000.tar");
  ASSERT_EQ(plain.md5sum, io::Md5Hex(plain_bytes));
  const std::vector<std::vector<int>> patterns = {
      {1, 1, 1, 1},  // every sample moved
      {0, 0, 0, 1},  // only the last
      {0, 1, 0, 1},  // alternating
  };
  for (size_t t = 0; t < patterns.size(); ++t) {
    const std::string path = dir + "/mixed" + std::to_string(t) + "-000000.tar";
    TarShardWriter writer(path);
    for (size_t k = 0; k < samples.size(); ++k) {
      Sample copy = samples[k];
      if (patterns[t][k] == 1) {
        writer.Add(std::move(copy));
      } else {
        writer.Add(copy);
      }
    }
    const ShardInfo info = writer.Finish();
    const std::string bytes = io::ReadFileBytes(path);
    EXPECT_TRUE(bytes == plain_bytes) << "pattern " << t;
    EXPECT_EQ(info.md5sum, plain.md5sum) << "pattern " << t;
    EXPECT_EQ(info.md5sum, io::Md5Hex(bytes)) << "pattern " << t;
    EXPECT_EQ(info.filesize, plain.filesize);
    EXPECT_EQ(info.nsamples, 4);
  }
}

TEST(TarShard, MovedSampleOfAnAbandonedOrFailedShardLeavesNothing) {
  const std::string dir = test::ScratchDir("shards_tar_moved_fail");
  {
    TarShardWriter writer(dir + "/a-000000.tar");
    writer.Add(std::move(LargeSamples(1, 3)[0]));
    EXPECT_TRUE(fs::exists(dir + "/a-000000.tar.tmp"));
  }
  EXPECT_TRUE(fs::is_empty(dir));
  // Every write(2) fails (ENOSPC): Add or Finish throws naming the shard.
  ExpectDiskFullFailsAndPublishesNothing(dir + "/b-000000.tar", [](TarShardWriter& writer) {
    writer.Add(std::move(LargeSamples(1, 4)[0]));
  });
}

TEST(TarShard, HeadersOrderAndSizesMatchTheSamples) {
  const std::string dir = test::ScratchDir("shards_tar_headers");
  const std::string path = dir + "/train-000000.tar";
  const auto samples = MakeSamples();
  const ShardInfo info = WriteShard(path, samples);
  EXPECT_EQ(info.nsamples, 3);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  const std::string tar = io::ReadFileBytes(path);
  EXPECT_EQ(info.filesize, static_cast<int64_t>(tar.size()));
  EXPECT_EQ(info.md5sum, io::Md5Hex(tar));

  std::vector<std::string> expected_names;
  int64_t expected_size = 0;
  for (const auto& s : samples) {
    for (const auto& f : s.fields) {
      expected_names.push_back(s.key + "." + f.name);
      expected_size += 512 + (static_cast<int64_t>(f.bytes.size()) + 511) / 512 * 512;
    }
  }
  expected_size += 1024;  // two zero end blocks, no padding to 10240 (unblocked archive)
  EXPECT_EQ(static_cast<int64_t>(tar.size()), expected_size);
  EXPECT_EQ(tar.size() % 512, 0u);
  EXPECT_NE(tar.size() % 10240, 0u);

  int64_t end = 0;
  const auto raw = ParseUstar(tar, &end);
  ASSERT_EQ(raw.size(), expected_names.size());
  EXPECT_EQ(std::string(tar.begin() + end, tar.end()), std::string(1024, '\0'));
  size_t i = 0;
  for (const auto& s : samples) {
    for (const auto& f : s.fields) {
      const RawMember& m = raw[i];
      EXPECT_EQ(m.name, expected_names[i]);
      EXPECT_EQ(m.size, static_cast<int64_t>(f.bytes.size()));
      EXPECT_EQ(tar.substr(static_cast<size_t>(m.data_offset), f.bytes.size()), f.bytes);
      EXPECT_EQ(m.magic, std::string("ustar\0", 6));
      EXPECT_EQ(m.version, "00");
      EXPECT_EQ(m.typeflag, '0');
      EXPECT_EQ(ParseOctal(m.mode), 0644);
      EXPECT_EQ(ParseOctal(m.uid), 0);
      EXPECT_EQ(ParseOctal(m.gid), 0);
      EXPECT_EQ(ParseOctal(m.mtime), 0);
      EXPECT_EQ(m.uname, "");
      EXPECT_EQ(m.gname, "");
      EXPECT_TRUE(m.checksum_ok) << m.name;
      ++i;
    }
  }

  // libarchive's view agrees.
  i = 0;
  ForEachTarMember(path, [&](const TarMemberInfo& info, std::string_view data) {
    ASSERT_LT(i, raw.size());
    EXPECT_EQ(info.path, raw[i].name);
    EXPECT_EQ(info.size, raw[i].size);
    EXPECT_EQ(info.data_offset, raw[i].data_offset);
    EXPECT_EQ(info.mtime, 0);
    EXPECT_EQ(info.uid, 0);
    EXPECT_EQ(info.gid, 0);
    EXPECT_EQ(info.mode, 0644);
    EXPECT_TRUE(info.regular_file);
    EXPECT_EQ(data, tar.substr(static_cast<size_t>(raw[i].data_offset),
                               static_cast<size_t>(raw[i].size)));
    ++i;
  });
  EXPECT_EQ(i, raw.size());

  // Grouped read-back gives the samples.
  const auto back = ReadShardSamples(path);
  ASSERT_EQ(back.size(), samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    EXPECT_EQ(back[k].key, samples[k].key);
    ASSERT_EQ(back[k].fields.size(), samples[k].fields.size());
    for (size_t f = 0; f < samples[k].fields.size(); ++f) {
      EXPECT_EQ(back[k].fields[f].name, samples[k].fields[f].name);
      EXPECT_EQ(back[k].fields[f].bytes, samples[k].fields[f].bytes);
    }
  }
  EXPECT_EQ(ReadShardSample(path, samples[1].key).fields[2].bytes, samples[1].fields[2].bytes);
  EXPECT_THROW(ReadShardSample(path, "scene0707_00/nothere"), InputError);
}

TEST(TarShard, IdenticalInputGivesIdenticalBytes) {
  const std::string dir = test::ScratchDir("shards_tar_determinism");
  const ShardInfo a = WriteShard(dir + "/a/train-000000.tar", MakeSamples());
  const ShardInfo b = WriteShard(dir + "/b/train-000000.tar", MakeSamples());
  EXPECT_EQ(io::ReadFileBytes(a.path), io::ReadFileBytes(b.path));
  EXPECT_EQ(a.md5sum, b.md5sum);
  auto changed = MakeSamples();
  changed[2].fields[0].bytes = "{\"seed\": 4}";
  const ShardInfo c = WriteShard(dir + "/c/train-000000.tar", changed);
  EXPECT_NE(a.md5sum, c.md5sum);
}

TEST(TarShard, NpyArrayDataIs64ByteAlignedInsideTheTar) {
  const std::string dir = test::ScratchDir("shards_tar_alignment");
  // Members of many different sizes so that data offsets take many values mod 512.
  std::vector<Sample> samples;
  std::mt19937 rng(7);
  for (int k = 0; k < 40; ++k) {
    Sample s;
    s.key = "s/" + std::to_string(1000 + k);
    const int64_t n = 1 + static_cast<int64_t>(rng() % 3000);
    s.fields.push_back({"a.npy", io::EncodeNpy<uint8_t>({n}, std::vector<uint8_t>(n, 1))});
    s.fields.push_back({"json", std::string(rng() % 900, ' ')});
    s.fields.push_back({"b.npy", io::EncodeNpy<double>({n, 3}, std::vector<double>(n * 3, 0.5))});
    samples.push_back(s);
  }
  const ShardInfo info = WriteShard(dir + "/x-000000.tar", samples);
  const std::string tar = io::ReadFileBytes(info.path);
  int64_t end = 0;
  int checked = 0;
  for (const RawMember& m : ParseUstar(tar, &end)) {
    EXPECT_EQ(m.data_offset % 512, 0);
    if (m.name.size() < 4 || m.name.substr(m.name.size() - 4) != ".npy") continue;
    const std::string head = tar.substr(static_cast<size_t>(m.data_offset), 10);
    ASSERT_EQ(head.substr(0, 6), "\x93NUMPY");
    ASSERT_EQ(head[6], '\x01');
    const int header_len =
        static_cast<unsigned char>(head[8]) | (static_cast<unsigned char>(head[9]) << 8);
    const int64_t array_offset = m.data_offset + 10 + header_len;
    EXPECT_EQ(array_offset % 64, 0) << m.name;
    ++checked;
  }
  EXPECT_EQ(checked, 80);
}

TEST(SampleKey, RejectsUnsafeKeys) {
  EXPECT_EQ(CheckSampleKey("scene0707_00/000015_000585"), "");
  EXPECT_EQ(CheckSampleKey("a/b-c/d_e"), "");
  for (const std::string& bad :
       {std::string(""), std::string("../x"), std::string("a/../b"), std::string("/abs/key"),
        std::string("a//b"), std::string("a/./b"), std::string("a/b.c"), std::string("ab.c"),
        std::string("a/\x01x"), std::string("tab\tkey"), std::string("caf\xc3\xa9"),
        std::string("a/__meta__"), std::string("a\\b"), std::string(99, 'k')}) {
    EXPECT_NE(CheckSampleKey(bad), "") << "accepted: " << bad;
  }
  // A dot in a folder component is allowed (only the basename is split at a dot).
  EXPECT_EQ(CheckSampleKey("v1.2/abc"), "");
  EXPECT_EQ(CheckFieldName("label01.npy"), "");
  EXPECT_NE(CheckFieldName("Label.npy"), "");
  EXPECT_NE(CheckFieldName("npy."), "");
  EXPECT_NE(CheckFieldName(".npy"), "");
  // Member path length is checked with the field: 95 + ".json" = 100 ok, 101 not.
  Sample ok{std::string(95, 'k'), {{"json", "{}"}}};
  EXPECT_EQ(CheckSample(ok), "");
  Sample too_long{std::string(95, 'k'), {{"jsonx", "{}"}}};
  EXPECT_NE(CheckSample(too_long), "");
  Sample duplicate{"k", {{"json", "{}"}, {"json", "{}"}}};
  EXPECT_NE(CheckSample(duplicate), "");
}

TEST(SampleKey, SanitisingGivesValidDeterministicKeys) {
  EXPECT_EQ(MakeSampleKey("scene0707_00", "000015", "000585"), "scene0707_00/000015_000585");
  EXPECT_EQ(MakeSampleKey("hospital/Easy/P036", "000010", "000020"),
            "hospital/Easy/P036/000010_000020");
  EXPECT_EQ(MakeSampleKey("seq.01", "frame-1.a", "2"), "seq_01/frame-1_a_2");
  EXPECT_EQ(MakeSampleKey("/../a/./b/", "1", "2"), "a/b/1_2");
  EXPECT_EQ(SanitizeKeyComponent("__x"), "x__x");
  EXPECT_EQ(SanitizeKeyComponent(""), "x");
  // Property: sanitised keys of random byte strings always pass CheckSampleKey (or are
  // rejected only for length), and sanitising is idempotent.
  std::mt19937 rng(11);
  for (int t = 0; t < 2000; ++t) {
    std::string scene(rng() % 30, ' ');
    for (char& c : scene) c = static_cast<char>(rng() % 256);
    std::string f0(rng() % 8, ' ');
    for (char& c : f0) c = static_cast<char>(rng() % 256);
    const std::string key = MakeSampleKey(scene, f0, "7");
    EXPECT_EQ(CheckSampleKey(key), "") << key;
    EXPECT_EQ(SanitizeScenePath(SanitizeScenePath(scene)), SanitizeScenePath(scene));
  }
  EXPECT_THROW(MakeSampleKey(std::string(120, 's'), "1", "2"), InputError);
}

TEST(TarShard, BadSampleThrowsNamingShardAndKeyAndPublishesNothing) {
  const std::string dir = test::ScratchDir("shards_tar_bad_key");
  const std::string path = dir + "/train-000000.tar";
  for (const std::string& bad : std::vector<std::string>{"../escape", "/abs", "a/b.c", "ctl\x07"}) {
    TarShardWriter writer(path);
    writer.Add(MakeSample("good/1_2", 1));
    try {
      writer.Add(Sample{bad, {{"json", "{}"}}});
      ADD_FAILURE() << "accepted key " << bad;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(bad.substr(0, 3)), std::string::npos) << what;
    }
    EXPECT_THROW(writer.Add(MakeSample("good/3_4", 2)), InputError);  // writer is dead
    EXPECT_THROW(writer.Finish(), InputError);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_FALSE(fs::exists(path + ".tmp"));
  }
  TarShardWriter writer(path);
  writer.Add(MakeSample("k/1_2", 1));
  EXPECT_THROW(writer.Add(MakeSample("k/1_2", 1)), InputError);  // key repeats
  EXPECT_FALSE(fs::exists(path));
}

TEST(TarShard, DestroyedWithoutFinishLeavesNothing) {
  const std::string dir = test::ScratchDir("shards_tar_no_finish");
  const std::string path = dir + "/train-000003.tar";
  {
    TarShardWriter writer(path);
    for (int k = 0; k < 20; ++k) writer.Add(MakeSample("s/" + std::to_string(k), k));
    EXPECT_TRUE(fs::exists(path + ".tmp"));
    EXPECT_GT(writer.bytes_written(), 0);
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(TarShard, DiskFullFailsLoudlyAndPublishesNothing) {
  // "<shard>.tmp" is a symlink to /dev/full: every write(2) fails with ENOSPC.
  ASSERT_TRUE(fs::exists("/dev/full"));
  const std::string dir = test::ScratchDir("shards_tar_disk_full");
  ExpectDiskFullFailsAndPublishesNothing(dir + "/train-000000.tar", [](TarShardWriter& writer) {
    // More than one 10240-byte block so that libarchive flushes inside Add().
    for (int k = 0; k < 50; ++k) writer.Add(MakeSample("s/" + std::to_string(k), k));
  });

  // Same with a file-size limit in a child process (SIGXFSZ ignored -> EFBIG).
  const std::string path2 = dir + "/train-000001.tar";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    signal(SIGXFSZ, SIG_IGN);
    rlimit limit{20000, 20000};
    setrlimit(RLIMIT_FSIZE, &limit);
    int code = 3;
    try {
      TarShardWriter writer(path2);
      for (int k = 0; k < 50; ++k) writer.Add(MakeSample("s/" + std::to_string(k), k));
      writer.Finish();
      code = 2;  // should not succeed
    } catch (const InputError& e) {
      code = std::string(e.what()).find(path2) != std::string::npos ? 0 : 4;
    }
    _exit(code);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_FALSE(fs::exists(path2));
  EXPECT_FALSE(fs::exists(path2 + ".tmp"));
}

TEST(TarShard, TruncatedOrGarbageTarIsAnInputErrorNamingIt) {
  const std::string dir = test::ScratchDir("shards_tar_truncated");
  const ShardInfo info = WriteShard(dir + "/t-000000.tar", MakeSamples());
  const std::string tar = io::ReadFileBytes(info.path);
  const std::string cut = dir + "/cut.tar";
  io::WriteFileAtomic(cut, tar.substr(0, 512 + 100));
  EXPECT_THROW(ReadShardSamples(cut), InputError);
  const std::string garbage = dir + "/garbage.tar";
  io::WriteFileAtomic(garbage, std::string(4096, 'g'));
  try {
    ReadShardSamples(garbage);
    ADD_FAILURE() << "garbage accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(garbage), std::string::npos);
  }
}

TEST(TarShard, MemberSizeBeyondTheArchiveFailsBeforeAllocating) {
  // A header claiming an 8 GiB member (valid checksum) in a small file: one InputError
  // naming the member, not an 8 GiB allocation.
  const std::string dir = test::ScratchDir("shards_tar_huge_member");
  const ShardInfo info = WriteShard(dir + "/t-000000.tar", MakeSamples());
  std::string tar = io::ReadFileBytes(info.path);
  const std::string size_field = "77777777777";
  tar.replace(124, 11, size_field);
  std::fill(tar.begin() + 148, tar.begin() + 156, ' ');
  unsigned sum = 0;
  for (int i = 0; i < 512; ++i) sum += static_cast<unsigned char>(tar[i]);
  char checksum[8];
  std::snprintf(checksum, sizeof(checksum), "%06o", sum);
  tar.replace(148, 7, std::string(checksum, 6) + '\0');
  const std::string huge = dir + "/huge.tar";
  io::WriteFileAtomic(huge, tar);
  try {
    ReadShardSamples(huge);
    ADD_FAILURE() << "huge member accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(huge), std::string::npos) << e.what();
  }
}

// ListShardSamples (occgt.torch.ShardDataset's index): from the headers only, each
// sample's byte range and each member's offset and size are where the writer put them
// (checked against the independent parser and the bytes), in both small and multi-MiB
// members (seeked past, not read).
TEST(TarShard, ListShardSamplesGivesTheOffsetsAndSizesTheWriterWrote) {
  const std::string dir = test::ScratchDir("shards_tar_list");
  for (const auto& samples : {MakeSamples(), LargeSamples(3, 5)}) {
    const std::string path = dir + "/list-" + std::to_string(samples.size()) + ".tar";
    WriteShard(path, samples);
    const std::string tar = io::ReadFileBytes(path);
    int64_t end = 0;
    const std::vector<RawMember> raw = ParseUstar(tar, &end);
    const std::vector<ShardSampleRange> listed = ListShardSamples(path);
    ASSERT_EQ(listed.size(), samples.size());
    size_t r = 0;
    for (size_t k = 0; k < samples.size(); ++k) {
      const ShardSampleRange& got = listed[k];
      EXPECT_EQ(got.key, samples[k].key);
      ASSERT_EQ(got.members.size(), samples[k].fields.size()) << got.key;
      EXPECT_EQ(got.start, raw[r].data_offset) << got.key;
      for (size_t f = 0; f < got.members.size(); ++f, ++r) {
        const ShardMemberRange& m = got.members[f];
        const SampleField& want = samples[k].fields[f];
        EXPECT_EQ(m.field, want.name);
        EXPECT_EQ(m.size, static_cast<int64_t>(want.bytes.size())) << m.field;
        EXPECT_EQ(got.start + m.offset, raw[r].data_offset) << m.field;
        EXPECT_TRUE(tar.compare(static_cast<size_t>(got.start + m.offset), want.bytes.size(),
                                want.bytes) == 0)
            << got.key << "." << m.field;
      }
      const ShardMemberRange& last = got.members.back();
      EXPECT_EQ(got.length, last.offset + last.size);
    }
    EXPECT_EQ(r, raw.size());
    // The header pass gives ForEachTarMember's headers.
    std::vector<int64_t> offsets, header_offsets;
    ForEachTarMember(path, [&](const TarMemberInfo& info, std::string_view) {
      offsets.push_back(info.data_offset);
    });
    ForEachTarHeader(path, [&](const TarMemberInfo& info) {
      header_offsets.push_back(info.data_offset);
      EXPECT_TRUE(info.regular_file);
      EXPECT_FALSE(info.sparse);
    });
    EXPECT_EQ(header_offsets, offsets);
  }
}

TEST(TarShard, ListShardSamplesGroupsByKeyAndSkipsNonSampleMembers) {
  const std::string dir = test::ScratchDir("shards_tar_list_grouping");
  const std::string end(1024, '\0');
  const std::string path = dir + "/g.tar";
  // A folder, a member without a dot, __meta__.json, then two samples; the first has a
  // hard and a symbolic link (not sample members: no data of their own).
  io::WriteFileAtomic(path, UstarMember("s/", "", '5') + UstarMember("s/README", "r") +
                                UstarMember("s/__meta__.json", "{}") +
                                UstarMember("s/a.json", "{1}") +
                                UstarMember("s/a.label01.npy.gz", std::string(600, 'l')) +
                                UstarMember("s/a.hard", "", '1', "s/a.json") +
                                UstarMember("s/a.soft", "", '2', "s/a.json") +
                                UstarMember("s/b.json", "{2}") + end);
  const std::vector<ShardSampleRange> listed = ListShardSamples(path);
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_EQ(listed[0].key, "s/a");
  ASSERT_EQ(listed[0].members.size(), 2u);
  EXPECT_EQ(listed[0].start, 512 + 2 * 1024 + 512);  // after 3 members and its header
  EXPECT_EQ(listed[0].members[0].field, "json");
  EXPECT_EQ(listed[0].members[0].offset, 0);
  EXPECT_EQ(listed[0].members[0].size, 3);
  EXPECT_EQ(listed[0].members[1].field, "label01.npy.gz");
  EXPECT_EQ(listed[0].members[1].offset, 1024);
  EXPECT_EQ(listed[0].members[1].size, 600);
  EXPECT_EQ(listed[0].length, 1024 + 600);
  EXPECT_EQ(listed[1].key, "s/b");
  EXPECT_EQ(listed[1].start, 3072 + 1024 + 1024 + 2 * 512 + 512);  // links: a header each

  const std::string split = dir + "/split.tar";  // sample s/a, then s/b, then s/a again
  io::WriteFileAtomic(split, UstarMember("s/a.json", "{}") + UstarMember("s/b.json", "{}") +
                                 UstarMember("s/a.txt", "x") + end);
  std::string e = ErrorOf([&] { ListShardSamples(split); });
  EXPECT_NE(e.find(split + ": s/a.txt: members of sample s/a are not consecutive"),
            std::string::npos)
      << e;
  const std::string twice = dir + "/twice.tar";
  io::WriteFileAtomic(twice, UstarMember("s/a.json", "{}") + UstarMember("s/a.json", "{}") + end);
  e = ErrorOf([&] { ListShardSamples(twice); });
  EXPECT_NE(e.find(twice + ": s/a.json: sample s/a has two json members"), std::string::npos) << e;
}

// A damaged or cut shard: one InputError naming the file and the header byte or the
// member, whether the data is read (ForEachTarMember) or only listed (ListShardSamples).
TEST(TarShard, BadOrTruncatedTarErrorsNameTheFileAndTheMember) {
  const std::string dir = test::ScratchDir("shards_tar_list_bad");
  const ShardInfo info = WriteShard(dir + "/t-000000.tar", MakeSamples());
  const std::string tar = io::ReadFileBytes(info.path);
  int64_t end = 0;
  const std::vector<RawMember> raw = ParseUstar(tar, &end);
  ASSERT_GE(raw.size(), 3u);
  const auto expect_both = [&](const std::string& name, const std::string& bytes,
                               const std::string& message) {
    const std::string path = dir + "/" + name + ".tar";
    io::WriteFileAtomic(path, bytes);
    for (const std::string& e :
         {ErrorOf([&] { ListShardSamples(path); }), ErrorOf([&] { ReadShardSamples(path); })}) {
      EXPECT_NE(e.find(path + ": " + message), std::string::npos)
          << name << ": " << e << "\n  expected: " << message;
    }
  };
  // Cut inside the second member's data.
  expect_both("cut_data", tar.substr(0, static_cast<size_t>(raw[1].data_offset + 100)),
              raw[1].name + ": member of " + std::to_string(raw[1].size) + " bytes at byte " +
                  std::to_string(raw[1].data_offset) + " runs past the end of the file");
  // Cut inside the third header, and at a member boundary (no end blocks).
  expect_both("cut_header", tar.substr(0, static_cast<size_t>(raw[2].header_offset + 100)),
              "tar header at byte " + std::to_string(raw[2].header_offset) + " (after member " +
                  raw[1].name + "): the file ends inside the 512-byte header");
  expect_both("cut_at_member", tar.substr(0, static_cast<size_t>(end)),
              "ends at byte " + std::to_string(end) + ", after member " + raw.back().name +
                  ", without the zero end-of-archive blocks");
  // A flipped byte in the name of the first and of the third header.
  for (const RawMember* m : {&raw[0], &raw[2]}) {
    std::string bad = tar;
    bad[static_cast<size_t>(m->header_offset) + 3] ^= 1;
    expect_both("checksum" + std::to_string(m->header_offset), bad,
                "tar header at byte " + std::to_string(m->header_offset) +
                    (m == &raw[0] ? "" : " (after member " + raw[1].name + ")") +
                    ": checksum mismatch");
  }
  expect_both("empty", "", "tar header at byte 0: the file ends inside the 512-byte header");
  EXPECT_NE(ErrorOf([&] {
              ListShardSamples(dir + "/none.tar");
            }).find(dir + "/none.tar: cannot open the tar archive"),
            std::string::npos);
}

// The one ".gz" rule of compressed members: PlainFieldName picks the field, DecodeMember
// strips the same suffix and inflates; other fields pass through unchanged.
TEST(TarShard, CompressedMemberNamesDecodeByOneRule) {
  EXPECT_EQ(PlainFieldName("label01.npy.gz"), "label01.npy");
  EXPECT_EQ(PlainFieldName("label01.npy"), "label01.npy");
  EXPECT_EQ(PlainFieldName("json"), "json");
  EXPECT_EQ(PlainFieldName(".gz"), ".gz");  // nothing left to name
  const std::string npy = io::EncodeNpy<uint8_t>({2, 3}, std::vector<uint8_t>{1, 2, 3, 4, 5, 6});
  std::string field = "cells0.npy.gz";
  EXPECT_EQ(DecodeMember(&field, io::GzipBytes(npy, 1), "m"), npy);
  EXPECT_EQ(field, std::string(PlainFieldName("cells0.npy.gz")));
  field = "cells0.npy";
  EXPECT_EQ(DecodeMember(&field, npy, "m"), npy);
  EXPECT_EQ(field, "cells0.npy");
  field = "cells0.npy.gz";
  EXPECT_THROW((void)DecodeMember(&field, npy, "m"), InputError);  // not gzip
  // A .npy is inflated only up to its header's size: 32 MiB behind a 6-byte array stop
  // there, while another field inflates to its end.
  const std::string tail(size_t{32} << 20, '\0');
  field = "cells0.npy.gz";
  try {
    (void)DecodeMember(&field, io::GzipBytes(npy + tail, 9), "s.tar:k.cells0.npy.gz");
    ADD_FAILURE() << "a .npy.gz running past its array was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.tar:k.cells0.npy.gz: gzip data inflates to more than " +
                                         std::to_string(npy.size()) + " bytes"),
              std::string::npos)
        << e.what();
  }
  field = "json.gz";
  EXPECT_EQ(DecodeMember(&field, io::GzipBytes("{}" + tail, 9), "m").size(), 2 + tail.size());
}

}  // namespace
}  // namespace gt::shards

// file_read.h, atomic_file.h, md5.h, text_parsing.h: MD5 against the RFC 1321 test suite
// and a slow bit-level check over random inputs of every length around the block boundaries,
// ParseNumbers tokens and errors, ReadLines, WriteFileAtomic and WriteFilesAtomic publication,
// PrefetchFile.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <thread>

#include "libgt/core/error.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "libgt/io/md5.h"
#include "tests/support/test_support.h"

namespace gt::io {
using namespace gt::datasets;  // NOLINT: the readers' parsers, tested beside the files
namespace {
namespace fs = std::filesystem;

TEST(Md5, Rfc1321TestSuite) {
  // Appendix A.5 of RFC 1321.
  EXPECT_EQ(Md5Hex(""), "d41d8cd98f00b204e9800998ecf8427e");
  EXPECT_EQ(Md5Hex("a"), "0cc175b9c0f1b6a831c399e269772661");
  EXPECT_EQ(Md5Hex("abc"), "900150983cd24fb0d6963f7d28e17f72");
  EXPECT_EQ(Md5Hex("message digest"), "f96b697d7cb7938d525a2f31aaf161d0");
  EXPECT_EQ(Md5Hex("abcdefghijklmnopqrstuvwxyz"), "c3fcd3d76192e4007dfb496cca67e13b");
  EXPECT_EQ(Md5Hex("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789"),
            "d174ab98d277d9f5a5611c2c9f419d9f");
  EXPECT_EQ(Md5Hex("1234567890123456789012345678901234567890123456789012345678901234567890"
                   "1234567890"),
            "57edf4a22be3c955ac49da2e2107b67a");
  EXPECT_EQ(Md5Hex("The quick brown fox jumps over the lazy dog"),
            "9e107d9d372bb6826bd81d3542a419d6");
}

TEST(Md5, FileDigestEqualsBytesDigestAcrossBlockBoundaries) {
  // Lengths 0..200 exercise the padding branches (55, 56, 63, 64, 119, 120 bytes);
  // the file path reads in 64 KiB chunks, so a 200 KB file crosses chunk boundaries too.
  const std::string dir = test::ScratchDir("md5");
  std::mt19937 rng(7);
  std::string bytes;
  for (int n = 0; n <= 200; ++n) {
    bytes.assign(n, '\0');
    for (auto& c : bytes) c = static_cast<char>(rng() & 0xff);
    const std::string p = dir + "/f.bin";
    WriteFileAtomic(p, bytes);
    ASSERT_EQ(Md5HexOfFile(p), Md5Hex(bytes)) << n;
  }
  std::string big(200000, '\0');
  for (auto& c : big) c = static_cast<char>(rng() & 0xff);
  WriteFileAtomic(dir + "/big.bin", big);
  EXPECT_EQ(Md5HexOfFile(dir + "/big.bin"), Md5Hex(big));
  // A million 'a' (a classic long-message vector).
  EXPECT_EQ(Md5Hex(std::string(1000000, 'a')), "7707d6ae4e027c70eea2a935c2296f21");
}

TEST(Md5, IncrementalUpdatesEqualOneShot) {
  // Any split of the input into Update calls (empty pieces, pieces inside one block,
  // across blocks, whole blocks) gives the digest of the whole.
  std::mt19937 rng(11);
  for (int n : {0, 1, 55, 56, 63, 64, 65, 119, 120, 128, 1000, 70000}) {
    std::string bytes(n, '\0');
    for (auto& c : bytes) c = static_cast<char>(rng() & 0xff);
    for (int trial = 0; trial < 8; ++trial) {
      Md5 md5;
      size_t at = 0;
      while (at < bytes.size()) {
        const size_t piece = std::min<size_t>(bytes.size() - at, rng() % (trial < 4 ? 70 : 9000));
        md5.Update(bytes.data() + at, piece);
        at += piece;
      }
      md5.Update(nullptr, 0);
      ASSERT_EQ(md5.HexDigest(), Md5Hex(bytes)) << n << " " << trial;
    }
  }
}

TEST(Md5, MissingFileNamesThePath) {
  try {
    Md5HexOfFile("/nonexistent/occgt/x.bin");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/occgt/x.bin"), std::string::npos);
  }
}

TEST(ParseNumbers, PlainScientificAndNonFiniteTokens) {
  const auto v = ParseNumbers(" 1 -2.5\t3e2 +4.25E-1 inf -inf NaN -INF Infinity\r", "p.txt", 1);
  ASSERT_EQ(v.size(), 9u);
  EXPECT_EQ(v[0], 1.0);
  EXPECT_EQ(v[1], -2.5);
  EXPECT_EQ(v[2], 300.0);
  EXPECT_EQ(v[3], 0.425);
  EXPECT_TRUE(std::isinf(v[4]) && v[4] > 0);
  EXPECT_TRUE(std::isinf(v[5]) && v[5] < 0);
  EXPECT_TRUE(std::isnan(v[6]));
  EXPECT_TRUE(std::isinf(v[7]) && v[7] < 0);
  EXPECT_TRUE(std::isinf(v[8]) && v[8] > 0);
  EXPECT_TRUE(ParseNumbers("", "p.txt", 1).empty());
  EXPECT_TRUE(ParseNumbers("   \t ", "p.txt", 1).empty());
}

TEST(ParseNumbers, RandomValuesRoundTripThroughText) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  for (int i = 0; i < 1000; ++i) {
    const double x = u(rng);
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.17g", x);
    const auto v = ParseNumbers(std::string(buf) + " 0", "r.txt", i + 1);
    ASSERT_EQ(v.size(), 2u);
    ASSERT_EQ(v[0], x) << buf;
  }
}

TEST(ParseNumbers, BadTokenNamesFileAndLine) {
  for (const char* bad : {"1 2 x3", "1 0x10", "1.0.0", "abc", "1 2 3-", "nan(12)"}) {
    try {
      ParseNumbers(bad, "pose/12.txt", 3);
      FAIL() << "expected InputError for '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "pose/12.txt:3") << bad;
      EXPECT_NE(std::string(e.what()).find("expected a number"), std::string::npos);
    }
  }
}

// A byte-order mark (as some editors save) is invisible in a message: it is named.
TEST(ParseNumbers, ByteOrderMarkIsNamed) {
  try {
    (void)ParseNumbers("\xEF\xBB\xBF-1.5 2 3", "pose_left.txt", 1);
    ADD_FAILURE() << "a leading byte-order mark was read as a number";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "pose_left.txt:1: the file starts with a UTF-8 byte-order mark (bytes EF BB BF); "
              "expected a number: save it without the mark");
  }
}

TEST(ReadLines, StripsCarriageReturnsAndKeepsEmptyLines) {
  const std::string dir = test::ScratchDir("readlines");
  WriteFileAtomic(dir + "/a.txt", "one\r\n\ntwo\nthree");
  const auto lines = ReadLines(dir + "/a.txt");
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "one");
  EXPECT_EQ(lines[1], "");
  EXPECT_EQ(lines[2], "two");
  EXPECT_EQ(lines[3], "three");
  try {
    ReadLines(dir + "/missing.txt");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/missing.txt");
  }
}

// Pages of `path` in the page cache (mincore over a mapping of the file).
size_t ResidentPages(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  struct stat st {};
  ::fstat(fd, &st);
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  const size_t pages = (static_cast<size_t>(st.st_size) + page - 1) / page;
  void* map = ::mmap(nullptr, static_cast<size_t>(st.st_size), PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) return 0;
  std::vector<unsigned char> in_core(pages);
  size_t resident = 0;
  if (::mincore(map, static_cast<size_t>(st.st_size), in_core.data()) == 0) {
    for (unsigned char c : in_core) resident += c & 1;
  }
  ::munmap(map, static_cast<size_t>(st.st_size));
  return resident;
}

TEST(PrefetchFile, ReadsAnEvictedFileBackIntoThePageCacheAndIgnoresMissingFiles) {
  const std::string dir = test::ScratchDir("prefetch");
  const std::string p = dir + "/data.bin";
  WriteFileAtomic(p, std::string(size_t{4} << 20, 'x'));  // fsynced: its pages are clean
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);  // evicts the clean pages
  ::close(fd);
  if (ResidentPages(p) != 0) {
    GTEST_SKIP() << "the file system of " << dir << " keeps evicted pages (tmpfs?)";
  }
  PrefetchFile(p);
  const size_t want = (size_t{4} << 20) / static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  size_t resident = 0;  // the readahead runs in the background: wait up to 5 s
  for (int i = 0; i < 500 && resident < want; ++i) {
    resident = ResidentPages(p);
    if (resident < want) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(resident, want);                                       // all 4 MiB
  EXPECT_EQ(ReadFileBytes(p), std::string(size_t{4} << 20, 'x'));  // content unchanged
  EXPECT_NO_THROW(PrefetchFile(dir + "/missing.bin"));             // a hint: its reader reports it
  EXPECT_NO_THROW(PrefetchFile(""));
  EXPECT_NO_THROW(PrefetchFile(dir));  // a folder
}

TEST(WriteFileAtomic, CreatesParentsReplacesAndLeavesNoTemporary) {
  const std::string dir = test::ScratchDir("atomic");
  const std::string p = dir + "/a/b/out.bin";
  WriteFileAtomic(p, "first");
  EXPECT_EQ(ReadFileBytes(p), "first");
  WriteFileAtomic(p, std::string("sec\0ond", 7));
  EXPECT_EQ(ReadFileBytes(p), std::string("sec\0ond", 7));
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  EXPECT_TRUE(FileExists(p));
  EXPECT_FALSE(FileExists(dir + "/a"));  // a folder is not a file
}

TEST(WriteFileAtomic, FailureNamesThePathAndKeepsTheOldFile) {
  const std::string dir = test::ScratchDir("atomic_fail");
  // The target is an existing non-empty folder: rename must fail, and nothing is left.
  fs::create_directories(dir + "/target/inner");
  try {
    WriteFileAtomic(dir + "/target", "x");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/target");
  }
  EXPECT_FALSE(fs::exists(dir + "/target.tmp"));
  EXPECT_TRUE(fs::is_directory(dir + "/target/inner"));
  try {
    ReadFileBytes(dir + "/target");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/target");
  }
}

// A path that cannot take a new file is refused before anything is written (renaming onto a
// device or FIFO replaced the node: /dev/null as root); a symbolic link is written through.
TEST(WriteFileAtomic, RefusesFoldersAndSpecialFilesAndWritesThroughLinks) {
  const std::string dir = test::ScratchDir("atomic_special");
  EXPECT_EQ(OutputFileProblem(""), "expected a file path, got ''");
  EXPECT_EQ(OutputFileProblem(dir + "/new/"),
            "names a folder (it ends with '/'): expected a file path");
  EXPECT_EQ(OutputFileProblem(dir), "is a folder: expected a file path");
  EXPECT_EQ(OutputFileProblem(dir + "/absent.json"), "");
  const std::string fifo = dir + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  for (const std::string& special : {fifo, std::string("/dev/null")}) {
    EXPECT_EQ(OutputFileProblem(special).rfind("exists and is not a regular file", 0), 0u);
    try {
      WriteFileAtomic(special, "x");
      ADD_FAILURE() << special;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), special);
    }
  }
  struct stat st {};
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_FALSE(fs::exists(dir + "/new"));
  // A link to a file (and a link to a link): the target gets the bytes, the links stay.
  WriteFileAtomic(dir + "/target.json", "old");
  fs::create_symlink(dir + "/target.json", dir + "/link.json");
  fs::create_symlink("link.json", dir + "/link2.json");
  WriteFileAtomic(dir + "/link2.json", "new");
  EXPECT_TRUE(fs::is_symlink(dir + "/link.json"));
  EXPECT_TRUE(fs::is_symlink(dir + "/link2.json"));
  EXPECT_EQ(ReadFileBytes(dir + "/target.json"), "new");
  EXPECT_FALSE(fs::exists(dir + "/target.json.tmp"));
  // A link to a file that does not exist yet (relative, into a subfolder), through a link:
  // the target is created and the links stay (the link itself was replaced).
  fs::create_directories(dir + "/sub");
  fs::create_symlink("sub/later.json", dir + "/dangling.json");
  fs::create_symlink("dangling.json", dir + "/dangling2.json");
  WriteFileAtomic(dir + "/dangling2.json", "created");
  EXPECT_TRUE(fs::is_symlink(dir + "/dangling.json"));
  EXPECT_TRUE(fs::is_symlink(dir + "/dangling2.json"));
  EXPECT_EQ(ReadFileBytes(dir + "/sub/later.json"), "created");
  // A loop of links: refused, naming the path.
  fs::create_symlink("loop_b.json", dir + "/loop_a.json");
  fs::create_symlink("loop_a.json", dir + "/loop_b.json");
  EXPECT_THROW(WriteFileAtomic(dir + "/loop_a.json", "x"), InputError);
}

TEST(WriteFilesAtomic, WritesEveryFileAndLeavesNoTemporary) {
  const std::string dir = test::ScratchDir("atomic_batch");
  std::vector<FileToWrite> files;
  for (int i = 0; i < 6; ++i) {
    files.push_back({dir + "/d" + std::to_string(i % 2) + "/f" + std::to_string(i) + ".txt",
                     std::string(1000 * i + 1, static_cast<char>('a' + i))});
  }
  WriteFilesAtomic(files);
  for (const FileToWrite& f : files) {
    EXPECT_EQ(ReadFileBytes(f.path), f.bytes) << f.path;
    EXPECT_FALSE(fs::exists(f.path + ".tmp")) << f.path;
  }
  WriteFilesAtomic({{files[0].path, "replaced"}});
  EXPECT_EQ(ReadFileBytes(files[0].path), "replaced");
}

TEST(WriteFilesAtomic, AWriteFailurePublishesNothingAndNamesTheFirstFailingFile) {
  const std::string dir = test::ScratchDir("atomic_batch_fail");
  WriteFileAtomic(dir + "/a.txt", "old");
  { std::ofstream(dir + "/plain") << "x"; }  // a file where a folder is needed
  const std::vector<FileToWrite> files = {{dir + "/a.txt", "new"},
                                          {dir + "/plain/b.txt", "b"},
                                          {dir + "/c.txt", "c"},
                                          {dir + "/plain/d.txt", "d"}};
  for (int repeat = 0; repeat < 20; ++repeat) {  // the same error whatever the timing
    try {
      WriteFilesAtomic(files);
      FAIL() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), dir + "/plain/b.txt");
    }
    EXPECT_EQ(ReadFileBytes(dir + "/a.txt"), "old");  // not published
    EXPECT_FALSE(fs::exists(dir + "/c.txt"));
    for (const FileToWrite& f : files) EXPECT_FALSE(fs::exists(f.path + ".tmp")) << f.path;
  }
}

TEST(WriteFilesAtomic, ARenameFailureKeepsTheEarlierFilesAndRemovesTheTemporaries) {
  const std::string dir = test::ScratchDir("atomic_batch_rename");
  fs::create_directories(dir + "/target/inner");  // rename onto a non-empty folder fails
  try {
    WriteFilesAtomic({{dir + "/first.txt", "1"}, {dir + "/target", "2"}, {dir + "/last.txt", "3"}});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/target");
  }
  EXPECT_EQ(ReadFileBytes(dir + "/first.txt"), "1");
  EXPECT_TRUE(fs::is_directory(dir + "/target/inner"));
  EXPECT_FALSE(fs::exists(dir + "/last.txt"));
  for (const char* name : {"/first.txt.tmp", "/target.tmp", "/last.txt.tmp"}) {
    EXPECT_FALSE(fs::exists(dir + name)) << name;
  }
}

TEST(ListNumberedFiles, UnreadableEntriesAndDuplicateNumbersAreErrors) {
  const std::string dir = test::ScratchDir("io_numbered_files");
  for (const char* name : {"0.txt", "1.txt", "2.txt"}) std::ofstream(dir + "/" + name) << "x";
  EXPECT_EQ(ListNumberedFiles(dir, "", ".txt").size(), 3u);
  // "01.txt" next to "1.txt": two files for frame 1.
  std::ofstream(dir + "/01.txt") << "x";
  try {
    ListNumberedFiles(dir, "", ".txt");
    ADD_FAILURE() << "duplicate frame number accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("01.txt and 1.txt both give frame number 1"),
              std::string::npos)
        << e.what();
  }
  fs::remove(dir + "/01.txt");
  // A folder or a dangling link where a frame file is expected (root reads chmod 000).
  fs::create_directory(dir + "/3.txt");
  EXPECT_THROW(ListNumberedFiles(dir, "", ".txt"), InputError);
  fs::remove(dir + "/3.txt");
  fs::create_symlink("missing", dir + "/4.txt");
  try {
    ListNumberedFiles(dir, "", ".txt");
    ADD_FAILURE() << "dangling link accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("4.txt: dangling"), std::string::npos) << e.what();
  }
}

TEST(SceneName, DotDotAndAbsoluteNamesNeverLeaveTheRoot) {
  EXPECT_EQ(CheckSceneName("scene0000_00"), "");
  EXPECT_EQ(CheckSceneName("office/Easy/P001"), "");
  EXPECT_EQ(CheckSceneName("a..b"), "");
  for (const char* bad : {"..", "../x", "a/../../x", "a/..", "/etc"}) {
    EXPECT_NE(CheckSceneName(bad), "") << bad;
  }
  const std::string root = test::ScratchDir("io_scene_escape");
  fs::create_directories(root + "/inside");
  EXPECT_THROW(ResolveSceneFolder(root + "/inside", "../inside", false), InputError);
}

TEST(PngDamage, CompleteTruncatedAndNonPng) {
  // A 1x1 grey PNG.
  const std::string png(
      "\211\120\116\107\015\012\032\012\000\000\000\015\111\110\104\122"
      "\000\000\000\001\000\000\000\001\010\000\000\000\000\072\176\233"
      "\125\000\000\000\012\111\104\101\124\170\234\143\140\000\000\000"
      "\002\000\001\110\257\244\161\000\000\000\000\111\105\116\104\256"
      "\102\140\202",
      67);
  EXPECT_EQ(PngDamage(png), "");
  EXPECT_EQ(PngDamage("not a png"), "");
  for (size_t keep : {8u, 20u, 40u, 60u}) {
    EXPECT_NE(PngDamage(png.substr(0, keep)), "") << keep;
  }
}

}  // namespace
}  // namespace gt::io

// io/gzip.h: round trips at every size class, the same bytes for the same input, Python's
// gzip module reading what is written (a standard tool), and each bad input (not gzip,
// truncated, corrupt, trailing bytes, inflating past the limit) as one InputError.
#include "libgt/io/gzip.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "libgt/core/error.h"
#include "tests/support/test_support.h"

namespace gt::io {
namespace {

std::string Random(size_t n, uint32_t seed, int alphabet) {
  std::mt19937 rng(seed);
  std::string s(n, '\0');
  for (char& c : s) c = static_cast<char>(rng() % alphabet);
  return s;
}

TEST(Gzip, RoundTripsAndIsDeterministic) {
  for (size_t n : {size_t{0}, size_t{1}, size_t{1000}, size_t{300000}}) {
    for (int alphabet : {2, 256}) {
      const std::string data = Random(n, static_cast<uint32_t>(n + alphabet), alphabet);
      for (int level : {1, 6, 9}) {
        const std::string gz = GzipBytes(data, level);
        EXPECT_EQ(GunzipBytes(gz, "x"), data) << n << " " << level;
        EXPECT_EQ(GzipBytes(data, level), gz);
        // The header: 1f 8b, deflate, no flags, mtime 0.
        ASSERT_GE(gz.size(), 18u);
        EXPECT_EQ(gz.substr(0, 8), std::string("\x1f\x8b\x08\x00\x00\x00\x00\x00", 8));
      }
    }
  }
  EXPECT_LT(GzipBytes(std::string(100000, 'a'), 1).size(), 1000u);
}

TEST(Gzip, PythonReadsIt) {
  const std::string dir = test::ScratchDir("gzip");
  const std::string data = Random(5000, 3, 7);
  std::ofstream(dir + "/a.gz", std::ios::binary) << GzipBytes(data, 1);
  std::ofstream(dir + "/a.raw", std::ios::binary) << data;
  const auto r = test::RunShell(
      "/usr/bin/python3 -c \"import gzip,sys; "
      "assert gzip.open(sys.argv[1]).read() == open(sys.argv[2], 'rb')"
      ".read(); print('ok')\" '" +
      dir + "/a.gz' '" + dir + "/a.raw'");
  EXPECT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_EQ(r.stdout_text, "ok\n");
}

TEST(Gzip, BadInputIsOneInputError) {
  const std::string gz = GzipBytes(Random(20000, 9, 256), 6);
  auto message = [](const std::string& bytes, size_t limit) {
    try {
      (void)GunzipBytes(bytes, "m.npy.gz", limit);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("plain bytes, not gzip at all", 1 << 20).find("not gzip"), std::string::npos);
  EXPECT_NE(message(gz.substr(0, gz.size() / 2), 1 << 20).find("truncated"), std::string::npos);
  EXPECT_NE(message(gz + "xx", 1 << 20).find("trailing"), std::string::npos);
  std::string corrupt = gz;
  corrupt[gz.size() / 2] ^= 0x55;
  EXPECT_NE(message(corrupt, 1 << 20).find("bad gzip data"), std::string::npos);
  EXPECT_NE(message(GzipBytes(std::string(1 << 20, 'z'), 9), 1000).find("more than 1000 bytes"),
            std::string::npos);
  for (size_t n = 0; n < gz.size(); n += 97) {
    EXPECT_THROW((void)GunzipBytes(gz.substr(0, n), "cut"), InputError) << n;
  }
}

// The trailer records the plain size; GunzipBytes sizes its buffer from it (libdeflate) and
// falls back to zlib when it lies. Every lie is an error, never a wrong result or a huge
// allocation, and a multi-member file (what `cat a.gz b.gz` makes) is refused as trailing.
TEST(Gzip, TrailerSizeIsOnlyAHint) {
  const std::string data = Random(50000, 4, 5);
  const std::string gz = GzipBytes(data, 1);
  EXPECT_EQ(GzipTrailerSize(gz), data.size());
  EXPECT_EQ(GzipTrailerSize("ab"), 0u);
  auto with_isize = [&](uint32_t isize) {
    std::string out = gz;
    for (size_t k = 0; k < 4; ++k) out[out.size() - 4 + k] = static_cast<char>(isize >> (8 * k));
    return out;
  };
  for (uint32_t lie :
       {uint32_t{0}, uint32_t{1}, uint32_t{49999}, uint32_t{50001}, uint32_t{0xffffffffu}}) {
    EXPECT_THROW((void)GunzipBytes(with_isize(lie), "lie"), InputError) << lie;
  }
  EXPECT_THROW((void)GunzipBytes(gz + gz, "two members"), InputError);
}

TEST(Gzip, GunzipIntoNeedsTheExactSize) {
  for (size_t n : {size_t{0}, size_t{7}, size_t{100000}}) {
    const std::string data = Random(n, static_cast<uint32_t>(n), 3);
    const std::string gz = GzipBytes(data, 1);
    std::string out(n, 'x');
    GunzipInto(gz, out.data(), out.size(), "into");
    EXPECT_EQ(out, data) << n;
    std::string small(n + 1, 'x');
    EXPECT_THROW(GunzipInto(gz, small.data(), small.size(), "into"), InputError) << n;
    if (n > 0) {
      EXPECT_THROW(GunzipInto(gz, out.data(), n - 1, "into"), InputError) << n;
    }
  }
  std::string out(10, 'x');
  EXPECT_THROW(GunzipInto("not gzip at all, no", out.data(), out.size(), "into"), InputError);
}

// GunzipBytes and GunzipInto give the same bytes across sizes around the 64 KiB window.
TEST(Gzip, BytesAndIntoAgree) {
  for (size_t n : {size_t{1}, size_t{4096}, size_t{65535}, size_t{65537}, size_t{400000}}) {
    const std::string data = Random(n, static_cast<uint32_t>(7 * n), 11);
    const std::string gz = GzipBytes(data, 1);
    EXPECT_EQ(GunzipBytes(gz, "bytes"), data) << n;
    std::string out(n, '\0');
    GunzipInto(gz, out.data(), n, "into");
    EXPECT_EQ(out, data) << n;
  }
}

// GzipPlainSize, for callers that allocate before GunzipInto (the Python binding): the
// trailer's size when DEFLATE can reach it from these bytes, one InputError otherwise.
TEST(Gzip, PlainSizeRefusesImpossibleTrailers) {
  const std::string data = Random(20000, 5, 4);
  std::string gz = GzipBytes(data, 1);
  EXPECT_EQ(GzipPlainSize(gz, "m"), data.size());
  EXPECT_THROW((void)GzipPlainSize("not gzip data at all", "m"), InputError);
  for (size_t k = 0; k < 4; ++k) gz[gz.size() - 4 + k] = static_cast<char>(0xff);
  try {
    (void)GzipPlainSize(gz, "m.npy.gz");
    ADD_FAILURE() << "a 4 GiB trailer on " << gz.size() << " bytes was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.npy.gz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("trailer claims 4294967295"), std::string::npos)
        << e.what();
  }
}

// GunzipPrefix inflates only the first bytes: exactly the plain prefix, all of a shorter
// stream, and an error only for damage inside what it inflates.
TEST(Gzip, PrefixInflatesOnlyTheStart) {
  const std::string data = Random(200000, 6, 9);
  const std::string gz = GzipBytes(data, 1);
  for (size_t n :
       {size_t{0}, size_t{1}, size_t{10012}, size_t{199999}, size_t{200000}, size_t{300000}}) {
    EXPECT_EQ(GunzipPrefix(gz, n, "p"), data.substr(0, n)) << n;
  }
  // A cut stream: its start is still there; asking past the cut is "truncated".
  const std::string cut = gz.substr(0, gz.size() / 2);
  EXPECT_EQ(GunzipPrefix(cut, 100, "p"), data.substr(0, 100));
  try {
    (void)GunzipPrefix(cut, data.size(), "cut.npy.gz");
    ADD_FAILURE() << "a cut stream gave its whole prefix";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.npy.gz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)GunzipPrefix("not gzip data at all", 10, "p"), InputError);
}

}  // namespace
}  // namespace gt::io

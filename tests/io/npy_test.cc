// .npy / .npz: round trips for every dtype and shape, the exact header layout of the spec
// (SHARDS.md "NumPy .npy / .npz"), every rejection on hand-crafted bytes, LoFTR's real
// test-1500 index, and exchange with NumPy itself (/usr/bin/python3) in both directions.
#include "libgt/io/npy.h"

#include <gtest/gtest.h>
#include <zip.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <thread>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/gzip.h"
#include "tests/support/test_support.h"

namespace gt::io {
namespace {

// Little-endian integer at offset.
uint64_t Le(const std::string& s, size_t offset, int nbytes) {
  uint64_t v = 0;
  for (int i = nbytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(s[offset + i]);
  return v;
}

// Runs a NumPy script with Debian's Python: `body` follows "import numpy as np, sys" and
// "d = sys.argv[1]" (d = dir), and is written to DIR/NAME first.
test::CommandResult RunNumPy(const std::string& dir, const std::string& name,
                             const std::string& body) {
  const std::string script = dir + "/" + name;
  {
    std::ofstream py(script);
    py << "import numpy as np, sys\n"
          "d = sys.argv[1]\n"
       << body;
  }
  return test::RunShell("/usr/bin/python3 '" + script + "' '" + dir + "'");
}

// A .npy file built by hand from a header dict: magic, version, length, dict padded with
// spaces to 64 bytes and '\n', then raw data. Independent of EncodeNpy.
std::string CraftNpy(const std::string& dict, const std::string& data, int major = 1,
                     int minor = 0) {
  const size_t prefix = major == 1 ? 10 : 12;
  size_t total = prefix + dict.size() + 1;
  total = (total + 63) / 64 * 64;
  const size_t header_len = total - prefix;
  std::string out = "\x93NUMPY";
  out.push_back(static_cast<char>(major));
  out.push_back(static_cast<char>(minor));
  for (size_t i = 0; i < prefix - 8; ++i) out.push_back(static_cast<char>(header_len >> (8 * i)));
  out += dict;
  out.append(header_len - dict.size() - 1, ' ');
  out += '\n';
  return out + data;
}

std::string Dict(const std::string& descr, const std::string& shape, bool fortran = false) {
  return "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
         ", 'shape': " + shape + ", }";
}

// Runs f, expects InputError whose message contains every one of `parts`.
template <typename F>
void ExpectInputError(F f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "expected gt::InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const auto& p : parts) EXPECT_NE(what.find(p), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

template <typename T>
std::vector<T> Values(int64_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::vector<T> v(static_cast<size_t>(n));
  for (auto& x : v) {
    if constexpr (std::is_floating_point_v<T>) {
      x = static_cast<T>(std::uniform_real_distribution<double>(-1e6, 1e6)(rng));
    } else {
      x = static_cast<T>(rng());
    }
  }
  return v;
}

template <typename T>
class NpyRoundTrip : public ::testing::Test {};
using AllTypes =
    ::testing::Types<float, double, int32_t, int64_t, uint8_t, uint16_t, uint32_t, uint64_t>;
TYPED_TEST_SUITE(NpyRoundTrip, AllTypes);

TYPED_TEST(NpyRoundTrip, EveryShapeRoundTripsWithAlignedData) {
  using T = TypeParam;
  const std::vector<std::vector<int64_t>> shapes = {{},     {0},       {1},       {3},
                                                    {2, 3}, {4, 0, 2}, {2, 3, 4}, {7, 5}};
  unsigned seed = 1;
  for (const auto& shape : shapes) {
    int64_t n = 1;
    for (auto d : shape) n *= d;
    const std::vector<T> values = Values<T>(n, seed++);
    const std::string bytes = EncodeNpy(shape, values);
    // Header: version 1.0, length such that data starts at a multiple of 64, '\n' last.
    ASSERT_EQ(bytes.substr(0, 6), "\x93NUMPY");
    EXPECT_EQ(bytes[6], 1);
    EXPECT_EQ(bytes[7], 0);
    const size_t data_offset = 10 + Le(bytes, 8, 2);
    EXPECT_EQ(data_offset % 64, 0u);
    EXPECT_EQ(bytes[data_offset - 1], '\n');
    EXPECT_EQ(bytes.size(), data_offset + n * sizeof(T));

    const NpyArray a = ParseNpy(bytes, "mem.npy");
    EXPECT_EQ(a.descr, NpyDescr<T>());
    EXPECT_EQ(a.shape, shape);
    EXPECT_FALSE(a.fortran_order);
    EXPECT_EQ(a.NumElements(), n);
    EXPECT_EQ(a.ItemSize(), sizeof(T));
    const T* p = a.template As<T>("mem.npy");
    for (int64_t i = 0; i < n; ++i) ASSERT_EQ(p[i], values[i]) << i;
  }
}

TYPED_TEST(NpyRoundTrip, FileRoundTrip) {
  using T = TypeParam;
  const std::string dir =
      test::ScratchDir(std::string("npy_file_") + NpyDescr<T>()[2] + NpyDescr<T>()[1]);
  const std::string path = dir + "/a.npy";
  const std::vector<T> values = Values<T>(12, 42);
  WriteNpy<T>(path, {3, 4}, values);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const NpyArray a = ReadNpy(path);
  EXPECT_EQ(a.shape, (std::vector<int64_t>{3, 4}));
  EXPECT_EQ(std::vector<T>(a.As<T>(path), a.As<T>(path) + 12), values);
}

TEST(Npy, HeaderTextFollowsTheSpec) {
  const std::vector<float> one = {1.5f, 2.5f, 3.5f};
  const std::string b1 = EncodeNpy<float>({3}, one);
  const std::string expect1 = "{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }";
  EXPECT_EQ(b1.substr(10, expect1.size()), expect1);
  // Padding is spaces only, up to the '\n' before the data.
  const size_t header_end = 10 + Le(b1, 8, 2);
  for (size_t i = 10 + expect1.size(); i + 1 < header_end; ++i) ASSERT_EQ(b1[i], ' ');
  float f[3];
  std::memcpy(f, b1.data() + header_end, 12);
  EXPECT_EQ(f[0], 1.5f);
  EXPECT_EQ(f[2], 3.5f);

  const std::string b0 = EncodeNpy<double>({}, std::vector<double>{2.0});
  EXPECT_NE(b0.find("'shape': (), }"), std::string::npos);
  const std::string b2 = EncodeNpy<uint8_t>({480, 640}, std::vector<uint8_t>(480 * 640));
  EXPECT_NE(b2.find("{'descr': '|u1', 'fortran_order': False, 'shape': (480, 640), }"),
            std::string::npos);
}

TEST(Npy, HugeHeaderUsesVersion2AndTheReaderLimitsHeaders) {
  // 30000 dimensions of 1: the dict is ~90 kB, beyond the uint16 length of version 1.0.
  const std::vector<int64_t> shape(30000, 1);
  const std::string bytes = EncodeNpy<float>(shape, std::vector<float>{7.0f});
  EXPECT_EQ(bytes[6], 2);
  EXPECT_EQ(bytes[7], 0);
  const uint64_t header_len = Le(bytes, 8, 4);
  EXPECT_GT(header_len, 65535u);
  EXPECT_EQ((12 + header_len) % 64, 0u);
  EXPECT_EQ(bytes[12 + header_len - 1], '\n');
  EXPECT_EQ(bytes.size(), 12 + header_len + 4);
  ExpectInputError([&] { ParseNpy(bytes, "big.npy"); }, {"big.npy", "header", "10000"});
}

TEST(Npy, SmallVersion2And3FilesAreRead) {
  for (int major : {2, 3}) {
    const std::string bytes =
        CraftNpy(Dict("<i4", "(2,)"), std::string("\x01\0\0\0\x02\0\0\0", 8), major);
    const NpyArray a = ParseNpy(bytes, "v.npy");
    EXPECT_EQ(a.As<int32_t>("v.npy")[1], 2);
  }
}

TEST(Npy, HeaderParsingIsRobustToOrderQuotesAndSpacing) {
  const std::string data(24, '\0');
  const std::vector<std::string> dicts = {
      "{'shape': (2, 3), 'fortran_order': False, 'descr': '<f4'}",
      "{\"descr\":\"<f4\",\"fortran_order\":False,\"shape\":(2,3)}",
      "{ 'descr' : '<f4' ,  'fortran_order' :False , 'shape' : ( 2 , 3 , ) , }",
      "{'descr': '<f4', 'fortran_order': False, 'shape': (2L, 3L), }",
  };
  for (const auto& d : dicts) {
    const NpyArray a = ParseNpy(CraftNpy(d, data), "x.npy");
    EXPECT_EQ(a.descr, "<f4") << d;
    EXPECT_EQ(a.shape, (std::vector<int64_t>{2, 3})) << d;
  }
  // A one-byte type written with an explicit byte order is normalised.
  EXPECT_EQ(ParseNpy(CraftNpy(Dict("<u1", "(2,)"), "ab"), "x.npy").descr, "|u1");
  // Extra bytes after the data are ignored as NumPy does.
  EXPECT_EQ(ParseNpy(CraftNpy(Dict("|u1", "(1,)"), "abc"), "x.npy").data, "a");
}

TEST(Npy, Rejections) {
  const std::string f4x3(12, '\0');
  ExpectInputError([&] { ParseNpy("PK\x03\x04 not numpy at all", "a.npy"); }, {"a.npy", "magic"});
  ExpectInputError([&] { ParseNpy("\x93NUM", "a.npy"); }, {"a.npy", "magic"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(3,)"), f4x3, 4), "a.npy"); },
                   {"a.npy", "version", "4.0"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(3,)"), f4x3, 1, 1), "a.npy"); },
                   {"a.npy", "version", "1.1"});
  // Declared header length 20000 (> 10000) even though the file is short.
  {
    std::string b = CraftNpy(Dict("<f4", "(3,)"), f4x3);
    b[8] = static_cast<char>(20000 & 0xff);
    b[9] = static_cast<char>(20000 >> 8);
    ExpectInputError([&] { ParseNpy(b, "a.npy"); }, {"a.npy", "header", "10000"});
  }
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("|O", "(3,)"), f4x3), "a.npy"); },
                   {"a.npy", "descr", "object"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<c16", "(3,)"), f4x3), "a.npy"); },
                   {"a.npy", "descr", "unsupported dtype '<c16'"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<U5", "(3,)"), f4x3), "a.npy"); },
                   {"a.npy", "descr", "unsupported"});
  ExpectInputError(
      [&] {
        ParseNpy(CraftNpy("{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (3,)}", f4x3),
                 "a.npy");
      },
      {"a.npy", "descr", "structured"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict(">f4", "(3,)"), f4x3), "a.npy"); },
                   {"a.npy", "descr", "big-endian"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(3,)", true), f4x3), "a.npy"); },
                   {"a.npy", "fortran_order", "not supported"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(3, -1)"), f4x3), "a.npy"); },
                   {"a.npy", "shape", "negative"});
  ExpectInputError(
      [&] { ParseNpy(CraftNpy(Dict("<f4", "(4294967296, 4294967296)"), f4x3), "a.npy"); },
      {"a.npy", "shape", "overflow"});
  ExpectInputError(
      [&] { ParseNpy(CraftNpy(Dict("<f4", "(99999999999999999999,)"), f4x3), "a.npy"); },
      {"a.npy", "shape", "int64"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(4,)"), f4x3), "a.npy"); },
                   {"a.npy", "shape", "16", "12"});
  ExpectInputError([&] { ParseNpy(CraftNpy("{'descr': '<f4', 'shape': (3,)}", f4x3), "a.npy"); },
                   {"a.npy", "fortran_order", "missing"});
  ExpectInputError(
      [&] {
        ParseNpy(CraftNpy("{'descr': '<f4', 'fortran_order': False, 'shape': (3,), 'x': 1}", f4x3),
                 "a.npy");
      },
      {"a.npy", "unexpected key 'x'"});
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(3,"), f4x3), "a.npy"); },
                   {"a.npy", "shape"});
  // File ends inside the header.
  ExpectInputError([&] { ParseNpy(CraftNpy(Dict("<f4", "(3,)"), "").substr(0, 40), "a.npy"); },
                   {"a.npy", "header"});
  // Typed view with the wrong type.
  const NpyArray a = ParseNpy(CraftNpy(Dict("<f4", "(3,)"), f4x3), "a.npy");
  ExpectInputError([&] { a.As<double>("a.npy"); }, {"a.npy", "<f4", "<f8"});
  // Missing file.
  ExpectInputError([&] { ReadNpy("/nonexistent/x.npy"); }, {"/nonexistent/x.npy"});
}

// A shard's `<field>.npy.gz`: its plain size comes from the .npy header inside, so a
// member whose stream runs on past the array its header declares (a gzip bomb behind a
// small header, a lying trailer) is refused after inflating that much, not 2 GiB.
TEST(NpyGzip, PlainSizeComesFromTheHeaderInside) {
  const std::vector<std::string> arrays = {
      EncodeNpy({480, 640}, Values<float>(480 * 640, 1)),
      EncodeNpy({0}, std::vector<uint8_t>{}),
      EncodeNpy({3, 2}, Values<uint64_t>(6, 2)),
      EncodeStringsNpy({"scene0000_00", "a"}, "strings"),
      CraftNpy(Dict("|S3", "(2,)"), "abcdef"),
      // A header longer than the short prefix inflated first (80 dimensions of 1).
      CraftNpy(Dict(
                   "<u2", "(" +
                              [] {
                                std::string dims;
                                for (int k = 0; k < 80; ++k) dims += "1, ";
                                return dims;
                              }() +
                              "3)"),
               std::string(6, '\x01')),
  };
  ASSERT_GT(arrays.back().find('\n'), 256u);  // its header runs past the short prefix
  for (const std::string& npy : arrays) {
    const std::string gz = GzipBytes(npy, 1);
    EXPECT_EQ(GzippedNpyPlainSize(gz, "m.npy.gz"), npy.size());
    EXPECT_EQ(GunzipNpy(gz, "m.npy.gz"), npy);
    // The trailer is not what sizes it, and a lie there is still refused.
    std::string lie = gz;
    for (size_t k = 0; k < 4; ++k) lie[lie.size() - 4 + k] = static_cast<char>(0xff);
    EXPECT_THROW((void)GunzipNpy(lie, "m.npy.gz"), InputError);
  }

  // 64 MiB of zeros behind a header of 4 floats: refused at 4 floats' size.
  const std::string small = EncodeNpy({4}, Values<float>(4, 3));
  const std::string bomb = GzipBytes(small + std::string(size_t{64} << 20, '\0'), 9);
  ASSERT_LT(bomb.size(), size_t{1} << 20);
  EXPECT_EQ(GzippedNpyPlainSize(bomb, "bomb.npy.gz"), small.size());
  ExpectInputError([&] { (void)GunzipNpy(bomb, "bomb.npy.gz"); },
                   {"bomb.npy.gz", "more than " + std::to_string(small.size()) + " bytes"});

  // A header that declares more than 2 GiB, or more than DEFLATE can reach from the bytes.
  ExpectInputError(
      [&] {
        (void)GzippedNpyPlainSize(GzipBytes(CraftNpy(Dict("<f8", "(100000, 100000)"), ""), 1),
                                  "huge.npy.gz");
      },
      {"huge.npy.gz", "'shape'", "2 GiB"});
  ExpectInputError(
      [&] {
        (void)GzippedNpyPlainSize(GzipBytes(CraftNpy(Dict("<f4", "(1000000,)"), ""), 1),
                                  "short.npy.gz");
      },
      {"short.npy.gz", "'shape'", "gzip bytes can hold"});
  // Not a .npy inside, or not gzip at all: the reader's own messages.
  ExpectInputError([&] { (void)GzippedNpyPlainSize(GzipBytes("plain text", 1), "t.npy.gz"); },
                   {"t.npy.gz", "not a .npy file"});
  ExpectInputError([&] { (void)GzippedNpyPlainSize("not gzip data at all", "n.npy.gz"); },
                   {"n.npy.gz", "not gzip"});
}

TEST(Npz, WriteIsStoredSortedDeterministicAndReadBack) {
  const std::string dir = test::ScratchDir("npz_write");
  std::map<std::string, std::string> members;
  members["zeta"] = EncodeNpy<int32_t>({2}, {5, -6});
  members["alpha"] = EncodeNpy<double>({2, 2}, {1, 2, 3, 4});
  WriteNpz(dir + "/a.npz", members);
  // DOS timestamps have a 2 s resolution: wait so that a clock-dependent writer would differ.
  std::this_thread::sleep_for(std::chrono::milliseconds(2100));
  WriteNpz(dir + "/b.npz", members);
  const std::string a = ReadFileBytes(dir + "/a.npz");
  EXPECT_EQ(a, ReadFileBytes(dir + "/b.npz"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/a.npz.tmp"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/a.npz.zip.tmp"));
  // First local file header: signature, method 0 (stored) at offset 8, name at offset 30.
  ASSERT_EQ(a.substr(0, 4), "PK\x03\x04");
  EXPECT_EQ(Le(a, 8, 2), 0u);
  const size_t name_len = Le(a, 26, 2);
  EXPECT_EQ(a.substr(30, name_len), "alpha.npy");
  EXPECT_LT(a.find("alpha.npy"), a.find("zeta.npy"));

  const auto read = ReadNpz(dir + "/a.npz");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read.at("alpha").shape, (std::vector<int64_t>{2, 2}));
  EXPECT_EQ(read.at("alpha").As<double>("alpha")[3], 4.0);
  EXPECT_EQ(read.at("zeta").As<int32_t>("zeta")[1], -6);

  // No member (a LoFTR export of a split without pairs): libzip would write no file at all.
  WriteNpz(dir + "/empty.npz", {});
  EXPECT_EQ(ReadFileBytes(dir + "/empty.npz").size(), 22u);
  EXPECT_TRUE(ReadNpz(dir + "/empty.npz").empty());
  EXPECT_FALSE(std::filesystem::exists(dir + "/empty.npz.zip.tmp"));
}

TEST(Npz, Rejections) {
  const std::string dir = test::ScratchDir("npz_bad");
  ExpectInputError([&] { ReadNpz(dir + "/missing.npz"); }, {"missing.npz"});
  WriteFileAtomic(dir + "/notzip.npz", "hello, not a zip file");
  ExpectInputError([&] { ReadNpz(dir + "/notzip.npz"); }, {"notzip.npz", "zip"});
  WriteNpz(dir + "/badmember.npz",
           {{"good", EncodeNpy<float>({1}, {1.0f})}, {"broken", "\x93NUMPX garbage"}});
  ExpectInputError([&] { ReadNpz(dir + "/badmember.npz"); }, {"badmember.npz:broken.npy", "magic"});
  // A member that is not a .npy.
  {
    int err = 0;
    zip_t* z = zip_open((dir + "/other.npz").c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    ASSERT_NE(z, nullptr);
    static const char kText[] = "hello";
    zip_source_t* src = zip_source_buffer(z, kText, 5, 0);
    ASSERT_GE(zip_file_add(z, "readme.txt", src, 0), 0);
    ASSERT_EQ(zip_close(z), 0);
  }
  ExpectInputError([&] { ReadNpz(dir + "/other.npz"); }, {"other.npz:readme.txt", ".npy"});
}

// LoFTR's real ScanNet test-1500 index, written by NumPy (deflated members).
TEST(Npz, LoftrScanNetTest1500) {
  const std::string root = test::SharedData("loftr_scannet_test_1500");
  ASSERT_FALSE(root.empty());
  const auto test = ReadNpz(root + "/test.npz");
  ASSERT_EQ(test.size(), 2u);
  const NpyArray& name = test.at("name");
  const NpyArray& rel = test.at("rel_pose");
  EXPECT_EQ(name.descr, "<u2");
  EXPECT_EQ(name.shape, (std::vector<int64_t>{1500, 4}));
  EXPECT_EQ(rel.descr, "<f4");
  EXPECT_EQ(rel.shape, (std::vector<int64_t>{1500, 12}));

  const uint16_t* n = name.As<uint16_t>("name");
  std::map<int, int> pairs_per_scene;
  for (int i = 0; i < 1500; ++i) {
    const int scene = n[4 * i];
    ASSERT_GE(scene, 707);
    ASSERT_LE(scene, 806);
    ++pairs_per_scene[scene];
  }
  EXPECT_EQ(pairs_per_scene.size(), 100u);
  for (const auto& [scene, count] : pairs_per_scene) EXPECT_EQ(count, 15) << scene;

  const float* r = rel.As<float>("rel_pose");
  for (int i = 0; i < 1500; ++i) {
    Eigen::Matrix3d R;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) R(row, col) = r[12 * i + 4 * row + col];
    }
    ASSERT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-4)
        << "pair " << i;
    ASSERT_NEAR(R.determinant(), 1.0, 1e-4) << "pair " << i;
  }

  const auto intrinsics = ReadNpz(root + "/intrinsics.npz");
  EXPECT_EQ(intrinsics.size(), 100u);
  std::set<int> scenes_with_k;
  for (const auto& [key, k] : intrinsics) {
    ASSERT_EQ(k.shape, (std::vector<int64_t>{3, 3})) << key;
    ASSERT_EQ(k.descr, "<f8") << key;
    const double* K = k.As<double>(key);
    EXPECT_GT(K[0], 100.0) << key;
    EXPECT_EQ(K[3], 0.0);
    EXPECT_EQ(K[6], 0.0);
    EXPECT_EQ(K[7], 0.0);
    EXPECT_EQ(K[8], 1.0);
    ASSERT_EQ(key.rfind("scene", 0), 0u) << key;
    scenes_with_k.insert(std::stoi(key.substr(5, 4)));
  }
  std::set<int> scenes_with_pairs;
  for (const auto& [scene, count] : pairs_per_scene) scenes_with_pairs.insert(scene);
  EXPECT_EQ(scenes_with_k, scenes_with_pairs);
}

// NumPy writes (np.save, np.savez, np.savez_compressed, several dtypes, Fortran order and
// big-endian for the rejections) and occgt reads; occgt writes and NumPy reads.
TEST(Npy, ExchangeWithNumPy) {
  const std::string dir = test::ScratchDir("npy_numpy");
  const auto made =
      RunNumPy(dir, "make.py",
               "np.save(d + '/f4.npy', np.arange(12, dtype=np.float32).reshape(3, 4) / 4)\n"
               "np.save(d + '/scalar.npy', np.float64(2.5))\n"
               "np.save(d + '/u2.npy', np.arange(5, dtype=np.uint16) * 1000)\n"
               "np.save(d + '/big.npy', np.arange(3, dtype='>f4'))\n"
               "np.save(d + '/fortran.npy', np.asfortranarray(np.ones((2, 3))))\n"
               "np.save(d + '/obj.npy', np.array([{}, 1], dtype=object), allow_pickle=True)\n"
               "np.savez(d + '/s.npz', b=np.arange(6, dtype=np.int64).reshape(2, 3), "
               "a=np.array([1, 2], dtype=np.uint8))\n"
               "np.savez_compressed(d + '/c.npz', x=np.linspace(0, 1, 1000, dtype=np.float64))\n");
  ASSERT_EQ(made.exit_code, 0) << made.stderr_text;

  const NpyArray f4 = ReadNpy(dir + "/f4.npy");
  EXPECT_EQ(f4.shape, (std::vector<int64_t>{3, 4}));
  for (int i = 0; i < 12; ++i) EXPECT_EQ(f4.As<float>("f4")[i], i / 4.0f);
  const NpyArray scalar = ReadNpy(dir + "/scalar.npy");
  EXPECT_TRUE(scalar.shape.empty());
  EXPECT_EQ(scalar.As<double>("scalar")[0], 2.5);
  EXPECT_EQ(ReadNpy(dir + "/u2.npy").As<uint16_t>("u2")[4], 4000);
  ExpectInputError([&] { ReadNpy(dir + "/big.npy"); }, {"big.npy", "big-endian"});
  ExpectInputError([&] { ReadNpy(dir + "/fortran.npy"); }, {"fortran.npy", "not supported"});
  ExpectInputError([&] { ReadNpy(dir + "/obj.npy"); }, {"obj.npy", "object"});

  const auto s = ReadNpz(dir + "/s.npz");
  EXPECT_EQ(s.at("b").shape, (std::vector<int64_t>{2, 3}));
  EXPECT_EQ(s.at("b").As<int64_t>("b")[5], 5);
  EXPECT_EQ(s.at("a").As<uint8_t>("a")[1], 2);
  const auto c = ReadNpz(dir + "/c.npz");
  const double* x = c.at("x").As<double>("x");
  EXPECT_EQ(c.at("x").shape, (std::vector<int64_t>{1000}));
  for (int i = 0; i < 1000; ++i) EXPECT_NEAR(x[i], i / 999.0, 1e-15);

  // occgt writes, NumPy reads and checks dtype, shape, values and the 64-byte data offset.
  std::vector<float> depth(6 * 5);
  for (size_t i = 0; i < depth.size(); ++i) depth[i] = 0.25f * static_cast<float>(i);
  WriteNpy<float>(dir + "/ours.npy", {6, 5}, depth);
  WriteNpy<uint64_t>(dir + "/ours_u8.npy", {3}, {1, 2, 1ull << 63});
  WriteNpz(dir + "/ours.npz", {{"k", EncodeNpy<double>({3, 3}, {1, 0, 2, 0, 1, 3, 0, 0, 1})},
                               {"ids", EncodeNpy<int32_t>({2}, {-1, 7})}});
  WriteNpz(dir + "/ours_empty.npz", {});
  const auto checked =
      RunNumPy(dir, "check.py",
               "a = np.load(d + '/ours.npy')\n"
               "assert a.dtype == np.dtype('<f4') and a.shape == (6, 5), (a.dtype, a.shape)\n"
               "assert (a == 0.25 * np.arange(30, dtype=np.float32).reshape(6, 5)).all()\n"
               "m = np.load(d + '/ours.npy', mmap_mode='r')\n"
               "assert m.offset % 64 == 0, m.offset\n"
               "u = np.load(d + '/ours_u8.npy')\n"
               "assert u.dtype == np.uint64 and u.tolist() == [1, 2, 2**63]\n"
               "z = np.load(d + '/ours.npz')\n"
               "assert sorted(z.files) == ['ids', 'k']\n"
               "assert (z['k'] == [[1, 0, 2], [0, 1, 3], [0, 0, 1]]).all() and z['k'].dtype == "
               "np.float64\n"
               "assert z['ids'].tolist() == [-1, 7] and z['ids'].dtype == np.int32\n"
               "assert np.load(d + '/ours_empty.npz').files == []\n"
               "print('ok')\n");
  EXPECT_EQ(checked.exit_code, 0) << checked.stderr_text;
  EXPECT_EQ(checked.stdout_text, "ok\n");
}

// Strings: '<U<n>' arrays round-trip UTF-8 text (ASCII ids, accents, a CJK character, an
// emoji outside the BMP), are laid out as NumPy's (n = the longest, NUL padding, data at a
// multiple of 64) and are exchanged with NumPy both ways; bad text and bad arrays are refused.
TEST(NpyStrings, RoundTripLayoutAndExchangeWithNumPy) {
  const std::vector<std::string> values = {"000150", "", "caf\xc3\xa9", "\xe6\x88\xbf",
                                           "a\xf0\x9f\x98\x80z"};
  const std::string bytes = EncodeStringsNpy(values, "test");
  EXPECT_EQ(DecodeStringsNpy(bytes, "test"), values);
  const NpyHeader h = ParseNpyHeader(bytes, "test");
  EXPECT_EQ(h.descr, "<U6");
  EXPECT_EQ(h.shape, (std::vector<int64_t>{5}));
  EXPECT_EQ(h.data_offset % 64, 0u);
  EXPECT_EQ(bytes.size(), h.data_offset + 5 * 6 * 4);
  // U+00E9 of "café" is code unit 3 of string 2, little-endian.
  EXPECT_EQ(static_cast<unsigned char>(bytes[h.data_offset + (2 * 6 + 3) * 4]), 0xE9);
  EXPECT_EQ(DecodeStringsNpy(EncodeStringsNpy({}, "test"), "test"), std::vector<std::string>{});
  EXPECT_EQ(ParseNpyHeader(EncodeStringsNpy({}, "test"), "test").descr, "<U1");

  const std::string dir = test::ScratchDir("npy_strings");
  WriteFileAtomic(dir + "/ours.npy", bytes);
  const auto checked =
      RunNumPy(dir, "check.py",
               "a = np.load(d + '/ours.npy')\n"
               "assert a.dtype == np.dtype('<U6'), a.dtype\n"
               "assert a.tolist() == ['000150', '', 'caf\\u00e9', '\\u623f', 'a\\U0001F600z'], a\n"
               "np.save(d + '/numpy.npy', np.array(['x', 'f\\u00fc\\u00df', '000001']))\n"
               "print('ok')\n");
  ASSERT_EQ(checked.exit_code, 0) << checked.stderr_text;
  EXPECT_EQ(DecodeStringsNpy(ReadFileBytes(dir + "/numpy.npy"), "numpy.npy"),
            (std::vector<std::string>{"x", "f\xc3\xbc\xc3\x9f", "000001"}));

  for (const std::string& bad : {std::string("\xff"), std::string("\xc3"), std::string("\xc0\xaf"),
                                 std::string("\xed\xa0\x80")}) {
    ExpectInputError(
        [&] {
          EncodeStringsNpy({"ok", bad}, "frame_ids");
        },
        {"frame_ids", "not UTF-8 text"});
  }
  ExpectInputError(
      [&] {
        DecodeStringsNpy(EncodeNpy<int32_t>({2}, {1, 2}), "ids.npy");
      },
      {"ids.npy", "expected a 1-D '<U' string array, got <i4"});
  std::string cut = bytes;
  cut.resize(cut.size() - 4);
  ExpectInputError([&] { DecodeStringsNpy(cut, "cut.npy"); }, {"cut.npy", "truncated"});
  std::string surrogate = EncodeStringsNpy({"ab"}, "test");
  surrogate[surrogate.size() - 4] = '\x00';
  surrogate[surrogate.size() - 3] = '\xd8';  // U+D800
  ExpectInputError([&] { DecodeStringsNpy(surrogate, "s.npy"); },
                   {"s.npy", "string 0: code unit 55296 is not a Unicode character"});
}

}  // namespace
}  // namespace gt::io

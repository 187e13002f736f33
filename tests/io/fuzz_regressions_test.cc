// Regression cases for the bugs the fuzz targets (tests/fuzz, docs/RELIABILITY.md) found in
// libgt/io, each reduced to the smallest input that showed it, plus the from-memory entry
// points the fuzz targets use agreeing with the file readers.
#include <gtest/gtest.h>

#include <string>

#include "libgt/core/error.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "tests/support/test_support.h"

namespace gt::io {
using namespace gt::datasets;  // NOLINT: the readers' parsers, tested beside the files
namespace {

// The InputError message of `f`, or "" when it does not throw one.
template <typename F>
std::string InputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// fuzz_manifest: a number beyond double's range made nlohmann::json throw out_of_range
// (not parse_error), which escaped the reader as a non-InputError exception.
TEST(FuzzRegressions, ManifestNumberOverflowIsInputError) {
  ReaderOptions options;
  options.check_depth_files = false;
  const std::string msg = InputErrorOf(
      [&] { ParseGenericManifest(R"({"format": 1e999999})", "/x/scene.json", "", options); });
  EXPECT_NE(msg.find("/x/scene.json: not valid JSON"), std::string::npos) << msg;
}

// fuzz_depth_png: arbitrary bytes went to cv::imdecode, which tries every codec OpenCV
// has (JPEG 2000, GDAL through temporary files in /tmp). Only PNG and PGM are depth.
TEST(FuzzRegressions, Png16DepthAcceptsOnlyPngOrPgmBytes) {
  DepthSource s;
  s.path = "d/0.png";
  s.format = DepthFormat::kPng16;
  s.scale_m_per_unit = 0.001;
  for (const std::string& bytes :
       {std::string("\0\0\0\x0cjP  \r\n\x87\n", 12), std::string("II*\0"), std::string("")}) {
    const std::string msg = InputErrorOf([&] { DecodeDepth(bytes, s); });
    EXPECT_EQ(msg, "d/0.png: not a PNG or PGM file (bad signature)");
  }
  // A binary PGM (the ScanNet C++ exporter's .depth.pgm) still decodes.
  const DepthImage d = DecodeDepth(std::string("P5\n2 1\n65535\n\x03\xe8\x00\x00", 17), s);
  ASSERT_EQ(d.width, 2);
  EXPECT_FLOAT_EQ(d.at(0, 0), 1.0f);
  EXPECT_EQ(d.at(1, 0), 0.0f);
}

// fuzz_depth_exr: a 29-byte corrupt header declared a 1.8 GB attribute and OpenEXR
// allocated it before failing (2 s per input under ASan). The header walk refuses it,
// and a data window too large to be a depth map, before OpenEXR runs.
TEST(FuzzRegressions, ExrHeaderSizesAreCheckedBeforeOpenExr) {
  DepthSource s;
  s.path = "d/0.exr";
  s.format = DepthFormat::kExr;
  const std::string crash("v/1\x01\x02\0\0\0\x01\0a\x10\0\0\x87@owCenter\0v2\0\0", 29);
  EXPECT_EQ(InputErrorOf([&] { DecodeDepth(crash, s); }),
            "d/0.exr: cannot read EXR: header attribute '\x01' is larger than the file");
  // Magic, version 2, then dataWindow (0,0)-(99999,0): 100000 pixels wide.
  std::string wide("v/1\x01\x02\0\0\0dataWindow\0box2i\0\x10\0\0\0", 29);
  for (const uint32_t v : {0u, 0u, 99999u, 0u}) {
    for (int k = 0; k < 4; ++k) wide.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
  }
  wide.push_back('\0');
  EXPECT_EQ(InputErrorOf([&] { DecodeDepth(wide, s); }),
            "d/0.exr: cannot read EXR: data window has an empty or implausible size");
  EXPECT_EQ(InputErrorOf([&] { DecodeDepth("not an exr", s); }),
            "d/0.exr: cannot read EXR: not an OpenEXR file (bad magic)");
}

// The from-memory parsers are the file readers' own code: same values, same messages.
TEST(FuzzRegressions, FromMemoryParsersMatchFileReaders) {
  const std::string dir = test::ScratchDir("fuzz_regressions_memory");
  const std::string pose = "1 0 0 0.5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  WriteFileAtomic(dir + "/0.txt", pose);
  EXPECT_EQ(ReadMatrixText(dir + "/0.txt", 4, 4), ParseMatrixText(pose, dir + "/0.txt", 4, 4));
  EXPECT_EQ(InputErrorOf([&] { ParseMatrixText("1 2 x\n", "p.txt", 4, 4); }),
            "p.txt:1: expected a number, found 'x'");

  const std::vector<int32_t> v = {1, 2, 3};
  WriteNpz(dir + "/a.npz", {{"v", EncodeNpy<int32_t>({3}, v)}});
  const auto from_file = ReadNpz(dir + "/a.npz");
  const auto from_bytes = ParseNpz(ReadFileBytes(dir + "/a.npz"), "a.npz");
  ASSERT_EQ(from_bytes.size(), 1u);
  EXPECT_EQ(from_bytes.at("v").data, from_file.at("v").data);
  EXPECT_NE(InputErrorOf([] { ParseNpz("PK\x03\x04junk", "b.npz"); }).find("b.npz: "),
            std::string::npos);

  const auto lines = ParseTQLines("1 2 3 0 0 0 1\n\n4 5 6 0 0 0 1\n", "pose_left.txt");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1].line_no, 3);
  EXPECT_EQ(InputErrorOf([] { ParseTQLines("1 2 3\n", "pose_left.txt"); }),
            "pose_left.txt:1: expected 7 numbers (tx ty tz qx qy qz qw), found 3");
  const auto list = ParseTimedPathList("# c\n2.0 b.png\n1.0 a.png\n", "depth.txt");
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0].file, "a.png");
  EXPECT_EQ(InputErrorOf([] { ParseTimedPathList("nan a.png\n", "depth.txt"); }),
            "depth.txt:1: expected a finite timestamp");
}

}  // namespace
}  // namespace gt::io

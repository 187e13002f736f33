// ScanNet reader: the real sample's poses and intrinsics against an independent parse
// (std::ifstream >> double), numeric frame order, and the bad-input fixtures in
// tests/fixtures/io (lost tracking, short pose file, bad token, empty scene) plus scratch
// scenes for depth PNG sizes and intrinsic_color.txt.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/datasets/scan.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/depth_io.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {
namespace fs = std::filesystem;

const std::string kFixtures = std::string(OCCGT_FIXTURES_DIR) + "/io";

Eigen::Matrix4d ReadMatrixWithStream(const std::string& path) {
  std::ifstream in(path);
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (!(in >> m(r, c))) ADD_FAILURE() << "cannot parse " << path;
    }
  }
  return m;
}

TEST(ScanNet, SamplePosesAndIntrinsicsExact) {
  const std::string root = test::SharedData("scannet_posed_color/scene_sample");
  ASSERT_FALSE(root.empty());
  const auto reader = MakeReader(gt::DatasetFormat::kScanNet);
  ASSERT_EQ(reader->ListScenes(root), std::vector<std::string>{"scene_sample"});
  ASSERT_EQ(reader->ListScenes(fs::path(root).parent_path().string()),
            std::vector<std::string>{"scene_sample"});
  const Scene s = reader->ReadScene(root, "scene_sample");
  EXPECT_EQ(s.min_depth_m, 0.1);
  EXPECT_EQ(s.max_depth_m, 10.0);
  ASSERT_EQ(s.frames.size(), 4u);
  const std::vector<std::string> ids = {"0048", "0054", "0060", "0066"};
  const Eigen::Matrix4d K4 = ReadMatrixWithStream(root + "/intrinsic/intrinsic_depth.txt");
  for (size_t i = 0; i < 4; ++i) {
    const Frame& f = s.frames[i];
    EXPECT_EQ(f.id, ids[i]);
    EXPECT_EQ(f.number, std::stoll(ids[i]));
    EXPECT_EQ(f.depth_camera.fx, K4(0, 0));
    EXPECT_EQ(f.depth_camera.fy, K4(1, 1));
    EXPECT_EQ(f.depth_camera.cx, K4(0, 2));
    EXPECT_EQ(f.depth_camera.cy, K4(1, 2));
    EXPECT_EQ(f.depth_camera.width, 640);  // no depth/ folder: the documented default
    EXPECT_EQ(f.depth_camera.height, 480);
    // Colour is 640x480 in the sample and has no intrinsic_color.txt: the depth K.
    EXPECT_EQ(f.color_path, root + "/color/" + ids[i] + ".png");
    EXPECT_EQ(f.color_camera.width, 640);
    EXPECT_EQ(f.color_camera.height, 480);
    EXPECT_NEAR(f.color_camera.fx, K4(0, 0), 1e-9);
    EXPECT_NEAR(f.color_camera.cx, K4(0, 2), 1e-9);
    EXPECT_FALSE(f.usable);
    EXPECT_EQ(f.unusable_reason, "depth: missing file");
    const Eigen::Matrix4d m = ReadMatrixWithStream(root + "/pose/" + ids[i] + ".txt");
    EXPECT_TRUE((f.world_from_cam.translation() - m.topRightCorner<3, 1>()).isZero(0.0));
    // Rotation re-orthonormalised: equal to the file within its 6-decimal rounding.
    EXPECT_LT((f.world_from_cam.linear() - m.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 2e-5);
  }
}

TEST(ScanNet, LostTrackingTokensMakeFramesUnusableNotFatal) {
  const std::string root = kFixtures + "/scannet_lost_tracking";
  ReaderOptions options;
  options.check_depth_files = false;  // the fixture has no depth: isolate the pose reasons
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet, options)->ReadScene(root, "");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].id, "0");  // numeric order: 0, 7, 12
  EXPECT_EQ(s.frames[1].id, "7");
  EXPECT_EQ(s.frames[2].id, "12");
  EXPECT_TRUE(s.frames[0].usable);
  for (int i : {1, 2}) {
    EXPECT_FALSE(s.frames[i].usable);
    EXPECT_EQ(s.frames[i].unusable_reason, "pose: non-finite pose entries (lost tracking)");
    // The first non-finite value of the file, on its first line.
    EXPECT_EQ(s.frames[i].unusable_detail,
              root + "/pose/" + s.frames[i].id + ".txt:1: non-finite value");
  }
  EXPECT_EQ(s.frames[0].world_from_cam.translation(), Eigen::Vector3d(0.5, 0.25, -1.0));
}

// A bad value in one pose file names the file and its line; non-rigid rotations name the
// row (line) holding the wrong value, a reflection the rotation's lines.
TEST(ScanNet, BadPoseValuesNameFileAndLine) {
  const std::string dir = test::ScratchDir("sn_bad_pose");
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "500 0 320\n0 500 240\n0 0 1\n");
  WriteFileAtomic(dir + "/pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  WriteFileAtomic(dir + "/pose/1.txt", "1 0 0 0\n0 1 0 0\n0 0 1 nan\n0 0 0 1\n");
  WriteFileAtomic(dir + "/pose/2.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 INF\n");
  WriteFileAtomic(dir + "/pose/3.txt", "1 0 0 0\n0.2 1 0 0\n0 0 1 0\n0 0 0 1\n");
  WriteFileAtomic(dir + "/pose/4.txt", "0 1 0 0\n1 0 0 0\n0 0 1 0\n0 0 0 1\n");
  ReaderOptions options;
  options.check_depth_files = false;
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet, options)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 5u);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_EQ(s.frames[1].unusable_detail, dir + "/pose/1.txt:3: non-finite value");
  EXPECT_EQ(s.frames[2].unusable_detail, dir + "/pose/2.txt:4: non-finite value");
  EXPECT_EQ(s.frames[3].unusable_reason, "pose: rotation is not orthonormal (|R^T R - I| > 0.001)");
  EXPECT_EQ(
      s.frames[3].unusable_detail.rfind(dir + "/pose/3.txt:2: rotation is not orthonormal (", 0),
      0u)
      << s.frames[3].unusable_detail;
  EXPECT_EQ(s.frames[4].unusable_detail,
            dir + "/pose/4.txt:1-3: rotation has det < 0 (a reflection)");
}

void ExpectErrorWhere(const std::string& root, const std::string& where, const std::string& text) {
  try {
    MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(root, "");
    ADD_FAILURE() << "expected InputError for " << root;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), where) << e.what();
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

// A malformed per-frame pose file makes its frame unusable, the detail the parse error
// naming the file (and line); the other frames read (it stopped the whole scene).
void ExpectOneMalformedPose(const std::string& root, const std::string& frame_id,
                            const std::string& detail) {
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(root, "");
  int malformed = 0;  // (the fixtures' other frame has no depth file)
  for (const Frame& f : s.frames) {
    if (f.unusable_reason != kReasonPoseMalformed) continue;
    ++malformed;
    EXPECT_EQ(f.id, frame_id);
    EXPECT_EQ(f.unusable_detail, detail);
  }
  EXPECT_EQ(malformed, 1);
  EXPECT_EQ(s.frames.size(), 2u);
}

TEST(ScanNet, ShortPoseFileMakesItsFrameUnusable) {
  ExpectOneMalformedPose(kFixtures + "/scannet_short_pose", "1",
                         kFixtures +
                             "/scannet_short_pose/pose/1.txt: expected 16 numbers (4x4 matrix), "
                             "found 12");
}

TEST(ScanNet, NonNumberTokenMakesItsFrameUnusableWithLine) {
  ExpectOneMalformedPose(
      kFixtures + "/scannet_bad_token", "3",
      kFixtures + "/scannet_bad_token/pose/3.txt:3: expected a number, found 'O.5'");
}

TEST(ScanNet, EmptyOrUnreadablePoseFileMakesItsFrameUnusable) {
  const std::string dir = test::ScratchDir("sn_empty_pose");
  const std::string pose = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "50 0 31.5\n0 50 23.5\n0 0 1\n");
  fs::create_directories(dir + "/depth");
  for (const char* n : {"0", "1", "2"}) {
    WriteFileAtomic(dir + "/pose/" + n + ".txt", pose);
    ASSERT_TRUE(
        cv::imwrite(dir + "/depth/" + n + ".png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(9))));
  }
  WriteFileAtomic(dir + "/pose/1.txt", "");  // an interrupted export
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_FALSE(s.frames[1].usable);
  EXPECT_EQ(s.frames[1].unusable_reason, kReasonPoseMalformed);
  EXPECT_EQ(s.frames[1].unusable_detail,
            dir + "/pose/1.txt: expected 16 numbers (4x4 matrix), found 0");
  EXPECT_TRUE(s.frames[2].usable);
}

TEST(ScanNet, EmptySceneIsFatal) {
  ExpectErrorWhere(kFixtures + "/scannet_empty", kFixtures + "/scannet_empty/pose", "empty scene");
}

TEST(ScanNet, MissingIntrinsicsIsFatal) {
  const std::string dir = test::ScratchDir("sn_no_k");
  WriteFileAtomic(dir + "/pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  ExpectErrorWhere(dir, dir + "/intrinsic/intrinsic_depth.txt", "cannot open");
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "500 0 320\n0 500 240\n0 0 0\n");
  ExpectErrorWhere(dir, dir + "/intrinsic/intrinsic_depth.txt", "expected K");
}

TEST(ScanNet, DepthSizeFromPngAndColourIntrinsicsFile) {
  const std::string dir = test::ScratchDir("sn_depth");
  const std::string pose = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  for (const char* n : {"2", "10", "100"}) WriteFileAtomic(dir + "/pose/" + n + ".txt", pose);
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "200 0 79.5\n0 200 59.5\n0 0 1\n");
  WriteFileAtomic(dir + "/intrinsic/intrinsic_color.txt",
                  "1100 0 647.5 0\n0 1100 483.5 0\n0 0 1 0\n0 0 0 1\n");
  fs::create_directories(dir + "/depth");
  fs::create_directories(dir + "/color");
  cv::Mat depth(120, 160, CV_16UC1, cv::Scalar(1500));
  depth.at<uint16_t>(3, 5) = 0;
  ASSERT_TRUE(cv::imwrite(dir + "/depth/2.png", depth));
  ASSERT_TRUE(cv::imwrite(dir + "/depth/100.png", cv::Mat(60, 80, CV_16UC1, cv::Scalar(1))));
  ASSERT_TRUE(cv::imwrite(dir + "/color/10.jpg", cv::Mat(968, 1296, CV_8UC3, cv::Scalar(1, 2, 3))));
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].id, "2");
  EXPECT_EQ(s.frames[1].id, "10");
  EXPECT_EQ(s.frames[2].id, "100");
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_FALSE(s.frames[1].usable);  // no depth/10.png
  EXPECT_EQ(s.frames[0].depth_camera.width, 160);
  EXPECT_EQ(s.frames[0].depth_camera.height, 120);
  EXPECT_EQ(s.frames[1].color_path, dir + "/color/10.jpg");
  EXPECT_EQ(s.frames[1].color_camera.width, 1296);
  EXPECT_EQ(s.frames[1].color_camera.height, 968);
  EXPECT_EQ(s.frames[1].color_camera.fx, 1100.0);
  EXPECT_EQ(s.frames[1].color_camera.cx, 647.5);
  EXPECT_TRUE(s.frames[0].color_path.empty());
  const DepthImage d = ReadDepth(s.frames[0].depth, 160, 120);
  EXPECT_FLOAT_EQ(d.at(0, 0), 1.5f);
  EXPECT_EQ(d.at(5, 3), 0.0f);
  // Depth of the wrong size (80x60 instead of the scene's 160x120).
  try {
    ReadDepth(s.frames[2].depth, s.frames[2].depth_camera.width, s.frames[2].depth_camera.height);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/depth/100.png");
    EXPECT_NE(std::string(e.what()).find("depth is 80x60, expected 160x120"), std::string::npos);
  }
}

// The C++ SensReader export: frame-XXXXXX.{color.jpg,depth.pgm,pose.txt} + _info.txt, K and
// sizes from _info.txt, depth in units of 1/m_depthShift metres, lost tracking skipped.
void WriteCppExport(const std::string& dir, const std::string& info) {
  const std::string pose = "1 0 0 0.5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  WriteFileAtomic(dir + "/frame-000000.pose.txt", pose);
  WriteFileAtomic(
      dir + "/frame-000001.pose.txt",
      "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n");
  WriteFileAtomic(dir + "/frame-000002.pose.txt", pose);
  WriteFileAtomic(dir + "/_info.txt", info);
  cv::Mat depth(24, 32, CV_16UC1, cv::Scalar(3000));
  depth.at<uint16_t>(2, 7) = 0;
  ASSERT_TRUE(cv::imwrite(dir + "/frame-000000.depth.pgm", depth));
  ASSERT_TRUE(cv::imwrite(dir + "/frame-000001.depth.pgm", depth));
  ASSERT_TRUE(
      cv::imwrite(dir + "/frame-000000.color.jpg", cv::Mat(48, 64, CV_8UC3, cv::Scalar(9))));
}

const char* kCppInfo =
    "m_versionNumber = 4\n"
    "m_sensorName = StructureSensor\n"
    "m_colorWidth = 64\n"
    "m_colorHeight = 48\n"
    "m_depthWidth = 32\n"
    "m_depthHeight = 24\n"
    "m_depthShift = 2000\n"
    "m_calibrationColorIntrinsic = 60 0 31.5 0 0 61 23.5 0 0 0 1 0 0 0 0 1 \n"
    "m_calibrationColorExtrinsic = 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 \n"
    "m_calibrationDepthIntrinsic = 30 0 15.5 0 0 30.5 11.5 0 0 0 1 0 0 0 0 1 \n"
    "m_calibrationDepthExtrinsic = 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 \n"
    "m_frames.size = 3\n";

TEST(ScanNet, CppExporterLayout) {
  const std::string root = test::ScratchDir("sn_cpp");
  const std::string dir = root + "/scene0001_00";
  WriteCppExport(dir, kCppInfo);
  const auto reader = MakeReader(gt::DatasetFormat::kScanNet);
  ASSERT_EQ(reader->ListScenes(root), std::vector<std::string>{"scene0001_00"});
  const Scene s = reader->ReadScene(root, "scene0001_00");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].id, "000000");
  EXPECT_EQ(s.frames[2].number, 2);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_FALSE(s.frames[1].usable);  // -inf pose: lost tracking
  EXPECT_EQ(s.frames[1].unusable_reason, "pose: non-finite pose entries (lost tracking)");
  EXPECT_EQ(s.frames[1].unusable_detail, dir + "/frame-000001.pose.txt:1: non-finite value");
  EXPECT_FALSE(s.frames[2].usable);  // no depth file
  EXPECT_EQ(s.frames[2].unusable_reason, "depth: missing file");
  const Frame& f = s.frames[0];
  EXPECT_EQ(f.depth_camera.width, 32);
  EXPECT_EQ(f.depth_camera.height, 24);
  EXPECT_EQ(f.depth_camera.fx, 30.0);
  EXPECT_EQ(f.depth_camera.fy, 30.5);
  EXPECT_EQ(f.depth_camera.cx, 15.5);
  EXPECT_EQ(f.depth_camera.cy, 11.5);
  EXPECT_EQ(f.color_path, dir + "/frame-000000.color.jpg");
  EXPECT_EQ(f.color_camera.width, 64);
  EXPECT_EQ(f.color_camera.fx, 60.0);
  EXPECT_EQ(f.color_camera.cy, 23.5);
  EXPECT_TRUE(s.frames[2].color_path.empty());
  EXPECT_EQ(f.world_from_cam.translation().x(), 0.5);
  const DepthImage d = ReadDepth(f.depth, 32, 24);
  EXPECT_FLOAT_EQ(d.at(0, 0), 1.5f);  // 3000 / m_depthShift 2000
  EXPECT_EQ(d.at(7, 2), 0.0f);
}

// Two depth (or colour) files for one frame of the C++ export: the export's own .depth.pgm
// (.color.jpg) is read, and the scene says so once for each role.
TEST(ScanNet, CppExporterTwoFilesForAFrameAreNamed) {
  const std::string dir = test::ScratchDir("sn_cpp_two") + "/scene0001_00";
  WriteCppExport(dir, kCppInfo);
  EXPECT_TRUE(MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "").reader_warnings.empty());
  ASSERT_TRUE(
      cv::imwrite(dir + "/frame-000000.depth.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(1))));
  ASSERT_TRUE(
      cv::imwrite(dir + "/frame-000000.color.png", cv::Mat(48, 64, CV_8UC3, cv::Scalar(1))));
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  EXPECT_EQ(s.frames[0].depth.path, dir + "/frame-000000.depth.pgm");
  EXPECT_EQ(s.frames[0].color_path, dir + "/frame-000000.color.jpg");
  EXPECT_EQ(
      s.reader_warnings,
      (std::vector<std::string>{
          "1 frame(s) have two depth files, and each reads the first (the first frame: " + dir +
              "/frame-000000.depth.pgm, not " + dir + "/frame-000000.depth.png)",
          "1 frame(s) have two colour files, and each reads the first (the first frame: " + dir +
              "/frame-000000.color.jpg, not " + dir + "/frame-000000.color.png)"}));
}

TEST(ScanNet, CppExporterBadInfo) {
  const std::string dir = test::ScratchDir("sn_cpp_bad");
  std::string info = kCppInfo;
  WriteCppExport(dir, info.substr(0, info.find("m_depthShift")) +
                          info.substr(info.find("m_calibrationColorIntrinsic")));
  ExpectErrorWhere(dir, dir + "/_info.txt", "m_depthShift: missing");
  WriteFileAtomic(dir + "/_info.txt",
                  "m_depthWidth = 32\nm_depthHeight = 24\nm_depthShift = 1000\n"
                  "m_calibrationDepthIntrinsic = 30 0 15.5 0 30 11.5 0 0 1\n");
  ExpectErrorWhere(dir, dir + "/_info.txt:4", "expected 16 (4x4) or 12 (3x4) numbers, found 9");
  WriteFileAtomic(dir + "/_info.txt",
                  "m_depthWidth = 32\nm_depthHeight = 24\nm_depthShift = 1000\n"
                  "m_calibrationDepthIntrinsic = 0 0 15.5 0 0 30 11.5 0 0 0 1 0\n");
  ExpectErrorWhere(dir, dir + "/_info.txt:4 m_calibrationDepthIntrinsic", "expected K");
  WriteFileAtomic(dir + "/_info.txt",
                  "m_depthWidth = -3\nm_depthHeight = 24\nm_depthShift = 1000\n"
                  "m_calibrationDepthIntrinsic = 30 0 15.5 0 0 30 11.5 0 0 0 1 0\n");
  ExpectErrorWhere(dir, dir + "/_info.txt:1", "positive integer");
  WriteFileAtomic(dir + "/_info.txt",
                  "m_depthWidth = 32\nm_depthHeight = 24\nm_depthShift = nan\n"
                  "m_calibrationDepthIntrinsic = 30 0 15.5 0 0 30 11.5 0 0 0 1 0\n");
  ExpectErrorWhere(dir, dir + "/_info.txt:3", "m_depthShift");
  // A key given twice: refused, not the last value taken (a second m_depthShift scaled every
  // depth silently).
  WriteFileAtomic(dir + "/_info.txt", info + "m_depthShift = 5000\n");
  ExpectErrorWhere(dir, dir + "/_info.txt:13", "m_depthShift: repeats line");
}

// Each frame reads the files listed for its number, whatever their zero padding (pose/54.txt
// beside depth/0054.png and color/0054.jpg: the depth was reported missing); a frame with
// both colour files reads the .jpg and the scene says so (it was picked silently), and the
// scan prints it among its warnings.
TEST(ScanNet, FilesMatchByNumberAndTwoColourFilesAreNamed) {
  const std::string dir = test::ScratchDir("sn_padding");
  const std::string pose = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "50 0 31.5\n0 50 23.5\n0 0 1\n");
  fs::create_directories(dir + "/depth");
  fs::create_directories(dir + "/color");
  for (const char* n : {"53", "54"}) {
    WriteFileAtomic(dir + "/pose/" + n + ".txt", pose);
    const std::string padded = std::string("00") + n;
    ASSERT_TRUE(
        cv::imwrite(dir + "/depth/" + padded + ".png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(9))));
    ASSERT_TRUE(
        cv::imwrite(dir + "/color/" + padded + ".jpg", cv::Mat(48, 64, CV_8UC3, cv::Scalar(9))));
  }
  ASSERT_TRUE(cv::imwrite(dir + "/color/0054.png", cv::Mat(48, 64, CV_8UC3, cv::Scalar(9))));
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 2u);
  for (const Frame& f : s.frames) {
    EXPECT_TRUE(f.usable) << f.id << ": " << f.UnusableMessage();
    EXPECT_EQ(f.depth.path, dir + "/depth/00" + f.id + ".png");
    EXPECT_EQ(f.color_path, dir + "/color/00" + f.id + ".jpg");
  }
  ASSERT_EQ(s.reader_warnings.size(), 1u);
  EXPECT_EQ(s.reader_warnings[0],
            "1 frame(s) have two colour files, and each reads the first (the first frame: " + dir +
                "/color/0054.jpg, not " + dir + "/color/0054.png)");
  const SceneSummary summary = SummarizeScene(s, ScanOptions{});
  EXPECT_NE(std::find(summary.warnings.begin(), summary.warnings.end(), s.reader_warnings[0]),
            summary.warnings.end());
}

// A frame with depth and colour but no pose file is listed, unusable ("pose: missing
// file", the detail naming the pose file expected), and `occgt scan` counts it; in both
// exported layouts. Before, frames were listed from the pose files only: it vanished.
TEST(ScanNet, FrameWithoutPoseFileIsCountedUnusable) {
  const std::string dir = test::ScratchDir("sn_no_pose");
  const std::string pose = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "50 0 31.5\n0 50 23.5\n0 0 1\n");
  fs::create_directories(dir + "/depth");
  fs::create_directories(dir + "/color");
  for (const char* n : {"0", "1", "2"}) {
    if (std::string(n) != "1") WriteFileAtomic(dir + "/pose/" + n + ".txt", pose);
    ASSERT_TRUE(
        cv::imwrite(dir + "/depth/" + n + ".png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(9))));
    ASSERT_TRUE(cv::imwrite(dir + "/color/" + n + ".jpg", cv::Mat(48, 64, CV_8UC3, cv::Scalar(9))));
  }
  ASSERT_TRUE(cv::imwrite(dir + "/depth/3.png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(9))));
  const Scene s = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 4u);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_TRUE(s.frames[2].usable);
  for (int i : {1, 3}) {
    const Frame& f = s.frames[i];
    EXPECT_EQ(f.id, std::to_string(i));
    EXPECT_EQ(f.number, i);
    EXPECT_FALSE(f.usable);
    EXPECT_EQ(f.unusable_reason, "pose: missing file");
    EXPECT_EQ(f.unusable_detail, dir + "/pose/" + std::to_string(i) + ".txt");
    EXPECT_EQ(f.depth.path, dir + "/depth/" + std::to_string(i) + ".png");
  }
  EXPECT_EQ(s.frames[1].color_path, dir + "/color/1.jpg");
  const SceneSummary sum = SummarizeScene(s, ScanOptions());
  EXPECT_EQ(sum.usable, 2u);
  EXPECT_EQ(sum.unusable_reasons.at("pose: missing file"), 2u);

  // The C++ exporter's layout: frame-000003 has depth and colour but no .pose.txt.
  const std::string cpp = test::ScratchDir("sn_cpp_no_pose");
  WriteCppExport(cpp, kCppInfo);
  ASSERT_TRUE(
      cv::imwrite(cpp + "/frame-000003.depth.pgm", cv::Mat(24, 32, CV_16UC1, cv::Scalar(9))));
  ASSERT_TRUE(
      cv::imwrite(cpp + "/frame-000003.color.jpg", cv::Mat(48, 64, CV_8UC3, cv::Scalar(9))));
  const Scene c = MakeReader(gt::DatasetFormat::kScanNet)->ReadScene(cpp, "");
  ASSERT_EQ(c.frames.size(), 4u);
  EXPECT_EQ(c.frames[3].id, "000003");
  EXPECT_EQ(c.frames[3].unusable_reason, "pose: missing file");
  EXPECT_EQ(c.frames[3].unusable_detail, cpp + "/frame-000003.pose.txt");
  EXPECT_EQ(c.frames[3].color_path, cpp + "/frame-000003.color.jpg");
}

// An export whose colour was resized to 64x48 beside the intrinsic_color.txt of the
// 1296x968 original: the colour K's principal point (647.5, 483.5) lies outside the image,
// which `occgt scan` says in one line naming the file and both sizes. Consistent data (the
// 1296x968 image of DepthSizeFromPngAndColourIntrinsicsFile's K) gets no such warning.
TEST(ScanNet, ColourKOutsideTheColourImageIsReported) {
  const std::string dir = test::ScratchDir("sn_color_k");
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "50 0 31.5\n0 50 23.5\n0 0 1\n");
  const std::string color_k = dir + "/intrinsic/intrinsic_color.txt";
  WriteFileAtomic(color_k, "1100 0 647.5 0\n0 1100 483.5 0\n0 0 1 0\n0 0 0 1\n");
  WriteFileAtomic(dir + "/pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  fs::create_directories(dir + "/depth");
  fs::create_directories(dir + "/color");
  ASSERT_TRUE(cv::imwrite(dir + "/depth/0.png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(9))));
  ASSERT_TRUE(cv::imwrite(dir + "/color/0.jpg", cv::Mat(48, 64, CV_8UC3, cv::Scalar(9))));
  const auto reader = MakeReader(gt::DatasetFormat::kScanNet);
  const Scene s = reader->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 1u);
  EXPECT_EQ(s.frames[0].color_camera.cx, 647.5);  // unchanged: reported, not corrected
  const auto warning_about = [](const SceneSummary& sum, const std::string& text) {
    for (const std::string& w : sum.warnings) {
      if (w.find(text) != std::string::npos) return w;
    }
    return std::string();
  };
  const std::string w = warning_about(SummarizeScene(s, ScanOptions()), "principal point");
  EXPECT_EQ(w.rfind(color_k + ": principal point (647.5, 483.5) lies outside the 64x48 colour "
                              "image (1 of 1 frames with colour; first: frame 0): expected a K "
                              "for 64x48 images",
                    0),
            0u)
      << w;
  EXPECT_EQ(w.find('\n'), std::string::npos);
  // The same K at the original size is consistent.
  ASSERT_TRUE(cv::imwrite(dir + "/color/0.jpg", cv::Mat(968, 1296, CV_8UC3, cv::Scalar(9))));
  EXPECT_EQ(
      warning_about(SummarizeScene(reader->ReadScene(dir, ""), ScanOptions()), "principal point"),
      "");
}

// A depth K of another size than the depth maps (a 64x48 K beside 32x24 depth): the depth
// K's principal point (31.5, 23.5) is at the far edge of the 32x24 depth map, outside its
// central half, which `occgt scan` says in one line (only the colour K was checked).
TEST(ScanNet, DepthKOutsideTheDepthMapIsReported) {
  const std::string dir = test::ScratchDir("sn_depth_k");
  WriteFileAtomic(dir + "/intrinsic/intrinsic_depth.txt", "50 0 31.5\n0 50 23.5\n0 0 1\n");
  WriteFileAtomic(dir + "/pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  fs::create_directories(dir + "/depth");
  ASSERT_TRUE(cv::imwrite(dir + "/depth/0.png", cv::Mat(24, 32, CV_16UC1, cv::Scalar(9))));
  const auto reader = MakeReader(gt::DatasetFormat::kScanNet);
  const std::vector<std::string> warnings =
      SummarizeScene(reader->ReadScene(dir, ""), ScanOptions()).warnings;
  const std::string want =
      "depth K: principal point (31.5, 23.5) lies outside the central half of the 32x24 depth "
      "map (1 of 1 frames; "
      "first: frame 0): expected a K for 32x24 depth maps (intrinsics of another size?); every "
      "label of these frames would be misplaced";
  EXPECT_NE(std::find(warnings.begin(), warnings.end(), want), warnings.end())
      << ::testing::PrintToString(warnings);
  // The same K beside 64x48 depth maps is consistent.
  ASSERT_TRUE(cv::imwrite(dir + "/depth/0.png", cv::Mat(48, 64, CV_16UC1, cv::Scalar(9))));
  for (const std::string& w : SummarizeScene(reader->ReadScene(dir, ""), ScanOptions()).warnings) {
    EXPECT_EQ(w.find("principal point"), std::string::npos) << w;
  }
}

// A scene folder whose name is not UTF-8 is refused when the scenes are listed, naming the
// folder: `occgt build` failed at its first JSON line with nlohmann's "invalid UTF-8 byte",
// naming no file, and `scan --json` likewise.
TEST(ScanNet, SceneFolderNameThatIsNotUtf8IsRefused) {
  const std::string root = test::ScratchDir("sn_utf8");
  for (const std::string name : {std::string("scene0000_00"), std::string("sc\xff")}) {
    WriteFileAtomic(root + "/" + name + "/pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  }
  const auto reader = MakeReader(gt::DatasetFormat::kScanNet);
  EXPECT_EQ(reader->ListScenes(root).size(), 2u);
  try {
    ListSceneNames(*reader, root);
    ADD_FAILURE() << "a name that is not UTF-8";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              root +
                  "/sc\xff: the scene's folder name is not UTF-8 text (occgt names each "
                  "scene by it in JSON and Python): rename the folder");
  }
  fs::remove_all(root + "/sc\xff");
  WriteFileAtomic(root + "/sc\xc3\xa9ne/pose/0.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  // UTF-8: accepted (sorted by bytes).
  EXPECT_EQ(ListSceneNames(*reader, root),
            (std::vector<std::string>{"scene0000_00", "sc\xc3\xa9ne"}));
}

}  // namespace
}  // namespace gt::datasets

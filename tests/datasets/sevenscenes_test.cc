// 7-Scenes reader on the real sample (sevenscenes/rgbd-frames, frames 150-199): frame
// listing, K from camera-intrinsics.txt, poses parsed independently, depth markers
// (0 and 65535 -> 0) against a direct OpenCV decode, and reprojection of 150 <-> 160.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/datasets/scan.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "tests/datasets/consistency.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {

TEST(SevenScenes, SampleFramesIntrinsicsAndPoses) {
  const std::string parent = test::SharedData("sevenscenes");
  ASSERT_FALSE(parent.empty());
  const auto reader = MakeReader(gt::DatasetFormat::kSevenScenes);
  ASSERT_EQ(reader->ListScenes(parent), std::vector<std::string>{"rgbd-frames"});
  const std::string root = parent + "/rgbd-frames";
  ASSERT_EQ(reader->ListScenes(root), std::vector<std::string>{"rgbd-frames"});
  const Scene s = reader->ReadScene(parent, "rgbd-frames");
  ASSERT_EQ(s.frames.size(), 50u);
  EXPECT_EQ(s.NumUsable(), 50u);
  // camera-intrinsics.txt, read with >>.
  std::ifstream kin(parent + "/camera-intrinsics.txt");
  double K[9];
  for (double& k : K) ASSERT_TRUE(kin >> k);
  for (size_t i = 0; i < s.frames.size(); ++i) {
    const Frame& f = s.frames[i];
    char id[32];
    std::snprintf(id, sizeof(id), "%06zu", 150 + i);
    ASSERT_EQ(f.id, id);
    EXPECT_EQ(f.number, static_cast<int64_t>(150 + i));
    EXPECT_EQ(f.depth_camera.fx, K[0]);
    EXPECT_EQ(f.depth_camera.cx, K[2]);
    EXPECT_EQ(f.depth_camera.fy, K[4]);
    EXPECT_EQ(f.depth_camera.cy, K[5]);
    EXPECT_EQ(f.depth_camera.width, 640);
    EXPECT_EQ(f.depth_camera.height, 480);
    EXPECT_EQ(f.depth.invalid_value, 65535);
    EXPECT_EQ(f.depth.scale_m_per_unit, 0.001);
    std::ifstream pin(root + "/frame-" + f.id + ".pose.txt");
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) ASSERT_TRUE(pin >> m(r, c));
    }
    // RigidFromMatrix re-orthonormalises R; the files are orthonormal to ~6e-5 only.
    EXPECT_LT((f.world_from_cam.matrix() - m).cwiseAbs().maxCoeff(), 2e-4) << f.id;
    EXPECT_TRUE((f.world_from_cam.translation() - m.topRightCorner<3, 1>()).isZero(0.0)) << f.id;
  }
}

TEST(SevenScenes, DepthMarkersBecomeZeroAndMillimetresMetres) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  ASSERT_FALSE(root.empty());
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(root, "");
  const Frame& f = s.frames[0];
  const DepthImage d = ReadDepth(f.depth, 640, 480);
  const cv::Mat raw = cv::imread(f.depth.path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  long invalid_raw = 0;
  for (int v = 0; v < raw.rows; ++v) {
    for (int u = 0; u < raw.cols; ++u) {
      const uint16_t r = raw.at<uint16_t>(v, u);
      if (r == 0 || r == 65535) {
        ++invalid_raw;
        ASSERT_EQ(d.at(u, v), 0.0f);
      } else {
        ASSERT_FLOAT_EQ(d.at(u, v), r * 0.001f);
      }
    }
  }
  EXPECT_GT(invalid_raw, 0);  // the sample has holes: the branch above was exercised
}

TEST(SevenScenes, Frames150And160ReprojectConsistently) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  ASSERT_FALSE(root.empty());
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(root, "");
  const Frame& a = s.frames[0];
  const Frame& b = s.frames[10];
  ASSERT_EQ(a.id, "000150");
  ASSERT_EQ(b.id, "000160");
  const DepthImage da = ReadDepth(a.depth, 640, 480);
  const DepthImage db = ReadDepth(b.depth, 640, 480);
  const auto ab = test::DepthConsistency(da, a.depth_camera, a.world_from_cam, db, b.depth_camera,
                                         b.world_from_cam, s.min_depth_m, s.max_depth_m, 0.05);
  const auto ba = test::DepthConsistency(db, b.depth_camera, b.world_from_cam, da, a.depth_camera,
                                         a.world_from_cam, s.min_depth_m, s.max_depth_m, 0.05);
  EXPECT_GT(ab.compared, 50000);
  EXPECT_GE(ab.fraction(), 0.95);
  EXPECT_GE(ba.fraction(), 0.95);
  // Negative control: swapping the poses (a wrong convention) must do much worse.
  const auto swapped =
      test::DepthConsistency(da, a.depth_camera, a.world_from_cam.inverse(), db, b.depth_camera,
                             b.world_from_cam.inverse(), s.min_depth_m, s.max_depth_m, 0.05);
  std::printf("7-Scenes 150->160 %.4f, 160->150 %.4f, inverted poses %.4f\n", ab.fraction(),
              ba.fraction(), swapped.fraction());
  EXPECT_LT(swapped.fraction(), ab.fraction() - 0.2) << swapped.fraction();
}

TEST(SevenScenes, WrongDepthSizeNamesTheFile) {
  const std::string root = test::SharedData("sevenscenes/rgbd-frames");
  ASSERT_FALSE(root.empty());
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(root, "");
  try {
    ReadDepth(s.frames[0].depth, 320, 240);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), s.frames[0].depth.path);
    EXPECT_NE(std::string(e.what()).find("depth is 640x480, expected 320x240"), std::string::npos)
        << e.what();
  }
}

TEST(SevenScenes, EmptyAndMissingFolders) {
  const auto reader = MakeReader(gt::DatasetFormat::kSevenScenes);
  const std::string empty = test::ScratchDir("7s_empty");
  try {
    reader->ListScenes(empty);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), empty);
  }
  try {
    reader->ReadScene(empty, "seq-01");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), empty + "/seq-01");
  }
  try {
    reader->ReadScene(empty + "/nope", "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), empty + "/nope");
  }
}

TEST(SevenScenes, MissingDepthIsUnusableNotFatal) {
  const std::string dir = test::ScratchDir("7s_missing_depth");
  WriteFileAtomic(dir + "/seq-01/frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(dir, "seq-01");
  ASSERT_EQ(s.frames.size(), 1u);
  EXPECT_FALSE(s.frames[0].usable);
  EXPECT_EQ(s.frames[0].unusable_reason, "depth: missing file");
  EXPECT_EQ(s.frames[0].depth_camera.fx, 585.0);  // default K without camera-intrinsics.txt
}

// A frame with depth and colour but no .pose.txt is listed, unusable ("pose: missing
// file", the detail naming the pose file expected), and counted by `occgt scan`; before,
// frames were listed from the pose files only and it vanished.
TEST(SevenScenes, FrameWithoutPoseFileIsCountedUnusable) {
  const std::string dir = test::ScratchDir("7s_no_pose") + "/seq-01";
  for (const char* id : {"000000", "000001", "000002"}) {
    const std::string base = dir + "/frame-" + id;
    if (std::string(id) != "000001") {
      WriteFileAtomic(base + ".pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    }
    ASSERT_TRUE(cv::imwrite(base + ".depth.png", cv::Mat(480, 640, CV_16UC1, cv::Scalar(900))));
    ASSERT_TRUE(cv::imwrite(base + ".color.png", cv::Mat(480, 640, CV_8UC3, cv::Scalar(9))));
  }
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_TRUE(s.frames[2].usable);
  const Frame& f = s.frames[1];
  EXPECT_EQ(f.id, "000001");
  EXPECT_FALSE(f.usable);
  EXPECT_EQ(f.unusable_reason, "pose: missing file");
  EXPECT_EQ(f.unusable_detail, dir + "/frame-000001.pose.txt");
  EXPECT_EQ(f.color_path, dir + "/frame-000001.color.png");
  const SceneSummary sum = SummarizeScene(s, ScanOptions());
  EXPECT_EQ(sum.frames, 3u);
  EXPECT_EQ(sum.usable, 2u);
  EXPECT_EQ(sum.unusable_reasons.at("pose: missing file"), 1u);
}

// Releases ship colour as frame-NNNNNN.color.png or .color.jpg: both are read; a frame
// with neither has no colour (and is counted by a build that asks for images).
TEST(SevenScenes, ColourAsPngOrJpgAndFramesWithout) {
  const std::string real = test::SharedData("sevenscenes/rgbd-frames");
  ASSERT_FALSE(real.empty());
  const std::string dir = test::ScratchDir("7s_color_jpg");
  for (const char* id : {"000150", "000151", "000152"}) {
    const std::string base = std::string("/frame-") + id;
    for (const char* f : {".pose.txt", ".depth.png"}) {
      WriteFileAtomic(dir + "/seq-01" + base + f, ReadFileBytes(real + base + f));
    }
  }
  const cv::Mat bgr = cv::imread(real + "/frame-000150.color.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(bgr.empty());
  std::vector<uint8_t> jpg;
  ASSERT_TRUE(cv::imencode(".jpg", bgr, jpg));
  WriteFileAtomic(dir + "/seq-01/frame-000150.color.jpg", std::string(jpg.begin(), jpg.end()));
  WriteFileAtomic(dir + "/seq-01/frame-000151.color.png",
                  ReadFileBytes(real + "/frame-000151.color.png"));
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(dir, "seq-01");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].color_path, dir + "/seq-01/frame-000150.color.jpg");
  EXPECT_EQ(s.frames[1].color_path, dir + "/seq-01/frame-000151.color.png");
  EXPECT_TRUE(s.frames[2].color_path.empty());
  EXPECT_EQ(s.frames[0].color_camera.width, 640);
  const ColorImage c = ReadColor(s.frames[0].color_path);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_TRUE(s.reader_warnings.empty());
  // Both files for one frame: the .png is read, and the scene says so (it was silent).
  WriteFileAtomic(dir + "/seq-01/frame-000151.color.jpg", std::string(jpg.begin(), jpg.end()));
  const Scene both = MakeReader(gt::DatasetFormat::kSevenScenes)->ReadScene(dir, "seq-01");
  EXPECT_EQ(both.frames[1].color_path, dir + "/seq-01/frame-000151.color.png");
  ASSERT_EQ(both.reader_warnings.size(), 1u);
  EXPECT_EQ(both.reader_warnings[0],
            "1 frame(s) have two colour files, and each reads the first (the first frame: " + dir +
                "/seq-01/frame-000151.color.png, not " + dir + "/seq-01/frame-000151.color.jpg)");
}

// One pose file per frame: a bad pose names its file and the line (1..4 of the matrix, as
// the file lays it out) where the bad value is; the frame is unusable, not the scene.
TEST(SevenScenes, BadPoseValuesNameFileAndLine) {
  const std::string dir = test::ScratchDir("7s_bad_pose") + "/seq-01";
  const std::vector<std::pair<std::string, std::string>> poses = {
      {"000000", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"},
      {"000001", "1 0 0 0\n0 1 NaN 0\n0 0 1 0\n0 0 0 1\n"},
      {"000002", "\n1 0 0 0\n0 1 0 inf\n0 0 1 0\n0 0 0 1\n"},  // a blank first line
      {"000003", "1 0 0 0\n0 1 0 0\n0 0 1.5 0\n0 0 0 1\n"},    // a typo in row 3
      {"000004", "1 0 0 0\n0 -1 0 0\n0 0 1 0\n0 0 0 1\n"},
      {"000005", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n"},
      {"000006", "1 0 0 0 0 1 0 0\n0 0 1 0 0 0 0 -inf\n"},  // two rows a line
  };
  for (const auto& [id, text] : poses) WriteFileAtomic(dir + "/frame-" + id + ".pose.txt", text);
  ReaderOptions options;
  options.check_depth_files = false;  // no depth: isolate the pose reasons
  const Scene s = MakeReader(gt::DatasetFormat::kSevenScenes, options)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), poses.size());
  EXPECT_TRUE(s.frames[0].usable);
  const auto file = [&](int i) { return dir + "/frame-00000" + std::to_string(i) + ".pose.txt"; };
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"pose: non-finite pose entries (lost tracking)", file(1) + ":2: non-finite value"},
      {"pose: non-finite pose entries (lost tracking)", file(2) + ":3: non-finite value"},
      {"pose: rotation is not orthonormal (|R^T R - I| > 0.001)",
       file(3) + ":3: rotation is not orthonormal (|R^T R - I| = 1.25 > 0.001)"},
      {"pose: rotation has det < 0 (a reflection)",
       file(4) + ":1-3: rotation has det < 0 (a reflection)"},
      {"pose: last row of the pose is not [0 0 0 1]",
       file(5) + ":4: last row of the pose is not [0 0 0 1]"},
      {"pose: non-finite pose entries (lost tracking)", file(6) + ":2: non-finite value"},
  };
  for (size_t i = 1; i < s.frames.size(); ++i) {
    EXPECT_FALSE(s.frames[i].usable) << i;
    EXPECT_EQ(s.frames[i].unusable_reason, expected[i - 1].first) << i;
    EXPECT_EQ(s.frames[i].unusable_detail, expected[i - 1].second) << i;
  }
}

// The dataset root as the release unzips it (7scenes/chess/seq-01, 7scenes/fire/seq-01):
// every sequence of every scene, named <scene>/<sequence> so that the two seq-01 do not
// collide; camera-intrinsics.txt found at the dataset root. A root mixing sequence folders
// with scene folders of sequences, or holding no sequence at any depth, is refused.
TEST(SevenScenes, DatasetRootNamesSceneAndSequence) {
  const std::string root = test::ScratchDir("7s_dataset_root");
  const auto sequence = [](const std::string& dir, const std::string& translation) {
    WriteFileAtomic(dir + "/frame-000000.pose.txt",
                    "1 0 0 " + translation + "\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  };
  sequence(root + "/chess/seq-01", "1");
  sequence(root + "/chess/seq-02", "2");
  sequence(root + "/fire/seq-01", "3");
  WriteFileAtomic(root + "/fire/TestSplit.txt", "sequence1\n");  // files beside are ignored
  WriteFileAtomic(root + "/camera-intrinsics.txt", "500 0 321\n0 501 239\n0 0 1\n");
  ReaderOptions options;
  options.check_depth_files = false;
  const auto reader = MakeReader(gt::DatasetFormat::kSevenScenes, options);
  const std::vector<std::string> names = ListSceneNames(*reader, root);
  EXPECT_EQ(names, (std::vector<std::string>{"chess/seq-01", "chess/seq-02", "fire/seq-01"}));
  const std::vector<double> tx = {1, 2, 3};
  for (size_t i = 0; i < names.size(); ++i) {
    const Scene s = reader->ReadScene(root, names[i]);
    EXPECT_EQ(s.name, names[i]);
    ASSERT_EQ(s.frames.size(), 1u);
    EXPECT_DOUBLE_EQ(s.frames[0].world_from_cam.translation().x(), tx[i]) << names[i];
    EXPECT_EQ(s.frames[0].depth_camera.fx, 500.0);  // the dataset root's K
    EXPECT_EQ(s.frames[0].depth_camera.cy, 239.0);
  }
  // A scene folder's own K comes first.
  WriteFileAtomic(root + "/fire/camera-intrinsics.txt", "400 0 320\n0 400 240\n0 0 1\n");
  EXPECT_EQ(reader->ReadScene(root, "fire/seq-01").frames[0].depth_camera.fx, 400.0);
  EXPECT_EQ(reader->ReadScene(root, "chess/seq-01").frames[0].depth_camera.fx, 500.0);
  // The scene folder as root keeps its names.
  EXPECT_EQ(ListSceneNames(*reader, root + "/chess"),
            (std::vector<std::string>{"seq-01", "seq-02"}));

  sequence(root + "/seq-09", "0");  // a sequence beside the scene folders
  try {
    reader->ListScenes(root);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root);
    EXPECT_NE(std::string(e.what()).find("sequence folders (seq-09) beside scene folders of "
                                         "sequences (chess/seq-01)"),
              std::string::npos)
        << e.what();
  }
  const std::string none = test::ScratchDir("7s_dataset_root_none");
  WriteFileAtomic(none + "/chess/notes.txt", "x\n");
  EXPECT_THROW(reader->ListScenes(none), InputError);
}

}  // namespace
}  // namespace gt::datasets

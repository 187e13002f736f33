// TUM RGB-D reader on a hand-made sequence written into a scratch folder with known
// answers: nearest-in-time association of poses and colour (including timestamps that do
// not associate), intrinsics by sequence name, depth scale 1/5000, and bad files.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/datasets/scan.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/depth_io.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {

// depth at t = 10.00, 10.10, 10.20, 10.50; groundtruth at 9.99 (x=1), 10.015 (x=2),
// 10.115 (x=3), 10.30 (x=4), 10.51 (x=5, bad quaternion); rgb at 10.005, 10.13, 10.49.
std::string MakeSequence(const std::string& name) {
  const std::string dir = test::ScratchDir(name);
  WriteFileAtomic(dir + "/depth.txt",
                  "# depth maps\n# file: 'x.bag'\n# timestamp filename\n"
                  "10.100000 depth/10.100000.png\n"  // out of order on purpose
                  "10.000000 depth/10.000000.png\n"
                  "10.200000 depth/10.200000.png\n"
                  "10.500000 depth/10.500000.png\n");
  WriteFileAtomic(dir + "/rgb.txt",
                  "# color images\n10.005 rgb/10.005.png\n10.130 rgb/10.130.png\n"
                  "10.490 rgb/10.490.png\n");
  WriteFileAtomic(dir + "/groundtruth.txt",
                  "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
                  "9.99 1 0 0 0 0 0 1\n"
                  "10.015 2 0 0 0 0 0 1\n"
                  "10.115 3 0 0 0 0.7071067811865476 0 0.7071067811865476\n"
                  "10.30 4 0 0 0 0 0 1\n"
                  "10.51 5 0 0 0 0 0 2\n");
  std::filesystem::create_directories(dir + "/depth");
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(5000));
  depth.at<uint16_t>(10, 20) = 0;
  depth.at<uint16_t>(11, 20) = 12345;
  for (const char* t : {"10.000000", "10.100000", "10.500000"}) {
    EXPECT_TRUE(cv::imwrite(dir + "/depth/" + t + ".png", depth));
  }
  std::filesystem::create_directories(dir + "/rgb");
  for (const char* t : {"10.005", "10.130", "10.490"}) {
    EXPECT_TRUE(cv::imwrite(dir + "/rgb/" + t + ".png", cv::Mat(480, 640, CV_8UC3, cv::Scalar(9))));
  }
  return dir;
}

TEST(Tum, AssociatesNearestWithinTolerance) {
  const std::string root = MakeSequence("rgbd_dataset_freiburg2_xyz");
  const auto reader = MakeReader(gt::DatasetFormat::kTum);
  ASSERT_EQ(reader->ListScenes(root), std::vector<std::string>{"rgbd_dataset_freiburg2_xyz"});
  const Scene s = reader->ReadScene(root, "");
  ASSERT_EQ(s.frames.size(), 4u);
  // Sorted by time.
  EXPECT_EQ(s.frames[0].id, "10.000000");
  EXPECT_EQ(s.frames[1].id, "10.100000");
  EXPECT_EQ(s.frames[2].id, "10.200000");
  EXPECT_EQ(s.frames[3].id, "10.500000");
  EXPECT_DOUBLE_EQ(s.frames[1].timestamp_s, 10.1);
  // t=10.00: gt 9.99 (dt 0.010) beats 10.015 (dt 0.015); rgb 10.005.
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_EQ(s.frames[0].world_from_cam.translation().x(), 1.0);
  EXPECT_EQ(s.frames[0].color_path, root + "/rgb/10.005.png");
  // t=10.10: gt 10.115 (dt 0.015, a 90 degree turn about y); rgb 10.13 is 0.03 away: none.
  EXPECT_TRUE(s.frames[1].usable);
  EXPECT_EQ(s.frames[1].world_from_cam.translation().x(), 3.0);
  EXPECT_NEAR(
      (s.frames[1].world_from_cam.linear() * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX())
          .norm(),
      0.0, 1e-12);
  EXPECT_TRUE(s.frames[1].color_path.empty());
  // t=10.20: nearest gt is 0.085 (10.115) / 0.10 (10.30) away: unusable; and no depth file.
  EXPECT_FALSE(s.frames[2].usable);
  EXPECT_EQ(s.frames[2].unusable_reason, "pose: no groundtruth within 0.02s");
  // t=10.50: gt 10.51 has a quaternion of norm 2.
  EXPECT_FALSE(s.frames[3].usable);
  EXPECT_EQ(s.frames[3].unusable_reason, "pose: quaternion norm is not within 0.001 of 1");
  EXPECT_EQ(s.frames[3].unusable_detail,
            root + "/groundtruth.txt:7: quaternion norm is 2, expected 1");
  EXPECT_TRUE(s.frames[2].unusable_detail.empty());  // the reason says it all
  EXPECT_EQ(s.frames[3].color_path, root + "/rgb/10.490.png");
  // fr2 intrinsics by folder name, depth 1/5000 m.
  EXPECT_EQ(s.frames[0].depth_camera.fx, 520.9);
  EXPECT_EQ(s.frames[0].depth_camera.cy, 249.7);
  const DepthImage d = ReadDepth(s.frames[0].depth, 640, 480);
  EXPECT_FLOAT_EQ(d.at(0, 0), 1.0f);
  EXPECT_EQ(d.at(20, 10), 0.0f);
  EXPECT_FLOAT_EQ(d.at(20, 11), 12345.0f / 5000.0f);
}

TEST(Tum, WiderToleranceAssociatesMore) {
  const std::string root = MakeSequence("rgbd_dataset_freiburg3_office");
  ReaderOptions options;
  options.tum_max_dt_s = 0.09;
  const Scene s = MakeReader(gt::DatasetFormat::kTum, options)->ReadScene(root, "");
  EXPECT_TRUE(s.frames[1].usable);
  EXPECT_EQ(s.frames[1].color_path, root + "/rgb/10.130.png");
  EXPECT_EQ(s.frames[2].world_from_cam.translation().x(), 3.0);  // 10.115 is 0.085 away
  EXPECT_EQ(s.frames[2].unusable_reason, "depth: missing file");
  EXPECT_EQ(s.frames[0].depth_camera.fx, 535.4);  // fr3
  options.tum_max_dt_s = -1;
  EXPECT_THROW(MakeReader(gt::DatasetFormat::kTum, options), InputError);
}

TEST(Tum, DefaultIntrinsicsAreFreiburg1) {
  const std::string root = MakeSequence("my_sequence");
  const Scene s = MakeReader(gt::DatasetFormat::kTum)->ReadScene(root, "");
  EXPECT_EQ(s.frames[0].depth_camera.fx, 517.3);
  EXPECT_EQ(s.frames[0].depth_camera.cy, 255.3);
}

// The warnings of `occgt scan` for a TUM scene that contain `text`.
std::vector<std::string> ScanWarnings(const Scene& scene, const std::string& text) {
  std::vector<std::string> out;
  for (const std::string& w : SummarizeScene(scene, ScanOptions()).warnings) {
    if (w.find(text) != std::string::npos) out.push_back(w);
  }
  return out;
}

// A folder name naming no freiburg sequence gets fr1's K: `occgt scan` says it was assumed,
// which K and why, in one line; a named sequence gets no such warning.
TEST(Tum, ScanSaysWhenTheKIsAssumed) {
  const auto reader = MakeReader(gt::DatasetFormat::kTum);
  const std::vector<std::string> assumed =
      ScanWarnings(reader->ReadScene(MakeSequence("my_sequence"), ""), "TUM intrinsics");
  ASSERT_EQ(assumed.size(), 1u);
  EXPECT_EQ(assumed[0],
            "TUM intrinsics assumed: fr1 (fx 517.3, fy 516.5, cx 318.6, cy 255.3), as the folder "
            "name 'my_sequence' names no freiburg1/2/3 (fr1/fr2/fr3); name the folder after its "
            "TUM sequence (rgbd_dataset_freiburg3_...) to get its K");
  for (const char* named : {"rgbd_dataset_freiburg1_desk", "rgbd_dataset_freiburg2_xyz", "fr3_x"}) {
    EXPECT_TRUE(ScanWarnings(reader->ReadScene(MakeSequence(named), ""), "TUM intrinsics").empty())
        << named;
  }
}

// An rgb.txt entry whose image does not exist gives no colour (as the folder readers do for
// a missing colour file), and `occgt scan` counts the frame among those without colour; a
// missing rgb.txt is named by a scan warning. Before, the entry's path was kept (counted
// "with colour") and a missing rgb.txt was silent.
TEST(Tum, MissingColourImageOrListMeansNoColourAndScanSaysSo) {
  const std::string root = MakeSequence("rgbd_dataset_freiburg1_rgb");
  std::filesystem::remove(root + "/rgb/10.005.png");
  const auto reader = MakeReader(gt::DatasetFormat::kTum);
  const Scene s = reader->ReadScene(root, "");
  ASSERT_EQ(s.frames.size(), 4u);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_TRUE(s.frames[0].color_path.empty());
  EXPECT_EQ(s.frames[0].color_camera.width, 0);
  EXPECT_EQ(s.frames[3].color_path, root + "/rgb/10.490.png");
  const SceneSummary sum = SummarizeScene(s, ScanOptions());
  EXPECT_EQ(sum.usable, 2u);  // frames 0 and 1
  EXPECT_EQ(sum.usable_with_color, 0u);
  EXPECT_TRUE(ScanWarnings(s, "rgb.txt").empty());

  std::filesystem::remove(root + "/rgb.txt");
  const Scene no_list = reader->ReadScene(root, "");
  for (const Frame& f : no_list.frames) EXPECT_TRUE(f.color_path.empty()) << f.id;
  const std::vector<std::string> said = ScanWarnings(no_list, "rgb.txt");
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0], root +
                         "/rgb.txt: missing (expected 'timestamp filename' lines of the colour "
                         "images): no frame has colour");
}

// A non-finite groundtruth value makes its frame unusable, naming the file and the line as
// written (groundtruth.txt is sorted by time after reading: the line is not the index).
TEST(Tum, NonFiniteGroundtruthNamesFileAndLine) {
  const std::string root = MakeSequence("tum_nan_gt");
  WriteFileAtomic(root + "/groundtruth.txt",
                  "# ground truth\n"
                  "10.115 3 0 0 0 0 0 1\n"
                  "10.000 nan 0 0 0 0 0 1\n"
                  "10.100 0 0 0 0 0 inf 1\n"
                  "10.500 0 0 0 0 0 0 1\n");
  const Scene s = MakeReader(gt::DatasetFormat::kTum)->ReadScene(root, "");
  ASSERT_EQ(s.frames.size(), 4u);
  const std::string file = root + "/groundtruth.txt";
  for (int i : {0, 1}) {
    EXPECT_FALSE(s.frames[i].usable);
    EXPECT_EQ(s.frames[i].unusable_reason, "pose: non-finite pose entries");
  }
  EXPECT_EQ(s.frames[0].unusable_detail, file + ":3: non-finite value");
  EXPECT_EQ(s.frames[1].unusable_detail, file + ":4: non-finite value");
  EXPECT_TRUE(s.frames[3].usable);
  EXPECT_EQ(s.frames[3].world_from_cam.translation(), Eigen::Vector3d::Zero());
}

TEST(Tum, BadFilesNameFileAndLine) {
  const auto reader = MakeReader(gt::DatasetFormat::kTum);
  {
    const std::string root = MakeSequence("tum_bad_gt");
    WriteFileAtomic(root + "/groundtruth.txt", "# x\n10.0 1 2 3 0 0 0\n");
    try {
      reader->ReadScene(root, "");
      FAIL();
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), root + "/groundtruth.txt:2") << e.what();
    }
  }
  {
    const std::string root = MakeSequence("tum_bad_token");
    WriteFileAtomic(root + "/depth.txt", "10.0 depth/10.000000.png\nten depth/x.png\n");
    try {
      reader->ReadScene(root, "");
      FAIL();
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), root + "/depth.txt:2") << e.what();
    }
  }
  {
    const std::string root = MakeSequence("tum_empty");
    WriteFileAtomic(root + "/depth.txt", "# nothing\n");
    try {
      reader->ReadScene(root, "");
      FAIL();
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), root + "/depth.txt");
      EXPECT_NE(std::string(e.what()).find("no entries (expected 'timestamp filename' lines)"),
                std::string::npos);
    }
  }
}

std::string ErrorOfScene(const std::string& root) {
  try {
    MakeReader(gt::DatasetFormat::kTum)->ReadScene(root, "");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A groundtruth.txt or rgb.txt without an entry is named (every frame was "no groundtruth
// within 0.02s", or had no colour, without the file named); with CR-only line endings (the
// whole file one comment line), the message says so.
TEST(Tum, ListsWithoutEntriesAreNamed) {
  const std::string root = MakeSequence("tum_no_entries");
  WriteFileAtomic(root + "/groundtruth.txt",
                  "# timestamp tx ty tz qx qy qz qw\r10.0 1 0 0 0 0 0 1\r");
  EXPECT_EQ(ErrorOfScene(root),
            root +
                "/groundtruth.txt: no pose entries (expected 'timestamp tx ty tz qx qy qz qw' "
                "lines); its lines end in CR alone, read as one comment line: convert them "
                "to LF");
  WriteFileAtomic(root + "/groundtruth.txt", "# nothing yet\n");
  EXPECT_EQ(ErrorOfScene(root), root +
                                    "/groundtruth.txt: no pose entries (expected 'timestamp "
                                    "tx ty tz qx qy qz qw' lines)");
  WriteFileAtomic(root + "/groundtruth.txt", "10.0 1 0 0 0 0 0 1\n");
  WriteFileAtomic(root + "/rgb.txt", "# colour\n");
  EXPECT_EQ(ErrorOfScene(root),
            root + "/rgb.txt: no entries (expected 'timestamp filename' lines)");
}

// One timestamp with two different poses is refused, naming both lines (the first was
// taken silently); the same pose twice is accepted.
TEST(Tum, RepeatedTimestampWithAnotherPoseIsRefused) {
  const std::string root = MakeSequence("tum_repeated_t");
  WriteFileAtomic(root + "/groundtruth.txt",
                  "# t\n10.0 1 0 0 0 0 0 1\n10.1 2 0 0 0 0 0 1\n10.0 1 0 0 0 0 0 1\n");
  EXPECT_EQ(ErrorOfScene(root), "");
  WriteFileAtomic(root + "/groundtruth.txt",
                  "# t\n10.0 1 0 0 0 0 0 1\n10.1 2 0 0 0 0 0 1\n10.0 9 9 9 0 0 0 1\n");
  EXPECT_EQ(ErrorOfScene(root), root +
                                    "/groundtruth.txt:4: timestamp 10.0 repeats line 2 with "
                                    "another pose (expected one pose per timestamp)");
}

// The nearest rgb.txt entry whose image exists gives the colour: a missing image 1 ms from
// the depth time gives way to an existing one 3 ms away (DATASETS.md). Before, the frame had
// no colour.
TEST(Tum, MissingColourImageGivesWayToTheNextNearest) {
  const std::string root = MakeSequence("rgbd_dataset_freiburg1_rgb_next");
  WriteFileAtomic(root + "/rgb.txt",
                  "# color images\n10.001 rgb/missing.png\n10.003 rgb/10.005.png\n"
                  "10.101 rgb/gone.png\n10.490 rgb/10.490.png\n");
  const auto reader = MakeReader(gt::DatasetFormat::kTum);
  const Scene s = reader->ReadScene(root, "");
  ASSERT_EQ(s.frames.size(), 4u);
  EXPECT_EQ(s.frames[0].color_path, root + "/rgb/10.005.png");  // t = 10.00
  EXPECT_EQ(s.frames[0].color_camera.width, 640);
  EXPECT_TRUE(s.frames[1].color_path.empty());  // t = 10.10: only a missing image near
  EXPECT_EQ(s.frames[3].color_path, root + "/rgb/10.490.png");
}

// depth.txt or rgb.txt giving one timestamp two files is refused, naming both lines; the
// same entry twice is one frame. Two entries naming one depth file name the lines too.
TEST(Tum, RepeatedListEntries) {
  const std::string root = MakeSequence("tum_repeated_list");
  WriteFileAtomic(root + "/depth.txt",
                  "# d\n10.0 depth/10.000000.png\n10.1 depth/10.100000.png\n"
                  "10.0 depth/10.000000.png\n");
  EXPECT_EQ(ErrorOfScene(root), "");
  const auto reader = MakeReader(gt::DatasetFormat::kTum);
  EXPECT_EQ(reader->ReadScene(root, "").frames.size(), 2u);
  WriteFileAtomic(root + "/depth.txt",
                  "# d\n10.0 depth/10.000000.png\n10.1 depth/10.100000.png\n"
                  "10.0 depth/10.500000.png\n");
  EXPECT_EQ(ErrorOfScene(root), root +
                                    "/depth.txt:4: timestamp repeats line 2 with another file "
                                    "(depth/10.500000.png; expected one file per timestamp)");
  WriteFileAtomic(root + "/depth.txt", "# d\n10.0 depth/10.000000.png\n10.1 depth/10.100000.png\n");
  WriteFileAtomic(root + "/rgb.txt", "10.3 rgb/10.490.png\n10.2 rgb/10.005.png\n10.3 x.png\n");
  EXPECT_EQ(ErrorOfScene(root), root +
                                    "/rgb.txt:3: timestamp repeats line 1 with another file "
                                    "(x.png; expected one file per timestamp)");
  WriteFileAtomic(root + "/rgb.txt", "10.0 rgb/10.005.png\n");
  WriteFileAtomic(root + "/depth.txt", "# d\n10.0 depth/10.000000.png\n10.1 other/10.000000.png\n");
  EXPECT_EQ(ErrorOfScene(root), root +
                                    "/depth.txt:3: depth file name '10.000000' repeats line 2 "
                                    "(expected one name per frame: the frame id)");
}

}  // namespace
}  // namespace gt::datasets

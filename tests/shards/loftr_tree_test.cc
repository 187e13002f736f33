// LoFTR export tree (loftr_tree.h): links for files already in ScanNet's form, conversions
// (65535 marker -> 0, float metres -> uint16 mm with what does not fit zeroed and counted,
// other sizes -> 640x480 nearest), pose text np.loadtxt(delimiter=' ') reads, exactly the
// given frames (stale files of an earlier export removed), and the folder names.
#include "libgt/shards/loftr_tree.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "tests/support/test_support.h"

namespace gt::shards {
namespace {

namespace fs = std::filesystem;

Camera Cam(int w, int h) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fx = c.fy = 0.75 * w;
  c.cx = 0.5 * w - 0.5;
  c.cy = 0.5 * h - 0.5;
  return c;
}

cv::Mat ReadPng16(const std::string& path) {
  return io::DecodeImageBytes(io::ReadFileBytes(path), io::ChannelOrder::kRgb, path);
}

std::string WriteColor(const std::string& path, int w, int h, bool jpeg) {
  cv::Mat rgb(h, w, CV_8UC3, cv::Scalar(30, 90, 200));
  io::WriteFileAtomic(path, jpeg ? io::EncodeJpegBytes(rgb, io::ChannelOrder::kRgb, 90, path)
                                 : io::EncodePngBytes(rgb, io::ChannelOrder::kRgb, 1, path));
  return path;
}

// A frame whose depth is a 640x480 uint16 PNG of `mm` (kPng16, scale 1 mm, marker).
Frame PngFrame(const std::string& dir, int64_t number, const cv::Mat& mm, int invalid_value,
               bool jpeg) {
  Frame f;
  f.id = std::to_string(number);
  f.number = number;
  f.depth.path = dir + "/d" + f.id + ".png";
  f.depth.format = DepthFormat::kPng16;
  f.depth.scale_m_per_unit = 0.001;
  f.depth.invalid_value = invalid_value;
  io::WriteFileAtomic(f.depth.path, io::EncodePngBytes(mm, io::ChannelOrder::kRgb, 1, "d"));
  f.depth_camera = Cam(mm.cols, mm.rows);
  f.color_path = WriteColor(dir + "/c" + f.id + (jpeg ? ".jpg" : ".png"), 64, 48, jpeg);
  f.color_camera = Cam(64, 48);
  return f;
}

TEST(LoftrTree, FolderNamesFollowTheNameRows) {
  const auto folders = LoftrSceneFolders({"scene0003_01", "seq-01", "hospital/Easy/P036"});
  EXPECT_EQ(folders.at("scene0003_01"), "scene0003_01");
  EXPECT_EQ(folders.at("hospital/Easy/P036"), "scene0000_00");  // sorted: 'h' < 's'
  EXPECT_EQ(folders.at("seq-01"), "scene0001_00");
  EXPECT_THROW(LoftrSceneFolders({"scene0000_00", "seq-01"}), InputError);
}

TEST(LoftrTree, LinksScanNetFormAndConvertsTheRest) {
  const std::string dir = test::ScratchDir("shards_loftr_tree");
  const std::string src = dir + "/src";
  fs::create_directories(src);
  cv::Mat mm(480, 640, CV_16UC1);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) mm.at<uint16_t>(v, u) = static_cast<uint16_t>((u * 7 + v) % 5000);
  }
  mm.at<uint16_t>(5, 6) = 65535;

  Scene scannet;  // depth in ScanNet's form, JPEG colour: both linked
  scannet.name = "scene0007_00";
  scannet.frames.push_back(PngFrame(src, 3, mm, -1, true));
  Eigen::Matrix3d r;
  r << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  scannet.frames[0].world_from_cam.linear() = r;
  scannet.frames[0].world_from_cam.translation() = Eigen::Vector3d(0.5, -2, 0.25);

  Scene seven;  // 7-Scenes: 65535 means no depth; PNG colour: both converted
  seven.name = "seq-01";
  seven.frames.push_back(PngFrame(src, 150, mm, 65535, false));

  Scene tartan;  // float metres at 320x240: 1.25 m, 70 m (> 65.535 m), NaN
  tartan.name = "P000";
  Frame f;
  f.id = "000004";
  f.number = 4;
  std::vector<float> m(320 * 240, 1.25f);
  m[0] = 70.0f;
  m[1] = std::nanf("");
  f.depth.path = src + "/000004_depth.npy";
  f.depth.format = DepthFormat::kNpyFloat32;
  io::WriteFileAtomic(f.depth.path, io::EncodeNpy<float>({240, 320}, m));
  f.depth_camera = Cam(320, 240);
  f.color_path = WriteColor(src + "/000004_left.png", 320, 240, false);
  tartan.frames.push_back(f);

  const std::string tree = dir + "/data";
  const auto folders = LoftrSceneFolders({scannet.name, seven.name, tartan.name});
  ASSERT_EQ(folders.at("P000"), "scene0000_00");
  ASSERT_EQ(folders.at("seq-01"), "scene0001_00");
  const LoftrTreeStats stats = ExportLoftrTree(tree,
                                               {{&scannet, "scene0007_00", {3}},
                                                {&seven, "scene0001_00", {150}},
                                                {&tartan, "scene0000_00", {4}}},
                                               {});
  EXPECT_EQ(stats.frames, 3u);
  EXPECT_EQ(stats.linked, 2u);
  EXPECT_EQ(stats.converted, 4u);
  EXPECT_EQ(stats.depth_zeroed_px, 4u);  // 70 m, one pixel -> a 2x2 block at 640x480

  // ScanNet: the same files, linked.
  EXPECT_TRUE(fs::equivalent(tree + "/scene0007_00/depth/3.png", scannet.frames[0].depth.path));
  EXPECT_TRUE(fs::equivalent(tree + "/scene0007_00/color/3.jpg", scannet.frames[0].color_path));
  EXPECT_EQ(io::ReadFileBytes(tree + "/scene0007_00/pose/3.txt"),
            "0 -1 0 0.5\n1 0 0 -2\n0 0 1 0.25\n0 0 0 1\n");
  EXPECT_EQ(io::ReadFileBytes(tree + "/scene0007_00/intrinsic/intrinsic_depth.txt"),
            "480 0 319.5 0\n0 480 239.5 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_EQ(io::ReadFileBytes(tree + "/scene0007_00/intrinsic/intrinsic_color.txt"),
            "48 0 31.5 0\n0 48 23.5 0\n0 0 1 0\n0 0 0 1\n");

  // 7-Scenes: the marker is 0, every other value kept; colour is a JPEG now.
  const cv::Mat seven_mm = ReadPng16(tree + "/scene0001_00/depth/150.png");
  ASSERT_EQ(seven_mm.type(), CV_16UC1);
  EXPECT_EQ(seven_mm.at<uint16_t>(5, 6), 0);
  mm.at<uint16_t>(5, 6) = 0;
  EXPECT_EQ(cv::countNonZero(seven_mm != mm), 0);
  const std::string jpg = io::ReadFileBytes(tree + "/scene0001_00/color/150.jpg");
  ASSERT_GE(jpg.size(), 3u);
  EXPECT_EQ(static_cast<unsigned char>(jpg[0]), 0xFF);
  EXPECT_EQ(static_cast<unsigned char>(jpg[1]), 0xD8);

  // TartanAir-like: mm at 640x480, 2x2 blocks; what does not fit and NaN are 0.
  const cv::Mat t_mm = ReadPng16(tree + "/scene0000_00/depth/4.png");
  ASSERT_EQ(t_mm.rows, 480);
  ASSERT_EQ(t_mm.cols, 640);
  for (int u : {0, 1}) {
    for (int v : {0, 1}) EXPECT_EQ(t_mm.at<uint16_t>(v, u), 0) << u << "," << v;
  }
  EXPECT_EQ(t_mm.at<uint16_t>(0, 2), 0);  // NaN
  EXPECT_EQ(t_mm.at<uint16_t>(1, 3), 0);
  EXPECT_EQ(t_mm.at<uint16_t>(0, 4), 1250);
  EXPECT_EQ(t_mm.at<uint16_t>(479, 639), 1250);

  // Deterministic bytes, and exactly the frames given: an export with fewer frames and
  // scenes removes the rest.
  const std::string before = io::ReadFileBytes(tree + "/scene0000_00/depth/4.png");
  seven.frames.push_back(PngFrame(src, 152, mm, 65535, false));
  ExportLoftrTree(tree, {{&seven, "scene0001_00", {152}}, {&tartan, "scene0000_00", {4}}}, {});
  EXPECT_EQ(io::ReadFileBytes(tree + "/scene0000_00/depth/4.png"), before);
  EXPECT_FALSE(fs::exists(tree + "/scene0007_00"));
  EXPECT_FALSE(fs::exists(tree + "/scene0001_00/depth/150.png"));
  EXPECT_FALSE(fs::exists(tree + "/scene0001_00/color/150.jpg"));
  EXPECT_FALSE(fs::exists(tree + "/scene0001_00/pose/150.txt"));
  EXPECT_TRUE(fs::exists(tree + "/scene0001_00/pose/152.txt"));
  EXPECT_TRUE(fs::exists(scannet.frames[0].depth.path));  // the source is untouched

  // A frame without colour or an unknown number: one clear error.
  tartan.frames[0].color_path.clear();
  EXPECT_THROW(ExportLoftrTree(tree, {{&tartan, "scene0000_00", {4}}}, {}), InputError);
  EXPECT_THROW(ExportLoftrTree(tree, {{&seven, "scene0001_00", {999}}}, {}), InputError);
}

}  // namespace
}  // namespace gt::shards

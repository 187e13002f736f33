// Posed-image exports (posed_export.h): glue-factory's depth in 1/256 m and DUSt3R's in mm
// from the same frames (what does not fit zeroed and counted, 65535 marker -> 0), links for
// files already in the required form at the working size, views.txt's exact text
// (world-to-camera R|t, COLMAP's +0.5 principal point), and a smaller second export removing
// the stale views and scenes. The readers of the real samples are in
// tests/integration/posed_readers.py.
#include "libgt/shards/posed_export.h"

#include <gtest/gtest.h>

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

cv::Mat ReadPng(const std::string& path) {
  return io::DecodeImageBytes(io::ReadFileBytes(path), io::ChannelOrder::kRgb, path);
}

// A 64x48 frame: uint16 mm PNG depth (1500 mm, one 65535 marker pixel) and JPEG colour.
Frame MmFrame(const std::string& dir, int64_t number) {
  Frame f;
  f.id = std::to_string(number);
  f.number = number;
  cv::Mat mm(48, 64, CV_16UC1, cv::Scalar(1500));
  mm.at<uint16_t>(2, 3) = 65535;
  f.depth.path = dir + "/d" + f.id + ".png";
  f.depth.format = DepthFormat::kPng16;
  f.depth.scale_m_per_unit = 0.001;
  f.depth.invalid_value = 65535;
  io::WriteFileAtomic(f.depth.path, io::EncodePngBytes(mm, io::ChannelOrder::kRgb, 1, "d"));
  f.depth_camera = Cam(64, 48);
  cv::Mat rgb(48, 64, CV_8UC3, cv::Scalar(30, 90, 200));
  f.color_path = dir + "/c" + f.id + ".jpg";
  io::WriteFileAtomic(f.color_path, io::EncodeJpegBytes(rgb, io::ChannelOrder::kRgb, 90, "c"));
  f.color_camera = Cam(64, 48);
  return f;
}

TEST(PosedExport, DepthUnitsLinksViewsAndStaleFiles) {
  const std::string dir = test::ScratchDir("shards_posed_export");
  const std::string src = dir + "/src";
  fs::create_directories(src);
  Scene a;  // "seq/01": folder seq_01
  a.name = "seq/01";
  a.frames = {MmFrame(src, 7), MmFrame(src, 9), MmFrame(src, 11)};
  a.frames[1].world_from_cam.translation() = Eigen::Vector3d(1, 2, 3);
  a.frames[1].depth.invalid_value = -1;  // no marker: exactly ScanNet's form, DUSt3R links it
  Scene b;  // float metres: 1.25 m, 70 m (fits 1/256 m, not mm), 300 m (fits neither)
  b.name = "P000";
  Frame f;
  f.id = "000004";
  f.number = 4;
  std::vector<float> m(64 * 48, 1.25f);
  m[0] = 70.0f;
  m[1] = 300.0f;
  f.depth.path = src + "/000004_depth.npy";
  f.depth.format = DepthFormat::kNpyFloat32;
  io::WriteFileAtomic(f.depth.path, io::EncodeNpy<float>({48, 64}, m));
  f.depth_camera = Cam(64, 48);
  f.color_path = MmFrame(src, 99).color_path;
  f.color_camera = Cam(64, 48);
  b.frames = {f, MmFrame(src, 5)};
  const std::map<std::string, const Scene*> scenes = {{a.name, &a}, {b.name, &b}};
  std::vector<PosedPair> pairs = {{"seq/01", 7, 9, 0.5, 0.4, 0.6},
                                  {"seq/01", 11, 7, 0.25, 0.2, 0.3},
                                  {"P000", 4, 5, 0.75, 0.7, 0.8}};
  PosedExportOptions o;
  o.width = 64;
  o.height = 48;

  const std::string gf = dir + "/gf";
  const PosedExportStats g = ExportGlueFactory(gf, scenes, pairs, o);
  EXPECT_EQ(g.scenes, 2u);
  EXPECT_EQ(g.views, 5u);
  EXPECT_EQ(g.pairs, 3u);
  EXPECT_EQ(g.linked, 5u);  // the 64x48 JPEGs; every depth is converted to 1/256 m
  EXPECT_EQ(g.converted, 5u);
  EXPECT_EQ(g.depth_zeroed_px, 1u);  // 300 m
  const cv::Mat g7 = ReadPng(gf + "/data/seq_01/depths/7.png");
  ASSERT_EQ(g7.type(), CV_16UC1);
  EXPECT_EQ(g7.at<uint16_t>(0, 0), 384);  // 1.5 m * 256
  EXPECT_EQ(g7.at<uint16_t>(2, 3), 0);    // the marker
  const cv::Mat g4 = ReadPng(gf + "/data/P000/depths/4.png");
  EXPECT_EQ(g4.at<uint16_t>(0, 0), 17920);  // 70 m * 256
  EXPECT_EQ(g4.at<uint16_t>(0, 1), 0);
  EXPECT_EQ(g4.at<uint16_t>(0, 2), 320);  // 1.25 m * 256
  EXPECT_TRUE(fs::equivalent(gf + "/data/seq_01/images/9.jpg", a.frames[1].color_path));
  // World-to-camera of a camera at (1, 2, 3) with R = I: t = (-1, -2, -3); cx, cy + 0.5.
  EXPECT_EQ(io::ReadFileBytes(gf + "/data/seq_01/views.txt"),
            "7.jpg 1 0 0 0 1 0 0 0 1 0 0 0 PINHOLE 64 48 48 48 32 24\n"
            "9.jpg 1 0 0 0 1 0 0 0 1 -1 -2 -3 PINHOLE 64 48 48 48 32 24\n"
            "11.jpg 1 0 0 0 1 0 0 0 1 0 0 0 PINHOLE 64 48 48 48 32 24\n");
  EXPECT_EQ(io::ReadFileBytes(gf + "/data/seq_01/pairs.txt"), "7.jpg 9.jpg\n11.jpg 7.jpg\n");
  EXPECT_EQ(io::ReadFileBytes(gf + "/data/seq_01/pair_scores.txt"),
            "7.jpg 9.jpg 0.5 0.4 0.6\n11.jpg 7.jpg 0.25 0.2 0.3\n");

  const std::string du = dir + "/du";
  const PosedExportStats d = ExportDust3r(du, scenes, pairs, o);
  EXPECT_EQ(d.linked, 6u);  // the 5 JPEGs and frame 9's mm PNG
  EXPECT_EQ(d.converted, 4u);
  EXPECT_TRUE(fs::equivalent(du + "/seq_01/depth/9.png", a.frames[1].depth.path));
  EXPECT_EQ(d.depth_zeroed_px, 2u);  // 70 m and 300 m
  const cv::Mat d4 = ReadPng(du + "/P000/depth/4.png");
  EXPECT_EQ(d4.at<uint16_t>(0, 0), 0);
  EXPECT_EQ(d4.at<uint16_t>(0, 2), 1250);
  // (all_metadata.npz and scene_metadata.npz hold numpy str arrays, which io::ReadNpz does
  // not read: integration/loftr_tree reads them with numpy.)
  EXPECT_TRUE(fs::exists(du + "/all_metadata.npz"));
  EXPECT_TRUE(fs::exists(du + "/P000/scene_metadata.npz"));

  // A smaller second export: the other scene and the unused views are gone.
  pairs.resize(1);
  ExportGlueFactory(gf, scenes, pairs, o);
  ExportDust3r(du, scenes, pairs, o);
  EXPECT_FALSE(fs::exists(gf + "/data/P000"));
  EXPECT_FALSE(fs::exists(gf + "/data/seq_01/images/11.jpg"));
  EXPECT_FALSE(fs::exists(du + "/P000"));
  EXPECT_FALSE(fs::exists(du + "/seq_01/depth/11.png"));
  EXPECT_TRUE(fs::exists(du + "/seq_01/depth/9.png"));
  EXPECT_TRUE(fs::exists(a.frames[2].depth.path));  // sources untouched

  // Unknown frame, unknown scene, missing colour: one clear error.
  EXPECT_THROW(ExportDust3r(du, scenes, {{"seq/01", 7, 8, 0, 0, 0}}, o), InputError);
  EXPECT_THROW(ExportDust3r(du, scenes, {{"nope", 7, 9, 0, 0, 0}}, o), InputError);
  a.frames[0].color_path.clear();
  EXPECT_THROW(ExportGlueFactory(gf, scenes, pairs, o), InputError);
}

}  // namespace
}  // namespace gt::shards

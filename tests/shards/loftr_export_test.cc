// LoFTR-family export: layouts and dtypes as LoFTR's loaders expect them, and a
// round trip of the real test-1500 index (../shared/data/loftr_scannet_test_1500):
// reading its test.npz / intrinsics.npz / statistics.json into LoftrPairs and exporting
// again must reproduce the same arrays, dtypes and statistics.
#include "libgt/shards/loftr_export.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "tests/support/test_support.h"

namespace gt::shards {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

TEST(LoftrExport, ParsesScanNetSceneNames) {
  EXPECT_EQ(ParseScanNetSceneName("scene0707_00"), std::make_pair(int64_t{707}, int64_t{0}));
  EXPECT_EQ(ParseScanNetSceneName("scene0000_02"), std::make_pair(int64_t{0}, int64_t{2}));
  EXPECT_FALSE(ParseScanNetSceneName("scene707_00"));
  EXPECT_FALSE(ParseScanNetSceneName("scene0707_00x"));
  EXPECT_FALSE(ParseScanNetSceneName("hospital/Easy/P036"));
}

TEST(LoftrExport, TrainLayoutForScanNetAndOtherScenes) {
  const std::string dir = test::ScratchDir("shards_loftr_train");
  std::vector<LoftrPair> pairs;
  // Interleaved scenes: each scene's pairs keep their relative order.
  pairs.push_back({"scene0002_01", 10, 40, 0.55, {}});
  pairs.push_back({"hospital/Easy/P036", 3, 9, 0.25, {}});
  pairs.push_back({"scene0002_01", 5, 70, 0.75, {}});
  pairs.push_back({"abandonedfactory/Hard/P001", 1, 2, 0.5, {}});
  SceneIntrinsics k;
  k["scene0002_01"] = {577.0, 0, 319.5, 0, 578.0, 239.5, 0, 0, 1};
  k["hospital/Easy/P036"] = {320, 0, 320, 0, 320, 240, 0, 0, 1};
  k["abandonedfactory/Hard/P001"] = {320, 0, 320, 0, 320, 240, 0, 0, 1};
  LoftrExportOptions options;
  options.split = "val";
  ExportLoftrTrain(dir, pairs, k, options);

  const auto scannet = io::ReadNpz(dir + "/scene_data/val/scene0002_01.npz");
  const io::NpyArray& name = scannet.at("name");
  EXPECT_EQ(name.descr, "<i8");
  EXPECT_EQ(name.shape, (std::vector<int64_t>{2, 4}));
  const int64_t* n = name.As<int64_t>("name");
  EXPECT_EQ(std::vector<int64_t>(n, n + 8), (std::vector<int64_t>{2, 1, 10, 40, 2, 1, 5, 70}));
  const io::NpyArray& score = scannet.at("score");
  EXPECT_EQ(score.descr, "<f4");
  EXPECT_EQ(score.shape, (std::vector<int64_t>{2}));
  EXPECT_FLOAT_EQ(score.As<float>("score")[0], 0.55f);
  EXPECT_FLOAT_EQ(score.As<float>("score")[1], 0.75f);

  // Other scenes: numbered by their index in the sorted list written to scenes.txt.
  const auto scenes = io::ReadLines(dir + "/scenes.txt");
  EXPECT_EQ(scenes, (std::vector<std::string>{"abandonedfactory/Hard/P001", "hospital/Easy/P036"}));
  const auto hosp = io::ReadNpz(dir + "/scene_data/val/hospital_Easy_P036.npz");
  const int64_t* h = hosp.at("name").As<int64_t>("name");
  EXPECT_EQ(std::vector<int64_t>(h, h + 4), (std::vector<int64_t>{1, 0, 3, 9}));

  EXPECT_EQ(io::ReadLines(dir + "/val_list.txt"),
            (std::vector<std::string>{"abandonedfactory_Hard_P001.npz", "hospital_Easy_P036.npz",
                                      "scene0002_01.npz"}));
  const auto intr = io::ReadNpz(dir + "/intrinsics.npz");
  // The three scenes, and the two non-ScanNet ones again under the folder names LoFTR
  // forms from their name rows (scene%04d_00 of their line in scenes.txt).
  ASSERT_EQ(intr.size(), 5u);
  EXPECT_EQ(intr.at("scene0000_00").data, intr.at("abandonedfactory/Hard/P001").data);
  EXPECT_EQ(intr.at("scene0001_00").data, intr.at("hospital/Easy/P036").data);
  const io::NpyArray& kk = intr.at("scene0002_01");
  EXPECT_EQ(kk.descr, "<f8");
  EXPECT_EQ(kk.shape, (std::vector<int64_t>{3, 3}));
  EXPECT_EQ(kk.As<double>("K")[2], 319.5);

  // Missing intrinsics is an input error, before anything is written.
  const std::string dir2 = test::ScratchDir("shards_loftr_train_missing");
  SceneIntrinsics partial = {{"scene0002_01", k["scene0002_01"]}};
  EXPECT_THROW(ExportLoftrTrain(dir2, pairs, partial, options), InputError);
  EXPECT_TRUE(fs::is_empty(dir2));
}

TEST(LoftrExport, RealTest1500RoundTrips) {
  const std::string src = test::SharedData("loftr_scannet_test_1500");
  ASSERT_FALSE(src.empty());
  const auto test_npz = io::ReadNpz(src + "/test.npz");
  const io::NpyArray& name = test_npz.at("name");
  const io::NpyArray& rel = test_npz.at("rel_pose");
  ASSERT_EQ(name.shape, (std::vector<int64_t>{1500, 4}));
  ASSERT_EQ(name.descr, "<u2");
  ASSERT_EQ(rel.descr, "<f4");
  const uint16_t* nv = name.As<uint16_t>("name");
  const float* rv = rel.As<float>("rel_pose");
  std::vector<LoftrPair> pairs;
  for (int i = 0; i < 1500; ++i) {
    LoftrPair p;
    char scene[32];
    std::snprintf(scene, sizeof(scene), "scene%04d_%02d", nv[4 * i], nv[4 * i + 1]);
    p.scene = scene;
    p.frame0 = nv[4 * i + 2];
    p.frame1 = nv[4 * i + 3];
    for (int j = 0; j < 12; ++j) p.cam1_from_cam0[j] = rv[12 * i + j];
    pairs.push_back(p);
  }
  SceneIntrinsics k;
  for (const auto& [scene, arr] : io::ReadNpz(src + "/intrinsics.npz")) {
    ASSERT_EQ(arr.shape, (std::vector<int64_t>{3, 3}));
    const double* d = arr.As<double>(scene);
    std::copy(d, d + 9, k[scene].begin());
  }
  const std::string dir = test::ScratchDir("shards_loftr_test1500");
  LoftrExportOptions options;
  options.list_name = "scannet_test.txt";
  ExportLoftrTest(dir, pairs, k, options);

  const auto out = io::ReadNpz(dir + "/test.npz");
  EXPECT_EQ(out.at("name").descr, "<u2");
  EXPECT_EQ(out.at("name").shape, name.shape);
  EXPECT_EQ(out.at("name").data, name.data);
  EXPECT_EQ(out.at("rel_pose").descr, "<f4");
  EXPECT_EQ(out.at("rel_pose").shape, rel.shape);
  EXPECT_EQ(out.at("rel_pose").data, rel.data);
  const auto intr = io::ReadNpz(dir + "/intrinsics.npz");
  for (const auto& [scene, arr] : io::ReadNpz(src + "/intrinsics.npz")) {
    // The export holds the scenes that have pairs; in test-1500 that is all 100.
    ASSERT_TRUE(intr.count(scene)) << scene;
    EXPECT_EQ(intr.at(scene).data, arr.data) << scene;
  }
  EXPECT_EQ(json::parse(io::ReadFileBytes(dir + "/statistics.json")),
            json::parse(io::ReadFileBytes(src + "/statistics.json")));
  EXPECT_EQ(io::ReadFileBytes(dir + "/scannet_test.txt"),
            io::ReadFileBytes(src + "/scannet_test.txt") + "\n");
  EXPECT_FALSE(fs::exists(dir + "/scenes.txt"));
}

TEST(LoftrExport, TestNameWidensWhenFrameNumbersExceedUint16) {
  const std::string dir = test::ScratchDir("shards_loftr_test_wide");
  std::vector<LoftrPair> pairs = {{"scene0001_00", 70000, 3, 0.5, {}}};
  ExportLoftrTest(dir, pairs, {{"scene0001_00", {1, 0, 0, 0, 1, 0, 0, 0, 1}}},
                  LoftrExportOptions{});
  const auto out = io::ReadNpz(dir + "/test.npz");
  EXPECT_EQ(out.at("name").descr, "<i8");
  EXPECT_EQ(out.at("name").As<int64_t>("name")[2], 70000);
  EXPECT_EQ(io::ReadLines(dir + "/test_list.txt"), std::vector<std::string>{"test.npz"});
}

}  // namespace
}  // namespace gt::shards

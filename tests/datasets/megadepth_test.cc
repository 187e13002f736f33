// MegaDepth v1 (`--format megadepth`, docs/DATASETS.md "MegaDepth"): a tiny download
// written here in its layout, phoenix/S6/zl548/MegaDepth_v1/<scene>/dense0/depths/*.h5
// with COLMAP text models in both places the reader looks (dense0/sparse/ and D2-Net's
// Undistorted_SfM/<scene>/sparse-txt/). Closed-form answers: a plane at depth 10 seen from
// two cameras 2 apart (fx = 100), so 20 columns leave the view; an image at 1.25 times the size
// with its own K gives the same working camera; ordinal (< 100 KiB), missing depth and a bad
// quaternion are unusable with their reasons; scan and pair run on it through the CLI.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/hdf5_depth.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

void WriteText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p.string()) << text;
}

void WritePlane(const fs::path& p, int w, int h, bool first_row_invalid) {
  fs::create_directories(p.parent_path());
  DepthImage d(w, h, 10.0f);
  if (first_row_invalid) {
    for (int u = 0; u < w; ++u) d.at(u, 0) = 0.0f;
  }
  WriteHdf5Depth(p.string(), d);
}

void WriteJpeg(const fs::path& p, int w, int h) {
  fs::create_directories(p.parent_path());
  ASSERT_TRUE(cv::imwrite(p.string(), cv::Mat(h, w, CV_8UC3, cv::Scalar(40, 80, 120))));
}

// The download folder (holding phoenix/ and Undistorted_SfM/), written once per process.
std::string Download() {
  static const std::string base = [] {
    const fs::path root = test::ScratchDir("megadepth");
    const fs::path v1 = root / "phoenix/S6/zl548/MegaDepth_v1";
    // Scene 0001: model in dense0/sparse (text), images in dense0/imgs.
    const fs::path s1 = v1 / "0001" / "dense0";
    WriteText(s1 / "sparse/cameras.txt",
              "# Camera list with one line of data per camera:\n"
              "1 PINHOLE 192 144 100 100 96.5 72.5\n"
              "2 SIMPLE_PINHOLE 240 180 125 120.625 90.625\n");
    WriteText(s1 / "sparse/images.txt",
              "# Image list with two lines of data per image:\n"
              "2 1 0 0 0 -2 0 0 1 b.jpg\n"
              "\n"
              "1 1 0 0 0 0 0 0 1 a.jpg\n"
              "10.5 20.5 -1\n"
              "3 1 0 0 0 0 0 0 2 c.jpg\n"
              "\n"
              "4 1 0 0 0 0 0 0 1 d.jpg\n"
              "\n"
              "5 1 0 0 0 0 0 0 1 e.jpg\n"
              "\n"
              "6 2 0 0 0 0 0 0 1 f.jpg\n"
              "\n");
    WritePlane(s1 / "depths/a.h5", 192, 144, true);
    WritePlane(s1 / "depths/b.h5", 192, 144, false);
    WritePlane(s1 / "depths/c.h5", 240, 180, false);
    WritePlane(s1 / "depths/d.h5", 32, 32, false);  // 4 KiB: an ordinal / mask map
    WritePlane(s1 / "depths/f.h5", 192, 144, false);
    WriteJpeg(s1 / "imgs/a.jpg", 192, 144);
    WriteJpeg(s1 / "imgs/b.jpg", 192, 144);
    // Scene 0002: D2-Net's undistortion beside phoenix/.
    const fs::path und = root / "Undistorted_SfM/0002";
    WriteText(und / "sparse-txt/cameras.txt", "1 PINHOLE 192 144 100 100 96.5 72.5\n");
    WriteText(und / "sparse-txt/images.txt",
              "1 1 0 0 0 0 0 0 1 x.jpg\n\n2 1 0 0 0 0 0 -1 1 y.jpg\n\n");
    WritePlane(v1 / "0002/dense0/depths/x.h5", 192, 144, false);
    WritePlane(v1 / "0002/dense0/depths/y.h5", 192, 144, false);
    WriteJpeg(und / "images/x.jpg", 192, 144);
    // Scene 0003: depth without any model (listed, its frames unusable).
    WritePlane(v1 / "0003/dense0/depths/z.h5", 192, 144, false);
    WritePlane(v1 / "0003/dense0/depths/w.h5", 192, 144, false);
    // Scene 0004: an empty depths/ folder and no model (no data: not listed).
    fs::create_directories(v1 / "0004/dense0/depths");
    return root.string();
  }();
  return base;
}

// A recipe over the download's scenes at 192x144 (megadepth preset, no occupancy, no
// images), with `extra` lines appended.
std::string TinyRecipe(const std::string& split, const std::string& root, const std::string& scenes,
                       double min_overlap, const std::string& extra) {
  return "name: " + split + "\nsplit: " + split + "\nresolution: [192, 144]\n" +
         "dataset: {format: megadepth, root: '" + root + "', scenes: " + scenes + "}\n" +
         "labels: {preset: megadepth}\nselection: {overlap: [" + std::to_string(min_overlap) +
         ", 1.0], occlusion: [0.0, 1.0], score_stride: 4}\noccupancy: {enabled: false}\n" +
         "sample: {image: none, depth: true, labels: true, occupancy: false}\n" + extra;
}

TEST(MegaDepth, ListsScenesFromEveryRootShape) {
  const auto reader = MakeReader(gt::DatasetFormat::kMegaDepth);
  const std::vector<std::string> all{"0001", "0002", "0003"};
  EXPECT_EQ(reader->ListScenes(Download()), all);
  const std::string v1 = Download() + "/phoenix/S6/zl548/MegaDepth_v1";
  EXPECT_EQ(reader->ListScenes(v1), all);
  EXPECT_EQ(reader->ListScenes(v1 + "/0002"), std::vector<std::string>{"0002"});
  try {
    reader->ListScenes(v1 + "/0003");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no COLMAP sparse model of the scene"), std::string::npos);
  }
}

TEST(MegaDepth, FramesPosesKAndReasons) {
  const Scene s = MakeReader(gt::DatasetFormat::kMegaDepth)->ReadScene(Download(), "0001");
  EXPECT_EQ(s.format, DatasetFormat::kMegaDepth);
  ASSERT_EQ(s.frames.size(), 6u);
  const char* ids[] = {"a", "b", "c", "d", "e", "f"};
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(s.frames[i].id, ids[i]);
  const Frame& a = s.frames[0];
  const Frame& b = s.frames[1];
  const Frame& c = s.frames[2];
  EXPECT_TRUE(a.usable && b.usable && c.usable);
  EXPECT_EQ(a.depth_camera.width, 192);
  EXPECT_DOUBLE_EQ(a.depth_camera.fx, 100);
  EXPECT_DOUBLE_EQ(a.depth_camera.cx, 96);  // COLMAP 96.5 - 0.5
  EXPECT_DOUBLE_EQ(a.depth_camera.cy, 72);
  EXPECT_EQ(c.depth_camera.width, 240);
  EXPECT_EQ(c.depth_camera.height, 180);
  EXPECT_DOUBLE_EQ(c.depth_camera.fy, 125);
  EXPECT_DOUBLE_EQ(c.depth_camera.cx, 120.125);
  // cam_from_world t = (-2, 0, 0): the camera sits at x = 2.
  EXPECT_TRUE(b.world_from_cam.translation().isApprox(Eigen::Vector3d(2, 0, 0)));
  EXPECT_EQ(a.color_path, Download() + "/phoenix/S6/zl548/MegaDepth_v1/0001/dense0/imgs/a.jpg");
  EXPECT_EQ(a.color_camera.fx, 100);
  EXPECT_TRUE(c.color_path.empty());
  EXPECT_EQ(s.frames[3].unusable_reason,
            "depth: under 100 KiB (an ordinal or mask map, not metric depth)");
  EXPECT_EQ(s.frames[4].unusable_reason, "depth: missing file");
  EXPECT_EQ(s.frames[5].unusable_reason, "pose: quaternion norm is not within 0.001 of 1");
  EXPECT_EQ(s.frames[5].unusable_detail,
            Download() +
                "/phoenix/S6/zl548/MegaDepth_v1/0001/dense0/sparse/images.txt: image 6: "
                "quaternion norm is 2, expected 1");
  const DepthImage d = ReadDepth(a.depth, 192, 144);
  EXPECT_EQ(d.at(5, 0), 0.0f);
  EXPECT_EQ(d.at(5, 1), 10.0f);

  const Scene s2 = MakeReader(gt::DatasetFormat::kMegaDepth)->ReadScene(Download(), "0002");
  ASSERT_EQ(s2.frames.size(), 2u);
  EXPECT_EQ(s2.frames[0].color_path, Download() + "/Undistorted_SfM/0002/images/x.jpg");
  EXPECT_TRUE(s2.frames[1].color_path.empty());
  EXPECT_TRUE(s2.frames[1].world_from_cam.translation().isApprox(Eigen::Vector3d(0, 0, 1)));
}

// A scene without a COLMAP model beside scenes with one is listed, never silently left
// out: its depth files are frames, unusable with the reason `occgt scan` counts and a
// detail naming the places looked at. Before, it was not listed and nothing said so.
TEST(MegaDepth, SceneWithoutAModelIsCountedNotDropped) {
  const std::string v1 = Download() + "/phoenix/S6/zl548/MegaDepth_v1";
  const Scene s = MakeReader(gt::DatasetFormat::kMegaDepth)->ReadScene(Download(), "0003");
  ASSERT_EQ(s.frames.size(), 2u);
  EXPECT_EQ(s.frames[0].id, "w");
  EXPECT_EQ(s.frames[1].id, "z");
  EXPECT_EQ(s.frames[1].depth.path, v1 + "/0003/dense0/depths/z.h5");
  for (const Frame& f : s.frames) {
    EXPECT_FALSE(f.usable);
    EXPECT_EQ(f.unusable_reason, "pose: no COLMAP model of the scene");
    EXPECT_EQ(f.unusable_detail, v1 + "/0003/dense0/sparse or " + Download() +
                                     "/Undistorted_SfM/0003/sparse: no COLMAP sparse model "
                                     "(expected cameras + images, .bin or .txt)");
  }
  const auto r = test::RunOccgt("scan '" + Download() + "' --format megadepth --json");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  const json j = json::parse(r.stdout_text);
  EXPECT_EQ(j["totals"]["unusable_reasons"]["pose: no COLMAP model of the scene"], 2);
}

// Two images whose names differ only by extension (one depth file) name the later image's
// line and the other image (it named the file only).
TEST(MegaDepth, ImagesSharingANameNameTheirLines) {
  const fs::path root = test::ScratchDir("megadepth_shared_name");
  const fs::path d = root / "0001" / "dense0";
  WriteText(d / "sparse/cameras.txt", "1 PINHOLE 64 48 50 50 32.5 24.5\n");
  WriteText(d / "sparse/images.txt",
            "1 1 0 0 0 0 0 0 1 a.jpg\n\n2 1 0 0 0 1 0 0 1 b.jpg\n\n3 1 0 0 0 2 0 0 1 a.png\n\n");
  fs::create_directories(d / "depths");
  WriteText(d / "depths/a.h5", "");
  try {
    MakeReader(gt::DatasetFormat::kMegaDepth)->ReadScene(root.string(), "0001");
    ADD_FAILURE() << "two images with one depth file";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (d / "sparse/images.txt").string() +
                  ":5: image a.png shares the name a without extension with image id 1 (line "
                  "1) (their depth files would be the same)");
  }
}

json Meta(const std::string& frames, const std::string& extra) {
  const std::string out =
      test::ScratchDir("megadepth_pair_" + frames.substr(0, 1) + frames.substr(2, 1));
  const auto r =
      test::RunOccgt("pair --root '" + Download() + "' --format megadepth --scene 0001 --frames " +
                     frames + " --score-stride 1 --out '" + out + "' " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.stderr_text;
  std::ifstream in(out + "/meta.json");
  return json::parse(in);
}

TEST(MegaDepth, PairLabelsOfAPlaneFromTwoPoses) {
  const json m = Meta("a,b", "--resolution 192x144");
  const json& ab = m["metrics"]["01"]["counts"];
  EXPECT_EQ(ab["NO_DEPTH"], 192);          // a's first row
  EXPECT_EQ(ab["OUT_OF_VIEW"], 20 * 143);  // u_b = u_a - 20 < -0.5
  EXPECT_EQ(ab["VISIBLE"], 172 * 143);
  const json& ba = m["metrics"]["10"]["counts"];
  EXPECT_EQ(ba["OUT_OF_VIEW"], 20 * 144);  // u_a = u_b + 20 >= 191.5
  EXPECT_EQ(ba["UNKNOWN"], 172);           // lands on a's invalid first row
  EXPECT_EQ(ba["VISIBLE"], 172 * 143);
  EXPECT_EQ(ab["INCONSISTENT"], 0);
}

// c is 240x180 with its own K (a's scaled by 1.25): at the working resolution (default 640x480) it
// is the same camera as a, so c -> a is the identity; only a's invalid rows give UNKNOWN.
TEST(MegaDepth, ImagesOfDifferentSizesMeetAtTheWorkingResolution) {
  const json m = Meta("c,a", "");
  EXPECT_EQ(m["resolution"], json::array({640, 480}));
  const json& ca = m["metrics"]["01"]["counts"];
  const json& ac = m["metrics"]["10"]["counts"];
  const int a_no_depth = ac["NO_DEPTH"];
  EXPECT_GT(a_no_depth, 0);
  EXPECT_EQ(a_no_depth % 640, 0);
  EXPECT_EQ(ca["UNKNOWN"], a_no_depth);
  EXPECT_EQ(ca["VISIBLE"], 640 * 480 - a_no_depth);
  EXPECT_EQ(ac["VISIBLE"], 640 * 480 - a_no_depth);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(m["K0"][r][k].get<double>(), m["K1"][r][k].get<double>(), 1e-9);
    }
  }
}

TEST(MegaDepth, ScanListsUsableCountsAndReasons) {
  const auto r = test::RunOccgt("scan '" + Download() + "' --format megadepth --json");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  const json j = json::parse(r.stdout_text);
  ASSERT_EQ(j["scenes"].size(), 3u);  // 0003 without a model: its 2 frames unusable
  EXPECT_EQ(j["scenes"][2]["unusable"], 2);
  const json& s = j["scenes"][0];
  EXPECT_EQ(s["name"], "0001");
  EXPECT_EQ(s["frames"], 6);
  EXPECT_EQ(s["usable"], 3);
  EXPECT_EQ(s["unusable_reasons"].size(), 3u);
  EXPECT_EQ(s["uniform_depth_camera"], false);
  ASSERT_GE(s["warnings"].size(), 1u);
  EXPECT_EQ(s["warnings"][0].get<std::string>().rfind("MegaDepth depth is multi-view stereo", 0),
            0u);
}

// occgt build on the download: scene 0002's two views (y is 1 closer along the optical
// axis, but its depth file says 10 too: a 10 % depth error) are one pair. With the
// megadepth preset (τ = 0.15 z = 1.35 >= 1) they are VISIBLE where x projects into y:
// u_y = 96 + (u - 96) 10/9 in the pixel area for u in 10..181, v in 7..136.
TEST(MegaDepth, BuildsASplit) {
  const std::string dir = test::ScratchDir("megadepth_build");
  const std::string recipe = dir + "/recipe.yaml";
  WriteText(recipe, TinyRecipe("megadepth-tiny", Download(), "['0002']", 0.1, ""));
  const auto r = test::RunOccgt("build '" + recipe + "' --out '" + dir + "/out' --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text << r.stdout_text;
  std::ifstream in(dir + "/out/pairs.jsonl");
  std::string line;
  int pairs = 0;
  json first;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (pairs++ == 0) first = json::parse(line);
  }
  ASSERT_EQ(pairs, 1);
  EXPECT_EQ(first["metrics"]["01"]["counts"]["VISIBLE"], 172 * 130);
  EXPECT_EQ(first["metrics"]["01"]["counts"]["INCONSISTENT"], 0);
  EXPECT_EQ(first["metrics"]["10"]["counts"]["VISIBLE"], 192 * 144);
}

// loftr_export.kind megadepth: LoFTR's MegaDepth index of the split (shards/megadepth_export.h),
// read by tests/datasets/megadepth_index_check.py as LoFTR's loader reads it and compared with what
// the reader says of every frame (paths relative to the download folder, K in COLMAP's
// convention, cam_from_world, the selected pairs by frame index with their overlap).
TEST(MegaDepth, WritesLoftrsMegaDepthIndex) {
  const std::string dir = test::ScratchDir("megadepth_index");
  const std::string recipe = dir + "/recipe.yaml";
  WriteText(recipe, TinyRecipe("train", Download() + "/phoenix/S6/zl548/MegaDepth_v1",
                               "['0001', '0002']", 0.05, "loftr_export: {kind: megadepth}\n"));
  const auto r = test::RunOccgt("build '" + recipe + "' --out '" + dir + "/out' --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text << r.stdout_text;
  // Expectations from the reader and pairs.jsonl.
  const auto reader = MakeReader(gt::DatasetFormat::kMegaDepth);
  const std::string root = Download();
  json expected;
  std::map<std::string, Scene> scenes;
  for (const std::string name : {"0001", "0002"}) {
    scenes[name] = reader->ReadScene(root + "/phoenix/S6/zl548/MegaDepth_v1", name);
    json s = {{"image_paths", json::array()},
              {"depth_paths", json::array()},
              {"intrinsics", json::array()},
              {"poses", json::array()},
              {"pairs", json::array()}};
    for (const Frame& f : scenes[name].frames) {
      s["image_paths"].push_back(fs::path(f.color_path).lexically_relative(root).string());
      if (!f.usable) {
        for (const char* k : {"depth_paths", "intrinsics", "poses"}) s[k].push_back(nullptr);
        continue;
      }
      s["depth_paths"].push_back(fs::path(f.depth.path).lexically_relative(root).string());
      const Camera& c = f.depth_camera;
      s["intrinsics"].push_back(
          {{c.fx, 0.0, c.cx + 0.5}, {0.0, c.fy, c.cy + 0.5}, {0.0, 0.0, 1.0}});
      const Eigen::Matrix4d T = f.world_from_cam.inverse().matrix();
      json rows = json::array();
      for (int i = 0; i < 4; ++i) rows.push_back({T(i, 0), T(i, 1), T(i, 2), T(i, 3)});
      s["poses"].push_back(rows);
    }
    expected[name] = s;
  }
  std::ifstream in(dir + "/out/pairs.jsonl");
  int pairs = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    const json p = json::parse(line);
    const Scene& scene = scenes.at(p["scene"]);
    auto index = [&](const json& frame) {
      for (size_t k = 0; k < scene.frames.size(); ++k) {
        if (scene.frames[k].id == frame["id"]) return static_cast<int64_t>(k);
      }
      return int64_t{-1};
    };
    // The selection's score (its grid, score_stride), as the LoFTR ScanNet index.
    const double overlap = 0.5 * (p["score_metrics"]["01"]["overlap"].get<double>() +
                                  p["score_metrics"]["10"]["overlap"].get<double>());
    expected[p["scene"].get<std::string>()]["pairs"].push_back(
        {{index(p["frame0"]), index(p["frame1"])}, overlap});
    ++pairs;
  }
  ASSERT_GE(pairs, 2);
  EXPECT_EQ(expected["0001"]["depth_paths"][3], nullptr);  // d.h5: an ordinal map
  std::ofstream(dir + "/expected.json") << expected.dump();
  const auto check = test::RunShell("/usr/bin/python3 '" + std::string(OCCGT_SOURCE_DIR) +
                                    "/tests/datasets/megadepth_index_check.py' '" + dir +
                                    "/out/loftr' '" + root + "' '" + dir + "/expected.json'");
  EXPECT_EQ(check.exit_code, 0) << check.stdout_text << check.stderr_text;
  EXPECT_EQ(check.stdout_text, "ok 2\n");
  // The same build twice writes the same bytes.
  const auto again = test::RunOccgt("build '" + recipe + "' --out '" + dir + "/out2' --threads 2");
  ASSERT_EQ(again.exit_code, 0) << again.stderr_text;
  for (const char* f : {"scene_info/0001.npz", "scene_info/0002.npz", "train_list.txt"}) {
    std::ifstream a(dir + "/out/loftr/" + f, std::ios::binary),
        b(dir + "/out2/loftr/" + f, std::ios::binary);
    const std::string sa((std::istreambuf_iterator<char>(a)), {}),
        sb((std::istreambuf_iterator<char>(b)), {});
    EXPECT_TRUE(!sa.empty() && sa == sb) << f;
  }
  // The shipped recipe runs on the download (MEGADEPTH_ROOT; an unset
  // MEGADEPTH_TRAIN_SPLIT means every scene) and writes the index beside its shards.
  const auto shipped =
      test::RunShell("env -u MEGADEPTH_TRAIN_SPLIT MEGADEPTH_ROOT='" + root + "' '" +
                     test::OccgtBinary() + "' build '" + std::string(OCCGT_SOURCE_DIR) +
                     "/recipes/megadepth-train.yaml' --out '" + dir + "/shipped'");
  ASSERT_EQ(shipped.exit_code, 0) << shipped.stderr_text << shipped.stdout_text;
  EXPECT_TRUE(fs::exists(dir + "/shipped/loftr/train_list.txt"));
  // 0003 (no model) is a scene of the root: 0 pairs, its 2 frames counted in scan.unusable.
  EXPECT_NE(shipped.stdout_text.find("in 3 scenes"), std::string::npos) << shipped.stdout_text;
  // Another dataset format is refused.
  WriteText(dir + "/bad.yaml",
            "name: x\nsplit: x\ndataset: {format: synthetic}\n"
            "loftr_export: {kind: megadepth}\n");
  const auto bad = test::RunOccgt("build '" + dir + "/bad.yaml' --out '" + dir + "/bad'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.stderr_text.find("loftr_export.kind"), std::string::npos) << bad.stderr_text;
}

// recipes/megadepth-1500.yaml on the download: LoFTR's MegaDepth scene_info files (pickled
// dicts of NumPy arrays, written here by Python as LoFTR's are) named by a list file are
// imported as pairs by image name; a pair naming an image the model does not have is
// counted (import.missing_frame), and a listed file that is missing is one error line.
TEST(MegaDepth, ImportsLoftrsMegaDepthPairs) {
  const std::string dir = test::ScratchDir("megadepth_1500");
  const std::string script = R"PY(
import pickle, sys
import numpy as np
out = sys.argv[1]
info = {"image_paths": np.array(["Undistorted_SfM/0002/images/x.jpg",
                                 "Undistorted_SfM/0002/images/y.jpg",
                                 "Undistorted_SfM/0002/images/nope.jpg"], dtype=object),
        "depth_paths": np.array(["phoenix/S6/zl548/MegaDepth_v1/0002/dense0/depths/x.h5",
                                 "phoenix/S6/zl548/MegaDepth_v1/0002/dense0/depths/y.h5",
                                 None], dtype=object),
        "intrinsics": np.array([np.eye(3), np.eye(3), None], dtype=object),
        "poses": np.array([np.eye(4), np.eye(4), None], dtype=object),
        "pair_infos": np.array([((0, 1), np.float64(0.4), np.zeros((3, 2))),
                                ((1, 2), np.float64(0.2), np.zeros((0, 2)))], dtype=object)}
with open(out + "/0002_0.1_0.3.npz", "wb") as f:
    pickle.dump(info, f)
with open(out + "/megadepth_test_1500.txt", "w") as f:
    f.write("0002_0.1_0.3\n")
with open(out + "/bad_list.txt", "w") as f:
    f.write("0002_0.1_0.3\n0002_gone\n")
)PY";
  std::ofstream(dir + "/make.py") << script;
  const auto made = test::RunShell("/usr/bin/python3 '" + dir + "/make.py' '" + dir + "'");
  ASSERT_EQ(made.exit_code, 0) << made.stderr_text;
  const std::string root = Download();
  auto build = [&](const std::string& list, const std::string& out) {
    return test::RunShell("MEGADEPTH_ROOT='" + root + "' MEGADEPTH_1500_LIST='" + list + "' '" +
                          test::OccgtBinary() + "' build '" + std::string(OCCGT_SOURCE_DIR) +
                          "/recipes/megadepth-1500.yaml' --out '" + out + "' --threads 1");
  };
  const auto r = build(dir + "/megadepth_test_1500.txt", dir + "/out");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text << r.stdout_text;
  std::ifstream in(dir + "/out/pairs.jsonl");
  std::vector<json> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(json::parse(line));
  }
  // x (with colour) and y (no colour image in the fixture): the recipe stores images, so
  // the pair is counted as import.no_color; nope.jpg is not in the model.
  const json summary = json::parse(std::ifstream(dir + "/out/summary.json"));
  EXPECT_EQ(summary["drops"].value("import.missing_frame", 0), 1) << summary.dump();
  EXPECT_EQ(lines.size() + summary["drops"].value("import.no_color", 0), 1u) << summary.dump();
  // Without images (sample.image none through a copy of the recipe) the pair is built.
  std::ifstream shipped(std::string(OCCGT_SOURCE_DIR) + "/recipes/megadepth-1500.yaml");
  std::string text((std::istreambuf_iterator<char>(shipped)), {});
  text.replace(text.find("image: jpg"), 10, "image: none");
  WriteText(dir + "/noimg.yaml", text);
  const auto r2 = test::RunShell("MEGADEPTH_ROOT='" + root + "' MEGADEPTH_1500_LIST='" + dir +
                                 "/megadepth_test_1500.txt' '" + test::OccgtBinary() + "' build '" +
                                 dir + "/noimg.yaml' --out '" + dir + "/out2' --threads 1");
  ASSERT_EQ(r2.exit_code, 0) << r2.stderr_text << r2.stdout_text;
  std::ifstream in2(dir + "/out2/pairs.jsonl");
  std::string first;
  std::getline(in2, first);
  const json p = json::parse(first);
  EXPECT_EQ(p["scene"], "0002");
  EXPECT_EQ(p["frame0"]["id"], "x");
  EXPECT_EQ(p["frame1"]["id"], "y");
  EXPECT_TRUE(fs::exists(dir + "/out2/loftr/scene_info/0002.npz"));
  EXPECT_TRUE(fs::exists(dir + "/out2/loftr/test_list.txt"));
  // A listed file that is missing: one line naming the list and the file.
  const auto bad = build(dir + "/bad_list.txt", dir + "/out3");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.stderr_text.find("0002_gone.npz is missing"), std::string::npos) << bad.stderr_text;
}

}  // namespace
}  // namespace gt::datasets

// The written dataset: byte-identical reruns (library and CLI), holes exactly where
// dataset.json records them, depth files equal to a fresh render, manifests with the
// stated K and poses, options and CLI errors.
#include "libgt/synth/dataset.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "libgt/synth/render.h"
#include "tests/support/test_support.h"

namespace gt::synth {
namespace {
namespace fs = std::filesystem;

SynthOptions Small() {
  SynthOptions o;
  o.scenes = 2;
  o.frames_per_scene = 4;
  o.width = 128;
  o.height = 96;
  o.seed = 5;
  return o;
}

// Relative path -> bytes of every file under dir.
std::map<std::string, std::string> Tree(const std::string& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) {
      out[fs::relative(e.path(), dir).string()] = io::ReadFileBytes(e.path().string());
    }
  }
  return out;
}

TEST(SynthDataset, RerunsAreByteIdenticalAndSeedsDiffer) {
  const std::string a = test::ScratchDir("synth_a"), b = test::ScratchDir("synth_b"),
                    c = test::ScratchDir("synth_c");
  const SynthSummary s = WriteSyntheticDataset(a, Small());
  WriteSyntheticDataset(b, Small());
  EXPECT_EQ(s.scene_names, (std::vector<std::string>{"synth_000", "synth_001"}));
  EXPECT_EQ(s.frames, 8);
  const auto ta = Tree(a), tb = Tree(b);
  EXPECT_EQ(ta.size(), static_cast<size_t>(s.files));
  EXPECT_EQ(ta.size(), 2u + 2 * (1 + 4 * 2));  // .occgt-synth.json, dataset.json, 2 scenes
  EXPECT_TRUE(ta == tb);
  for (const auto& [path, bytes] : ta) EXPECT_EQ(path.find(".tmp"), std::string::npos) << path;
  SynthOptions other = Small();
  other.seed = 6;
  WriteSyntheticDataset(c, other);
  const auto tc = Tree(c);
  EXPECT_NE(ta.at("synth_000/depth/000000.npy"), tc.at("synth_000/depth/000000.npy"));
  EXPECT_NE(ta.at("synth_000/scene.json"), tc.at("synth_000/scene.json"));

  // The same options again into the same folder: the same files. Other options (one scene
  // fewer would leave synth_001 behind) or another program's dataset.json: refused, nothing
  // changed.
  WriteSyntheticDataset(a, Small());
  EXPECT_TRUE(Tree(a) == ta);
  SynthOptions fewer = Small();
  fewer.scenes = 1;
  try {
    WriteSyntheticDataset(a, fewer);
    ADD_FAILURE() << "other options into the same folder";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), a + "/.occgt-synth.json");
    EXPECT_NE(std::string(e.what()).find("holds a synthetic dataset of other options"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(Tree(a) == ta);
  const std::string d = test::ScratchDir("synth_d");
  io::WriteFileAtomic(d + "/dataset.json", "{\"name\": \"mine\"}\n");
  EXPECT_THROW(WriteSyntheticDataset(d, Small()), InputError);
  EXPECT_EQ(Tree(d).size(), 1u);

  // A dataset.json of the same options written before the claim existed: accepted, claimed.
  fs::remove(a + "/.occgt-synth.json");
  WriteSyntheticDataset(a, Small());
  EXPECT_TRUE(Tree(a) == ta);
  // A folder holding other files and no claim (a user's folder, or a run killed before
  // the claim existed): refused, naming it, nothing written.
  const std::string e = test::ScratchDir("synth_e");
  io::WriteFileAtomic(e + "/notes.txt", "mine\n");
  try {
    WriteSyntheticDataset(e, Small());
    ADD_FAILURE() << "a folder of other files";
  } catch (const InputError& err) {
    EXPECT_EQ(std::string(err.what()),
              e + ": holds files and no occgt synth dataset: write into an empty folder, or "
                  "delete this one, so that the two do not mix");
  }
  EXPECT_EQ(Tree(e).size(), 1u);
  // A run killed after its claim (some frames written, no dataset.json): the same options
  // resume and give the same files as one run.
  const std::string k = test::ScratchDir("synth_k");
  WriteSyntheticDataset(k, Small());
  fs::remove(k + "/dataset.json");
  fs::remove_all(k + "/synth_001");
  fs::remove(k + "/synth_000/depth/000003.npy");
  WriteSyntheticDataset(k, Small());
  EXPECT_TRUE(Tree(k) == ta);
}

TEST(SynthDataset, FilesMatchManifestRenderAndRecordedHoles) {
  const std::string dir = test::ScratchDir("synth_holes");
  const SynthOptions o = Small();
  WriteSyntheticDataset(dir, o);
  const auto dataset = nlohmann::json::parse(io::ReadFileBytes(dir + "/dataset.json"));
  ASSERT_EQ(dataset["scenes"].size(), 2u);
  const Camera cam = SynthCamera(o);
  EXPECT_EQ(cam.cx, 63.5);
  EXPECT_EQ(cam.cy, 47.5);
  EXPECT_EQ(cam.fx, 105.0);
  int hole_pixels = 0;
  for (int s = 0; s < 2; ++s) {
    const auto& entry = dataset["scenes"][s];
    const std::string name = entry["name"];
    const auto manifest =
        nlohmann::json::parse(io::ReadFileBytes(dir + "/" + name + "/scene.json"));
    EXPECT_EQ(manifest["scene"], name);
    ASSERT_EQ(manifest["frames"].size(), 4u);
    SynthScene scene = MakeRoomScene(SynthSceneSeed(o.seed, s), o.room);
    TrajectoryOptions t = o.trajectory;
    t.frames = 4;
    const auto poses = Trajectory(scene, t);
    for (int f = 0; f < 4; ++f) {
      const auto& frame = manifest["frames"][f];
      const std::string id = frame["id"];
      EXPECT_EQ(frame["K"][0][0].get<double>(), cam.fx);
      EXPECT_EQ(frame["K"][1][2].get<double>(), cam.cy);
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
          EXPECT_EQ(frame["world_from_cam"][r][c].get<double>(), poses[f].matrix()(r, c));
        }
      }
      const io::NpyArray depth =
          io::ReadNpy(dir + "/" + name + "/" + frame["depth"]["path"].get<std::string>());
      ASSERT_EQ(depth.shape, (std::vector<int64_t>{96, 128}));
      const float* d = depth.As<float>("depth");
      const DepthImage rendered = RenderDepth(scene, cam, poses[f]);
      // Hole membership from dataset.json alone.
      std::vector<bool> in_hole(128 * 96, false);
      ASSERT_TRUE(entry["holes"].contains(id));
      ASSERT_GE(entry["holes"][id].size(), 1u);
      ASSERT_LE(entry["holes"][id].size(), 3u);
      for (const auto& r : entry["holes"][id]) {
        for (int v = r[1].get<int>(); v < r[3].get<int>(); ++v) {
          for (int u = r[0].get<int>(); u < r[2].get<int>(); ++u) in_hole[v * 128 + u] = true;
        }
      }
      for (int i = 0; i < 128 * 96; ++i) {
        if (in_hole[i]) {
          ASSERT_EQ(d[i], 0.0f) << i;
          ++hole_pixels;
        } else {
          ASSERT_EQ(d[i], rendered.values_m[i]) << i;
          ASSERT_GT(d[i], 0.0f);
        }
      }
      const cv::Mat color = cv::imread(
          dir + "/" + name + "/" + frame["color"]["path"].get<std::string>(), cv::IMREAD_UNCHANGED);
      ASSERT_EQ(color.cols, 128);
      ASSERT_EQ(color.rows, 96);
      ASSERT_EQ(color.type(), CV_8UC3);
    }
  }
  EXPECT_GT(hole_pixels, 8 * 16);

  // Without holes every pixel has depth.
  SynthOptions no = o;
  no.holes = false;
  no.scenes = 1;
  no.frames_per_scene = 2;
  const std::string dir2 = test::ScratchDir("synth_noholes");
  WriteSyntheticDataset(dir2, no);
  const io::NpyArray d0 = io::ReadNpy(dir2 + "/synth_000/depth/000000.npy");
  for (int i = 0; i < 128 * 96; ++i) ASSERT_GT(d0.As<float>("d")[i], 0.0f);
}

TEST(SynthDataset, HolesStayInsideTheImage) {
  for (int f = 0; f < 500; ++f) {
    const auto holes = MakeHoles(12345, f, 64, 48, 3);
    ASSERT_GE(holes.size(), 1u);
    ASSERT_LE(holes.size(), 3u);
    for (const auto& r : holes) {
      ASSERT_GE(r.x0, 0);
      ASSERT_GE(r.y0, 0);
      ASSERT_LE(r.x1, 64);
      ASSERT_LE(r.y1, 48);
      ASSERT_GE(r.x1 - r.x0, 4);
      ASSERT_GE(r.y1 - r.y0, 4);
    }
  }
}

TEST(SynthDataset, OptionsAreChecked) {
  std::string error;
  EXPECT_TRUE(SynthOptions().Check(&error)) << error;
  SynthOptions o;
  o.scenes = 0;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_NE(error.find("scenes"), std::string::npos);
  o = SynthOptions();
  o.width = 8;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_THROW(WriteSyntheticDataset(test::ScratchDir("synth_bad"), o), InputError);
}

TEST(SynthCli, WritesDeterministicallyAndRejectsBadFlags) {
  const std::string a = test::ScratchDir("synth_cli_a"), b = test::ScratchDir("synth_cli_b");
  const std::string flags = " --scenes 1 --frames 3 --resolution 80x60 --seed 9";
  const auto ra = test::RunOccgt("synth --out '" + a + "'" + flags);
  ASSERT_EQ(ra.exit_code, 0) << ra.stderr_text;
  EXPECT_NE(ra.stdout_text.find("1 scene, 3 frames"), std::string::npos) << ra.stdout_text;
  ASSERT_EQ(test::RunOccgt("synth --out '" + b + "'" + flags).exit_code, 0);
  EXPECT_TRUE(Tree(a) == Tree(b));
  EXPECT_EQ(io::ReadNpy(a + "/synth_000/depth/000002.npy").shape, (std::vector<int64_t>{60, 80}));

  const auto bad = test::RunOccgt("synth --out '" + a + "' --resolution 80by60");
  // Usage errors (docs/CLI.md): one `occgt: error: --flag: ...` line, exit 2.
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.stderr_text.rfind("occgt: error: --resolution: ", 0), 0) << bad.stderr_text;
  EXPECT_EQ(std::count(bad.stderr_text.begin(), bad.stderr_text.end(), '\n'), 1);
  const auto zero = test::RunOccgt("synth --out '" + a + "' --frames 0");
  EXPECT_EQ(zero.exit_code, 2);
  EXPECT_EQ(zero.stderr_text.rfind("occgt: error: --frames: ", 0), 0) << zero.stderr_text;
  const auto tiny = test::RunOccgt("synth --out '" + a + "' --resolution 8x8");
  EXPECT_EQ(tiny.exit_code, 2);
  EXPECT_EQ(tiny.stderr_text.rfind("occgt: error: --resolution: ", 0), 0) << tiny.stderr_text;
}

}  // namespace
}  // namespace gt::synth

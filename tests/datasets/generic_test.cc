// Generic manifest reader: a valid manifest with npy, png16 and exr frames; scene root
// resolution (a .json file, a folder with scene.json, a folder of scene folders); and
// malformed fields, each error naming the manifest and the field path.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/datasets/scan.h"
#include "libgt/io/atomic_file.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {
using nlohmann::json;

json ValidManifest() {
  const json K = {{100, 0, 31.5}, {0, 110, 23.5}, {0, 0, 1}};
  const json I = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
  json shifted = I;
  shifted[0][3] = 0.25;
  return {{"format", "occgt-scene-manifest"},
          {"version", 1},
          {"scene", "room_01"},
          {"depth_range_m", {0.2, 20}},
          {"frames",
           {{{"id", "f0"},
             {"depth", {{"path", "depth/f0.npy"}, {"format", "npy"}}},
             {"K", K},
             {"width", 64},
             {"height", 48},
             {"world_from_cam", I},
             {"color", {{"path", "color/f0.png"}, {"width", 128}, {"height", 96}}}},
            {{"id", "f1"},
             {"depth",
              {{"path", "depth/f1.png"},
               {"format", "png16"},
               {"scale_m", 0.001},
               {"invalid_value", 65535}}},
             {"K", K},
             {"width", 64},
             {"height", 48},
             {"world_from_cam", shifted}},
            {{"id", "f2"},
             {"depth", {{"path", "depth/f2.exr"}, {"format", "exr"}}},
             {"K", K},
             {"width", 64},
             {"height", 48},
             {"world_from_cam", I},
             {"color",
              {{"path", "/abs/c.jpg"},
               {"K", {{300, 0, 63.5}, {0, 300, 47.5}, {0, 0, 1}}},
               {"width", 128},
               {"height", 96}}}}}}};
}

std::string WriteManifest(const std::string& dir, const json& j,
                          const std::string& name = "scene.json") {
  WriteFileAtomic(dir + "/" + name, j.dump(1));
  return dir + "/" + name;
}

TEST(Generic, ReadsFramesWithDefaults) {
  const std::string dir = test::ScratchDir("gen_ok");
  json manifest = ValidManifest();
  manifest["frames"][2]["color"]["path"] = dir + "/abs/c.jpg";  // an absolute path
  WriteManifest(dir, manifest);
  // The colour files exist (their sizes come from the manifest; the bytes are not read).
  WriteFileAtomic(dir + "/color/f0.png", "x");
  WriteFileAtomic(dir + "/abs/c.jpg", "x");
  ReaderOptions options;
  options.exr_channel = "Depth.Z";
  options.check_depth_files = false;
  const auto reader = MakeReader(gt::DatasetFormat::kGeneric, options);
  ASSERT_EQ(reader->ListScenes(dir), std::vector<std::string>{"room_01"});
  const Scene s = reader->ReadScene(dir, "");
  EXPECT_EQ(s.name, "room_01");
  EXPECT_EQ(s.path, dir + "/scene.json");
  EXPECT_EQ(s.min_depth_m, 0.2);
  EXPECT_EQ(s.max_depth_m, 20.0);
  ASSERT_EQ(s.frames.size(), 3u);
  const Frame& f0 = s.frames[0];
  EXPECT_EQ(f0.id, "f0");
  EXPECT_EQ(f0.number, 0);
  EXPECT_EQ(f0.depth.path, dir + "/depth/f0.npy");
  EXPECT_EQ(f0.depth.format, DepthFormat::kNpyFloat32);
  EXPECT_EQ(f0.depth_camera.fx, 100.0);
  EXPECT_EQ(f0.depth_camera.fy, 110.0);
  EXPECT_EQ(f0.depth_camera.width, 64);
  EXPECT_EQ(f0.color_path, dir + "/color/f0.png");
  // Colour K defaults to the depth K rescaled (x2): fx 200, cx 2 * 32 - 0.5.
  EXPECT_EQ(f0.color_camera.width, 128);
  EXPECT_DOUBLE_EQ(f0.color_camera.fx, 200.0);
  EXPECT_DOUBLE_EQ(f0.color_camera.cx, 63.5);
  EXPECT_TRUE(f0.usable);
  EXPECT_EQ(s.frames[1].depth.format, DepthFormat::kPng16);
  EXPECT_EQ(s.frames[1].depth.scale_m_per_unit, 0.001);
  EXPECT_EQ(s.frames[1].depth.invalid_value, 65535);
  EXPECT_EQ(s.frames[1].world_from_cam.translation().x(), 0.25);
  EXPECT_EQ(s.frames[2].depth.exr_channel, "Depth.Z");  // the reader option
  EXPECT_EQ(s.frames[2].color_path, dir + "/abs/c.jpg");
  EXPECT_EQ(s.frames[2].color_camera.fx, 300.0);
  // With the default check_depth_files, the missing depth files make frames unusable.
  const Scene checked = MakeReader(gt::DatasetFormat::kGeneric)->ReadScene(dir + "/scene.json", "");
  EXPECT_EQ(checked.NumUsable(), 0u);
  EXPECT_EQ(checked.frames[0].unusable_reason, "depth: missing file");
}

// A colour path whose file does not exist gives a frame without colour, as the folder
// readers (ScanNet, 7-Scenes, TartanAir) do for a missing colour file: still usable, no
// colour_path, and `occgt scan` counts it among the usable frames without colour (naming
// the first). Before, it was kept and counted "with colour".
TEST(Generic, MissingColourFileMeansNoColour) {
  const std::string dir = test::ScratchDir("gen_no_color");
  json manifest = ValidManifest();
  manifest["frames"][2]["color"]["path"] = "color/f2.jpg";  // not written
  WriteManifest(dir, manifest);
  WriteFileAtomic(dir + "/color/f0.png", "x");
  ReaderOptions options;
  options.check_depth_files = false;
  const Scene s = MakeReader(gt::DatasetFormat::kGeneric, options)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].color_path, dir + "/color/f0.png");
  const Frame& f2 = s.frames[2];
  EXPECT_TRUE(f2.usable);
  EXPECT_TRUE(f2.color_path.empty());
  EXPECT_EQ(f2.color_camera.width, 0);
  const SceneSummary sum = SummarizeScene(s, ScanOptions());
  EXPECT_EQ(sum.usable, 3u);
  EXPECT_EQ(sum.usable_with_color, 1u);
  bool said = false;
  for (const std::string& w : sum.warnings) {
    said = said || w.rfind("2 of 3 usable frames have no colour image (first: frame f1)", 0) == 0;
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(sum.warnings);
}

// A colour file that exists but whose header cannot be read (no width/height in the
// manifest, so the reader reads it): that frame is unusable with the read error naming the
// file, counted; the scene and its other frames still read (before, the whole scene failed).
// A missing depth file's detail is the manifest's path (a frame id does not name it).
TEST(Generic, DamagedColourHeaderIsTheFramesProblem) {
  const std::string dir = test::ScratchDir("gen_bad_color");
  json manifest = ValidManifest();
  manifest["frames"][1]["color"] = {{"path", "color/f1.png"}};
  WriteManifest(dir, manifest);
  WriteFileAtomic(dir + "/color/f1.png", std::string("\x89PNG\r\n\x1a\n", 8) + "cut");
  const Scene s = MakeReader(gt::DatasetFormat::kGeneric)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 3u);
  const Frame& f1 = s.frames[1];
  EXPECT_FALSE(f1.usable);
  EXPECT_EQ(f1.unusable_reason, "colour: unreadable image");
  EXPECT_NE(f1.unusable_detail.find(dir + "/color/f1.png"), std::string::npos)
      << f1.unusable_detail;
  EXPECT_TRUE(f1.color_path.empty());
  // The other frames: their depth files are missing here, said with the path.
  EXPECT_EQ(s.frames[0].unusable_reason, "depth: missing file");
  EXPECT_EQ(s.frames[0].unusable_detail, s.frames[0].depth.path);
  const SceneSummary sum = SummarizeScene(s, ScanOptions());
  EXPECT_EQ(sum.unusable_reasons.at("colour: unreadable image"), 1u);
}

TEST(Generic, RootLayouts) {
  const std::string root = test::ScratchDir("gen_roots");
  json a = ValidManifest();
  a["scene"] = "a";
  json b = ValidManifest();
  b["scene"] = "b";
  WriteManifest(root + "/b_dir", b);
  WriteManifest(root + "/a_dir", a);
  std::filesystem::create_directories(root + "/not_a_scene");
  const auto reader = MakeReader(gt::DatasetFormat::kGeneric);
  EXPECT_EQ(reader->ListScenes(root), (std::vector<std::string>{"a_dir", "b_dir"}));
  EXPECT_EQ(reader->ReadScene(root, "b_dir").path, root + "/b_dir/scene.json");
  EXPECT_EQ(reader->ListScenes(root + "/a_dir/scene.json"), std::vector<std::string>{"a"});
  try {
    reader->ReadScene(root, "c_dir");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root + "/c_dir/scene.json");
  }
  try {
    reader->ListScenes(root + "/not_a_scene");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root + "/not_a_scene");
  }
}

struct BadCase {
  std::string field;  // expected field path in the message
  void (*mutate)(json&);
};

TEST(Generic, MalformedFieldsNameManifestAndField) {
  const std::vector<BadCase> cases = {
      {"format", [](json& j) { j["format"] = "other"; }},
      {"version", [](json& j) { j["version"] = 2; }},
      {"scene", [](json& j) { j["scene"] = "bad name/"; }},
      {"extra", [](json& j) { j["extra"] = 1; }},
      {"frames", [](json& j) { j.erase("frames"); }},
      {"frames", [](json& j) { j["frames"] = json::array(); }},
      {"depth_range_m[1]",
       [](json& j) {
         j["depth_range_m"] = {5, 1};
       }},
      {"frames[1].K",
       [](json& j) {
         j["frames"][1]["K"] = {{1, 0, 0}, {0, 1, 0}};
       }},
      {"frames[1].K", [](json& j) { j["frames"][1]["K"][0][0] = "100"; }},
      {"frames[1].K", [](json& j) { j["frames"][1]["K"][0][0] = -100; }},
      {"frames[2].world_from_cam",
       [](json& j) {
         j["frames"][2]["world_from_cam"][3] = {0, 0, 1};
       }},
      {"frames[0].width", [](json& j) { j["frames"][0]["width"] = 0; }},
      {"frames[0].height", [](json& j) { j["frames"][0]["height"] = 4.5; }},
      {"frames[0].id", [](json& j) { j["frames"][0]["id"] = "a b"; }},
      {"frames[1].id", [](json& j) { j["frames"][1]["id"] = "f0"; }},  // duplicate
      {"frames[0].depth.format", [](json& j) { j["frames"][0]["depth"]["format"] = "tiff"; }},
      {"frames[0].depth.path", [](json& j) { j["frames"][0]["depth"]["path"] = ""; }},
      {"frames[1].depth.scale_m", [](json& j) { j["frames"][1]["depth"].erase("scale_m"); }},
      {"frames[1].depth.scale_m", [](json& j) { j["frames"][1]["depth"]["scale_m"] = 0; }},
      {"frames[0].depth.channel", [](json& j) { j["frames"][0]["depth"]["channel"] = "Z"; }},
      {"frames[1].depth.invalid_value",
       [](json& j) { j["frames"][1]["depth"]["invalid_value"] = 70000; }},
      {"frames[0].color.height", [](json& j) { j["frames"][0]["color"].erase("height"); }},
      {"frames[0].color.oops", [](json& j) { j["frames"][0]["color"]["oops"] = 1; }},
  };
  const std::string dir = test::ScratchDir("gen_bad");
  const auto reader = MakeReader(gt::DatasetFormat::kGeneric);
  for (const auto& c : cases) {
    json j = ValidManifest();
    c.mutate(j);
    const std::string path = WriteManifest(dir, j);
    try {
      reader->ReadScene(dir, "");
      ADD_FAILURE() << "expected InputError for " << c.field;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), path) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind(path + ": " + c.field + ": ", 0), 0u) << e.what();
    }
  }
  WriteFileAtomic(dir + "/scene.json", "{\"format\": ");
  try {
    reader->ReadScene(dir, "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/scene.json");
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos);
  }
}

TEST(Generic, FixturesDuplicateIdsAndBadK) {
  const std::string fixtures = std::string(OCCGT_FIXTURES_DIR) + "/io";
  const auto reader = MakeReader(gt::DatasetFormat::kGeneric);
  try {
    reader->ReadScene(fixtures + "/generic_duplicate_ids", "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), fixtures +
                                         "/generic_duplicate_ids/scene.json: frames[1].id: "
                                         "duplicate frame id 'a'");
  }
  try {
    reader->ReadScene(fixtures + "/generic_bad_k", "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), fixtures +
                                         "/generic_bad_k/scene.json: frames[1].K: expected a "
                                         "3x3 array of numbers");
  }
}

TEST(Generic, NonRigidPoseIsUnusable) {
  const std::string dir = test::ScratchDir("gen_pose");
  json j = ValidManifest();
  j["frames"][0]["world_from_cam"][0][0] = 2.0;
  WriteManifest(dir, j);
  ReaderOptions options;
  options.check_depth_files = false;
  const Scene s = MakeReader(gt::DatasetFormat::kGeneric, options)->ReadScene(dir, "");
  EXPECT_FALSE(s.frames[0].usable);
  EXPECT_EQ(s.frames[0].unusable_reason, "pose: rotation is not orthonormal (|R^T R - I| > 0.001)");
  EXPECT_TRUE(s.frames[1].usable);
}

// A manifest's bad pose names the manifest and the JSON field path of the pose: the row
// holding the wrong value, or the whole matrix for a reflection. JSON has no NaN or inf, so
// a non-finite pose cannot be written: such a token (or a number beyond double's range) is
// invalid JSON, an error naming the manifest.
TEST(Generic, BadPoseNamesTheFieldPath) {
  const std::string dir = test::ScratchDir("gen_pose_where");
  json j = ValidManifest();
  j["frames"][0]["world_from_cam"][1][1] = 2.0;
  j["frames"][1]["world_from_cam"][3][2] = 0.5;
  j["frames"][2]["world_from_cam"][2][2] = -1.0;
  const std::string manifest = WriteManifest(dir, j);
  ReaderOptions options;
  options.check_depth_files = false;
  const auto reader = MakeReader(gt::DatasetFormat::kGeneric, options);
  const Scene s = reader->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 3u);
  EXPECT_EQ(s.frames[0].unusable_detail,
            manifest +
                ": frames[0].world_from_cam[1]: rotation is not orthonormal (|R^T R - I| = 3 > "
                "0.001)");
  EXPECT_EQ(s.frames[1].unusable_reason, "pose: last row of the pose is not [0 0 0 1]");
  EXPECT_EQ(s.frames[1].unusable_detail,
            manifest + ": frames[1].world_from_cam[3]: last row of the pose is not [0 0 0 1]");
  EXPECT_EQ(s.frames[2].unusable_detail,
            manifest + ": frames[2].world_from_cam: rotation has det < 0 (a reflection)");
  for (const char* token : {"NaN", "Infinity", "1e999"}) {
    // frames[0].world_from_cam[0][0]: the first '1' after the key (keys are sorted).
    std::string text = j.dump(1);
    const size_t at = text.find('1', text.find("\"world_from_cam\""));
    ASSERT_NE(at, std::string::npos) << text;
    text.replace(at, 1, token);
    WriteFileAtomic(manifest, text);
    try {
      reader->ReadScene(dir, "");
      ADD_FAILURE() << token << ": expected InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), manifest) << e.what();
      EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
    }
  }
}

// nlohmann::json keeps the last of two equal keys; an edited manifest that gives a key twice
// is refused instead, with the JSON field path of the second one. Equal keys in different
// objects, and equal strings as values, are fine.
TEST(Generic, DuplicateKeyNamesTheFieldPath) {
  const std::string dir = test::ScratchDir("gen_dup_key");
  const json j = ValidManifest();
  const std::string manifest = WriteManifest(dir, j);
  ReaderOptions options;
  options.check_depth_files = false;
  const auto reader = MakeReader(gt::DatasetFormat::kGeneric, options);
  ASSERT_EQ(reader->ReadScene(dir, "").frames.size(), 3u);  // keys "K" in every frame: fine
  const std::string text = j.dump();
  struct Case {
    std::string after, insert, field;  // insert `insert` right after the first `after`
  };
  const std::vector<Case> cases = {
      {"{", "\"format\": \"generic\", ", "format"},
      {"\"frames\":[{", "\"K\": [[1,0,0],[0,1,0],[0,0,1]], ", "frames[0].K"},
      {"\"frames\":[{", "\"extra\": {\"a\": 1, \"a\": 2}, ", "frames[0].extra.a"},
  };
  for (const Case& c : cases) {
    std::string edited = text;
    size_t at = edited.find(c.after);
    ASSERT_NE(at, std::string::npos) << c.after;
    edited.insert(at + c.after.size(), c.insert);
    WriteFileAtomic(manifest, edited);
    try {
      reader->ReadScene(dir, "");
      ADD_FAILURE() << c.field << ": expected InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()),
                manifest + ": " + c.field + ": duplicate key (a key may appear once in an object)");
    }
  }
  // The third frame's K given twice: the path counts the array elements before it.
  std::string edited = text;
  size_t at = 0;
  for (int k = 0; k < 3; ++k) at = edited.find("\"K\":", at) + 1;
  edited.insert(at - 1, "\"K\":[[1,0,0],[0,1,0],[0,0,1]],");
  WriteFileAtomic(manifest, edited);
  try {
    reader->ReadScene(dir, "");
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              manifest + ": frames[2].K: duplicate key (a key may appear once in an object)");
  }
}

TEST(Readers, UnknownFormatAndKnownFormats) {
  EXPECT_EQ(KnownFormats(), (std::vector<std::string>{"scannet", "tartanair", "sevenscenes", "tum",
                                                      "megadepth", "generic", "scannetpp"}));
  for (const auto& f : KnownFormats()) {
    EXPECT_EQ(DatasetFormatName(MakeReader(ParseDatasetFormat(f))->Format()), f);
  }
  try {
    ParseDatasetFormat("colmap");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--format");
  }
}

}  // namespace
}  // namespace gt::datasets

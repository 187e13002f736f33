// libgt/truth, the per-pair entry point: the frame loader (size check, resize, K rule, frame
// lookup with its messages), ComputePairTruth against the functions it composes (labels of
// geometry/pair.h and occupancy of occupancy/pair_occupancy.h, called directly here), and
// FuseScope's skipping of unreadable scope frames and its list of unusable ones.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/geometry/pair.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/synth/dataset.h"
#include "libgt/truth/pair_truth.h"
#include "libgt/truth/working_frame.h"
#include "tests/support/test_support.h"

namespace gt::truth {
namespace {

namespace fs = std::filesystem;

// A synthetic scene of 24 frames at 80×60 (exact ray-cast depth), generated once.
const Scene& SynthScene() {
  static const Scene scene = [] {
    const std::string dir = test::ScratchDir("truth_synth");
    synth::SynthOptions o;
    o.scenes = 1;
    o.frames_per_scene = 24;
    o.width = 80;
    o.height = 60;
    synth::WriteSyntheticDataset(dir, o);
    const auto reader = datasets::MakeReader(gt::DatasetFormat::kGeneric);
    return reader->ReadScene(dir, reader->ListScenes(dir).at(0));
  }();
  return scene;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Resolution, ParsesAndChecksOneRange) {
  const Resolution r = ParseResolution("640x480", "--resolution");
  EXPECT_EQ(r.width, 640);
  EXPECT_EQ(r.height, 480);
  EXPECT_EQ(ParseResolution("2x8192", "--r").height, 8192);
  for (const char* bad :
       {"1x480", "640x8193", "640x", "x480", "640x480x3", "640*480", "", "-2x4"}) {
    const std::string e = ErrorOf([&] { ParseResolution(bad, "--resolution"); });
    EXPECT_NE(e.find("--resolution: expected WxH with integers in 2..8192"), std::string::npos)
        << bad << ": " << e;
  }
}

TEST(ParseFramePair, TwoIdsOrAnError) {
  EXPECT_EQ(ParseFramePair("000150,000160"),
            std::make_pair(std::string("000150"), std::string("000160")));
  for (const char* bad : {"000150", ",1", "1,", "1,2,3", ""}) {
    EXPECT_NE(ErrorOf([&] { ParseFramePair(bad); }).find("--frames: expected two frame ids"),
              std::string::npos)
        << bad;
  }
  // A frame with itself (every pixel VISIBLE) is a typo, refused as render's --frames is.
  EXPECT_EQ(ErrorOf([] { ParseFramePair("000150,000150"); }),
            "--frames: '000150' given twice in '000150,000150': expected two different frames");
  EXPECT_EQ(ParseFramePair("000150,0001500"),
            std::make_pair(std::string("000150"), std::string("0001500")));
}

TEST(FindFrame, NamesUnknownAndUnusableFramesAndSuggestsTheIdOfANumber) {
  Scene scene = SynthScene();
  EXPECT_EQ(FindFrame(scene, scene.frames[3].id), 3u);
  const std::string by_number = std::to_string(scene.frames[3].number);
  const std::string e = ErrorOf([&] { FindFrame(scene, by_number + "x"); });
  EXPECT_NE(e.find("no frame with id"), std::string::npos) << e;
  EXPECT_NE(e.find("ids look like '" + scene.frames[0].id + "'"), std::string::npos) << e;
  if (by_number != scene.frames[3].id) {
    const std::string s = ErrorOf([&] { FindFrame(scene, by_number); });
    EXPECT_NE(s.find("did you mean '" + scene.frames[3].id + "'"), std::string::npos) << s;
  }
  scene.frames[2].usable = false;
  scene.frames[2].unusable_reason = "pose: non-finite pose entries (lost tracking)";
  const std::string u = ErrorOf([&] { FindFrame(scene, scene.frames[2].id, "--x"); });
  EXPECT_NE(u.find("--x: frame " + scene.frames[2].id + " is unusable: pose: non-finite"),
            std::string::npos)
      << u;
  // With a detail (where the reader found it), the message adds it.
  scene.frames[2].unusable_detail = "pose_left.txt:3: non-finite value";
  const std::string d = ErrorOf([&] { FindFrame(scene, scene.frames[2].id, "--x"); });
  EXPECT_EQ(d, "--x: frame " + scene.frames[2].id +
                   " is unusable: pose: non-finite pose entries (lost tracking); pose_left.txt:3: "
                   "non-finite value");
}

TEST(LoadWorkingFrame, ResizesNearestAndRescalesK) {
  const Frame& f = SynthScene().frames[0];
  const WorkingFrame same = LoadWorkingFrame(f, {80, 60});
  const WorkingFrame half = LoadWorkingFrame(f, {40, 30});
  ASSERT_EQ(same.depth->width, 80);
  ASSERT_EQ(half.depth->width, 40);
  ASSERT_EQ(half.depth->height, 30);
  // Nearest neighbour at a factor of 2: pixel (u, v) of the half map is (2u, 2v) or its
  // neighbour (2u + 1, 2v + 1) of the full one (core/depth.h's rule); every value is one
  // of the full map's values of that 2×2 block.
  for (int v = 0; v < 30; ++v) {
    for (int u = 0; u < 40; ++u) {
      const float x = half.depth->at(u, v);
      bool found = false;
      for (int dv = 0; dv < 2; ++dv) {
        for (int du = 0; du < 2; ++du) found = found || same.depth->at(2 * u + du, 2 * v + dv) == x;
      }
      EXPECT_TRUE(found) << u << "," << v;
    }
  }
  // fx' = sx fx, cx' = sx (cx + 0.5) - 0.5 (GROUND_TRUTH.md §1).
  EXPECT_DOUBLE_EQ(half.camera.fx, 0.5 * same.camera.fx);
  EXPECT_DOUBLE_EQ(half.camera.cx, 0.5 * (same.camera.cx + 0.5) - 0.5);
  EXPECT_DOUBLE_EQ(half.camera.cy, 0.5 * (same.camera.cy + 0.5) - 0.5);
  EXPECT_TRUE(half.world_from_cam.matrix().isApprox(f.world_from_cam.matrix()));
}

TEST(LoadWorkingFrame, ADepthFileOfAnotherSizeNamesTheFile) {
  Frame f = SynthScene().frames[0];
  f.depth_camera = f.depth_camera.Resized(40, 30);  // the reader announced 40×30
  const std::string e = ErrorOf([&] { LoadWorkingFrame(f, {40, 30}); });
  EXPECT_NE(e.find(f.depth.path), std::string::npos) << e;
}

TEST(ComputePairTruth, EqualsTheFunctionsItComposes) {
  const Scene& scene = SynthScene();
  const WorkingFrame a = LoadWorkingFrame(scene.frames[1], {80, 60});
  const WorkingFrame b = LoadWorkingFrame(scene.frames[2], {80, 60});
  PairTruthOptions o;
  o.labels = LabelPreset("default");
  o.labels.min_depth_m = scene.min_depth_m;
  o.labels.max_depth_m = scene.max_depth_m;
  o.fusion.voxel_m = 0.1;
  const PairTruth t = ComputePairTruth(a, b, o);
  const PairLabels l = LabelPair(*a.depth, a.camera, a.world_from_cam, *b.depth, b.camera,
                                 b.world_from_cam, o.labels, o.patches);
  EXPECT_EQ(t.labels.l01.labels, l.l01.labels);
  EXPECT_EQ(t.labels.l10.labels, l.l10.labels);
  EXPECT_EQ(t.labels.patches.matches, l.patches.matches);
  EXPECT_EQ(t.labels.patches.match_xy, l.patches.match_xy);
  EXPECT_EQ(t.labels.m01.counts, l.m01.counts);
  EXPECT_GT(l.patches.size(), 0u);
  ASSERT_TRUE(t.occupancy.has_value());
  const occupancy::PairOccupancy occ = occupancy::ComputePairOccupancy(
      FusionInputOf(a, o.labels), FusionInputOf(b, o.labels), o.fusion, o.bins, o.mode);
  EXPECT_EQ(t.occupancy->cam0.occ, occ.cam0.occ);
  EXPECT_EQ(t.occupancy->cam1.known, occ.cam1.known);
  // Parts switched off are not computed.
  o.occupancy = false;
  EXPECT_FALSE(ComputePairTruth(a, b, o).occupancy.has_value());
  o.labels_and_matches = false;
  o.occupancy = true;
  const PairTruth occ_only = ComputePairTruth(a, b, o);
  EXPECT_TRUE(occ_only.labels.l01.labels.empty());
  EXPECT_EQ(occ_only.occupancy->cam0.occ, occ.cam0.occ);
  // Options are checked before any work.
  o.bins.num_bins = 65;
  EXPECT_NE(ErrorOf([&] { ComputePairTruth(a, b, o); }).find("pair options: occupancy"),
            std::string::npos);
}

// The pair's own fusion reports what it dropped (not only a scope map), and a voxel size
// whose key range cannot hold the ray range is refused, naming voxel_m.
TEST(ComputePairTruth, ReportsFusionStatsAndRefusesAVoxelTooSmall) {
  const Scene& scene = SynthScene();
  const WorkingFrame a = LoadWorkingFrame(scene.frames[1], {80, 60});
  WorkingFrame b = LoadWorkingFrame(scene.frames[2], {80, 60});
  auto depth = std::make_shared<DepthImage>(*b.depth);
  for (int u = 0; u < 80; u += 3) depth->at(u, 7) = 0.0f;  // 27 more invalid pixels
  b.depth = depth;
  PairTruthOptions o;
  o.labels.min_depth_m = scene.min_depth_m;
  o.labels.max_depth_m = scene.max_depth_m;
  o.fusion.voxel_m = 0.1;
  int64_t invalid = 0;
  for (const WorkingFrame* f : std::initializer_list<const WorkingFrame*>{&a, &b}) {
    for (float z : f->depth->values_m)
      invalid += IsValidDepth(z, o.labels.min_depth_m, o.labels.max_depth_m) ? 0 : 1;
  }
  ASSERT_GE(invalid, 27);
  const PairTruth t = ComputePairTruth(a, b, o);
  ASSERT_TRUE(t.occupancy && t.occupancy->fusion_stats);
  const occupancy::FusionStats& st = *t.occupancy->fusion_stats;
  EXPECT_EQ(st.frames, 2);
  EXPECT_EQ(st.pixels, 2 * 80 * 60);
  EXPECT_EQ(st.invalid_pixels, invalid);
  EXPECT_EQ(st.out_of_key_range, 0);
  EXPECT_EQ(st.inserted_points, st.pixels - invalid);
  // With a scope map, its stats.
  o.fusion.scope = occupancy::FusionScope::kWindow;
  o.fusion.window = 1;
  const ScopeMap m = FuseScope(scene, 1, 2, o, [&](size_t i) {
    return LoadWorkingFrame(scene.frames[i], {80, 60});
  });
  const PairTruth ts = ComputePairTruth(a, b, o, &m.map);
  EXPECT_EQ(ts.occupancy->fusion_stats->frames, 4);  // frames 0..3
  EXPECT_EQ(ts.occupancy->fusion_stats->pixels, m.map.stats().pixels);
  // two_point fuses nothing.
  o.fusion.scope = occupancy::FusionScope::kPair;
  o.mode = occupancy::OccupancyMode::kTwoPoint;
  EXPECT_FALSE(ComputePairTruth(a, b, o).occupancy->fusion_stats.has_value());

  o.mode = occupancy::OccupancyMode::kOctomap;
  o.fusion.voxel_m = 1e-6;  // +-0.0328 m around the origin; the range is 10 m
  try {
    ComputePairTruth(a, b, o);
    ADD_FAILURE() << "voxel 1e-6 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "voxel_m");
    EXPECT_NE(std::string(e.what()).find("with max_range_m 10 needs"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("use voxel_m >= "), std::string::npos) << e.what();
  }
  o.fusion.scope = occupancy::FusionScope::kWindow;  // FuseScope refuses it as well
  EXPECT_NE(ErrorOf([&] {
              FuseScope(scene, 1, 2, o, [&](size_t i) {
                return LoadWorkingFrame(scene.frames[i], {80, 60});
              });
            }).rfind("voxel_m: 1e-06 m holds", 0),
            std::string::npos);
}

TEST(FuseScope, SkipsUnreadableScopeFramesAndFailsOnThePairs) {
  const Scene& scene = SynthScene();
  PairTruthOptions o;
  o.labels.min_depth_m = scene.min_depth_m;
  o.labels.max_depth_m = scene.max_depth_m;
  o.fusion.voxel_m = 0.1;
  o.fusion.scope = occupancy::FusionScope::kWindow;
  o.fusion.window = 1;
  const FrameLoader load = [&](size_t i) {
    if (i == 4) throw InputError("frame4.npy", "cannot open file (test)");
    return LoadWorkingFrame(scene.frames[i], {80, 60});
  };
  const ScopeMap m = FuseScope(scene, 2, 3, o, load);  // window frames 1..4
  ASSERT_EQ(m.skipped.size(), 1u);
  EXPECT_EQ(m.skipped[0].frame_id, scene.frames[4].id);
  EXPECT_NE(m.skipped[0].reason.find("frame4.npy"), std::string::npos);
  EXPECT_FALSE(m.skipped[0].unusable);
  EXPECT_EQ(m.fused_ids,
            (std::vector<std::string>{scene.frames[1].id, scene.frames[2].id, scene.frames[3].id}));
  EXPECT_THROW(FuseScope(scene, 3, 4, o, load), InputError);  // a frame of the pair
}

// A window or scene scope lists the unusable frames it leaves out, with the reader's reason
// (they were left out without a word): a window's within its positions, a scene's all of them
// (the stride numbers the usable frames only).
TEST(FuseScope, ListsTheUnusableFramesOfTheScope) {
  Scene scene = SynthScene();
  scene.frames[1].usable = false;
  scene.frames[1].unusable_reason = "pose: non-finite pose entries";
  scene.frames[1].unusable_detail = "poses.txt:2: non-finite value";
  scene.frames[9].usable = false;  // outside the window
  scene.frames[9].unusable_reason = "depth: missing file";
  PairTruthOptions o;
  o.labels.min_depth_m = scene.min_depth_m;
  o.labels.max_depth_m = scene.max_depth_m;
  o.fusion.voxel_m = 0.1;
  o.fusion.scope = occupancy::FusionScope::kWindow;
  o.fusion.window = 1;
  const FrameLoader load = [&](size_t i) { return LoadWorkingFrame(scene.frames[i], {80, 60}); };
  const ScopeMap m = FuseScope(scene, 2, 3, o, load);  // window frames 1..4
  EXPECT_EQ(m.fused_ids,
            (std::vector<std::string>{scene.frames[2].id, scene.frames[3].id, scene.frames[4].id}));
  ASSERT_EQ(m.skipped.size(), 1u);
  EXPECT_EQ(m.skipped[0].frame_id, scene.frames[1].id);
  EXPECT_EQ(m.skipped[0].reason,
            "unusable: pose: non-finite pose entries; poses.txt:2: non-finite value");
  EXPECT_TRUE(m.skipped[0].unusable);  // the build fails a sample on the others only
  o.fusion.scope = occupancy::FusionScope::kScene;
  o.fusion.scene_stride = 30;
  const ScopeMap s = FuseScope(scene, 2, 3, o, load);
  EXPECT_EQ(s.fused_ids, (std::vector<std::string>{scene.frames[0].id}));
  ASSERT_EQ(s.skipped.size(), 2u);
  EXPECT_EQ(s.skipped[0].frame_id, scene.frames[1].id);
  EXPECT_EQ(s.skipped[1].frame_id, scene.frames[9].id);
  EXPECT_EQ(s.skipped[1].reason, "unusable: depth: missing file");
  // The pair scope is the pair's two frames: nothing else is left out.
  o.fusion.scope = occupancy::FusionScope::kPair;
  EXPECT_TRUE(FuseScope(scene, 2, 3, o, load).skipped.empty());
}

// A scene scope fuses every S-th usable frame, and one with nothing left to fuse is refused
// (it gave an empty map: every bin of every pair unknown, exit 0).
TEST(FuseScope, SceneScopeNeverFusesNothingSilently) {
  Scene scene = SynthScene();
  PairTruthOptions o;
  o.labels.min_depth_m = scene.min_depth_m;
  o.labels.max_depth_m = scene.max_depth_m;
  o.fusion.voxel_m = 0.1;
  o.fusion.scope = occupancy::FusionScope::kScene;
  o.fusion.scene_stride = 30;  // more than the 24 frames
  scene.frames[0].usable = false;
  const FrameLoader load = [&](size_t i) { return LoadWorkingFrame(scene.frames[i], {80, 60}); };
  const ScopeMap m = FuseScope(scene, 2, 3, o, load);
  EXPECT_EQ(m.fused_ids, (std::vector<std::string>{scene.frames[1].id}));
  EXPECT_GT(m.map.stats().pixels, 0);
  const FrameLoader broken = [&](size_t i) -> WorkingFrame {
    if (i == 1) throw InputError("frame1.npy", "cannot open file (test)");
    return LoadWorkingFrame(scene.frames[i], {80, 60});
  };
  const std::string e = ErrorOf([&] { FuseScope(scene, 2, 3, o, broken); });
  EXPECT_EQ(e.rfind(scene.name + ": occupancy scope scene:30: no frame to fuse: none of its 1 "
                                 "frames could be read, the first: frame1.npy",
                    0),
            0u)
      << e;
  for (Frame& f : scene.frames) f.usable = false;
  EXPECT_EQ(ErrorOf([&] { FuseScope(scene, 2, 3, o, load); }),
            scene.name +
                ": occupancy scope scene:30: no frame to fuse (the scene has no usable "
                "frame)");
}

}  // namespace
}  // namespace gt::truth

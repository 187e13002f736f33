// Depth sources of a frame: the fused rule pixel by pixel (each class, the tolerance's
// boundary, the scene's validity range), the names, and LoadFrameDepth on the 7-Scenes sample
// with the shared TSDF mesh as the scene's mesh: sensor = the depth file, mesh = the
// renderer's map, fused = the rule applied to both, the counts adding up to every pixel.
#include "libgt/render/frame_depth.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/depth_io.h"
#include "libgt/pipeline/recipe.h"
#include "tests/support/test_support.h"

namespace gt::render {
namespace {

DepthImage Row(std::vector<float> values) {
  DepthImage d(static_cast<int>(values.size()), 1);
  d.values_m = std::move(values);
  return d;
}

TEST(FrameDepth, FusedRulePixelByPixel) {
  const FusedDepthOptions options;  // 0.2 m + 1 %
  // sensor, mesh:  agree (|d| = 0.1) | boundary (0.2 + 0.01 * 4 = 0.24: agree) | 0.25 > 0.24:
  // disagree | sensor hole | mesh hole | neither | sensor above the range (a hole) | NaN sensor
  const DepthImage sensor = Row({2.1f, 4.24f, 4.25f, 0.0f, 3.0f, 0.0f, 12.0f, NAN});
  const DepthImage mesh = Row({2.0f, 4.0f, 4.0f, 1.5f, 0.0f, 0.0f, 5.0f, 2.5f});
  DepthAgreement counts;
  const DepthImage fused = FuseSensorAndMesh(sensor, mesh, 0.1, 10.0, options, &counts);
  const std::vector<float> expected = {2.1f, 4.24f, 0.0f, 1.5f, 3.0f, 0.0f, 5.0f, 2.5f};
  EXPECT_EQ(fused.values_m, expected);
  EXPECT_EQ(counts.agree, 2);
  EXPECT_EQ(counts.disagree, 1);
  EXPECT_EQ(counts.mesh_only, 3);
  EXPECT_EQ(counts.sensor_only, 1);
  EXPECT_EQ(counts.neither, 1);
  EXPECT_EQ(counts.Total(), 8);
  const DepthAgreement only = CompareSensorAndMesh(sensor, mesh, 0.1, 10.0, options);
  EXPECT_EQ(only.agree, 2);
  EXPECT_EQ(only.disagree, 1);
  // A tighter tolerance (5 cm) turns the 0.1 m and boundary pixels into disagreements.
  FusedDepthOptions tight;
  tight.abs_tol_m = 0.05;
  tight.rel_tol = 0;
  EXPECT_EQ(CompareSensorAndMesh(sensor, mesh, 0.1, 10.0, tight).disagree, 3);
  std::string error;
  tight.rel_tol = -1;
  EXPECT_FALSE(tight.Check(&error));
}

TEST(FrameDepth, Names) {
  for (DepthSourceMode m :
       {DepthSourceMode::kSensor, DepthSourceMode::kMesh, DepthSourceMode::kFused}) {
    EXPECT_EQ(ParseDepthSourceMode(DepthSourceModeName(m), "--depth-source"), m);
  }
  try {
    ParseDepthSourceMode("lidar", "--depth-source");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "--depth-source: unknown depth source 'lidar', expected sensor, mesh or fused");
  }
}

TEST(FrameDepth, SevenScenesWithTsdfMesh) {
  const std::string parent = gt::test::SharedData("sevenscenes");
  const std::string mesh_path = gt::test::SharedData("meshes/sevenscenes-rgbd-frames-tsdf.ply");
  ASSERT_FALSE(parent.empty());
  ASSERT_FALSE(mesh_path.empty());
  Scene scene = datasets::MakeReader(DatasetFormat::kSevenScenes)->ReadScene(parent, "rgbd-frames");
  const Frame& frame = scene.frames[20];
  const Camera camera = frame.depth_camera;
  FrameDepthOptions options;
  // Without a mesh: sensor works, mesh is refused naming the scene.
  EXPECT_EQ(LoadFrameDepth(scene, frame, camera, options).values_m,
            io::ReadDepth(frame.depth, camera.width, camera.height).values_m);
  options.source = DepthSourceMode::kMesh;
  EXPECT_THROW(LoadFrameDepth(scene, frame, camera, options), InputError);
  scene.mesh_path = mesh_path;
  DepthAgreement counts;
  const DepthImage mesh = LoadFrameDepth(scene, frame, camera, options, &counts);
  const RenderedDepth direct =
      MeshRenderer(ReadPlyMesh(mesh_path)).Render(camera, frame.world_from_cam, RenderOptions{});
  ASSERT_EQ(mesh.values_m.size(), direct.depth_m.total());
  EXPECT_TRUE(std::equal(mesh.values_m.begin(), mesh.values_m.end(), direct.depth_m.begin()));
  EXPECT_EQ(counts.Total(), int64_t{camera.width} * camera.height);
  // Fused: the same counts, and the rule against the two maps.
  options.source = DepthSourceMode::kFused;
  DepthAgreement fused_counts;
  const DepthImage fused = LoadFrameDepth(scene, frame, camera, options, &fused_counts);
  EXPECT_EQ(fused_counts.agree, counts.agree);
  EXPECT_EQ(fused_counts.mesh_only, counts.mesh_only);
  const DepthImage sensor = io::ReadDepth(frame.depth, camera.width, camera.height);
  EXPECT_EQ(fused.values_m,
            FuseSensorAndMesh(sensor, mesh, scene.min_depth_m, scene.max_depth_m, options.fused)
                .values_m);
  // The TSDF mesh was fused from these frames: nearly every pixel with both agrees, and the
  // mesh fills some of the sensor's holes.
  EXPECT_GT(counts.agree, 50 * counts.disagree);
  EXPECT_GT(counts.mesh_only, 0);
  // At another size: the mesh is rendered at that size, the sensor resized (nearest).
  const Camera half = camera.Resized(320, 240);
  const DepthImage small = LoadFrameDepth(scene, frame, half, options);
  EXPECT_EQ(small.width, 320);
  EXPECT_EQ(small.height, 240);
}

// ScanNet: <scene>_vh_clean_2.ply inside the scene folder (beside the .sens) or beside the
// folder becomes the scene's mesh; depth_source mesh renders it even for frames whose depth
// file is missing (the shared posed-colour sample has none).
TEST(FrameDepth, ScanNetFindsItsMesh) {
  namespace fs = std::filesystem;
  const std::string sample = gt::test::SharedData("scannet_posed_color/scene_sample");
  ASSERT_FALSE(sample.empty());
  const std::string root = gt::test::ScratchDir("scannet_mesh");
  const fs::path scene_dir = fs::path(root) / "scene0001_00";
  fs::copy(sample, scene_dir, fs::copy_options::recursive);
  const auto reader = datasets::MakeReader(DatasetFormat::kScanNet);
  EXPECT_EQ(reader->ReadScene(root, "scene0001_00").mesh_path, "");
  TriangleMesh wall;  // z = 3 m in the world, large
  wall.vertices_m = {-50, -50, 3, 50, -50, 3, 50, 50, 3, -50, 50, 3};
  wall.triangles = {0, 1, 2, 0, 2, 3};
  const std::string beside = (fs::path(root) / "scene0001_00_vh_clean_2.ply").string();
  io::WriteFileAtomic(beside, EncodePlyMesh(wall));
  EXPECT_EQ(reader->ReadScene(root, "scene0001_00").mesh_path, beside);
  const std::string inside = (scene_dir / "scene0001_00_vh_clean_2.ply").string();
  io::WriteFileAtomic(inside, EncodePlyMesh(wall));
  const Scene scene = reader->ReadScene(root, "scene0001_00");
  EXPECT_EQ(scene.mesh_path, inside);  // inside wins
  FrameDepthOptions options;
  options.source = DepthSourceMode::kMesh;
  const Frame& f = scene.frames[0];
  const DepthImage d = LoadFrameDepth(scene, f, f.depth_camera, options);
  const RenderedDepth direct =
      MeshRenderer(wall).Render(f.depth_camera, f.world_from_cam, RenderOptions{});
  EXPECT_TRUE(std::equal(d.values_m.begin(), d.values_m.end(), direct.depth_m.begin()));
}

// The recipe keys: dataset.depth_source, dataset.mesh_path ({scene}), dataset.fused_depth;
// a recipe without them (or with depth_source: sensor) keeps its digest.
TEST(FrameDepth, RecipeKeys) {
  const std::string base = "name: tiny\ndataset:\n  format: sevenscenes\n  root: data/seq\n";
  const pipeline::Recipe plain = pipeline::ParseRecipe(base, "r.yaml", "/base");
  EXPECT_EQ(plain.dataset.depth_source, DepthSourceMode::kSensor);
  EXPECT_EQ(plain.dataset.mesh_path, "");
  const pipeline::Recipe sensor =
      pipeline::ParseRecipe(base + "  depth_source: sensor\n", "r.yaml", "/base");
  EXPECT_EQ(sensor.Digest(), plain.Digest());
  const pipeline::Recipe fused =
      pipeline::ParseRecipe(base +
                                "  depth_source: fused\n  mesh_path: meshes/{scene}.ply\n  "
                                "fused_depth: {abs_tol_m: 0.05, rel_tol: 0.02}\n",
                            "r.yaml", "/base");
  EXPECT_EQ(fused.dataset.depth_source, DepthSourceMode::kFused);
  EXPECT_EQ(fused.dataset.mesh_path, "/base/meshes/{scene}.ply");
  EXPECT_EQ(fused.dataset.fused_depth.abs_tol_m, 0.05);
  EXPECT_EQ(fused.dataset.fused_depth.rel_tol, 0.02);
  EXPECT_NE(fused.Digest(), plain.Digest());
  const FrameDepthOptions o = pipeline::RecipeFrameDepthOptions(fused);
  EXPECT_EQ(o.source, DepthSourceMode::kFused);
  EXPECT_EQ(o.fused.abs_tol_m, 0.05);
  Scene scene;
  scene.name = "seq-01";
  pipeline::ApplyMeshPath(fused.dataset.mesh_path, &scene);
  EXPECT_EQ(scene.mesh_path, "/base/meshes/seq-01.ply");
  // Bad values name the field.
  for (const std::string& bad :
       {std::string("  depth_source: lidar\n"), std::string("  fused_depth: {abs_tol_m: -1}\n"),
        std::string("  fused_depth: {tol: 1}\n")}) {
    try {
      pipeline::ParseRecipe(base + bad, "r.yaml", "/base");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("dataset."), std::string::npos) << e.what();
    }
  }
  // --depth-source overrides the recipe.
  pipeline::RecipeOverrides overrides;
  overrides.depth_source = DepthSourceMode::kMesh;
  EXPECT_EQ(pipeline::ParseRecipe(base, "r.yaml", "/base", overrides).dataset.depth_source,
            DepthSourceMode::kMesh);
}

}  // namespace
}  // namespace gt::render

// TartanAir reader on the real sample (tartanair/hospital_sample): NED -> OpenCV pose
// conversion checked by depth reprojection, the raw NED pose as a negative control, the
// pose file parsed independently, bad layouts (short pose file, AppleDouble files), and the
// three root shapes (one trajectory, a folder of trajectories, the ENV/{Easy,Hard} root).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "tests/datasets/consistency.h"
#include "tests/support/test_support.h"

namespace gt::datasets {
using namespace gt::io;  // NOLINT: the file helpers of io/ beside the readers
namespace {
namespace fs = std::filesystem;

const Frame& FrameById(const Scene& s, const std::string& id) {
  for (const auto& f : s.frames) {
    if (f.id == id) return f;
  }
  ADD_FAILURE() << "no frame " << id;
  static Frame none;
  return none;
}

TEST(TartanAir, SampleListsOneTrajectoryOf24Frames) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  ASSERT_FALSE(root.empty());
  const auto reader = MakeReader(gt::DatasetFormat::kTartanAir);
  const auto names = reader->ListScenes(root);
  ASSERT_EQ(names, std::vector<std::string>{"hospital_sample"});
  const Scene s = reader->ReadScene(root, names[0]);
  ASSERT_EQ(s.frames.size(), 24u);
  EXPECT_EQ(s.NumUsable(), 24u);
  EXPECT_EQ(s.min_depth_m, 0.05);
  EXPECT_EQ(s.max_depth_m, 500.0);
  for (size_t i = 0; i < s.frames.size(); ++i) {
    const Frame& f = s.frames[i];
    char id[32];
    std::snprintf(id, sizeof(id), "%06zu", i);
    EXPECT_EQ(f.id, id);
    EXPECT_EQ(f.number, static_cast<int64_t>(i));
    EXPECT_EQ(f.depth_camera.width, 640);
    EXPECT_EQ(f.depth_camera.height, 480);
    EXPECT_EQ(f.depth_camera.fx, 320.0);
    EXPECT_EQ(f.depth_camera.fy, 320.0);
    EXPECT_EQ(f.depth_camera.cx, 320.0);
    EXPECT_EQ(f.depth_camera.cy, 240.0);
    EXPECT_TRUE(FileExists(f.color_path)) << f.color_path;
  }
}

TEST(TartanAir, PoseIsNedBodyTimesAxisPermutation) {
  // Independent parse of pose_left.txt with >> double; the camera's z axis (third column
  // of R) must be the body's x axis (forward), camera x = body y, camera y = body z.
  const std::string root = test::SharedData("tartanair/hospital_sample");
  ASSERT_FALSE(root.empty());
  const Scene s = MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(root, "");
  std::ifstream in(root + "/pose_left.txt");
  for (size_t i = 0; i < s.frames.size(); ++i) {
    double t[3], q[4];
    ASSERT_TRUE(in >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3]);
    const Eigen::Matrix3d R_body =
        Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
    const Rigid3d& T = s.frames[i].world_from_cam;
    EXPECT_NEAR((T.translation() - Eigen::Vector3d(t[0], t[1], t[2])).norm(), 0.0, 1e-12);
    EXPECT_NEAR((T.linear().col(2) - R_body.col(0)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((T.linear().col(0) - R_body.col(1)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((T.linear().col(1) - R_body.col(2)).norm(), 0.0, 1e-9);
  }
}

TEST(TartanAir, Frames0And10ReprojectConsistently) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  ASSERT_FALSE(root.empty());
  const Scene s = MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(root, "");
  const Frame& a = FrameById(s, "000000");
  const Frame& b = FrameById(s, "000010");
  const DepthImage da = ReadDepth(a.depth, 640, 480);
  const DepthImage db = ReadDepth(b.depth, 640, 480);
  for (bool a_to_b : {true, false}) {
    const auto c =
        a_to_b ? test::DepthConsistency(da, a.depth_camera, a.world_from_cam, db, b.depth_camera,
                                        b.world_from_cam, s.min_depth_m, s.max_depth_m, 0.05)
               : test::DepthConsistency(db, b.depth_camera, b.world_from_cam, da, a.depth_camera,
                                        a.world_from_cam, s.min_depth_m, s.max_depth_m, 0.05);
    EXPECT_GT(c.compared, 20000);
    std::printf("tartanair %s: %ld compared, fraction %.4f\n", a_to_b ? "0->10" : "10->0",
                c.compared, c.fraction());
    EXPECT_GE(c.fraction(), 0.95) << (a_to_b ? "0->10" : "10->0");
  }
  // Negative control: the raw NED poses (no axis permutation) must do much worse.
  std::ifstream in(root + "/pose_left.txt");
  std::vector<Rigid3d> raw;
  double t[3], q[4];
  while (in >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3]) {
    raw.push_back(
        RigidFromTQ(Eigen::Vector3d(t[0], t[1], t[2]), Eigen::Vector4d(q[0], q[1], q[2], q[3])));
  }
  ASSERT_EQ(raw.size(), 24u);
  const auto bad = test::DepthConsistency(da, a.depth_camera, raw[0], db, b.depth_camera, raw[10],
                                          s.min_depth_m, s.max_depth_m, 0.05);
  const auto good = test::DepthConsistency(da, a.depth_camera, a.world_from_cam, db, b.depth_camera,
                                           b.world_from_cam, s.min_depth_m, s.max_depth_m, 0.05);
  std::printf("tartanair raw NED 0->10: fraction %.4f\n", bad.fraction());
  EXPECT_LT(bad.fraction(), good.fraction() - 0.3) << "raw " << bad.fraction();
}

// A scratch trajectory with n depth files of 4x4 and the given pose lines.
std::string MakeTrajectory(const std::string& name, int n_depth, const std::string& poses) {
  const std::string dir = test::ScratchDir(name);
  const std::vector<float> depth(16, 2.0f);
  for (int i = 0; i < n_depth; ++i) {
    char file[64];
    std::snprintf(file, sizeof(file), "/depth_left/%06d_left_depth.npy", i);
    WriteFileAtomic(dir + file, EncodeNpy("<f4", {4, 4}, depth.data(), depth.size() * 4));
  }
  WriteFileAtomic(dir + "/pose_left.txt", poses);
  return dir;
}

TEST(TartanAir, ShortPoseFileIsFatalAndNamesTheFile) {
  const std::string fixture = std::string(OCCGT_FIXTURES_DIR) + "/io/tartanair_short_pose";
  try {
    MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(fixture, "");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), fixture + "/pose_left.txt") << e.what();
    EXPECT_NE(std::string(e.what()).find("fewer"), std::string::npos) << e.what();
  }
}

TEST(TartanAir, PoseLineWithSixNumbersNamesFileAndLine) {
  const std::string dir = MakeTrajectory("ta_six", 2, "0 0 0 0 0 0 1\n0 0 0 0 0 1\n");
  try {
    MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(dir, "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/pose_left.txt:2") << e.what();
  }
}

TEST(TartanAir, NonUnitQuaternionMakesFrameUnusable) {
  const std::string dir = MakeTrajectory("ta_quat", 2, "0 0 0 0 0 0 1\n0 0 0 0 0 0 2\n");
  const Scene s = MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 2u);
  EXPECT_TRUE(s.frames[0].usable);
  EXPECT_FALSE(s.frames[1].usable);
  EXPECT_EQ(s.frames[1].unusable_reason, "pose: quaternion norm is not within 0.001 of 1");
  EXPECT_EQ(s.frames[1].unusable_detail,
            dir + "/pose_left.txt:2: quaternion norm is 2, expected 1");
}

// Issue #32: a bad pose line names its file and line; the frame is unusable, not the scene,
// and the counted reason stays one category whatever the line.
TEST(TartanAir, BadPoseValuesNameFileAndLine) {
  std::string poses;
  for (int i = 0; i < 12; ++i) {
    poses += i == 10  ? "0.5 nan 0 0 0 0 1\n"
             : i == 5 ? "0 0 -inf 0 0 0 1\n"
             : i == 7 ? "0 0 0 0 0 0 2\n"
                      : "0 0 0 0 0 0 1\n";
  }
  const std::string dir = MakeTrajectory("ta_bad_values", 12, poses);
  const Scene s = MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(dir, "");
  ASSERT_EQ(s.frames.size(), 12u);
  EXPECT_EQ(s.NumUsable(), 9u);
  const std::string file = dir + "/pose_left.txt";
  EXPECT_FALSE(s.frames[10].usable);
  EXPECT_EQ(s.frames[10].unusable_reason, "pose: non-finite pose entries");
  EXPECT_EQ(s.frames[10].unusable_detail, file + ":11: non-finite value");
  EXPECT_EQ(s.frames[10].UnusableMessage(),
            "pose: non-finite pose entries; " + file + ":11: non-finite value");
  EXPECT_EQ(s.frames[5].unusable_reason, "pose: non-finite pose entries");
  EXPECT_EQ(s.frames[5].unusable_detail, file + ":6: non-finite value");
  EXPECT_EQ(s.frames[7].unusable_detail, file + ":8: quaternion norm is 2, expected 1");
  EXPECT_TRUE(s.frames[9].unusable_detail.empty());
  // Blank lines do not count as poses but do count as lines.
  const std::string gap =
      MakeTrajectory("ta_bad_line_gap", 2, "0 0 0 0 0 0 1\n\n  \n0 0 0 inf 0 0 1\n");
  const Scene g = MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(gap, "");
  EXPECT_EQ(g.frames[1].unusable_detail, gap + "/pose_left.txt:4: non-finite value");
}

TEST(TartanAir, AppleDoubleFilesIgnoredAndEnvLayoutListed) {
  const std::string root = test::ScratchDir("ta_env");
  for (const char* traj : {"office/Easy/P001", "office/Hard/P003", "amusement/Easy/P008"}) {
    const std::string dir = root + "/" + traj;
    const std::vector<float> depth(16, 1.0f);
    WriteFileAtomic(dir + "/depth_left/000000_left_depth.npy",
                    EncodeNpy("<f4", {4, 4}, depth.data(), depth.size() * 4));
    WriteFileAtomic(dir + "/depth_left/._000000_left_depth.npy", "mac resource fork");
    WriteFileAtomic(dir + "/pose_left.txt", "0 0 0 0 0 0 1\n");
  }
  fs::create_directories(root + "/office/Easy/._P001");
  const auto reader = MakeReader(gt::DatasetFormat::kTartanAir);
  EXPECT_EQ(
      reader->ListScenes(root),
      (std::vector<std::string>{"amusement/Easy/P008", "office/Easy/P001", "office/Hard/P003"}));
  const Scene s = reader->ReadScene(root, "office/Hard/P003");
  EXPECT_EQ(s.name, "office/Hard/P003");
  ASSERT_EQ(s.frames.size(), 1u);
  EXPECT_TRUE(s.frames[0].usable);
  try {
    reader->ReadScene(root, "office/Easy/P999");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root + "/office/Easy/P999");
  }
}

// root/P000 = sample frames 0-3, root/P001 = sample frames 10-13 renumbered 0-3 (symlinks
// to the real files, pose lines copied), so P001's frame 0 must carry the sample's frame 10.
std::string MakeFolderOfTrajectories(const std::string& sample) {
  const std::string root = test::ScratchDir("ta_folder_of_trajectories");
  std::ifstream in(sample + "/pose_left.txt");
  std::vector<std::string> pose_lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) pose_lines.push_back(line);
  }
  EXPECT_EQ(pose_lines.size(), 24u);
  for (const auto& [traj, first] : {std::pair<std::string, int>{"P000", 0}, {"P001", 10}}) {
    const fs::path dir = fs::path(root) / traj;
    fs::create_directories(dir / "depth_left");
    fs::create_directories(dir / "image_left");
    std::string poses;
    for (int i = 0; i < 4; ++i) {
      char src[32], dst[32];
      std::snprintf(src, sizeof(src), "%06d", first + i);
      std::snprintf(dst, sizeof(dst), "%06d", i);
      fs::create_symlink(fs::path(sample) / "depth_left" / (std::string(src) + "_left_depth.npy"),
                         dir / "depth_left" / (std::string(dst) + "_left_depth.npy"));
      fs::create_symlink(fs::path(sample) / "image_left" / (std::string(src) + "_left.png"),
                         dir / "image_left" / (std::string(dst) + "_left.png"));
      poses += pose_lines.at(static_cast<size_t>(first + i)) + "\n";
    }
    WriteFileAtomic((dir / "pose_left.txt").string(), poses);
  }
  fs::create_directories(fs::path(root) / "notes");  // not a trajectory: no depth/image folder
  return root;
}

TEST(TartanAir, FolderOfTrajectoriesListsAndReadsEachByFolderName) {
  const std::string sample = test::SharedData("tartanair/hospital_sample");
  ASSERT_FALSE(sample.empty());
  const std::string root = MakeFolderOfTrajectories(sample);
  const auto reader = MakeReader(gt::DatasetFormat::kTartanAir);
  ASSERT_EQ(reader->ListScenes(root), (std::vector<std::string>{"P000", "P001"}));
  const Scene full = reader->ReadScene(sample, "");
  const Scene p1 = reader->ReadScene(root, "P001");
  EXPECT_EQ(p1.name, "P001");
  EXPECT_EQ(p1.path, root + "/P001");
  ASSERT_EQ(p1.frames.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const Frame& f = p1.frames[static_cast<size_t>(i)];
    const Frame& ref = full.frames[static_cast<size_t>(10 + i)];
    EXPECT_TRUE(f.usable) << f.unusable_reason;
    EXPECT_EQ(f.number, i);
    EXPECT_NEAR((f.world_from_cam.matrix() - ref.world_from_cam.matrix()).norm(), 0.0, 1e-12);
    EXPECT_TRUE(FileExists(f.color_path)) << f.color_path;
  }
  const DepthImage d = ReadDepth(p1.frames[0].depth, 640, 480);
  const DepthImage d_ref = ReadDepth(full.frames[10].depth, 640, 480);
  EXPECT_EQ(d.values_m, d_ref.values_m);
  const Scene p0 = reader->ReadScene(root, "P000");
  ASSERT_EQ(p0.frames.size(), 4u);
  EXPECT_NEAR(
      (p0.frames[3].world_from_cam.matrix() - full.frames[3].world_from_cam.matrix()).norm(), 0.0,
      1e-12);
  try {
    reader->ReadScene(root, "P002");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root + "/P002");
  }
}

TEST(TartanAir, TrajectoryFolderWithoutPoseFileIsFatal) {
  const std::string root = test::ScratchDir("ta_no_pose");
  const std::vector<float> depth(16, 1.0f);
  for (const char* traj : {"P000", "P001"}) {
    WriteFileAtomic(root + "/" + traj + "/depth_left/000000_left_depth.npy",
                    EncodeNpy("<f4", {4, 4}, depth.data(), depth.size() * 4));
  }
  WriteFileAtomic(root + "/P000/pose_left.txt", "0 0 0 0 0 0 1\n");
  try {
    MakeReader(gt::DatasetFormat::kTartanAir)->ListScenes(root);
    FAIL() << "P001 has depth_left/ but no pose_left.txt";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root + "/P001/pose_left.txt") << e.what();
  }
}

TEST(TartanAir, MixedLayoutsAndNoTrajectoryAreFatalAndListTheShapes) {
  const std::string root = test::ScratchDir("ta_mixed");
  const std::vector<float> depth(16, 1.0f);
  for (const char* traj : {"P000", "office/Easy/P001"}) {
    const std::string dir = root + "/" + traj;
    WriteFileAtomic(dir + "/depth_left/000000_left_depth.npy",
                    EncodeNpy("<f4", {4, 4}, depth.data(), depth.size() * 4));
    WriteFileAtomic(dir + "/pose_left.txt", "0 0 0 0 0 0 1\n");
  }
  const auto reader = MakeReader(gt::DatasetFormat::kTartanAir);
  try {
    reader->ListScenes(root);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), root);
    const std::string what = e.what();
    EXPECT_NE(what.find("mixes"), std::string::npos) << what;
    EXPECT_NE(what.find("P000/pose_left.txt"), std::string::npos) << what;
    EXPECT_NE(what.find("office/Easy/P001/pose_left.txt"), std::string::npos) << what;
  }
  const std::string empty = test::ScratchDir("ta_no_trajectory");
  fs::create_directories(empty + "/notes");
  try {
    reader->ListScenes(empty);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), empty);
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    for (const char* shape :
         {"ROOT/pose_left.txt", "ROOT/Pxxx/pose_left.txt", "ROOT/ENV/{Easy,Hard}/Pxxx"}) {
      EXPECT_NE(what.find(shape), std::string::npos) << shape << " in " << what;
    }
  }
}

TEST(TartanAir, EmptyTrajectoryIsFatal) {
  const std::string dir = test::ScratchDir("ta_empty");
  WriteFileAtomic(dir + "/pose_left.txt", "0 0 0 0 0 0 1\n");
  try {
    MakeReader(gt::DatasetFormat::kTartanAir)->ReadScene(dir, "");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir);
    EXPECT_NE(std::string(e.what()).find("empty scene"), std::string::npos);
  }
}

}  // namespace
}  // namespace gt::datasets

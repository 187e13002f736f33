// TartanAir v1 reader (docs/DATASETS.md "TartanAir v1").
//
// pose_left.txt holds world_from_body as "tx ty tz qx qy qz qw" per line, both frames in
// NED axes (x forward, y right, z down). The OpenCV camera (x right, y down, z forward)
// relates to the body by p_in_body = M * p_in_cam with M = [[0,0,1],[1,0,0],[0,1,0]]
// (camera x = body y, camera y = body z, camera z = body x), so
// world_from_cam = world_from_body * M. The world frame stays NED.
#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/file_read.h"

namespace gt::datasets {
namespace fs = std::filesystem;
namespace {

constexpr int kTartanAirWidthPx = 640;
constexpr int kTartanAirHeightPx = 480;
constexpr double kFocal = 320.0;  // fx = fy (90 degree field of view)
constexpr double kCx = 320.0;
constexpr double kCy = 240.0;

bool IsTrajectory(const std::string& folder) {
  return io::FileExists((fs::path(folder) / "pose_left.txt").string());
}

// A folder holding depth_left/ or image_left/ is meant as a trajectory: without
// pose_left.txt it is an error, never silently skipped.
void RequirePoseFileIfTrajectoryLike(const std::string& folder) {
  std::error_code ec;
  if (IsTrajectory(folder)) return;
  if (fs::is_directory(fs::path(folder) / "depth_left", ec) ||
      fs::is_directory(fs::path(folder) / "image_left", ec)) {
    throw InputError((fs::path(folder) / "pose_left.txt").string(),
                     "missing (the folder holds depth_left/ or image_left/: a TartanAir "
                     "trajectory needs pose_left.txt)");
  }
}

// body_from_cam: columns are the camera axes expressed in the body (NED) frame.
Eigen::Matrix3d BodyFromCamRotation() {
  Eigen::Matrix3d m;
  m << 0, 0, 1,  //
      1, 0, 0,   //
      0, 1, 0;
  return m;
}

}  // namespace

// Which shape a root is (docs/DATASETS.md "TartanAir v1"): a trajectory when it holds
// pose_left.txt; else a folder of trajectories when subfolders hold pose_left.txt
// (root/P000); else a dataset root when ENV/{Easy,Hard}/Pxxx below it do. A root holding
// both of the last two shapes is an error.
std::vector<std::string> TartanAirReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  if (IsTrajectory(root)) return {FolderName(root)};
  RequirePoseFileIfTrajectoryLike(root);
  std::vector<std::string> trajectories;      // root/Pxxx
  std::vector<std::string> env_trajectories;  // root/ENV/{Easy,Hard}/Pxxx
  for (const auto& sub : ListSubfolders(root)) {
    const fs::path sub_dir = fs::path(root) / sub;
    RequirePoseFileIfTrajectoryLike(sub_dir.string());
    if (IsTrajectory(sub_dir.string())) {
      trajectories.push_back(sub);
      continue;
    }
    if (sub == "Easy" || sub == "Hard") {  // root is one environment: ENV/{Easy,Hard}/Pxxx
      for (const auto& traj : ListSubfolders(sub_dir.string())) {
        RequirePoseFileIfTrajectoryLike((sub_dir / traj).string());
        if (IsTrajectory((sub_dir / traj).string())) trajectories.push_back(sub + "/" + traj);
      }
      continue;
    }
    for (const char* level : {"Easy", "Hard"}) {
      const fs::path level_dir = sub_dir / level;
      for (const auto& traj : ListSubfolders(level_dir.string())) {
        RequirePoseFileIfTrajectoryLike((level_dir / traj).string());
        if (IsTrajectory((level_dir / traj).string())) {
          env_trajectories.push_back(sub + "/" + level + "/" + traj);
        }
      }
    }
  }
  if (!trajectories.empty() && !env_trajectories.empty()) {
    throw InputError(root, "mixes two TartanAir layouts (trajectory " + trajectories.front() +
                               "/pose_left.txt and " + env_trajectories.front() +
                               "/pose_left.txt); expected one: ROOT/Pxxx/pose_left.txt or "
                               "ROOT/ENV/{Easy,Hard}/Pxxx/pose_left.txt");
  }
  std::vector<std::string> out = trajectories.empty() ? env_trajectories : trajectories;
  std::sort(out.begin(), out.end());
  if (out.empty()) {
    throw InputError(root,
                     "no TartanAir trajectory found; expected ROOT/pose_left.txt (one "
                     "trajectory), ROOT/Pxxx/pose_left.txt (a folder of trajectories), "
                     "ROOT/{Easy,Hard}/Pxxx/pose_left.txt (one environment) or "
                     "ROOT/ENV/{Easy,Hard}/Pxxx/pose_left.txt (the dataset root)");
  }
  return out;
}

Scene TartanAirReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  const std::string folder = ResolveSceneFolder(root, scene_name, IsTrajectory(root));
  Scene scene = NewFolderScene(folder, scene_name, Format(), 0.05, 500.0);

  // Frames: the union of depth_left and image_left numbers.
  const auto depths =
      ListNumberedFiles((fs::path(folder) / "depth_left").string(), "", "_left_depth.npy");
  const auto images =
      ListNumberedFiles((fs::path(folder) / "image_left").string(), "", "_left.png");
  std::map<int64_t, std::string> stems;
  for (const auto& f : depths) stems.emplace(f.number, f.stem);
  for (const auto& f : images) stems.emplace(f.number, f.stem);
  if (stems.empty()) {
    throw InputError(folder,
                     "empty scene: no depth_left/NNNNNN_left_depth.npy or image_left files");
  }

  // Pose lines: frame n is the n-th non-empty line (0-based).
  const std::string pose_path = (fs::path(folder) / "pose_left.txt").string();
  const std::vector<TQLine> pose_rows = ParseTQLines(io::ReadFileBytes(pose_path), pose_path);
  const int64_t last_number = stems.rbegin()->first;
  if (static_cast<int64_t>(pose_rows.size()) < static_cast<int64_t>(depths.size()) ||
      static_cast<int64_t>(pose_rows.size()) <= last_number) {
    std::ostringstream s;
    s << "has " << pose_rows.size() << " poses, fewer than the frames on disk (" << depths.size()
      << " depth files, last frame " << last_number << ")";
    throw InputError(pose_path, s.str());
  }

  const Camera camera = [] {
    Camera c;
    c.width = kTartanAirWidthPx;
    c.height = kTartanAirHeightPx;
    c.fx = c.fy = kFocal;
    c.cx = kCx;
    c.cy = kCy;
    return c;
  }();
  const Eigen::Matrix3d body_from_cam = BodyFromCamRotation();
  for (const auto& [number, stem] : stems) {
    Frame f;
    f.id = stem;
    f.number = number;
    f.depth.path = (fs::path(folder) / "depth_left" / (stem + "_left_depth.npy")).string();
    f.depth.format = DepthFormat::kNpyFloat32;
    f.depth_camera = camera;
    const std::string color = (fs::path(folder) / "image_left" / (stem + "_left.png")).string();
    if (io::FileExists(color)) {
      f.color_path = color;
      f.color_camera = camera;
    }
    // The line's pose is world_from_body; world_from_cam = world_from_body * body_from_cam.
    const TQLine& pose = pose_rows[static_cast<size_t>(number)];
    if (SetTQPose(pose.translation, pose.q_xyzw,
                  PoseLocator::Whole(LineWhere(pose_path, pose.line_no)), &f)) {
      f.world_from_cam.linear() = f.world_from_cam.linear() * body_from_cam;
    }
    if (options_.check_depth_files && !io::FileExists(f.depth.path)) {
      MarkUnusable(&f, kReasonDepthMissing);
    }
    scene.frames.push_back(std::move(f));
  }
  return scene;
}

}  // namespace gt::datasets

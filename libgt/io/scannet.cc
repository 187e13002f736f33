// ScanNet reader, Python SensReader export (docs/DATASETS.md "ScanNet").
#include <filesystem>

#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/files.h"
#include "libgt/io/readers.h"
#include "libgt/io/text_parsing.h"

namespace gt::io {
namespace fs = std::filesystem;
namespace {

constexpr int kDefaultDepthWidth = 640;  // ScanNet's depth sensor resolution
constexpr int kDefaultDepthHeight = 480;

bool IsScanNetScene(const std::string& folder) {
  std::error_code ec;
  return fs::is_directory(fs::path(folder) / "pose", ec);
}

// Colour file of frame `stem`: color/<stem>.jpg, else .png; "" when neither exists.
std::string ColorPath(const std::string& folder, const std::string& stem) {
  for (const char* ext : {".jpg", ".png"}) {
    const std::string p = (fs::path(folder) / "color" / (stem + ext)).string();
    if (FileExists(p)) return p;
  }
  return "";
}

}  // namespace

std::vector<std::string> ScanNetReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  if (IsScanNetScene(root)) return {FolderName(root)};
  std::vector<std::string> out;
  for (const auto& name : ListSubfolders(root)) {
    if (IsScanNetScene((fs::path(root) / name).string())) out.push_back(name);
  }
  if (out.empty()) throw InputError(root, "no ScanNet scene found (expected a folder with pose/)");
  return out;
}

Scene ScanNetReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  const std::string folder = ResolveSceneFolder(root, scene_name, IsScanNetScene(root));
  const std::string pose_dir = (fs::path(folder) / "pose").string();
  std::error_code ec;
  if (!fs::is_directory(pose_dir, ec)) throw InputError(pose_dir, "pose folder not found");

  Scene scene;
  scene.name = scene_name.empty() ? FolderName(folder) : scene_name;
  scene.format = Format();
  scene.path = folder;
  scene.min_depth_m = 0.1;
  scene.max_depth_m = 10.0;

  const std::vector<NumberedFile> poses = ListNumberedFiles(pose_dir, "", ".txt");
  if (poses.empty()) throw InputError(pose_dir, "empty scene: no <n>.txt pose files");

  const std::string intrinsic_dir = (fs::path(folder) / "intrinsic").string();
  const Eigen::Matrix3d K_depth =
      ReadIntrinsicsText((fs::path(intrinsic_dir) / "intrinsic_depth.txt").string());

  // Sizes from the first depth / colour file present.
  int depth_w = kDefaultDepthWidth, depth_h = kDefaultDepthHeight;
  for (const auto& p : poses) {
    const std::string d = (fs::path(folder) / "depth" / (p.stem + ".png")).string();
    if (FileExists(d)) {
      const ImageSize s = ReadImageSize(d);
      depth_w = s.width;
      depth_h = s.height;
      break;
    }
  }
  const Camera depth_camera = Camera::FromK(K_depth, depth_w, depth_h);
  Camera color_camera;
  for (const auto& p : poses) {
    const std::string c = ColorPath(folder, p.stem);
    if (c.empty()) continue;
    const ImageSize s = ReadImageSize(c);
    const std::string color_k_path = (fs::path(intrinsic_dir) / "intrinsic_color.txt").string();
    color_camera = FileExists(color_k_path)
                       ? Camera::FromK(ReadIntrinsicsText(color_k_path), s.width, s.height)
                       : depth_camera.Resized(s.width, s.height);
    break;
  }

  for (const auto& p : poses) {
    Frame f;
    f.id = p.stem;
    f.number = p.number;
    f.depth.path = (fs::path(folder) / "depth" / (p.stem + ".png")).string();
    f.depth.format = DepthFormat::kPng16;
    f.depth.scale_m_per_unit = 0.001;
    f.depth_camera = depth_camera;
    f.color_path = ColorPath(folder, p.stem);
    if (!f.color_path.empty()) f.color_camera = color_camera;
    const Eigen::Matrix4d m = ReadMatrixText(p.path, 4, 4);
    if (const auto problem = PoseProblem(m)) {
      MarkUnusable(&f, PoseReason(*problem));
    } else {
      f.world_from_cam = RigidFromMatrix(m);
    }
    if (options_.check_depth_files && !FileExists(f.depth.path)) {
      MarkUnusable(&f, kReasonDepthMissing);
    }
    scene.frames.push_back(std::move(f));
  }
  return scene;
}

}  // namespace gt::io

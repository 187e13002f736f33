// Microsoft RGB-D 7-Scenes reader (docs/DATASETS.md "7-Scenes").
// Depth is uint16 millimetres with 0 and 65535 invalid; K defaults to 585/585/320/240 at
// 640x480 unless camera-intrinsics.txt (3x3) sits in the sequence folder or its parent.
// Colour and depth are not registered: the colour camera gets the same K (documented).
#include <filesystem>
#include <set>

#include "libgt/core/error.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"

namespace gt::datasets {
namespace fs = std::filesystem;
namespace {

constexpr int kSevenScenesWidthPx = 640;
constexpr int kSevenScenesHeightPx = 480;
constexpr int kInvalidRaw = 65535;

bool IsSequence(const std::string& folder) {
  return !ListNumberedFiles(folder, "frame-", ".pose.txt").empty();
}

// A folder holding frame depth or colour files is meant as a sequence: without any pose
// file it is an error, never silently skipped (one frame without its pose file is an
// unusable frame of its sequence).
void RequirePosesIfSequenceLike(const std::string& folder) {
  if (IsSequence(folder)) return;
  for (const char* suffix : {".depth.png", ".color.png", ".color.jpg"}) {
    const auto files = ListNumberedFiles(folder, "frame-", suffix);
    if (!files.empty()) {
      throw InputError(folder, "holds " + std::to_string(files.size()) + " frame-NNNNNN" + suffix +
                                   " files and no frame-NNNNNN.pose.txt (a 7-Scenes sequence "
                                   "needs its pose files)");
    }
  }
}

}  // namespace

std::vector<std::string> SevenScenesReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  std::vector<std::string> out;
  for (const auto& name : ListSubfolders(root)) {
    RequirePosesIfSequenceLike((fs::path(root) / name).string());
    if (IsSequence((fs::path(root) / name).string())) out.push_back(name);
  }
  if (IsSequence(root)) {
    // Frames of its own beside sequence folders: which is meant cannot be told.
    if (!out.empty()) {
      throw InputError(root, "holds frame-NNNNNN.pose.txt files and sequence folders (" +
                                 out.front() +
                                 "): expected a sequence folder or a folder of sequences");
    }
    return {FolderName(root)};
  }
  RequirePosesIfSequenceLike(root);
  if (out.empty()) {
    throw InputError(root, "no 7-Scenes sequence found (expected frame-NNNNNN.pose.txt files)");
  }
  return out;
}

Scene SevenScenesReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  const std::string folder = ResolveSceneFolder(root, scene_name, IsSequence(root));
  Scene scene = NewFolderScene(folder, scene_name, Format(), 0.1, 10.0);

  const auto poses = ListNumberedFiles(folder, "frame-", ".pose.txt");
  if (poses.empty()) throw InputError(folder, "empty scene: no frame-NNNNNN.pose.txt files");
  // Frames: every number with a pose, depth or colour file; one without its pose file is
  // kept, unusable (kReasonPoseMissing), so that it is counted, never silently dropped.
  std::set<int64_t> with_pose;
  for (const auto& p : poses) with_pose.insert(p.number);
  std::vector<std::vector<NumberedFile>> lists = {poses};
  for (const char* suffix : {".depth.png", ".color.png", ".color.jpg"}) {
    lists.push_back(ListNumberedFiles(folder, "frame-", suffix));
  }
  const std::vector<NumberedFile> frames = MergeNumberedFiles(lists);

  Eigen::Matrix3d K;
  K << 585, 0, 320, 0, 585, 240, 0, 0, 1;
  const fs::path abs_folder = fs::absolute(folder).lexically_normal();
  for (const fs::path& dir : {abs_folder, abs_folder.parent_path()}) {
    const std::string p = (dir / "camera-intrinsics.txt").string();
    if (io::FileExists(p)) {
      K = ReadIntrinsicsText(p);
      break;
    }
  }
  int width = kSevenScenesWidthPx, height = kSevenScenesHeightPx;
  for (const auto& p : frames) {
    const std::string d = (fs::path(folder) / ("frame-" + p.stem + ".depth.png")).string();
    if (!io::FileExists(d)) continue;
    try {  // a damaged first file is that frame's problem (when it is read), not the scene's
      const io::ImageSize s = io::ReadImageSize(d);
      width = s.width;
      height = s.height;
      break;
    } catch (const InputError&) {
    }
  }
  const Camera camera = Camera::FromK(K, width, height);

  PreferredFile colour("colour");  // the releases' .color.png, else .color.jpg
  for (const auto& p : frames) {
    const std::string base = (fs::path(folder) / ("frame-" + p.stem)).string();
    Frame f;
    f.id = p.stem;
    f.number = p.number;
    f.depth.path = base + ".depth.png";
    f.depth.format = DepthFormat::kPng16;
    f.depth.scale_m_per_unit = 0.001;
    f.depth.invalid_value = kInvalidRaw;
    f.depth_camera = camera;
    // Colour as the releases have it: frame-NNNNNN.color.png, or .color.jpg.
    f.color_path = colour.Pick({base + ".color.png", base + ".color.jpg"});
    if (!f.color_path.empty()) f.color_camera = camera;
    if (with_pose.count(p.number) != 0) {
      SetPoseFromText(p.path, &f);
    } else {
      MarkUnusable(&f, kReasonPoseMissing, base + ".pose.txt");
    }
    if (options_.check_depth_files && !io::FileExists(f.depth.path)) {
      MarkUnusable(&f, kReasonDepthMissing);
    }
    scene.frames.push_back(std::move(f));
  }
  colour.Note(&scene);
  return scene;
}

}  // namespace gt::datasets

// Microsoft RGB-D 7-Scenes reader (docs/DATASETS.md "7-Scenes").
// Depth is uint16 millimetres with 0 and 65535 invalid; K defaults to 585/585/320/240 at
// 640x480 unless camera-intrinsics.txt (3x3) sits in the sequence folder or its parent.
// Colour and depth are not registered: the colour camera gets the same K (documented).
#include <filesystem>
#include <set>
#include <string>
#include <vector>

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

// Three shapes of root (docs/DATASETS.md "7-Scenes"): a sequence folder (one scene, named
// after it); a scene folder of sequences (`chess`: scenes `seq-01`, ...); the dataset root, a
// folder of scene folders (scenes `chess/seq-01`, ..., unambiguous across scenes). A root
// that mixes the last two cannot be told apart and is refused, as one with frames of its own
// beside sequence folders.
std::vector<std::string> SevenScenesReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  std::vector<std::string> sequences;        // root/seq-XX
  std::vector<std::string> scene_sequences;  // root/SCENE/seq-XX
  for (const auto& name : ListSubfolders(root)) {
    const fs::path sub = fs::path(root) / name;
    RequirePosesIfSequenceLike(sub.string());
    if (IsSequence(sub.string())) {
      sequences.push_back(name);
      continue;
    }
    for (const auto& seq : ListSubfolders(sub.string())) {
      RequirePosesIfSequenceLike((sub / seq).string());
      if (IsSequence((sub / seq).string())) scene_sequences.push_back(name + "/" + seq);
    }
  }
  if (IsSequence(root)) {
    // Frames of its own beside sequence folders: which is meant cannot be told.
    if (!sequences.empty() || !scene_sequences.empty()) {
      throw InputError(root, "holds frame-NNNNNN.pose.txt files and sequence folders (" +
                                 (sequences.empty() ? scene_sequences : sequences).front() +
                                 "): expected a sequence folder or a folder of sequences");
    }
    return {FolderName(root)};
  }
  RequirePosesIfSequenceLike(root);
  if (!sequences.empty() && !scene_sequences.empty()) {
    throw InputError(root, "holds sequence folders (" + sequences.front() +
                               ") beside scene folders of sequences (" + scene_sequences.front() +
                               "): expected a scene folder (chess) or the dataset root holding "
                               "scene folders");
  }
  if (sequences.empty() && scene_sequences.empty()) {
    throw InputError(root, "no 7-Scenes sequence found (expected frame-NNNNNN.pose.txt files)");
  }
  return sequences.empty() ? scene_sequences : sequences;
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
  // camera-intrinsics.txt in the sequence folder, its scene folder, or the dataset root.
  std::vector<fs::path> k_dirs = {abs_folder, abs_folder.parent_path()};
  if (scene_name.find('/') != std::string::npos)
    k_dirs.push_back(abs_folder.parent_path().parent_path());
  for (const fs::path& dir : k_dirs) {
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

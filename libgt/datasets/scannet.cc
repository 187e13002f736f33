// ScanNet reader (docs/DATASETS.md "ScanNet"), two SensReader export layouts:
//   Python exporter: <scene>/color/<i>.jpg, depth/<i>.png (uint16 mm), pose/<i>.txt (4x4
//     camera-to-world), intrinsic/intrinsic_depth.txt (+ intrinsic_color.txt);
//   C++ exporter: <scene>/frame-XXXXXX.color.jpg, .depth.pgm (uint16, m = raw / m_depthShift),
//     .pose.txt, and _info.txt ("key = value" lines: m_depthWidth, m_depthHeight,
//     m_depthShift, m_calibrationDepthIntrinsic as 16 (4x4) or 12 (3x4) numbers, row-major;
//     the colour keys are optional).
//   raw: <scene>/<scene>.sens, read in place (libgt/datasets/sens.h): frame i is the exporters'
//     frame i; depth and colour are byte ranges of the .sens (DepthFormat::kSensZlib).
// A folder with pose/ is read as the Python layout, else one with _info.txt as the C++ one,
// else one holding <folder name>.sens as the raw file.
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "libgt/core/error.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/sens.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"

namespace gt::datasets {
namespace fs = std::filesystem;
namespace {

constexpr int kDefaultDepthWidth = 640;  // ScanNet's depth sensor resolution
constexpr int kDefaultDepthHeight = 480;

constexpr const char* kCppInfoFile = "_info.txt";

bool IsPythonExport(const std::string& folder) {
  std::error_code ec;
  return fs::is_directory(fs::path(folder) / "pose", ec);
}

bool IsCppExport(const std::string& folder) {
  return io::FileExists((fs::path(folder) / kCppInfoFile).string()) &&
         !ListNumberedFiles(folder, "frame-", ".pose.txt").empty();
}

// <folder>/<folder name>.sens (ScanNet's scans/sceneXXXX_XX/sceneXXXX_XX.sens).
std::string SensPath(const std::string& folder) {
  return (fs::path(folder) / (FolderName(folder) + ".sens")).string();
}

bool IsSensScene(const std::string& folder) {
  std::error_code ec;
  return fs::is_regular_file(SensPath(folder), ec);
}

bool IsScanNetScene(const std::string& folder) {
  return IsPythonExport(folder) || IsCppExport(folder) || IsSensScene(folder);
}

// A folder holding depth/ or color/ is meant as an exported scene: without pose/ (or the
// C++ exporter's files, or a .sens) it is an error, never silently skipped.
void RequirePosesIfSceneLike(const std::string& folder) {
  if (IsScanNetScene(folder)) return;
  std::error_code ec;
  for (const char* sub : {"depth", "color"}) {
    if (fs::is_directory(fs::path(folder) / sub, ec)) {
      throw InputError((fs::path(folder) / "pose").string(),
                       std::string("missing (the folder holds ") + sub +
                           "/: an exported ScanNet scene needs pose/)");
    }
  }
}

// The C++ exporter's _info.txt: every "key = value" line, values as numbers.
struct CppInfo {
  std::string path;
  std::map<std::string, std::pair<int, std::vector<double>>> values;  // key -> (line, numbers)

  const std::vector<double>* Find(const std::string& key) const {
    const auto it = values.find(key);
    return it == values.end() ? nullptr : &it->second.second;
  }
  std::string Where(const std::string& key) const {
    const auto it = values.find(key);
    return it == values.end() ? path : LineWhere(path, it->second.first);
  }
  double Number(const std::string& key) const {
    const std::vector<double>* v = Find(key);
    if (v == nullptr) throw InputError(path, key + ": missing (expected one number)");
    if (v->size() != 1) throw InputError(Where(key), key + ": expected one number");
    return v->front();
  }
  int Size(const std::string& key) const {
    const double v = Number(key);
    if (!(v >= 1 && v <= 1e6) || v != static_cast<int>(v)) {
      throw InputError(Where(key), key + ": expected a positive integer image size");
    }
    return static_cast<int>(v);
  }
  // K from a 4x4 (16 numbers) or 3x4 (12 numbers) row-major intrinsic matrix.
  Eigen::Matrix3d K(const std::string& key) const {
    const std::vector<double>* v = Find(key);
    if (v == nullptr) throw InputError(path, key + ": missing (expected a 4x4 intrinsic matrix)");
    if (v->size() != 16 && v->size() != 12) {
      throw InputError(Where(key), key + ": expected 16 (4x4) or 12 (3x4) numbers, found " +
                                       std::to_string(v->size()));
    }
    Eigen::Matrix3d K;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) K(r, c) = (*v)[static_cast<size_t>(r) * 4 + c];
    }
    return CheckedIntrinsics(K, Where(key) + " " + key);
  }
};

CppInfo ReadCppInfo(const std::string& path) {
  CppInfo info;
  info.path = path;
  const std::vector<std::string> lines = io::ReadLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    const size_t eq = line.find('=');
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (eq == std::string::npos) {
      throw InputError(LineWhere(path, static_cast<int>(i) + 1), "expected 'key = value'");
    }
    std::string key = line.substr(0, eq);
    key.erase(0, key.find_first_not_of(" \t"));
    key.erase(key.find_last_not_of(" \t") + 1);
    if (key != "m_depthWidth" && key != "m_depthHeight" && key != "m_depthShift" &&
        key != "m_colorWidth" && key != "m_colorHeight" && key != "m_calibrationDepthIntrinsic" &&
        key != "m_calibrationColorIntrinsic") {
      continue;  // sensor name, version, extrinsics, frame count: not needed
    }
    if (const auto it = info.values.find(key); it != info.values.end()) {
      throw InputError(
          LineWhere(path, static_cast<int>(i) + 1),
          key + ": repeats line " + std::to_string(it->second.first) + " (expected each key once)");
    }
    info.values[key] = {static_cast<int>(i) + 1, ParseNumbers(std::string_view(line).substr(eq + 1),
                                                              path, static_cast<int>(i) + 1)};
  }
  return info;
}

}  // namespace

std::vector<std::string> ScanNetReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  if (IsScanNetScene(root)) return {FolderName(root)};
  RequirePosesIfSceneLike(root);
  std::vector<std::string> out;
  for (const auto& name : ListSubfolders(root)) {
    RequirePosesIfSceneLike((fs::path(root) / name).string());
    if (IsScanNetScene((fs::path(root) / name).string())) out.push_back(name);
  }
  if (out.empty()) {
    throw InputError(root,
                     "no ScanNet scene found (expected a folder with pose/, _info.txt or "
                     "<folder name>.sens)");
  }
  return out;
}

namespace {
// ScanNet's reconstructed mesh of a scene folder, in the poses' world frame: the download's
// <scene>_vh_clean_2.ply inside the folder (beside <scene>.sens), or beside the folder; ""
// when neither exists (docs/DATASETS.md "ScanNet meshes").
std::string ScanNetMeshPath(const std::string& folder) {
  const fs::path dir(folder);
  const std::string name = dir.filename().string() + "_vh_clean_2.ply";
  for (const fs::path& p : {dir / name, dir.parent_path() / name}) {
    if (io::FileExists(p.string())) return p.string();
  }
  return "";
}
}  // namespace

std::string ScanNetColorIntrinsicsSource(const Scene& scene) {
  const std::string& folder = scene.path;
  if (IsPythonExport(folder)) {
    const std::string p = (fs::path(folder) / "intrinsic" / "intrinsic_color.txt").string();
    return io::FileExists(p) ? p : "";
  }
  if (IsCppExport(folder)) {
    const std::string p = (fs::path(folder) / kCppInfoFile).string();
    return ReadCppInfo(p).Find("m_calibrationColorIntrinsic") != nullptr
               ? p + " m_calibrationColorIntrinsic"
               : "";
  }
  if (IsSensScene(folder)) return SensPath(folder) + " colour intrinsic";
  return "";
}

Scene ScanNetReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  const std::string folder = ResolveSceneFolder(root, scene_name, IsScanNetScene(root));
  Scene scene = ReadSceneFolder(folder, scene_name);
  scene.mesh_path = ScanNetMeshPath(folder);
  if (scene.mesh_path.empty()) {
    const fs::path dir(folder);
    scene.mesh_expected_path = (dir / (dir.filename().string() + "_vh_clean_2.ply")).string();
  }
  return scene;
}

Scene ScanNetReader::ReadSceneFolder(const std::string& folder,
                                     const std::string& scene_name) const {
  if (!IsPythonExport(folder) && IsCppExport(folder)) return ReadCppExport(folder, scene_name);
  if (!IsPythonExport(folder) && IsSensScene(folder)) return ReadSens(folder, scene_name);
  const std::string pose_dir = (fs::path(folder) / "pose").string();
  std::error_code ec;
  if (!fs::is_directory(pose_dir, ec)) throw InputError(pose_dir, "pose folder not found");

  Scene scene = NewFolderScene(folder, scene_name, Format(), 0.1, 10.0);

  const std::vector<NumberedFile> poses = ListNumberedFiles(pose_dir, "", ".txt");
  if (poses.empty()) throw InputError(pose_dir, "empty scene: no <n>.txt pose files");
  // Frames: every number with a pose, depth or colour file; one without its pose file is
  // kept, unusable (kReasonPoseMissing), so that it is counted, never silently dropped.
  // Each file is the one listed for the frame's number, whatever its zero padding
  // (pose/54.txt with depth/0054.png).
  const std::string depth_dir = (fs::path(folder) / "depth").string();
  const std::string color_dir = (fs::path(folder) / "color").string();
  const std::vector<NumberedFile> depths = ListNumberedFiles(depth_dir, "", ".png");
  const std::vector<NumberedFile> jpgs = ListNumberedFiles(color_dir, "", ".jpg");
  const std::vector<NumberedFile> pngs = ListNumberedFiles(color_dir, "", ".png");
  const std::vector<NumberedFile> frames = MergeNumberedFiles({poses, depths, jpgs, pngs});
  const auto by_number = [](const std::vector<NumberedFile>& files) {
    std::map<int64_t, std::string> out;
    for (const NumberedFile& f : files) out.emplace(f.number, f.path);
    return out;
  };
  const std::map<int64_t, std::string> pose_of = by_number(poses), depth_of = by_number(depths),
                                       jpg_of = by_number(jpgs), png_of = by_number(pngs);
  const auto find = [](const std::map<int64_t, std::string>& m, int64_t n) {
    const auto it = m.find(n);
    return it == m.end() ? std::string() : it->second;
  };
  // A frame with both colour files reads the .jpg (the export's own format), and says so.
  std::map<int64_t, std::string> color_of;
  PreferredFile colour("colour");
  for (const auto& p : frames) {
    color_of[p.number] = colour.Pick({find(jpg_of, p.number), find(png_of, p.number)});
  }
  colour.Note(&scene);

  const std::string intrinsic_dir = (fs::path(folder) / "intrinsic").string();
  const Eigen::Matrix3d K_depth =
      ReadIntrinsicsText((fs::path(intrinsic_dir) / "intrinsic_depth.txt").string());

  // Sizes from the first depth / colour file that can be read: a damaged one is that
  // frame's problem (skipped and counted when it is read), not the scene's.
  int depth_w = kDefaultDepthWidth, depth_h = kDefaultDepthHeight;
  for (const auto& p : frames) {
    const std::string d = find(depth_of, p.number);
    if (d.empty()) continue;
    try {
      const io::ImageSize s = io::ReadImageSize(d);
      depth_w = s.width;
      depth_h = s.height;
      break;
    } catch (const InputError&) {
    }
  }
  const Camera depth_camera = Camera::FromK(K_depth, depth_w, depth_h);
  Camera color_camera;
  for (const auto& p : frames) {
    const std::string& c = color_of[p.number];
    if (c.empty()) continue;
    io::ImageSize s;
    try {
      s = io::ReadImageSize(c);
    } catch (const InputError&) {
      continue;
    }
    const std::string color_k_path = (fs::path(intrinsic_dir) / "intrinsic_color.txt").string();
    color_camera = io::FileExists(color_k_path)
                       ? Camera::FromK(ReadIntrinsicsText(color_k_path), s.width, s.height)
                       : depth_camera.Resized(s.width, s.height);
    break;
  }

  for (const auto& p : frames) {
    Frame f;
    f.id = p.stem;
    f.number = p.number;
    // A frame without a depth file names the one expected (the frame's stem).
    f.depth.path = find(depth_of, p.number);
    if (f.depth.path.empty()) f.depth.path = (fs::path(depth_dir) / (p.stem + ".png")).string();
    f.depth.format = DepthFormat::kPng16;
    f.depth.scale_m_per_unit = 0.001;
    f.depth_camera = depth_camera;
    f.color_path = color_of[p.number];
    if (!f.color_path.empty()) f.color_camera = color_camera;
    if (const std::string pose = find(pose_of, p.number); !pose.empty()) {
      SetPoseFromText(pose, &f);  // lost tracking (-inf) marks the frame unusable
    } else {
      MarkUnusable(&f, kReasonPoseMissing, (fs::path(pose_dir) / (p.stem + ".txt")).string());
    }
    if (options_.check_depth_files && !io::FileExists(f.depth.path)) {
      MarkUnusable(&f, kReasonDepthMissing);
    }
    scene.frames.push_back(std::move(f));
  }
  return scene;
}

Scene ScanNetReader::ReadCppExport(const std::string& folder, const std::string& scene_name) const {
  Scene scene = NewFolderScene(folder, scene_name, Format(), 0.1, 10.0);

  const CppInfo info = ReadCppInfo((fs::path(folder) / kCppInfoFile).string());
  const double depth_shift = info.Number("m_depthShift");
  if (!(depth_shift > 0) || !std::isfinite(depth_shift)) {
    throw InputError(info.Where("m_depthShift"), "m_depthShift: expected a positive number");
  }
  const Camera depth_camera = Camera::FromK(info.K("m_calibrationDepthIntrinsic"),
                                            info.Size("m_depthWidth"), info.Size("m_depthHeight"));
  Camera color_camera;
  if (info.Find("m_calibrationColorIntrinsic") != nullptr) {
    color_camera = Camera::FromK(info.K("m_calibrationColorIntrinsic"), info.Size("m_colorWidth"),
                                 info.Size("m_colorHeight"));
  }

  // Frames: every number with a pose, depth or colour file; one without its pose file is
  // kept, unusable (kReasonPoseMissing).
  const std::vector<NumberedFile> poses = ListNumberedFiles(folder, "frame-", ".pose.txt");
  std::set<int64_t> with_pose;
  for (const auto& p : poses) with_pose.insert(p.number);
  std::vector<std::vector<NumberedFile>> lists = {poses};
  for (const char* suffix : {".depth.pgm", ".depth.png", ".color.jpg", ".color.png"}) {
    lists.push_back(ListNumberedFiles(folder, "frame-", suffix));
  }
  // A frame with two depth or two colour files reads the first of each pair (the export's
  // own .depth.pgm and .color.jpg), and the scene says so.
  PreferredFile depth("depth"), colour("colour");
  for (const auto& p : MergeNumberedFiles(lists)) {
    const std::string base = (fs::path(folder) / ("frame-" + p.stem)).string();
    Frame f;
    f.id = p.stem;
    f.number = p.number;
    f.depth.path = depth.Pick({base + ".depth.pgm", base + ".depth.png"});
    if (f.depth.path.empty()) f.depth.path = base + ".depth.pgm";
    f.depth.format = DepthFormat::kPng16;  // 16-bit greyscale image, decoded by OpenCV
    f.depth.scale_m_per_unit = 1.0 / depth_shift;
    f.depth_camera = depth_camera;
    f.color_path = colour.Pick({base + ".color.jpg", base + ".color.png"});
    if (!f.color_path.empty()) {
      if (color_camera.width > 0) {
        f.color_camera = color_camera;
      } else {
        const io::ImageSize s = io::ReadImageSize(f.color_path);
        f.color_camera = depth_camera.Resized(s.width, s.height);
      }
    }
    if (with_pose.count(p.number) != 0) {
      SetPoseFromText(p.path, &f);  // lost tracking (-inf) marks the frame unusable
    } else {
      MarkUnusable(&f, kReasonPoseMissing, base + ".pose.txt");
    }
    if (options_.check_depth_files && !io::FileExists(f.depth.path)) {
      MarkUnusable(&f, kReasonDepthMissing);
    }
    scene.frames.push_back(std::move(f));
  }
  depth.Note(&scene);
  colour.Note(&scene);
  return scene;
}

Scene ScanNetReader::ReadSens(const std::string& folder, const std::string& scene_name) const {
  Scene scene = NewFolderScene(folder, scene_name, Format(), 0.1, 10.0);
  const std::string path = SensPath(folder);
  const SensIndex sens = ReadSensIndex(path);
  const Camera depth_camera = Camera::FromK(
      CheckedIntrinsics(sens.depth_intrinsic.topLeftCorner<3, 3>(), path + " depth intrinsic"),
      sens.depth_width, sens.depth_height);
  const Camera color_camera = Camera::FromK(
      CheckedIntrinsics(sens.color_intrinsic.topLeftCorner<3, 3>(), path + " colour intrinsic"),
      sens.color_width, sens.color_height);
  scene.frames.reserve(sens.frames.size());
  for (size_t i = 0; i < sens.frames.size(); ++i) {
    const SensFrameEntry& e = sens.frames[i];
    Frame f;
    f.id = std::to_string(i);
    f.number = static_cast<int64_t>(i);
    f.depth.path = path;
    f.depth.format = sens.depth_compression == SensDepthCompression::kZlib ? DepthFormat::kSensZlib
                                                                           : DepthFormat::kSensRaw;
    f.depth.scale_m_per_unit = 1.0 / sens.depth_shift;
    f.depth.range = e.depth;
    f.depth.width = sens.depth_width;
    f.depth.height = sens.depth_height;
    f.depth.frame_index = static_cast<int64_t>(i);
    f.depth_camera = depth_camera;
    if (e.color.size > 0) {
      f.color_path = path;
      f.color_range = e.color;
      f.color_raw_rgb = sens.color_compression == SensColorCompression::kRaw;
      f.color_camera = color_camera;
    }
    const std::string frame_where = io::ContainerFrameWhere(path, static_cast<int64_t>(i));
    SetMatrixPose(e.world_from_cam, PoseLocator::Whole(frame_where), &f);
    if (e.depth.size == 0) {
      MarkUnusable(&f, kReasonDepthMissing, frame_where + ": depthBytes is 0 (no depth payload)");
    }
    scene.frames.push_back(std::move(f));
  }
  return scene;
}

}  // namespace gt::datasets

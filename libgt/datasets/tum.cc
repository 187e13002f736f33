// TUM RGB-D reader (docs/DATASETS.md "TUM RGB-D").
// One frame per depth.txt entry; its pose is the groundtruth.txt entry nearest in time
// (camera-to-world "t tx ty tz qx qy qz qw", OpenCV camera axes), its colour the nearest
// rgb.txt entry, both within ReaderOptions::tum_max_dt_s. Depth is uint16 with
// 5000 units per metre. Intrinsics by sequence name (freiburg1/2/3, default fr1).
#include <algorithm>
#include <cmath>
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

constexpr int kTumWidthPx = 640;
constexpr int kTumHeightPx = 480;

bool IsTumSequence(const std::string& folder) {
  return io::FileExists((fs::path(folder) / "depth.txt").string());
}

// "timestamp filename" lists (rgb.txt, depth.txt), sorted by time, paths made absolute.
struct FramePath {
  double t = 0;
  std::string path;
  int line_no = 0;  // in its list
};
// "" or, for a file with no entry that holds carriage returns and no line feed, a hint.
std::string LineEndingHint(const std::string& text) {
  return text.find('\r') != std::string::npos && text.find('\n') == std::string::npos
             ? "; its lines end in CR alone, read as one comment line: convert them to LF"
             : "";
}

// The entries of folder/name; a file with none is an InputError naming it (`what`: the
// entries' layout).
std::vector<FramePath> ReadTimedPaths(const std::string& folder, const std::string& name) {
  const std::string path = (fs::path(folder) / name).string();
  const std::string text = io::ReadFileBytes(path);
  std::vector<FramePath> out;
  for (const TimedPath& e : ParseTimedPathList(text, path)) {
    out.push_back({e.t, (fs::path(folder) / e.file).string(), e.line_no});
  }
  if (out.empty()) {
    throw InputError(path,
                     "no entries (expected 'timestamp filename' lines)" + LineEndingHint(text));
  }
  return out;
}

// Index of the entry nearest to t in a time-sorted vector (ties: the earlier), or -1.
template <typename T>
int Nearest(const std::vector<T>& sorted, double t, double max_dt) {
  if (sorted.empty()) return -1;
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), t,
                                   [](const T& e, double value) { return e.t < value; });
  int best = -1;
  double best_dt = max_dt;
  auto consider = [&](typename std::vector<T>::const_iterator c) {
    const double dt = std::abs(c->t - t);
    if (dt < best_dt || (dt == best_dt && best < 0)) {
      best = static_cast<int>(c - sorted.begin());
      best_dt = dt;
    }
  };
  if (it != sorted.begin()) consider(it - 1);
  if (it != sorted.end()) consider(it);
  return best;
}

std::string Stem(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  const size_t dot = name.rfind('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace

TumIntrinsics TumIntrinsicsOf(const std::string& sequence_name) {
  TumIntrinsics out;
  Camera& c = out.camera;
  c.width = kTumWidthPx;
  c.height = kTumHeightPx;
  const auto has = [&](const char* s) { return sequence_name.find(s) != std::string::npos; };
  if (has("freiburg2") || has("fr2")) {
    c.fx = 520.9, c.fy = 521.0, c.cx = 325.1, c.cy = 249.7;
    out.sequence = "fr2";
    out.named = true;
  } else if (has("freiburg3") || has("fr3")) {
    c.fx = 535.4, c.fy = 539.2, c.cx = 320.1, c.cy = 247.6;
    out.sequence = "fr3";
    out.named = true;
  } else {  // freiburg1, and the documented default
    c.fx = 517.3, c.fy = 516.5, c.cx = 318.6, c.cy = 255.3;
    out.sequence = "fr1";
    out.named = has("freiburg1") || has("fr1");
  }
  return out;
}

std::vector<std::string> TumSceneWarnings(const Scene& scene) {
  std::vector<std::string> out;
  const std::string folder_name = FolderName(scene.path);
  const TumIntrinsics k = TumIntrinsicsOf(folder_name);
  if (!k.named) {
    std::ostringstream s;
    s << "TUM intrinsics assumed: " << k.sequence << " (fx " << k.camera.fx << ", fy "
      << k.camera.fy << ", cx " << k.camera.cx << ", cy " << k.camera.cy
      << "), as the folder name '" << folder_name
      << "' names no freiburg1/2/3 (fr1/fr2/fr3); name the folder after its TUM sequence "
         "(rgbd_dataset_freiburg3_...) to get its K";
    out.push_back(s.str());
  }
  const std::string rgb_list = (fs::path(scene.path) / "rgb.txt").string();
  if (!io::FileExists(rgb_list)) {
    out.push_back(rgb_list +
                  ": missing (expected 'timestamp filename' lines of the colour images): no "
                  "frame has colour");
  }
  return out;
}

namespace {
// A folder holding groundtruth.txt or rgb.txt is meant as a sequence: without depth.txt (its
// frames) it is an error, never silently skipped (as TartanAir's trajectories).
void RequireDepthListIfSequenceLike(const std::string& folder) {
  if (IsTumSequence(folder)) return;
  for (const char* name : {"groundtruth.txt", "rgb.txt"}) {
    if (io::FileExists((fs::path(folder) / name).string())) {
      throw InputError((fs::path(folder) / "depth.txt").string(),
                       std::string("missing (the folder holds ") + name +
                           ": a TUM sequence needs depth.txt, its frames)");
    }
  }
}
}  // namespace

std::vector<std::string> TumReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  if (IsTumSequence(root)) return {FolderName(root)};
  RequireDepthListIfSequenceLike(root);
  std::vector<std::string> out;
  for (const auto& name : ListSubfolders(root)) {
    RequireDepthListIfSequenceLike((fs::path(root) / name).string());
    if (IsTumSequence((fs::path(root) / name).string())) out.push_back(name);
  }
  if (out.empty()) throw InputError(root, "no TUM sequence found (expected depth.txt)");
  return out;
}

Scene TumReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  const std::string folder = ResolveSceneFolder(root, scene_name, IsTumSequence(root));
  Scene scene = NewFolderScene(folder, scene_name, Format(), 0.1, 10.0);

  const std::vector<FramePath> depths = ReadTimedPaths(folder, "depth.txt");
  // Colour: the rgb.txt entries whose image exists (a missing image gives way to the next
  // nearest entry within the tolerance).
  std::vector<FramePath> rgbs;
  if (io::FileExists((fs::path(folder) / "rgb.txt").string())) {
    for (FramePath& e : ReadTimedPaths(folder, "rgb.txt")) {
      if (io::FileExists(e.path)) rgbs.push_back(std::move(e));
    }
  }
  const std::string gt_path = (fs::path(folder) / "groundtruth.txt").string();
  const std::string gt_text = io::ReadFileBytes(gt_path);
  const std::vector<TimedPose> poses = ParseTimedPoses(gt_text, gt_path);
  if (poses.empty()) {
    throw InputError(gt_path, "no pose entries (expected 'timestamp tx ty tz qx qy qz qw' lines)" +
                                  LineEndingHint(gt_text));
  }
  const Camera camera = TumIntrinsicsOf(FolderName(folder)).camera;

  std::ostringstream no_gt;
  no_gt << "pose: no groundtruth within " << options_.tum_max_dt_s << "s";
  for (size_t i = 0; i < depths.size(); ++i) {
    Frame f;
    f.id = Stem(depths[i].path);
    f.number = static_cast<int64_t>(i);
    f.timestamp_s = depths[i].t;
    f.depth.path = depths[i].path;
    f.depth.format = DepthFormat::kPng16;
    f.depth.scale_m_per_unit = 1.0 / 5000.0;
    f.depth_camera = camera;
    // Colour: the nearest existing rgb.txt image within the tolerance; none gives no colour,
    // as in the folder readers (`occgt scan` counts the usable frames without).
    const int rgb = Nearest(rgbs, depths[i].t, options_.tum_max_dt_s);
    if (rgb >= 0) {
      f.color_path = rgbs[static_cast<size_t>(rgb)].path;
      f.color_camera = camera;
    }
    const int gt = Nearest(poses, depths[i].t, options_.tum_max_dt_s);
    if (gt < 0) {
      MarkUnusable(&f, no_gt.str());
    } else {
      const TimedPose& p = poses[static_cast<size_t>(gt)];
      SetTQPose(p.translation, p.q_xyzw, PoseLocator::Whole(LineWhere(gt_path, p.line_no)), &f);
    }
    if (options_.check_depth_files && !io::FileExists(f.depth.path)) {
      MarkUnusable(&f, kReasonDepthMissing);
    }
    scene.frames.push_back(std::move(f));
  }
  // Duplicate ids (two depth files with the same name) would break pair bookkeeping.
  std::map<std::string, int> line_of_id;
  for (size_t i = 0; i < depths.size(); ++i) {
    const auto [it, fresh] = line_of_id.emplace(scene.frames[i].id, depths[i].line_no);
    if (!fresh) {
      const int first = std::min(it->second, depths[i].line_no);
      const int second = std::max(it->second, depths[i].line_no);
      throw InputError(LineWhere((fs::path(folder) / "depth.txt").string(), second),
                       "depth file name '" + it->first + "' repeats line " + std::to_string(first) +
                           " (expected one name per frame: the frame id)");
    }
  }
  return scene;
}

}  // namespace gt::datasets

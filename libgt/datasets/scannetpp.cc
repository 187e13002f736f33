// ScanNet++ reader (docs/DATASETS.md "ScanNet++"; ../shared/design/MESHES.md).
//
// Root: the folder holding data/<scene>/, the data/ folder itself, or one scene folder.
// Device (ReaderOptions::scannetpp_device):
//  - dslr: dslr/colmap/{cameras,images}.{txt,bin} (one OPENCV_FISHEYE camera; poses
//    world-to-camera in the mesh's frame), dslr/resized_images/<name>,
//    dslr/resized_anon_masks/<stem>.png (255 valid, 0 anonymised), train_test_lists.json.
//    No sensor depth: depth is rendered from scans/mesh_aligned_0.05.ply in the undistorted
//    camera (Scene::mesh_path).
//  - iphone: iphone/colmap/ (OPENCV), iphone/rgb/<name>, iphone/rgb_masks/<stem>.png,
//    depth iphone/depth/<stem>.png (uint16 mm) or iphone/depth.bin (io/iphone_depth.h),
//    frame i of the video = frame_%06d.
// Every frame is presented as an undistorted pinhole frame: color_camera and depth_camera are
// ScanNetPPUndistortedCamera (datasets/undistorted_camera.h) of the COLMAP camera, color_lens
// the distorted camera (io::ReadFrameColor undistorts), mask_path the distorted mask, and for
// the iPhone's sensor depth depth_lens the distorted camera at the depth map's size.
#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "libgt/core/error.h"
#include "libgt/datasets/colmap.h"
#include "libgt/datasets/json_input.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/datasets/undistorted_camera.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/iphone_depth.h"

namespace gt::datasets {
namespace fs = std::filesystem;
namespace {

constexpr const char* kMeshPath = "scans/mesh_aligned_0.05.ply";
constexpr const char* kReasonColorMissing = "colour: missing file";
constexpr const char* kReasonNoPose = "pose: image not in the COLMAP model";
constexpr const char* kReasonMaskMissing = "mask: missing file";
// The range of ScanNet++'s own depth rendering (common/configs/render.yml: near 0.05 m,
// far 20 m).
constexpr double kMinDepthM = 0.05;
constexpr double kMaxDepthM = 20.0;

bool IsDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool IsSceneFolder(const fs::path& p) {
  return IsDir(p / "dslr") || IsDir(p / "iphone") || IsDir(p / "scans");
}

// The folder of scenes under root: root/data when it exists, else root.
fs::path ScenesDir(const std::string& root) {
  const fs::path data = fs::path(root) / "data";
  return IsDir(data) ? data : fs::path(root);
}

std::string FileName(const std::string& name) {
  const size_t slash = name.find_last_of('/');
  return slash == std::string::npos ? name : name.substr(slash + 1);
}

std::string Stem(const std::string& name) {
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

bool IsImageName(const std::string& name) {
  std::string ext = fs::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return (ext == ".jpg" || ext == ".jpeg" || ext == ".png") && name.rfind("._", 0) != 0;
}

// Image file names of a folder (sorted; none when the folder is missing).
std::set<std::string> ImageFiles(const fs::path& folder) {
  std::set<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file(ec) && IsImageName(name)) names.insert(name);
  }
  return names;
}

// train_test_lists.json: {"train": [names], "test": [names]} (other keys ignored).
std::set<std::string> ReadTrainTestLists(const fs::path& path) {
  std::set<std::string> names;
  if (!io::FileExists(path.string())) return names;
  const nlohmann::json j = ParseJsonInput(io::ReadFileBytes(path.string()), path.string());
  if (!j.is_object()) {
    throw InputError(path.string(), "expected an object {\"train\": [...], \"test\": [...]}");
  }
  for (const char* key : {"train", "test"}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_array()) {
      throw InputError(path.string(), std::string(key) + ": expected a list of image names");
    }
    for (const auto& v : j[key]) {
      if (!v.is_string() || v.get<std::string>().empty()) {
        throw InputError(path.string(), std::string(key) + ": expected image names (strings)");
      }
      names.insert(FileName(v.get<std::string>()));
    }
  }
  return names;
}

struct DeviceLayout {
  const char* device;  // "dslr" / "iphone"
  const char* colmap;  // relative to the scene
  const char* images;  // colour folder
  const char* masks;   // mask folder
  const char* lists;   // train/test lists ("" none)
};
constexpr DeviceLayout kDslr{"dslr", "dslr/colmap", "dslr/resized_images",
                             "dslr/resized_anon_masks", "dslr/train_test_lists.json"};
constexpr DeviceLayout kIphone{"iphone", "iphone/colmap", "iphone/rgb", "iphone/rgb_masks", ""};

// The frame number of an iPhone frame name ("frame_000123" -> 123), -1 when not of that form.
int64_t IphoneFrameNumber(const std::string& stem) {
  const std::string prefix = "frame_";
  if (stem.rfind(prefix, 0) != 0 || stem.size() == prefix.size()) return -1;
  int64_t n = 0;
  for (size_t i = prefix.size(); i < stem.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(stem[i])) || n > (int64_t{1} << 40)) return -1;
    n = n * 10 + (stem[i] - '0');
  }
  return n;
}

}  // namespace

std::vector<std::string> ScanNetPPReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  RequireFinishedSynth(root);
  if (IsSceneFolder(root)) return {FolderName(root)};
  const fs::path dir = ScenesDir(root);
  std::vector<std::string> out;
  for (const auto& name : ListSubfolders(dir.string())) {
    if (IsSceneFolder(dir / name)) out.push_back(name);
  }
  if (out.empty()) {
    throw InputError(root,
                     "no ScanNet++ scene found (expected data/<scene>/ with dslr/, iphone/ or "
                     "scans/ under the root, or the root to be data/ or one scene)");
  }
  return out;
}

Scene ScanNetPPReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  RequireRoot(root);
  RequireFinishedSynth(root);
  const bool root_is_scene = IsSceneFolder(root);
  const std::string folder = ResolveSceneFolder(root_is_scene ? root : ScenesDir(root).string(),
                                                scene_name, root_is_scene);
  Scene scene = NewFolderScene(folder, scene_name, Format(), kMinDepthM, kMaxDepthM);
  const fs::path dir(folder);
  if (io::FileExists((dir / kMeshPath).string())) {
    scene.mesh_path = (dir / kMeshPath).string();
  } else {
    scene.mesh_expected_path = (dir / kMeshPath).string();
  }

  const bool dslr = options_.scannetpp_device == ScanNetPPDevice::kDslr;
  const DeviceLayout& layout = dslr ? kDslr : kIphone;
  const fs::path colmap_dir = dir / layout.colmap;
  if (!HasColmapModel(colmap_dir.string())) {
    throw InputError(colmap_dir.string(),
                     std::string("no COLMAP model of the ") + layout.device +
                         " images (expected cameras.txt + images.txt, or the .bin pair)");
  }
  const ColmapModel model = ReadColmapModel(colmap_dir.string());
  struct CameraPair {
    LensCamera lens;
    Camera undistorted;
  };
  std::map<int64_t, CameraPair> cameras;
  for (const auto& [id, c] : model.cameras) {
    const LensCamera lens = ColmapLensCamera(c, model.cameras_path);
    if (dslr && lens.model != LensModel::kOpenCvFisheye) {
      throw InputError(model.cameras_path, "camera " + std::to_string(id) + ": model " + c.model +
                                               ", expected OPENCV_FISHEYE for the DSLR");
    }
    cameras[id] = {lens, ScanNetPPUndistortedCamera(lens, model.cameras_path, id)};
  }

  // Every image the scene names: COLMAP's, the colour folder's and the train/test lists'.
  std::map<std::string, const ColmapImage*> posed;  // by file name
  for (const ColmapImage& im : model.images) {
    const std::string name = FileName(im.name);
    if (!posed.emplace(name, &im).second) {
      throw InputError(model.images_path, "two images named " + name);
    }
  }
  const fs::path images_dir = dir / layout.images;
  const std::set<std::string> files = ImageFiles(images_dir);
  std::set<std::string> names = files;
  for (const auto& [name, im] : posed) names.insert(name);
  if (*layout.lists) {
    for (const std::string& n : ReadTrainTestLists(dir / layout.lists)) names.insert(n);
  }
  if (names.empty()) {
    throw InputError(folder, std::string("no ") + layout.device + " images (none in " +
                                 images_dir.string() + " nor in " + model.images_path + ")");
  }
  const fs::path masks_dir = dir / layout.masks;
  const bool have_masks = IsDir(masks_dir);

  // iPhone depth: PNGs, else depth.bin.
  const fs::path depth_dir = dir / "iphone" / "depth";
  const fs::path depth_bin = dir / "iphone" / "depth.bin";
  io::IphoneDepthBin bin;
  bool have_bin = false;
  if (!dslr && !IsDir(depth_dir) && io::FileExists(depth_bin.string())) {
    bin = io::ScanIphoneDepthBin(depth_bin.string());
    have_bin = true;
  }

  std::set<std::string> ids;
  int64_t index = 0;
  for (const std::string& name : names) {
    Frame f;
    f.id = Stem(name);
    if (!ids.insert(f.id).second) {
      throw InputError(images_dir.string(),
                       "two images share the name " + f.id + " without extension");
    }
    const int64_t iphone_number = IphoneFrameNumber(f.id);
    f.number = !dslr && iphone_number >= 0 ? iphone_number : index;
    ++index;
    const auto it = posed.find(name);
    const ColmapImage* im = it == posed.end() ? nullptr : it->second;
    const CameraPair* cam = im ? &cameras.at(im->camera_id)
                               : (cameras.size() == 1 ? &cameras.begin()->second : nullptr);
    if (cam) {
      f.color_lens = cam->lens;
      f.color_camera = cam->undistorted;
      f.depth_camera = cam->undistorted;
    }
    if (files.count(name)) f.color_path = (images_dir / name).string();
    if (have_masks) f.mask_path = (masks_dir / (f.id + ".png")).string();
    if (dslr) {
      // No sensor depth (rendered from the mesh); depth.path stays empty.
    } else if (IsDir(depth_dir)) {
      f.depth.path = (depth_dir / (f.id + ".png")).string();
      f.depth.format = DepthFormat::kPng16;
      f.depth.scale_m_per_unit = 0.001;
    } else if (have_bin && iphone_number >= 0) {
      f.depth.path = depth_bin.string();
      f.depth.format = bin.format;
      f.depth.frame_index = iphone_number;
      f.depth.width = io::kIphoneDepthWidth;
      f.depth.height = io::kIphoneDepthHeight;
      if (bin.format == DepthFormat::kIphoneBinRecord) {
        if (iphone_number < static_cast<int64_t>(bin.records.size())) {
          f.depth.range = bin.records[static_cast<size_t>(iphone_number)];
        } else {
          MarkUnusable(
              &f, kReasonDepthMissing,
              depth_bin.string() + ": holds " + std::to_string(bin.records.size()) + " frames");
        }
      }
    }
    if (!dslr && cam && !f.depth.path.empty()) {
      // ARKit's depth is registered to the (distorted) colour image, at 256 x 192.
      int w = io::kIphoneDepthWidth, h = io::kIphoneDepthHeight;
      if (f.depth.format == DepthFormat::kPng16 && io::FileExists(f.depth.path)) {
        const io::ImageSize size = io::ReadImageSize(f.depth.path);
        w = size.width;
        h = size.height;
      }
      LensCamera depth_lens = cam->lens;
      depth_lens.pinhole = cam->lens.pinhole.Resized(w, h);
      f.depth_lens = depth_lens;
      f.depth_camera = cam->undistorted.Resized(w, h);
    }

    // Why the frame cannot be used, first reason first.
    if (f.color_path.empty()) {
      MarkUnusable(&f, kReasonColorMissing, (images_dir / name).string());
    }
    if (!im) {
      MarkUnusable(&f, kReasonNoPose, model.images_path + ": no image " + name);
    } else if (const auto defect = ColmapPoseDefect(*im)) {
      MarkUnusable(&f, PoseUnusable(*defect, PoseLocator::Whole(model.images_path + ": image " +
                                                                std::to_string(im->id))));
    } else {
      f.world_from_cam = ColmapWorldFromCam(*im);
    }
    if (!f.mask_path.empty() && !io::FileExists(f.mask_path)) {
      MarkUnusable(&f, kReasonMaskMissing, f.mask_path);
    }
    if (!dslr && options_.check_depth_files) {
      if (f.depth.path.empty()) {
        MarkUnusable(&f, kReasonDepthMissing,
                     "no " + (depth_dir / (f.id + ".png")).string() + " nor " + depth_bin.string());
      } else if (f.depth.format == DepthFormat::kPng16 && !io::FileExists(f.depth.path)) {
        MarkUnusable(&f, kReasonDepthMissing, f.depth.path);
      }
    }
    scene.frames.push_back(std::move(f));
  }
  std::stable_sort(scene.frames.begin(), scene.frames.end(),
                   [](const Frame& a, const Frame& b) { return a.number < b.number; });
  return scene;
}

}  // namespace gt::datasets

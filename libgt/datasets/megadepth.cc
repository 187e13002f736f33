// MegaDepth v1 reader (docs/DATASETS.md "MegaDepth").
//
// Depth: MegaDepth_v1/<scene>/dense0/depths/<image name without extension>.h5 (HDF5
// dataset "depth", float32, 0 = no depth; io/hdf5_depth.h). The release has no intrinsics
// for its undistorted images, so poses and K come from a COLMAP sparse model of the
// undistorted images (datasets/colmap.h): <scene>/dense0/sparse/ (images in dense0/imgs/), else
// D2-Net's undistortion beside phoenix/: Undistorted_SfM/<scene>/sparse/ (or sparse-txt/),
// images in Undistorted_SfM/<scene>/images/ (dense0/imgs/ when missing there).
// A depth file under 100 KiB is one of MegaDepth's ordinal / mask maps, not metric depth
// (D2-Net's preprocessing test, which LoFTR's indices inherit): unusable, with its reason.
#include <algorithm>
#include <filesystem>
#include <map>

#include "libgt/core/error.h"
#include "libgt/datasets/colmap.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/file_read.h"

namespace gt::datasets {
namespace fs = std::filesystem;
namespace {

constexpr const char* kV1Path = "phoenix/S6/zl548/MegaDepth_v1";
constexpr uintmax_t kMinMetricDepthBytes = 100 * 1024;
constexpr const char* kReasonOrdinal =
    "depth: under 100 KiB (an ordinal or mask map, not metric depth)";
// Every frame of a scene listed beside others that have a model, but without one itself.
constexpr const char* kReasonNoModel = "pose: no COLMAP model of the scene";

bool DirectoryExists(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool IsMegaDepthSceneFolder(const fs::path& folder) {
  return DirectoryExists(folder / "dense0" / "depths");
}

// The MegaDepth download folder holding phoenix/ and Undistorted_SfM/ for scenes in
// `v1_dir` (a folder ending in phoenix/S6/zl548/MegaDepth_v1), or "" when it is not there.
fs::path BaseOf(const fs::path& v1_dir) {
  fs::path p = fs::absolute(v1_dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  const fs::path suffix(kV1Path);
  std::vector<fs::path> parts(p.begin(), p.end());
  std::vector<fs::path> tail(suffix.begin(), suffix.end());
  if (parts.size() <= tail.size() ||
      !std::equal(tail.begin(), tail.end(), parts.end() - static_cast<long>(tail.size()))) {
    return {};
  }
  for (size_t i = 0; i < tail.size(); ++i) p = p.parent_path();
  return p;
}

struct ModelPlace {
  fs::path model;                // folder of cameras.* / images.*
  std::vector<fs::path> images;  // image folders, first match wins
};

// Where the sparse model of `scene` (folder scene_dir) is, "" model when nowhere.
ModelPlace FindModel(const fs::path& scene_dir, const std::string& scene) {
  const fs::path dense = scene_dir / "dense0";
  if (HasColmapModel((dense / "sparse").string())) return {dense / "sparse", {dense / "imgs"}};
  const fs::path base = BaseOf(scene_dir.parent_path());
  if (!base.empty()) {
    const fs::path und = base / "Undistorted_SfM" / scene;
    for (const char* sub : {"sparse", "sparse-txt"}) {
      if (HasColmapModel((und / sub).string()))
        return {und / sub, {und / "images", dense / "imgs"}};
    }
  }
  return {};
}

std::string ModelPlacesText(const fs::path& scene_dir, const std::string& scene) {
  std::string s = (scene_dir / "dense0" / "sparse").string();
  const fs::path base = BaseOf(scene_dir.parent_path());
  if (!base.empty()) s += " or " + (base / "Undistorted_SfM" / scene / "sparse").string();
  return s;
}

// The depth files of a scene, dense0/depths/*.h5, by name (AppleDouble "._*" ignored).
std::vector<std::string> DepthFileNames(const fs::path& scene_dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(scene_dir / "dense0" / "depths", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("._", 0) == 0 || entry.path().extension() != ".h5") continue;
    out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The folder of scenes under root: root/phoenix/S6/zl548/MegaDepth_v1 when it exists,
// else root itself.
fs::path MegaDepthScenesDir(const std::string& root) {
  const fs::path v1 = fs::path(root) / kV1Path;
  return DirectoryExists(v1) ? v1 : fs::path(root);
}

// The name without its extension (os.path.splitext: folders kept).
std::string StemKeepingFolders(const std::string& name) {
  const size_t slash = name.find_last_of('/');
  const size_t dot = name.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) ||
      dot == (slash == std::string::npos ? 0 : slash + 1)) {
    return name;
  }
  return name.substr(0, dot);
}

}  // namespace

std::vector<std::string> MegaDepthReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  if (IsMegaDepthSceneFolder(root)) {
    const std::string name = FolderName(root);
    if (FindModel(fs::path(root), name).model.empty()) {
      throw InputError(root,
                       "no COLMAP sparse model of the scene (expected cameras + images "
                       ".bin or .txt in " +
                           ModelPlacesText(fs::path(root), name) + ")");
    }
    return {name};
  }
  const fs::path dir = MegaDepthScenesDir(root);
  // A scene without a model beside scenes with one is listed too (when it has depth files):
  // ReadScene gives its frames unusable (kReasonNoModel), so `occgt scan` counts them.
  std::vector<std::string> out;
  std::string first_without_model;
  size_t with_model = 0;
  for (const auto& name : ListSubfolders(dir.string())) {
    if (!IsMegaDepthSceneFolder(dir / name)) continue;
    if (FindModel(dir / name, name).model.empty()) {
      if (first_without_model.empty()) first_without_model = name;
      if (!DepthFileNames(dir / name).empty()) out.push_back(name);
      continue;
    }
    out.push_back(name);
    ++with_model;
  }
  if (with_model == 0) {
    if (!first_without_model.empty()) {
      throw InputError(root, "no MegaDepth scene with a COLMAP sparse model (scene " +
                                 first_without_model + " has dense0/depths/ but none in " +
                                 ModelPlacesText(dir / first_without_model, first_without_model) +
                                 ")");
    }
    throw InputError(root,
                     "no MegaDepth scene found (expected <scene>/dense0/depths/ under the root "
                     "or under its phoenix/S6/zl548/MegaDepth_v1/)");
  }
  return out;
}

Scene MegaDepthReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  const bool root_is_scene = IsMegaDepthSceneFolder(root);
  const std::string folder = ResolveSceneFolder(
      root_is_scene ? root : MegaDepthScenesDir(root).string(), scene_name, root_is_scene);
  // MegaDepth's scale is per scene and arbitrary (SfM): the range only drops absurd values.
  Scene scene = NewFolderScene(folder, scene_name, Format(), 1e-4, 1e6);
  const std::string name = FolderName(folder);
  const ModelPlace place = FindModel(fs::path(folder), name);
  if (place.model.empty()) {
    if (root_is_scene) {
      throw InputError(folder,
                       "no COLMAP sparse model of the scene (expected cameras + images "
                       ".bin or .txt in " +
                           ModelPlacesText(fs::path(folder), name) + ")");
    }
    // One scene among others: its depth files are frames without pose or K, counted.
    const std::vector<std::string> depth_files = DepthFileNames(fs::path(folder));
    if (depth_files.empty()) {
      throw InputError((fs::path(folder) / "dense0" / "depths").string(),
                       "empty scene: no .h5 depth files and no COLMAP sparse model");
    }
    const std::string detail = ModelPlacesText(fs::path(folder), name) +
                               ": no COLMAP sparse model (expected cameras + images, .bin or .txt)";
    for (size_t i = 0; i < depth_files.size(); ++i) {
      Frame f;
      f.id = fs::path(depth_files[i]).stem().string();
      f.number = static_cast<int64_t>(i);
      f.depth.path = (fs::path(folder) / "dense0" / "depths" / depth_files[i]).string();
      f.depth.format = DepthFormat::kHdf5;
      MarkUnusable(&f, kReasonNoModel, detail);  // no K: the depth camera stays 0x0
      scene.frames.push_back(std::move(f));
    }
    return scene;
  }
  const ColmapModel model = ReadColmapModel(place.model.string());
  if (model.images.empty()) throw InputError(model.images_path, "empty model: no images");
  std::map<int64_t, Camera> cameras;
  for (const auto& [id, c] : model.cameras)
    cameras[id] = ColmapPinholeCamera(c, model.cameras_path);

  std::vector<const ColmapImage*> images;
  for (const ColmapImage& im : model.images) images.push_back(&im);
  std::sort(images.begin(), images.end(),
            [](const ColmapImage* a, const ColmapImage* b) { return a->name < b->name; });
  std::map<std::string, const ColmapImage*> image_of_id;
  const fs::path depths = fs::path(folder) / "dense0" / "depths";
  for (size_t i = 0; i < images.size(); ++i) {
    const ColmapImage& im = *images[i];
    Frame f;
    f.id = StemKeepingFolders(im.name);
    if (const auto [it, fresh] = image_of_id.emplace(f.id, &im); !fresh) {
      // Named where the later of the two is, with the other's image id (and line).
      const ColmapImage& a = *it->second;
      const ColmapImage& later = a.line_no > im.line_no ? a : im;
      const ColmapImage& other = &later == &im ? a : im;
      throw InputError(ColmapImageWhere(model.images_path, later),
                       "image " + later.name + " shares the name " + f.id +
                           " without extension with image id " + std::to_string(other.id) +
                           (other.line_no > 0 ? " (line " + std::to_string(other.line_no) + ")"
                                              : std::string()) +
                           " (their depth files would be the same)");
    }
    f.number = static_cast<int64_t>(i);
    f.depth.path = (depths / (f.id + ".h5")).string();
    f.depth.format = DepthFormat::kHdf5;
    f.depth_camera = cameras.at(im.camera_id);
    for (const fs::path& dir : place.images) {
      const std::string p = (dir / im.name).string();
      if (io::FileExists(p)) {
        f.color_path = p;
        f.color_camera = f.depth_camera;
        break;
      }
    }
    if (const auto defect = ColmapPoseDefect(im)) {
      MarkUnusable(&f, PoseUnusable(*defect, PoseLocator::Whole(model.images_path + ": image " +
                                                                std::to_string(im.id))));
    } else {
      f.world_from_cam = ColmapWorldFromCam(im);
    }
    // The size is always looked at (an ordinal map must never be read as depth); a
    // missing file is marked when check_depth_files says so.
    std::error_code ec;
    const uintmax_t bytes = fs::file_size(f.depth.path, ec);
    if (ec) {
      if (options_.check_depth_files) MarkUnusable(&f, kReasonDepthMissing);
    } else if (bytes < kMinMetricDepthBytes) {
      MarkUnusable(&f, kReasonOrdinal);
    }
    scene.frames.push_back(std::move(f));
  }
  return scene;
}

}  // namespace gt::datasets

#include "libgt/shards/megadepth_export.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/pickle.h"

namespace gt::shards {
namespace {

using io::PyValue;

PyValue Matrix(const double* m, int rows, int cols) {
  std::vector<PyValue> out;
  for (int r = 0; r < rows; ++r) {
    std::vector<PyValue> row;
    for (int c = 0; c < cols; ++c) row.push_back(PyValue::Float(m[r * cols + c]));
    out.push_back(PyValue::List(std::move(row)));
  }
  return PyValue::List(std::move(out));
}

std::string FileStem(const std::string& scene) {
  std::string s = scene;
  std::replace(s.begin(), s.end(), '/', '_');
  return s;
}

}  // namespace

std::string MegaDepthSceneInfoBytes(const MegaDepthIndexScene& scene) {
  std::vector<PyValue> images, depths, intrinsics, poses, pairs;
  for (const MegaDepthIndexFrame& f : scene.frames) {
    images.push_back(PyValue::Str(f.image_path));
    depths.push_back(f.depth_path ? PyValue::Str(*f.depth_path) : PyValue::None());
    intrinsics.push_back(f.K ? Matrix(f.K->data(), 3, 3) : PyValue::None());
    poses.push_back(f.cam_from_world ? Matrix(f.cam_from_world->data(), 4, 4) : PyValue::None());
  }
  const int64_t n = static_cast<int64_t>(scene.frames.size());
  for (const MegaDepthIndexPair& p : scene.pairs) {
    if (p.i < 0 || p.j < 0 || p.i >= n || p.j >= n) {
      throw InputError("loftr export", "scene " + scene.scene + ": pair (" + std::to_string(p.i) +
                                           ", " + std::to_string(p.j) +
                                           ") names a frame outside 0.." + std::to_string(n - 1));
    }
    pairs.push_back(PyValue::Tuple({PyValue::Tuple({PyValue::Int(p.i), PyValue::Int(p.j)}),
                                    PyValue::Float(p.score), PyValue::List({})}));
  }
  return io::PickleBytes(PyValue::Dict({{"image_paths", PyValue::List(std::move(images))},
                                        {"depth_paths", PyValue::List(std::move(depths))},
                                        {"intrinsics", PyValue::List(std::move(intrinsics))},
                                        {"poses", PyValue::List(std::move(poses))},
                                        {"pair_infos", PyValue::List(std::move(pairs))}}));
}

void ExportLoftrMegaDepth(const std::string& out_dir, std::vector<MegaDepthIndexScene> scenes,
                          const LoftrExportOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("loftr export", error);
  std::sort(scenes.begin(), scenes.end(),
            [](const auto& a, const auto& b) { return a.scene < b.scene; });
  std::set<std::string> stems;
  std::string list;
  std::filesystem::create_directories(out_dir + "/scene_info");
  for (const MegaDepthIndexScene& s : scenes) {
    const std::string stem = FileStem(s.scene);
    if (!stems.insert(stem).second) {
      throw InputError("loftr export", "two scenes are written as scene_info/" + stem + ".npz");
    }
    io::WriteFileAtomic(out_dir + "/scene_info/" + stem + ".npz", MegaDepthSceneInfoBytes(s));
    list += stem + "\n";
  }
  const std::string list_name =
      options.list_name.empty() ? options.split + "_list.txt" : options.list_name;
  io::WriteFileAtomic(out_dir + "/" + list_name, list);
}

}  // namespace gt::shards

#include "libgt/shards/loftr_export.h"

#include <algorithm>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/npy.h"
#include "libgt/shards/loftr_tree.h"
#include "libgt/shards/sample.h"

namespace gt::shards {
namespace {

// The export's files, one after the other (a few small files: no thread pays here).
void RunInOrder(const std::vector<std::function<void()>>& writes) {
  for (const auto& write : writes) write();
}

namespace fs = std::filesystem;

// Scene number and sub-scene of every scene: ScanNet names parse, others get their index
// in the sorted list of non-ScanNet scenes (returned in `other_scenes`).
std::map<std::string, std::pair<int64_t, int64_t>> NumberScenes(
    const std::set<std::string>& scenes, std::vector<std::string>* other_scenes) {
  std::map<std::string, std::pair<int64_t, int64_t>> ids;
  other_scenes->clear();
  for (const std::string& s : scenes) {
    if (auto id = ParseScanNetSceneName(s)) {
      ids[s] = *id;
    } else {
      ids[s] = {static_cast<int64_t>(other_scenes->size()), 0};
      other_scenes->push_back(s);
    }
  }
  return ids;
}

std::string NpzStem(const std::string& scene) {
  if (ParseScanNetSceneName(scene)) return scene;
  std::string stem = SanitizeScenePath(scene);
  std::replace(stem.begin(), stem.end(), '/', '_');
  return stem;
}

void WriteIntrinsics(const std::string& out_dir, const std::set<std::string>& scenes,
                     const SceneIntrinsics& intrinsics) {
  std::map<std::string, std::string> members;
  for (const std::string& s : scenes) {
    const auto it = intrinsics.find(s);
    if (it == intrinsics.end()) throw InputError("loftr export", "no intrinsics for scene " + s);
    const std::vector<double> k(it->second.begin(), it->second.end());
    members[s] = io::EncodeNpy<double>({3, 3}, k);
  }
  // Also under the folder name LoFTR's ScanNetDataset looks K up by ("scene%04d_%02d" of
  // the name row), for scenes whose own name is not a ScanNet one.
  for (const auto& [scene, folder] : LoftrSceneFolders(scenes)) {
    if (folder != scene) members[folder] = members.at(scene);
  }
  io::WriteNpz((fs::path(out_dir) / "intrinsics.npz").string(), members);
}

void WriteSceneList(const std::string& out_dir, const std::vector<std::string>& other_scenes) {
  if (other_scenes.empty()) return;
  std::string text;
  for (const std::string& s : other_scenes) text += s + "\n";
  io::WriteFileAtomic((fs::path(out_dir) / "scenes.txt").string(), text);
}

// The scenes of the pairs; each must have intrinsics (checked before anything is written).
std::set<std::string> ScenesOf(const std::vector<LoftrPair>& pairs,
                               const SceneIntrinsics& intrinsics) {
  std::set<std::string> scenes;
  for (const LoftrPair& p : pairs) scenes.insert(p.scene);
  for (const std::string& s : scenes) {
    if (!intrinsics.count(s)) throw InputError("loftr export", "no intrinsics for scene " + s);
  }
  return scenes;
}

void CheckFrames(const LoftrPair& p) {
  if (p.frame0 < 0 || p.frame1 < 0) {
    throw InputError("loftr export", "negative frame number in scene " + p.scene);
  }
}

}  // namespace

std::optional<std::pair<int64_t, int64_t>> ParseScanNetSceneName(const std::string& scene) {
  static const std::regex kPattern("scene([0-9]{4})_([0-9]{2})");
  std::smatch m;
  if (!std::regex_match(scene, m, kPattern)) return std::nullopt;
  return std::make_pair(std::stoll(m[1].str()), std::stoll(m[2].str()));
}

bool LoftrExportOptions::Check(std::string* error) const {
  if (split.empty() || SanitizeKeyComponent(split) != split) {
    *error = "split: \"" + split + "\" must be [A-Za-z0-9_-]+";
    return false;
  }
  if (!list_name.empty() &&
      (list_name.find('/') != std::string::npos || list_name == "." || list_name == "..")) {
    *error = "list_name: \"" + list_name + "\" must be a plain file name";
    return false;
  }
  return true;
}

void ExportLoftrTrain(const std::string& out_dir, const std::vector<LoftrPair>& pairs,
                      const SceneIntrinsics& intrinsics, const LoftrExportOptions& options) {
  if (std::string e; !options.Check(&e)) throw InputError("loftr export options", e);
  const std::set<std::string> scenes = ScenesOf(pairs, intrinsics);
  std::vector<std::string> other_scenes;
  const auto ids = NumberScenes(scenes, &other_scenes);
  std::string list;
  std::set<std::string> stems;
  for (const std::string& scene : scenes) {
    if (!stems.insert(NpzStem(scene)).second) {
      throw InputError("loftr export", "scene " + scene + " maps to an npz name already used");
    }
  }
  // The .npz files, then the list files.
  std::vector<std::function<void()>> npz_writes;
  npz_writes.emplace_back([&] { WriteIntrinsics(out_dir, scenes, intrinsics); });
  for (const std::string& scene : scenes) {
    std::vector<int64_t> names;
    std::vector<float> scores;
    for (const LoftrPair& p : pairs) {
      if (p.scene != scene) continue;
      CheckFrames(p);
      const auto& id = ids.at(scene);
      names.insert(names.end(), {id.first, id.second, p.frame0, p.frame1});
      scores.push_back(static_cast<float>(p.score));
    }
    const auto n = static_cast<int64_t>(scores.size());
    const std::string file = NpzStem(scene) + ".npz";
    npz_writes.emplace_back(
        [&out_dir, &options, file, n, names = std::move(names), scores = std::move(scores)] {
          io::WriteNpz((fs::path(out_dir) / "scene_data" / options.split / file).string(),
                       {{"name", io::EncodeNpy<int64_t>({n, 4}, names)},
                        {"score", io::EncodeNpy<float>({n}, scores)}});
        });
    list += file + "\n";
  }
  const std::string list_name =
      options.list_name.empty() ? options.split + "_list.txt" : options.list_name;
  RunInOrder({
      [&] {
        for (const auto& write : npz_writes) write();
      },
      [&] { io::WriteFileAtomic((fs::path(out_dir) / list_name).string(), list); },
      [&] { WriteSceneList(out_dir, other_scenes); },
  });
}

void ExportLoftrTest(const std::string& out_dir, const std::vector<LoftrPair>& pairs,
                     const SceneIntrinsics& intrinsics, const LoftrExportOptions& options) {
  if (std::string e; !options.Check(&e)) throw InputError("loftr export options", e);
  const std::set<std::string> scenes = ScenesOf(pairs, intrinsics);
  std::vector<std::string> other_scenes;
  const auto ids = NumberScenes(scenes, &other_scenes);
  const auto n = static_cast<int64_t>(pairs.size());
  std::vector<int64_t> names;
  std::vector<float> rel_pose;
  nlohmann::json stats = nlohmann::json::object();
  bool fits_u16 = true;
  for (const LoftrPair& p : pairs) {
    CheckFrames(p);
    const auto& id = ids.at(p.scene);
    for (int64_t v : {id.first, id.second, p.frame0, p.frame1}) {
      names.push_back(v);
      fits_u16 = fits_u16 && v <= 65535;
    }
    for (double v : p.cam1_from_cam0) rel_pose.push_back(static_cast<float>(v));
    stats[p.scene] = stats.value(p.scene, 0) + 1;
  }
  std::string name_npy;
  if (fits_u16) {
    const std::vector<uint16_t> small(names.begin(), names.end());
    name_npy = io::EncodeNpy<uint16_t>({n, 4}, small);
  } else {
    name_npy = io::EncodeNpy<int64_t>({n, 4}, names);
  }
  const std::string list_name = options.list_name.empty() ? "test_list.txt" : options.list_name;
  RunInOrder({
      [&] {
        WriteIntrinsics(out_dir, scenes, intrinsics);
        io::WriteNpz((fs::path(out_dir) / "test.npz").string(),
                     {{"name", name_npy}, {"rel_pose", io::EncodeNpy<float>({n, 12}, rel_pose)}});
      },
      [&] {
        io::WriteFileAtomic((fs::path(out_dir) / "statistics.json").string(), stats.dump(4) + "\n");
      },
      [&] { io::WriteFileAtomic((fs::path(out_dir) / list_name).string(), "test.npz\n"); },
      [&] { WriteSceneList(out_dir, other_scenes); },
  });
}

}  // namespace gt::shards

// Pair indices in the layouts LoFTR-family training code reads unchanged (SHARDS.md
// "LoFTR-family index"), written with gt::io::WriteNpz (stored members, deterministic).
//
// Train/val (ScanNet style), under OUT:
//   scene_data/{split}/{scene}.npz   "name"  int64 [N, 4]  (scene number, sub-scene,
//                                                           frame0, frame1)
//                                    "score" float32 [N]   overlap of the pair
//   {split}_list.txt                 one npz file name per line ("scene0707_00.npz")
//   intrinsics.npz                   scene -> float64 [3, 3], K at 640x480 (row-major):
//                                    the resolution LoFTR's ScanNet loader resizes images
//                                    to (and uses this K unchanged), whatever the
//                                    recipe's working resolution (kLoftrWidth/Height);
//                                    a non-ScanNet scene's K is also stored under
//                                    "scene%04d_00" (LoftrSceneFolders, loftr_tree.h), the
//                                    key LoFTR forms from the name row
// LoFTR keeps pairs with score > min_overlap_score (strict) and recomputes relative poses
// from the dataset's pose files, so only names and scores go in.
// Test (test-1500 style), under OUT:
//   test.npz        "name" uint16 [N, 4] (int64 if any value exceeds 65535),
//                   "rel_pose" float32 [N, 12] = T_0to1 (cam1_from_cam0) row-major 3x4
//   intrinsics.npz  as above
//   statistics.json {scene: pairs} with sorted keys
//   {list_name}     "test.npz"
//
// Scene numbers: a ScanNet name "sceneXXXX_YY" gives (XXXX, YY). Any other scene name
// (TartanAir "hospital/Easy/P036", 7-Scenes, synthetic) gives (index of the scene in the
// sorted list of exported scene names, 0); that list is written to OUT/scenes.txt (one
// name per line, line i = scene number i) and its npz is named after the sanitised scene
// path with '/' replaced by '_'. Frame numbers are gt::Frame::number.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace gt::shards {

struct LoftrPair {
  std::string scene;   // dataset scene name
  int64_t frame0 = 0;  // frame numbers (gt::Frame::number)
  int64_t frame1 = 0;
  double score = 0.0;                       // overlap (train export)
  std::array<double, 12> cam1_from_cam0{};  // T_0to1, row-major 3x4 (test export)
};

// The image size of LoFTR's ScanNet loader (read_scannet_gray resizes every image to
// 640x480 and pairs it with intrinsics.npz's K as stored): intrinsics.npz holds K at this
// size, not at the working resolution of the shards.
inline constexpr int kLoftrWidth = 640;
inline constexpr int kLoftrHeight = 480;

// K (row-major 3x3) per scene name, at kLoftrWidth x kLoftrHeight.
using SceneIntrinsics = std::map<std::string, std::array<double, 9>>;

// (XXXX, YY) for "sceneXXXX_YY", nullopt otherwise.
std::optional<std::pair<int64_t, int64_t>> ParseScanNetSceneName(const std::string& scene);

struct LoftrExportOptions {
  std::string split = "train";  // train export: scene_data/{split}/ and list name
  std::string list_name;        // "" = "{split}_list.txt" (train), "test_list.txt" (test)
  bool Check(std::string* error) const;
};

// Train/val export. Pairs keep their order within a scene; scenes are written sorted.
// Throws InputError("loftr export", ...) when a pair's scene has no intrinsics.
void ExportLoftrTrain(const std::string& out_dir, const std::vector<LoftrPair>& pairs,
                      const SceneIntrinsics& intrinsics, const LoftrExportOptions& options);
// Test-1500 style export (pairs in the given order).
void ExportLoftrTest(const std::string& out_dir, const std::vector<LoftrPair>& pairs,
                     const SceneIntrinsics& intrinsics, const LoftrExportOptions& options);

}  // namespace gt::shards

// The pair index of LoFTR's MegaDepth loader (SHARDS.md "LoFTR-family index", docs/EXPORTS.md
// "MegaDepth"), written for a split built from `--format megadepth`:
//
//   OUT/scene_info/<scene>.npz   a pickled dict (np.load(path, allow_pickle=True) reads it,
//                                as LoFTR's loader does; io/pickle.h), keys:
//     "image_paths"  list [n] of str: each frame's colour image, relative to root_dir
//     "depth_paths"  list [n] of str or None (frames without usable depth)
//     "intrinsics"   list [n] of 3x3 nested lists of float, or None: K in COLMAP's pixel
//                    convention (centre of the top-left pixel at (0.5, 0.5)), as the
//                    D2-Net scene_info files LoFTR's indices come from
//     "poses"        list [n] of 4x4 nested lists of float, or None: cam_from_world
//     "pair_infos"   list of ((i, j), score, []): frame indices into the lists above, the
//                    pair's score (overlap or covisible share, recipe loftr_export.score)
//                    and an empty list where D2-Net kept its "central matches"
//   OUT/{split}_list.txt         one scene name a line (LoFTR appends ".npz")
//
// LoFTR's loader keeps pairs with score > min_overlap_score and reads
// root_dir/image_paths[i], root_dir/depth_paths[i] (HDF5 "depth"), K and poses as given.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "libgt/shards/loftr_export.h"

namespace gt::shards {

struct MegaDepthIndexFrame {
  std::string image_path;                                // relative to root_dir
  std::optional<std::string> depth_path;                 // relative to root_dir
  std::optional<std::array<double, 9>> K;                // row-major, COLMAP's pixel convention
  std::optional<std::array<double, 16>> cam_from_world;  // row-major 4x4
};

struct MegaDepthIndexPair {
  int64_t i = 0, j = 0;  // indices into the scene's frames
  double score = 0;
};

struct MegaDepthIndexScene {
  std::string scene;  // its npz is named after it ('/' -> '_')
  std::vector<MegaDepthIndexFrame> frames;
  std::vector<MegaDepthIndexPair> pairs;
};

// The dict of one scene (above), as the Python value the npz holds.
std::string MegaDepthSceneInfoBytes(const MegaDepthIndexScene& scene);

// Writes OUT/scene_info/<scene>.npz for every scene (sorted by name) and the list file
// (options.list_name, default "{split}_list.txt"), atomically. Throws InputError("loftr
// export", ...) when a pair names a frame out of range or two scenes share a file name.
void ExportLoftrMegaDepth(const std::string& out_dir, std::vector<MegaDepthIndexScene> scenes,
                          const LoftrExportOptions& options);

}  // namespace gt::shards

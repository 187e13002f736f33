// The frames of a LoFTR-family index in ScanNet's exported layout (docs/EXPORTS.md), so that
// LoFTR's unchanged ScanNetDataset (and ASpanFormer's, QuadTree's, MatchFormer's, Occ²Net's
// copies of it) reads any input format. Under TREE (= DIR/loftr/data):
//
//   <folder>/color/<n>.jpg    colour; a hard link (else symlink) to a .jpg/.jpeg source,
//                             else the decoded image re-encoded as JPEG at its own size
//                             (LoFTR's reader resizes colour to 640x480 itself)
//   <folder>/depth/<n>.png    uint16 grey PNG, millimetres, 0 = invalid, at 640x480 (the
//                             size of intrinsics.npz's K; LoFTR reads depth unresized);
//                             a link when the source already is exactly that (ScanNet),
//                             else converted: invalid markers (7-Scenes 65535) -> 0, float
//                             metres (TartanAir, synthetic .npy) -> round(1000 d), depth that
//                             does not fit (> 65.535 m, TartanAir's sky) -> 0 and counted,
//                             other sizes resampled nearest-neighbour (ResizeDepthNearest)
//   <folder>/pose/<n>.txt     Frame::world_from_cam (camera-to-world, OpenCV axes: x right,
//                             y down, z forward; TartanAir's NED already converted by its
//                             reader) as 4 lines of 4 numbers, one space apart, LF, %.17g
//                             (np.loadtxt(path, delimiter=' ') reads it)
//   <folder>/intrinsic/intrinsic_depth.txt  K at 640x480 (= intrinsics.npz), 4x4 as ScanNet
//   <folder>/intrinsic/intrinsic_color.txt  K of the colour file as written, 4x4
//
// <folder> is the name LoFTR forms from a `name` row, "scene%04d_%02d" of its first two
// numbers (LoftrSceneFolders); <n> is Frame::number in decimal, as the row's frame fields.
// Only the given frames are written; files and scene folders of an earlier export that the
// index no longer uses are removed. Every file is published atomically (temporary, then
// rename; links too). The output is deterministic (same bytes, or a link to the same file).
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "libgt/core/frame.h"
#include "libgt/shards/frame_files.h"

namespace gt::shards {

// Scene name -> the folder LoFTR opens for it: the name itself for "sceneXXXX_YY", else
// "scene%04d_00" of the scene's index among the sorted non-ScanNet names (the numbers the
// index's `name` rows hold, loftr_export.h). InputError when two scenes get one folder, or a
// non-ScanNet name holds a line break (it is a line of scenes.txt).
std::map<std::string, std::string> LoftrSceneFolders(const std::set<std::string>& scenes);

struct LoftrTreeOptions {
  int jpeg_quality = 95;  // converted colour (1..100)
  int png_level = 1;      // zlib level of converted depth PNGs (0..9): fast, still lossless
  // The depth written, when not the depth file (frame_files.h: the build's depth source);
  // empty = the depth file, linked or converted as above. Given, every depth is converted.
  FrameDepthLoader load_depth;
  bool Check(std::string* error) const;
};

struct LoftrTreeScene {
  const Scene* scene = nullptr;
  std::string folder;            // LoftrSceneFolders
  std::vector<int64_t> numbers;  // Frame::number of the frames the index uses
};

struct LoftrTreeStats {
  size_t frames = 0;
  size_t linked = 0;           // colour and depth files linked to their source
  size_t converted = 0;        // colour and depth files written converted
  size_t depth_zeroed_px = 0;  // finite depth > 65.535 m written as 0
};

// Writes the tree; InputError naming the frame's file on unreadable input or a frame
// without colour, before that frame's files are published.
LoftrTreeStats ExportLoftrTree(const std::string& tree_dir,
                               const std::vector<LoftrTreeScene>& scenes,
                               const LoftrTreeOptions& options);

}  // namespace gt::shards

// The selected pairs and the frames they use in the layouts two more trainer families read
// unchanged (docs/EXPORTS.md): glue-factory's posed-image dataset and DUSt3R's /
// MASt3R's preprocessed ScanNet++-style dataset. Both write the frames at the recipe's
// working resolution W x H, colour and depth at the same size (both loaders resize the two
// together with one transform), K = the working K (Frame::depth_camera resized, as in the
// shards), and the selection score with both directions' overlaps.
//
// glue-factory (PosedImageDataset, gluefactory/datasets/posed_images.py), under OUT:
//   data/<folder>/images/<n>.jpg   colour at W x H (a link when the source already is a
//                                  W x H JPEG file, else the image re-encoded)
//   data/<folder>/depths/<n>.png   uint16 grey PNG, round(256 d) (its loader divides by 256),
//                                  0 = invalid; depth beyond 255.996 m -> 0 and counted
//   data/<folder>/views.txt        one line per view: "<n>.jpg" R (9, row-major) t (3) of
//                                  world-to-camera (cam_from_world, OpenCV axes), then
//                                  "PINHOLE W H fx fy cx cy" with COLMAP's pixel-corner
//                                  convention (cx, cy = occgt's + 0.5)
//   data/<folder>/pairs.txt        "<n0>.jpg <n1>.jpg" per pair (its view_groups file)
//   data/<folder>/pair_scores.txt  "<n0>.jpg <n1>.jpg score overlap01 overlap10", the lines
//                                  of pairs.txt in the same order
//   export.json                    schemas/posed_export.schema.json
// data/ holds only the scene folders (the loader lists data/* as scenes).
//
// DUSt3R / MASt3R (the ScanNetpp dataset class, dust3r/datasets/scannetpp.py, with
// ROOT = OUT), under OUT:
//   all_metadata.npz    scenes <U [S] (folder names), counts int64 [S] (index of each
//                       scene's first view), sceneids int64 [V], images <U [V] (basenames
//                       "<n>"), intrinsics float64 [V, 3, 3] (K at W x H, OpenCV pixel
//                       centres), trajectories float64 [V, 4, 4] (camera-to-world, OpenCV
//                       axes), pairs float64 [P, 5] = (view i, view j, score, overlap_ij,
//                       overlap_ji) with global view indices
//   <folder>/images/<n>.jpg     colour at W x H as above
//   <folder>/depth/<n>.png      uint16 grey PNG, millimetres, 0 = invalid
//   <folder>/scene_metadata.npz the scene's trajectories, intrinsics, images and pairs
//                               (view indices local to the scene)
//   export.json                 schemas/posed_export.schema.json
//
// <folder>: the scene name sanitised (SanitizeScenePath) with '/' replaced by '_'; <n>:
// Frame::number. Views are the frames the pairs use, sorted by number within a scene;
// scenes sorted by name. Files and folders of an earlier export that are no longer used
// are removed; every file is published atomically; the output is deterministic.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "libgt/core/frame.h"
#include "libgt/shards/frame_files.h"

namespace gt::shards {

struct PosedPair {
  std::string scene;   // dataset scene name
  int64_t frame0 = 0;  // Frame::number
  int64_t frame1 = 0;
  double score = 0.0;      // the selection score (Combine of the two overlaps)
  double overlap01 = 0.0;  // score_metrics["01"].overlap: frame0's pixels seen in frame1
  double overlap10 = 0.0;
};

struct PosedExportOptions {
  int width = 640;  // the working resolution
  int height = 480;
  int jpeg_quality = 95;  // converted colour (1..100)
  int png_level = 1;      // zlib level of the depth PNGs (0..9)
  // The depth written, when not the depth file (frame_files.h: the build's depth source,
  // e.g. depth rendered from the mesh for ScanNet++'s DSLR, which has no depth file); empty =
  // the depth file, linked or converted. Given, every depth is converted.
  FrameDepthLoader load_depth;
  bool Check(std::string* error) const;
};

struct PosedExportStats {
  size_t scenes = 0;
  size_t views = 0;
  size_t pairs = 0;
  size_t linked = 0;           // colour and depth files linked to their source
  size_t converted = 0;        // colour and depth files written converted
  size_t depth_zeroed_px = 0;  // finite depth too far for the PNG's 16 bits, written as 0
};

// Scene name -> its folder (see above); InputError when two scenes get one folder.
std::map<std::string, std::string> PosedSceneFolders(const std::set<std::string>& scenes);

// `scenes` maps every scene name of `pairs` to the scene read by the dataset reader.
// InputError naming the file on unreadable input or a frame without colour; InputError
// ("... export", ...) on a pair whose scene or frame is unknown or unusable.
PosedExportStats ExportGlueFactory(const std::string& out_dir,
                                   const std::map<std::string, const Scene*>& scenes,
                                   const std::vector<PosedPair>& pairs,
                                   const PosedExportOptions& options);
PosedExportStats ExportDust3r(const std::string& out_dir,
                              const std::map<std::string, const Scene*>& scenes,
                              const std::vector<PosedPair>& pairs,
                              const PosedExportOptions& options);

}  // namespace gt::shards

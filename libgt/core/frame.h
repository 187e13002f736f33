// Frames and scenes: what every dataset reader yields (docs/DATASETS.md).
// A Frame holds metadata only; its depth is read on demand from `depth` by
// gt::io::ReadDepth, so that a scene of thousands of frames stays small in memory.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/lens.h"
#include "libgt/core/pose.h"

namespace gt {

// The dataset layouts occgt reads (libgt/datasets, docs/DATASETS.md). Parsed from its name
// once, where it enters (a flag, a recipe, meta.json), and named back only where written.
enum class DatasetFormat {
  kScanNet,      // "scannet"
  kTartanAir,    // "tartanair"
  kSevenScenes,  // "sevenscenes"
  kTum,          // "tum"
  kMegaDepth,    // "megadepth"
  kGeneric,      // "generic": occgt's own JSON manifest
  kScanNetPP,    // "scannetpp": ScanNet++ (DSLR or iPhone), undistorted at load
};
inline constexpr DatasetFormat kAllDatasetFormats[] = {
    DatasetFormat::kScanNet,  DatasetFormat::kTartanAir, DatasetFormat::kSevenScenes,
    DatasetFormat::kTum,      DatasetFormat::kMegaDepth, DatasetFormat::kGeneric,
    DatasetFormat::kScanNetPP};
const char* DatasetFormatName(DatasetFormat format);
// Throws InputError(field, "unknown format '<name>', expected one of: ...").
DatasetFormat ParseDatasetFormat(std::string_view name, const std::string& field = "--format");

enum class DepthFormat {
  kNpyFloat32,  // .npy float32 metres, shape (H, W)
  kPng16,       // 16-bit PNG (or PGM), metres = value * scale_m_per_unit; 0 invalid
  kExr,         // OpenEXR, one channel (matched by suffix), metres
  // A payload inside a container file (ScanNet .sens, libgt/datasets/sens.h): bytes `range` of
  // `path`, width x height uint16 (little-endian), metres = value * scale_m_per_unit; 0 invalid.
  kSensZlib,  // zlib stream of the uint16 values
  kSensRaw,   // the uint16 values as they are
  kHdf5,      // HDF5 file, 2-D float dataset "depth" (MegaDepth v1), metres; 0 invalid
  // ScanNet++ iPhone depth.bin (io/iphone_depth.h), width x height per frame:
  kIphoneBinDeflate,  // the whole file one raw-deflate stream of float32 metres; frame_index-th map
  kIphoneBinRecord,   // bytes `range`: one record's payload, LZ4 block of uint16 mm or raw
                      // deflate of float32 metres
};

// Bytes [offset, offset + size) of a file: a payload inside a container (.sens).
struct ByteRange {
  uint64_t offset = 0;
  uint64_t size = 0;  // 0: not a range (the whole file)
};

struct DepthSource {
  std::string path;
  DepthFormat format = DepthFormat::kNpyFloat32;
  double scale_m_per_unit = 1.0;  // png16: 0.001 for millimetres, 1/5000 for TUM
  std::string exr_channel;        // exr: channel name or suffix ("Z", "Depth.Z"); "" = auto
  int invalid_value = -1;         // png16: a raw value that means "no depth" (7-Scenes: 65535)
  ByteRange range;                // sens*: the payload inside `path`
  int width = 0;                  // sens*, iphone*: size of the map (the container's header)
  int height = 0;
  // sens*: the frame's index in the container, named in the errors of both its payloads
  // (depth and colour); -1 otherwise.
  int64_t frame_index = -1;
};

struct Frame {
  std::string id;      // stable id, unique within the scene ("000150", "0054")
  int64_t number = 0;  // numeric order within the scene (frame number or index)
  DepthSource depth;
  Camera depth_camera;  // K at the depth map's resolution
  Rigid3d world_from_cam = Rigid3d::Identity();
  bool usable = true;
  // Set when !usable: one stable category (pose problem, missing depth, ...), the string
  // `occgt scan` counts frames by, and where in the input it is and what was found
  // ("<file>:<line>: non-finite value"; "" when the category says it all). docs/DATASETS.md
  // "Errors and unusable frames".
  std::string unusable_reason;
  std::string unusable_detail;
  std::string color_path;    // may be empty when the dataset has no colour
  Camera color_camera;       // K at the colour image's resolution (0x0 when unknown)
  double timestamp_s = 0.0;  // TUM only
  // .sens: the colour payload inside color_path (size 0: color_path is the image file), JPEG
  // or PNG bytes, or with color_raw_rgb, color_camera.width x height x 3 bytes R, G, B.
  ByteRange color_range;
  bool color_raw_rgb = false;
  // A distorted colour camera (ScanNet++): color_path is an image of color_lens->pinhole's
  // size, presented undistorted in color_camera (a pinhole camera) by io::ReadFrameColor
  // (io/undistort.h: bilinear, BORDER_REFLECT_101).
  std::optional<LensCamera> color_lens;
  // An anonymisation mask of the (distorted) colour image, 8-bit, 255 = valid, anything else
  // anonymised (ScanNet++); "" when none. Its pixels have no depth: io::ReadFrameDepth remaps
  // it into depth_camera (border 255, < 255 -> 0) and zeroes the depth there.
  std::string mask_path;
  // Depth measured in a distorted camera (ScanNet++ iPhone: ARKit depth in the OPENCV camera
  // at the depth map's size): io::ReadFrameDepth resamples it (nearest, no new values) into
  // depth_camera. Unset: the depth map is in depth_camera.
  std::optional<LensCamera> depth_lens;

  // Why the frame is unusable, for a message about this frame: the reason, then the
  // detail when there is one ("pose: non-finite pose entries; <file>:<line>: non-finite
  // value").
  std::string UnusableMessage() const {
    return unusable_detail.empty() ? unusable_reason : unusable_reason + "; " + unusable_detail;
  }
};

struct Scene {
  std::string name;  // e.g. "scene0707_00", "hospital/Easy/P036", "seq-01"
  DatasetFormat format = DatasetFormat::kGeneric;  // the reader's format
  std::string path;                                // folder (or manifest) the scene was read from
  double min_depth_m = kDefaultMinDepthM;  // the reader's validity range (recipes may override)
  double max_depth_m = kDefaultMaxDepthM;
  // The scene's triangle mesh in the frames' world frame (ScanNet's <scene>_vh_clean_2.ply,
  // ScanNet++'s scans/mesh_aligned_0.05.ply, or a path from the recipe); "" when none.
  // Depth rendered from it (docs/GROUND_TRUTH.md "Depth sources") uses the frames' poses.
  std::string mesh_path;
  // Where the reader looked for the scene's own mesh when it found none (ScanNet++'s
  // <scene>/scans/mesh_aligned_0.05.ply), for messages; "" when found or when the format
  // has no mesh of its own.
  std::string mesh_expected_path;
  std::vector<Frame> frames;  // sorted by number
  // What the reader noticed and decided without an error, one sentence each (two colour
  // files for one frame, which one it read); `occgt scan` prints them among its warnings.
  std::vector<std::string> reader_warnings;

  // " (<mesh_expected_path> is missing)" or "": the end of a message that the scene has no
  // mesh.
  std::string MissingMeshNote() const {
    return mesh_expected_path.empty() ? "" : " (" + mesh_expected_path + " is missing)";
  }

  size_t NumUsable() const {
    size_t n = 0;
    for (const auto& f : frames) n += f.usable ? 1 : 0;
    return n;
  }
};

}  // namespace gt

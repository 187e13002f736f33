// Private to libgt/io: the reader classes behind MakeReader (reader.h), one .cc each.
// Layouts, conventions and unusable reasons are documented in docs/DATASETS.md.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "libgt/datasets/reader.h"

namespace gt::datasets {

// ScanNet, SensReader exports: Python (color/, depth/, pose/, intrinsic/) or C++
// (frame-XXXXXX.{color.jpg,depth.pgm,pose.txt} + _info.txt) (scannet.cc).
class ScanNetReader : public DatasetReader {
 public:
  explicit ScanNetReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kScanNet; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  Scene ReadCppExport(const std::string& folder, const std::string& scene_name) const;
  // The scene of a resolved folder, whatever its layout (ReadScene adds the mesh path).
  Scene ReadSceneFolder(const std::string& folder, const std::string& scene_name) const;
  Scene ReadSens(const std::string& folder, const std::string& scene_name) const;
  ReaderOptions options_;
};

// TartanAir v1 trajectories, NED poses converted to OpenCV axes (tartanair.cc).
class TartanAirReader : public DatasetReader {
 public:
  explicit TartanAirReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kTartanAir; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  ReaderOptions options_;
};

// Microsoft 7-Scenes sequences: frame-NNNNNN.{color.png,depth.png,pose.txt} (sevenscenes.cc).
class SevenScenesReader : public DatasetReader {
 public:
  explicit SevenScenesReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kSevenScenes; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  ReaderOptions options_;
};

// TUM RGB-D sequences: rgb.txt, depth.txt, groundtruth.txt, associated by time (tum.cc).
class TumReader : public DatasetReader {
 public:
  explicit TumReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kTum; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  ReaderOptions options_;
};

// TUM's K by sequence folder name (docs/DATASETS.md "TUM RGB-D"): fr2 when the name holds
// "freiburg2" or "fr2", else fr3 for "freiburg3"/"fr3", else fr1 (named only when the name
// holds "freiburg1" or "fr1"; otherwise fr1's K is assumed), at 640x480.
struct TumIntrinsics {
  Camera camera;
  std::string sequence;  // "fr1", "fr2", "fr3"
  bool named = false;    // the folder name says which sequence
};
TumIntrinsics TumIntrinsicsOf(const std::string& sequence_name);
// What `occgt scan` says of a TUM scene beside the counts (SummarizeScene's warnings), one
// line each: fr1's K assumed for a folder name that names no sequence; a missing rgb.txt.
std::vector<std::string> TumSceneWarnings(const Scene& scene);

// The file the colour K of a ScanNet scene comes from, for messages: the Python export's
// intrinsic/intrinsic_color.txt, the C++ export's _info.txt or the .sens; "" when the colour
// K is the depth K rescaled.
std::string ScanNetColorIntrinsicsSource(const Scene& scene);

// MegaDepth v1: dense0/depths/*.h5 with a COLMAP sparse model of the undistorted images
// (megadepth.cc).
class MegaDepthReader : public DatasetReader {
 public:
  explicit MegaDepthReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kMegaDepth; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  ReaderOptions options_;
};

// ScanNet++: data/<scene>/dslr (OPENCV_FISHEYE COLMAP model, resized images and anonymisation
// masks) or iphone (OPENCV model, extracted frames, masks, depth PNGs or depth.bin), frames
// presented undistorted (scannetpp.cc, docs/DATASETS.md "ScanNet++").
class ScanNetPPReader : public DatasetReader {
 public:
  explicit ScanNetPPReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kScanNetPP; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  ReaderOptions options_;
};

// occgt's own JSON manifest, schemas/manifest.schema.json (generic.cc).
class GenericReader : public DatasetReader {
 public:
  explicit GenericReader(const ReaderOptions& options) : options_(options) {}
  DatasetFormat Format() const override { return DatasetFormat::kGeneric; }
  std::vector<std::string> ListScenes(const std::string& root) const override;
  Scene ReadScene(const std::string& root, const std::string& scene_name) const override;

 private:
  ReaderOptions options_;
};

// The generic reader's validation of one manifest already in memory: `manifest` is its
// path (for messages and to resolve relative paths), `scene_name` overrides the manifest's
// scene name when not empty. Throws InputError("<manifest>", "<field>: ...").
Scene ParseGenericManifest(std::string_view text, const std::string& manifest,
                           const std::string& scene_name, const ReaderOptions& options);

}  // namespace gt::datasets

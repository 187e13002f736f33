// Scene summaries for `occgt scan`: frame counts, unusable frames counted by reason (the
// stable category, Frame::unusable_reason) with the first few of them listed as examples
// (frame id and Frame::unusable_detail, "<file>:<line>: non-finite value"), the depth
// camera, and (optionally) a read of every depth file that checks its size against the
// frame's depth camera and measures the fraction of valid depth pixels (IsValidDepth with
// the scene's [min_depth_m, max_depth_m]).
// A depth file that fails to read marks its frame unusable with kReasonDepthUnreadable
// and its error message is kept (the first ScanOptions::max_errors_listed of them).
#pragma once

#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "libgt/core/frame.h"

namespace gt::datasets {

inline constexpr const char* kReasonDepthUnreadable = "depth: unreadable or wrong size";
// A frame whose anonymisation mask (Frame::mask_path) has no valid pixel, or cannot be read.
inline constexpr const char* kReasonMaskCoversImage = "mask: covers the whole image";
inline constexpr const char* kReasonMaskUnreadable = "mask: unreadable";

struct ScanOptions {
  bool check_depth = false;     // read every usable frame's depth file
  int max_errors_listed = 5;    // depth read errors kept per scene (>= 0)
  int max_examples_listed = 5;  // unusable frames listed per reason and scene (>= 0)
  bool check_masks = true;      // read every usable frame's anonymisation mask (Frame::mask_path)

  bool Check(std::string* error) const;
};

// One unusable frame listed under its reason.
struct UnusableExample {
  std::string frame;   // Frame::id
  std::string detail;  // Frame::unusable_detail ("" when the reader gives none)
};

struct SceneSummary {
  std::string name;
  std::string path;
  size_t frames = 0;
  size_t usable = 0;
  std::map<std::string, size_t> unusable_reasons;  // reason -> frame count (sorted by reason)
  // reason -> its first ScanOptions::max_examples_listed frames, in frame order (a reason
  // is absent when none is listed).
  std::map<std::string, std::vector<UnusableExample>> unusable_examples;
  Camera depth_camera;               // of the first frame
  bool uniform_depth_camera = true;  // every frame has the same size and K
  double min_depth_m = 0.0;
  double max_depth_m = 0.0;
  // Colour coverage: usable frames with a colour file, and the colour camera of the first
  // of them (0x0 when none has colour).
  size_t usable_with_color = 0;
  Camera color_camera;
  bool uniform_color_camera = true;
  // Known caveats of the dataset (DatasetCaveats) and of this scene: what its reader
  // assumed (TUM's K by folder name), a missing colour list (TUM's rgb.txt), a colour K
  // whose principal point lies outside its image, frames without colour.
  std::vector<std::string> warnings;
  // check_depth only:
  bool depth_checked = false;
  size_t depth_files_read = 0;       // successfully read
  size_t depth_files_bad = 0;        // read failed (frame counted unusable)
  double mean_valid_fraction = 0.0;  // over the files read; 0 when none
  std::vector<std::string> depth_errors;

  // The ids of the frames counted usable above (the reader's, less those the mask and depth
  // checks refused), for a caller that goes on to read them.
  std::set<std::string> usable_ids;

  size_t unusable() const { return frames - usable; }
};

// Known caveats of a dataset format that a user must see before trusting its outputs, one
// sentence each (shown by `occgt scan` and in the split report); empty when none.
std::vector<std::string> DatasetCaveats(DatasetFormat format);

// Summarises `scene`; with check_depth, reads the depth of every usable frame.
SceneSummary SummarizeScene(const Scene& scene, const ScanOptions& options);

}  // namespace gt::datasets

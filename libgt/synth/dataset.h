// The synthetic dataset of `occgt synth` (docs/SYNTH.md): seeded rooms, a camera loop per
// room, exact ray-cast depth with a few recorded invalid-depth holes, shaded colour, all
// written in occgt's generic format (schemas/manifest.schema.json, DATASETS.md):
//
//   <out>/dataset.json                   scenes, options and the holes of every frame
//   <out>/synth_NNN/scene.json           generic manifest (K, world_from_cam, paths)
//   <out>/synth_NNN/depth/FFFFFF.npy     float32 metres, shape (height, width), 0 = invalid
//   <out>/synth_NNN/color/FFFFFF.png     8-bit RGB, same size and K as the depth
//
// K: fx = fy = focal_px * width / 640, cx = (width - 1) / 2, cy = (height - 1) / 2 (pixel
// centres at integer coordinates, camera.h). Every file is written atomically and the
// bytes depend only on the options (seed included).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/synth/scene.h"
#include "libgt/synth/trajectory.h"

namespace gt::synth {

// Claims out_dir for one synthetic dataset before anything is written, so that the scenes
// and frames of two runs never mix: `claim` (the layout and its options, a JSON text) is
// written to out_dir/.occgt-synth.json first. A folder whose claim differs, or that holds
// files without a claim (another run's that predates it, a killed run's, anything else),
// is an InputError naming it; the same claim (a re-run, a killed run resumed) passes.
// `legacy_options` is checked against the "options" of a dataset.json written before the
// claim existed ("" for none).
void ClaimSynthFolder(const std::string& out_dir, const std::string& claim,
                      const std::string& legacy_options);

struct SynthOptions {
  int scenes = 2;                // rooms
  int frames_per_scene = 24;     // poses on each room's camera loop
  int width = 640;               // pixels
  int height = 480;              // pixels
  uint64_t seed = 0;             // everything random derives from it
  bool holes = true;             // punch invalid-depth holes (depth 0) into every frame
  int max_holes_per_frame = 3;   // holes per frame drawn in [1, max] when `holes`
  double focal_px = 525.0;       // focal length at width 640 (scaled with the width)
  RoomOptions room;              // scene generator
  TrajectoryOptions trajectory;  // frames is overridden by frames_per_scene

  bool Check(std::string* error) const;
};

// The pinhole camera of every synthetic frame for these options.
Camera SynthCamera(const SynthOptions& options);

// Name of scene i ("synth_000") and its generator seed.
std::string SynthSceneName(int scene_index);
uint64_t SynthSceneSeed(uint64_t dataset_seed, int scene_index);

// An invalid-depth hole: pixels x0 <= u < x1, y0 <= v < y1.
struct HoleRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};
// Holes of frame `frame_index` of a scene, drawn from (scene_seed, frame_index): between 1
// and max_holes rectangles of 4..max(8, width/12) pixels per side, inside the image.
std::vector<HoleRect> MakeHoles(uint64_t scene_seed, int frame_index, int width, int height,
                                int max_holes);
// Sets the depth inside every hole to 0.
void ApplyHoles(const std::vector<HoleRect>& holes, DepthImage* depth);

struct SynthSummary {
  std::vector<std::string> scene_names;
  int frames = 0;  // total over scenes
  int files = 0;   // files written
};

// Writes the dataset under out_dir (created when missing); existing files of the same
// names are replaced. An out_dir whose dataset.json is not occgt synth's, or holds other
// options, is refused (files of both would mix). Throws InputError for invalid options, such
// a folder or a failed write.
SynthSummary WriteSyntheticDataset(const std::string& out_dir, const SynthOptions& options);

}  // namespace gt::synth

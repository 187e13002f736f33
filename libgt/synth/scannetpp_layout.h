// The synthetic dataset in ScanNet++'s layout (`occgt synth --layout scannetpp`,
// docs/SYNTH.md): the rooms of scene.h seen through ScanNet++'s distorted cameras, written as
// ScanNet++ writes them (docs/DATASETS.md "ScanNet++"), so that the scannetpp reader, its
// undistortion and mesh-rendered depth can be checked against exact answers.
//
//   <out>/data/<scene>/scans/mesh_aligned_0.05.ply   binary PLY of the room and its boxes
//                                                     (float x y z, uchar rgb; list uchar int)
//   <out>/data/<scene>/dslr/colmap/{cameras,images,points3D}.txt
//                                                     one OPENCV_FISHEYE camera (COLMAP's
//                                                     +0.5 principal point), world-to-camera
//   <out>/data/<scene>/dslr/resized_images/DSC%05d.JPG   rendered through the fisheye lens
//   <out>/data/<scene>/dslr/resized_anon_masks/DSC%05d.png   255 valid, 0 anonymised
//   <out>/data/<scene>/dslr/train_test_lists.json
//   <out>/data/<scene>/iphone/colmap/...              one OPENCV camera
//   <out>/data/<scene>/iphone/rgb/frame_%06d.jpg, rgb_masks/frame_%06d.png
//   <out>/data/<scene>/iphone/depth/frame_%06d.png    uint16 mm, 256 x 192, distorted camera
//   <out>/data/<scene>/iphone/depth.bin               the same depth, LZ4 records of uint16 mm
//
// The DSLR walks a third of the room's camera loop (synth/trajectory.h), the iPhone beside
// it. Every image pixel is shaded along its exact ray (UndistortPixel of the lens), every depth
// value is the planar z of the first hit along it. Defects a reader must explain are planted
// on purpose: DSC90000.JPG has no pose, DSC90001.JPG is listed in train_test_lists.json but
// has no file, the last DSLR frame's mask anonymises the whole image, and the iPhone frame
// after the last posed one has no pose. Even DSLR frames have an anonymised rectangle.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/lens.h"
#include "libgt/core/pose.h"
#include "libgt/synth/scene.h"

namespace gt::synth {

struct ScanNetPPSynthOptions {
  int scenes = 1;
  int frames = 6;        // posed DSLR images and posed iPhone frames per scene
  int dslr_width = 438;  // resized DSLR images (ScanNet++: 1752 x 1168)
  int dslr_height = 292;
  int iphone_width = 480;  // iPhone colour (ScanNet++: 1920 x 1440); depth is 256 x 192
  int iphone_height = 360;
  uint64_t seed = 0;

  bool Check(std::string* error) const;
};

// The scene names ("synthpp_000") and the cameras of the fixture.
std::string ScanNetPPSynthSceneName(int scene_index);
LensCamera ScanNetPPSynthDslrLens(const ScanNetPPSynthOptions& options);
LensCamera ScanNetPPSynthIphoneLens(const ScanNetPPSynthOptions& options);
// The scene and the world_from_cam of its posed DSLR and iPhone frames (the fixture's truth).
struct ScanNetPPSynthScene {
  SynthScene scene;
  std::vector<Rigid3d> dslr_poses;    // DSC%05d of 10 * (i + 1)
  std::vector<Rigid3d> iphone_poses;  // frame_%06d of i
};
ScanNetPPSynthScene MakeScanNetPPSynthScene(const ScanNetPPSynthOptions& options, int scene_index);
// The DSLR image name of posed frame i ("DSC00010.JPG").
std::string ScanNetPPSynthDslrName(int i);

struct ScanNetPPSynthSummary {
  std::vector<std::string> scene_names;
  int files = 0;
};
// Writes the fixture under out_dir; InputError for invalid options or a failed write.
ScanNetPPSynthSummary WriteScanNetPPSynth(const std::string& out_dir,
                                          const ScanNetPPSynthOptions& options);

}  // namespace gt::synth

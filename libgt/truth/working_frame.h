// Frames at the working resolution: the one way every caller (the build, `occgt pair`,
// `occgt occupancy`, `inspect pair`, the Python module) turns a dataset frame into what
// the per-pair ground truth needs (GROUND_TRUTH.md §1 "Working resolution").
//
// Depth is read with the size the reader announced for the frame (a file of another size is
// an InputError naming it) and resized with nearest neighbour; K is rescaled with the
// pixel-centre rule of libgt/core/camera.h (Camera::Resized). A resolution given on the
// command line is W×H with 2 <= W, H <= 8192 (a typo such as 60000x60000 must not become
// a multi-gigabyte allocation, and the half-resolution occupancy grid needs >= 1 ray per
// side); a recipe also needs W, H >= 8 (its patch grid, schemas/recipe.schema.json).
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/frame.h"
#include "libgt/core/pose.h"
#include "libgt/render/frame_depth.h"

namespace gt::truth {

inline constexpr int kMinResolution = 2;
inline constexpr int kMaxResolution = 8192;

struct Resolution {
  int width = 640;  // pixels
  int height = 480;

  bool Check(std::string* error) const;  // kMinResolution..kMaxResolution each
};
// "WxH" → Resolution; throws InputError(field, ...) naming the accepted range.
Resolution ParseResolution(const std::string& text, const std::string& field);

// One frame of a pair at the working resolution.
struct WorkingFrame {
  std::shared_ptr<const DepthImage> depth;  // [H, W] planar metres (0/NaN = invalid)
  Camera camera;                            // depth camera's K at W×H
  Rigid3d world_from_cam = Rigid3d::Identity();
};

// K of a frame's depth camera at the working resolution.
Camera WorkingCamera(const Frame& frame, const Resolution& resolution);
// The frame's depth map at the working resolution; throws InputError naming the file.
DepthImage LoadWorkingDepth(const Frame& frame, const Resolution& resolution);
WorkingFrame LoadWorkingFrame(const Frame& frame, const Resolution& resolution);
// The same with the depth from `depth.source` (render/frame_depth.h: sensor, mesh, fused),
// the mesh rendered directly at the working resolution in the working camera. The sensor
// source is exactly LoadWorkingDepth(frame, resolution). *agreement, when given, counts the
// sensor-vs-mesh comparison (mesh and fused sources).
DepthImage LoadWorkingDepth(const Scene& scene, const Frame& frame, const Resolution& resolution,
                            const render::FrameDepthOptions& depth,
                            render::DepthAgreement* agreement = nullptr);
WorkingFrame LoadWorkingFrame(const Scene& scene, const Frame& frame, const Resolution& resolution,
                              const render::FrameDepthOptions& depth);
// The sensor-vs-mesh comparison of one frame at the working resolution: the counts of
// `occgt scan --mesh` and of the split report (docs/GROUND_TRUTH.md "Depth sources"). The
// mesh is rendered whatever depth.source says; depth.fused is the tolerance, depth.near_m /
// far_m the render's range. A frame without a depth file has no sensor pixel.
render::DepthAgreement CompareWorkingDepthWithMesh(const Scene& scene, const Frame& frame,
                                                   const Resolution& resolution,
                                                   const render::FrameDepthOptions& depth);

// Index into scene.frames of the frame with id `id`; throws InputError(field, ...) when
// there is none or it is unusable (with the reader's reason).
size_t FindFrame(const Scene& scene, const std::string& id, const std::string& field = "--frames");
// "ID0,ID1" → the two ids; throws InputError(field, ...), also for one id given twice.
std::pair<std::string, std::string> ParseFramePair(const std::string& text,
                                                   const std::string& field = "--frames");

}  // namespace gt::truth

// Exact ray casting of a SynthScene: planar depth, a shaded colour image and the id of the
// surface seen at every pixel.
//
// The ray of pixel (u, v) (centre at the integer point, camera.h) has the direction
// d_in_cam = ((u - cx) / fx, (v - cy) / fy, 1) in OpenCV camera axes, so the ray parameter t
// of the first hit p = c + t * d is the planar depth z of p. Boxes are intersected with the
// slab method (Kay & Kajiya 1986) in their own frame; the camera is inside the closed room,
// so every ray hits a surface. Colour is Lambertian, albedo times a procedural pattern
// (scene.h Material), lit by one point light plus an ambient term, without shadows;
// 8-bit RGB. Array layouts: DepthImage is float32 metres [height, width]; ColorImage is
// uint8 [height, width, 3] in R, G, B order; surface ids are int32 [height, width].
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/depth.h"
#include "libgt/core/pose.h"
#include "libgt/io/image.h"
#include "libgt/synth/scene.h"

namespace gt::synth {

// Surface ids: room faces are 0..5 (RoomFace); object i is kFirstObjectId + i.
inline constexpr int kFirstObjectId = 6;
inline constexpr int kNoSurface = -1;

struct RayHit {
  double t = std::numeric_limits<double>::infinity();  // hit = origin + t * direction
  int surface_id = kNoSurface;
  Eigen::Vector3d normal_in_world = Eigen::Vector3d::Zero();  // unit, towards the ray origin
  Eigen::Vector2d uv_m = Eigen::Vector2d::Zero();             // texture coordinates on the surface
  bool hit() const { return surface_id != kNoSurface; }
};

// First surface along the ray (t > 0). The direction need not be unit length.
RayHit CastRay(const SynthScene& scene, const Eigen::Vector3d& origin_in_world,
               const Eigen::Vector3d& direction_in_world);

struct RenderedView {
  DepthImage depth;                  // planar z, metres; 0 where nothing was hit
  io::ColorImage color;              // 8-bit RGB
  std::vector<int32_t> surface_ids;  // [height, width], kNoSurface where nothing was hit
};

// Depth, colour and surface ids of one view in a single pass.
RenderedView RenderView(const SynthScene& scene, const Camera& camera,
                        const Rigid3d& world_from_cam);
DepthImage RenderDepth(const SynthScene& scene, const Camera& camera,
                       const Rigid3d& world_from_cam);
io::ColorImage RenderColor(const SynthScene& scene, const Camera& camera,
                           const Rigid3d& world_from_cam);

// Shaded colour of a hit, linear RGB in [0, 1] (RenderColor writes round(255 * value)).
Eigen::Vector3d ShadeHit(const SynthScene& scene, const Eigen::Vector3d& p_in_world,
                         const RayHit& hit);

}  // namespace gt::synth

// Depth and triangle ids rendered from a triangle mesh by ray casting (Embree 3).
//
// A MeshRenderer builds the mesh's BVH once; Render() is const and thread-safe, so one
// renderer serves every thread and every frame of a scene. For each pixel (u, v) the ray
// leaves the camera centre through the pixel's centre, the continuous image point (u, v)
// (GROUND_TRUTH.md §1; core/camera.h): for a pinhole camera through the normalised point
// ((u - cx) / fx, (v - cy) / fy, 1), for a distorted camera through the exact inverse of its
// distortion (core/lens.h UndistortPixel). The first surface hit along it (either side of a
// triangle: no back-face culling) gives the pixel's planar depth z in camera coordinates,
// metres. The depth is 0 where the ray hits nothing, or where the first surface lies outside
// [near_m, far_m] (a surface nearer than near_m hides what is behind it, as a depth sensor's
// near limit would; it is not clipped away).
//
// Embree is included only in mesh_renderer.cc and linked privately.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "libgt/core/camera.h"
#include "libgt/core/lens.h"
#include "libgt/core/pose.h"
#include "libgt/render/mesh.h"

namespace gt::render {

// How rays are handed to Embree. kCoherent is the renderer; kSingleRay (one rtcIntersect1
// call per pixel, no coherence hint) exists as the baseline of the benchmark and as a
// cross-check in tests. Both give the same depth.
enum class RayBatching { kCoherent, kSingleRay };

struct RenderOptions {
  double near_m = 0.05;       // metres (planar z); first surfaces nearer give 0
  double far_m = 20.0;        // metres (planar z); first surfaces farther give 0
  bool triangle_ids = false;  // also fill RenderedDepth::triangle_id
  RayBatching batching = RayBatching::kCoherent;

  // near_m >= 0, far_m > near_m, both finite.
  bool Check(std::string* error) const;
};

struct RenderedDepth {
  cv::Mat1f depth_m;      // [height, width] planar z, metres; 0 = none
  cv::Mat1i triangle_id;  // [height, width] index into TriangleMesh::triangles / 3, -1 = none;
                          // empty unless RenderOptions::triangle_ids
};

class MeshRenderer {
 public:
  // Builds the BVH (Embree, multi-threaded through TBB). The mesh is copied into Embree's
  // buffers: `mesh` may be freed afterwards. Throws InputError("mesh", ...) on an index out
  // of range or a non-finite vertex, std::runtime_error when Embree fails (out of memory).
  explicit MeshRenderer(const TriangleMesh& mesh);
  ~MeshRenderer();
  MeshRenderer(const MeshRenderer&) = delete;
  MeshRenderer& operator=(const MeshRenderer&) = delete;

  // Pinhole camera at its own resolution (width x height pixels). Throws InputError on a
  // camera that fails Camera::Check, a non-finite pose or options that fail Check.
  RenderedDepth Render(const Camera& camera, const Rigid3d& world_from_cam,
                       const RenderOptions& options) const;

  // A camera with lens distortion (core/lens.h): the ray of pixel (u, v) goes through the
  // pixel's exact undistorted direction UndistortPixel(camera, u, v); a pixel that has none
  // (outside the model's monotonic range) gets 0. The image is camera.pinhole's size.
  RenderedDepth Render(const LensCamera& camera, const Rigid3d& world_from_cam,
                       const RenderOptions& options) const;

  size_t NumTriangles() const;
  // Bytes Embree holds for the mesh copy and the BVH (from its memory monitor).
  size_t EmbreeBytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gt::render

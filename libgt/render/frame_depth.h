// Where a frame's depth comes from (docs/GROUND_TRUTH.md "Depth sources"): the sensor's depth
// file (`sensor`, the default), depth rendered from the scene's mesh (Scene::mesh_path) in the
// frame's depth camera at its pose (`mesh`), or both fused (`fused`): the sensor's depth where
// it agrees with the mesh within a tolerance, the mesh's where the sensor has none, and none
// (0) where they disagree. The tolerance follows ScanNet's own filter of rendered against
// sensor depth (ScanNet/ScanNet: ProjectAnnotations, zParametersScan.txt): 0.2 m + 1 % of the
// depth.
//
// A pixel of the sensor "has depth" when it is valid by the scene's range (GROUND_TRUTH.md
// §1: finite, min_depth_m < d < max_depth_m, as the labels use it); a rendered pixel when it
// is > 0 (a hit within the render's [near_m, far_m]).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "libgt/core/depth.h"
#include "libgt/core/frame.h"
#include "libgt/render/mesh_renderer.h"

namespace gt::render {

enum class DepthSourceMode {
  kSensor,  // "sensor": the dataset's depth files
  kMesh,    // "mesh": rendered from Scene::mesh_path
  kFused,   // "fused": sensor where it agrees with the mesh, mesh where the sensor has none
};
const char* DepthSourceModeName(DepthSourceMode mode);
// Throws InputError(field, "unknown depth source '<name>', expected sensor, mesh or fused").
DepthSourceMode ParseDepthSourceMode(std::string_view name, const std::string& field);

struct FusedDepthOptions {
  double abs_tol_m = 0.2;  // metres: agree when |sensor - mesh| <= abs_tol_m + rel_tol * mesh
  double rel_tol = 0.01;   // of the rendered depth

  bool Check(std::string* error) const;  // both finite and >= 0
};

struct FrameDepthOptions {
  DepthSourceMode source = DepthSourceMode::kSensor;
  FusedDepthOptions fused;
  double near_m = RenderOptions().near_m;  // metres: the render's range (RenderOptions)
  double far_m = RenderOptions().far_m;

  bool Check(std::string* error) const;
};

// How a frame's sensor and rendered depth compare, in pixels (each pixel in exactly one).
struct DepthAgreement {
  int64_t sensor_only = 0;  // the sensor has depth, the mesh none
  int64_t mesh_only = 0;    // the mesh has depth, the sensor none (a hole the mesh fills)
  int64_t agree = 0;        // both, within the tolerance
  int64_t disagree = 0;     // both, beyond it (fused: 0)
  int64_t neither = 0;

  int64_t Total() const { return sensor_only + mesh_only + agree + disagree + neither; }
  DepthAgreement& operator+=(const DepthAgreement& o);
};

// The fused map of two maps of one size (rules above); counts into *agreement when given.
DepthImage FuseSensorAndMesh(const DepthImage& sensor, const DepthImage& mesh, double min_depth_m,
                             double max_depth_m, const FusedDepthOptions& options,
                             DepthAgreement* agreement = nullptr);
// Only the counts.
DepthAgreement CompareSensorAndMesh(const DepthImage& sensor, const DepthImage& mesh,
                                    double min_depth_m, double max_depth_m,
                                    const FusedDepthOptions& options);

// The renderer of a mesh file, shared (thread-safe): built once while in use, the 4 most
// recently asked-for meshes kept (the frames of a scene reuse its BVH; a build over many
// scenes does not hold them all). Throws InputError naming the file.
std::shared_ptr<const MeshRenderer> SharedMeshRenderer(const std::string& path);

// Depth rendered from the scene's mesh in `camera` at the frame's pose, as a DepthImage.
// Throws InputError("<scene>", "no mesh ...") when the scene has none.
DepthImage RenderFrameDepth(const Scene& scene, const Frame& frame, const Camera& camera,
                            const FrameDepthOptions& options);

// The frame's depth from options.source, at `camera`'s size (the frame's depth camera,
// resized): the sensor's map read and resized with nearest neighbour (GROUND_TRUTH.md §1),
// the mesh rendered directly at that size. *agreement (when given, and a mesh and the
// sensor's depth are both used) counts the comparison. `sensor` gives the sensor's map at
// that size when the caller already has it (nullptr: read it).
DepthImage LoadFrameDepth(const Scene& scene, const Frame& frame, const Camera& camera,
                          const FrameDepthOptions& options, DepthAgreement* agreement = nullptr,
                          const DepthImage* sensor = nullptr);

}  // namespace gt::render

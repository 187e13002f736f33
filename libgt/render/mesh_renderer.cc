#include "libgt/render/mesh_renderer.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "libgt/core/error.h"

namespace gt::render {
namespace {

constexpr int kTile = 8;  // pixels: rays go to Embree as 8x8 coherent streams

void ErrorFunction(void* user, RTCError code, const char* text) {
  auto* message = static_cast<std::string*>(user);
  if (message->empty()) message->assign(text ? text : "unknown error");
  (void)code;
}

bool MemoryMonitor(void* user, ssize_t bytes, bool /*post*/) {
  static_cast<std::atomic<int64_t>*>(user)->fetch_add(bytes, std::memory_order_relaxed);
  return true;
}

}  // namespace

bool RenderOptions::Check(std::string* error) const {
  // Each message names its field first (the CLI names the flag from it).
  if (!std::isfinite(near_m) || near_m < 0) {
    *error = "near_m: expected a finite number >= 0 (render), got " + std::to_string(near_m);
    return false;
  }
  if (!std::isfinite(far_m) || far_m <= near_m) {
    *error = "far_m: expected a finite number > near_m " + std::to_string(near_m) +
             " (render), got " + std::to_string(far_m);
    return false;
  }
  return true;
}

struct MeshRenderer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  size_t num_triangles = 0;
  // The mesh as Embree holds it (its geometry buffers, alive with the scene): the hit
  // triangle's corners, to compute the depth of a hit from them.
  const float* vertices = nullptr;
  const uint32_t* triangles = nullptr;
  std::string error;  // Embree's first error message
  std::atomic<int64_t> embree_bytes{0};

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void ThrowIfError(const char* what) {
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE || !error.empty()) {
      throw std::runtime_error(std::string("Embree ") + what + ": " +
                               (error.empty() ? "failed" : error));
    }
  }

  // The distance along `direction` (world frame) from `origin` to the plane of triangle
  // `triangle`, in units of `direction`: with direction R (x, y, 1), the planar depth z of
  // the hit in the camera. NaN when the ray runs parallel to the plane.
  double PlanarDepthOnTriangle(uint32_t triangle, const Eigen::Vector3d& direction,
                               const Eigen::Vector3d& origin) const {
    const uint32_t* corner = triangles + 3 * static_cast<size_t>(triangle);
    auto vertex = [&](int k) {
      const float* p = vertices + 3 * static_cast<size_t>(corner[k]);
      return Eigen::Vector3d(p[0], p[1], p[2]);
    };
    const Eigen::Vector3d a = vertex(0);
    const Eigen::Vector3d normal = (vertex(1) - a).cross(vertex(2) - a);
    const double along = normal.dot(direction);
    if (along == 0.0) return std::numeric_limits<double>::quiet_NaN();
    return normal.dot(a - origin) / along;
  }

  // Casts the rays of every pixel. DirectionFn(u, v, &x, &y) gives the ray's normalised
  // direction (x, y, 1) in camera coordinates, or false where the pixel has no ray.
  template <typename DirectionFn>
  RenderedDepth Cast(int width, int height, const Rigid3d& world_from_cam,
                     const RenderOptions& options, const DirectionFn& direction) const;
};

MeshRenderer::MeshRenderer(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  const size_t nv = mesh.NumVertices();
  const size_t nt = mesh.NumTriangles();
  if (mesh.vertices_m.size() != nv * 3 || mesh.triangles.size() != nt * 3) {
    throw InputError("mesh", "vertex or triangle array size is not a multiple of 3");
  }
  for (uint32_t index : mesh.triangles) {
    if (index >= nv) {
      throw InputError("mesh", "vertex index " + std::to_string(index) + " outside [0, " +
                                   std::to_string(nv) + ")");
    }
  }
  for (float x : mesh.vertices_m) {
    if (!std::isfinite(x)) throw InputError("mesh", "non-finite vertex coordinate");
  }
  impl_->num_triangles = nt;
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(impl_->device, ErrorFunction, &impl_->error);
  rtcSetDeviceMemoryMonitorFunction(impl_->device, MemoryMonitor, &impl_->embree_bytes);
  impl_->scene = rtcNewScene(impl_->device);
  // Robust traversal: watertight, so that a ray through a shared edge or vertex of two
  // triangles cannot slip between them.
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  if (nt > 0) {
    RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), nt));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geometry);
      impl_->ThrowIfError("buffers");
      throw std::runtime_error("Embree: cannot allocate the mesh buffers");
    }
    std::copy(mesh.vertices_m.begin(), mesh.vertices_m.end(), vertices);
    std::copy(mesh.triangles.begin(), mesh.triangles.end(), indices);
    impl_->vertices = vertices;
    impl_->triangles = indices;
    rtcSetGeometryMask(geometry, 0xFFFFFFFFu);
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(impl_->scene, geometry, 0);
    rtcReleaseGeometry(geometry);
  }
  // The BVH build runs TBB tasks with flush-to-zero and denormals-are-zero set, and the
  // setting stayed with the caller's arena: every later parallel loop of the caller ran
  // with it (core/depth.h). In an arena of its own, it stays there.
  tbb::task_arena build_arena;
  build_arena.execute([&] { rtcCommitScene(impl_->scene); });
  impl_->ThrowIfError("BVH build");
}

MeshRenderer::~MeshRenderer() = default;

size_t MeshRenderer::NumTriangles() const { return impl_->num_triangles; }

size_t MeshRenderer::EmbreeBytes() const {
  return static_cast<size_t>(std::max<int64_t>(0, impl_->embree_bytes.load()));
}

template <typename DirectionFn>
RenderedDepth MeshRenderer::Impl::Cast(int width, int height, const Rigid3d& world_from_cam,
                                       const RenderOptions& options,
                                       const DirectionFn& direction) const {
  RenderedDepth out;
  out.depth_m = cv::Mat1f(height, width, 0.0f);
  if (options.triangle_ids) out.triangle_id = cv::Mat1i(height, width, -1);
  const Eigen::Matrix3d rotation = world_from_cam.linear();
  const Eigen::Vector3d origin = world_from_cam.translation();
  const float far = static_cast<float>(options.far_m);
  const double near = options.near_m;
  const int tiles_x = (width + kTile - 1) / kTile;
  const int tiles_y = (height + kTile - 1) / kTile;

  // One ray in Embree's layout: origin at the camera centre, direction d = R (x, y, 1), so
  // that the hit distance tfar is the planar depth z.
  auto make_ray = [&](RTCRayHit* rh, const Eigen::Vector3d& d) {
    RTCRay& ray = rh->ray;
    ray.org_x = static_cast<float>(origin.x());
    ray.org_y = static_cast<float>(origin.y());
    ray.org_z = static_cast<float>(origin.z());
    ray.dir_x = static_cast<float>(d.x());
    ray.dir_y = static_cast<float>(d.y());
    ray.dir_z = static_cast<float>(d.z());
    ray.tnear = 0.0f;
    ray.tfar = far;
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;  // Debian's Embree is built with ray masks: an unset mask hits nothing
    ray.id = 0;
    ray.flags = 0;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  };
  // Embree decides which triangle a ray hits; the depth is that triangle's plane along the
  // ray, computed here in double from the triangle's corners and the ray (x, y, 1): Embree's
  // own distance comes from kernels chosen by the CPU's instruction set (SSE, AVX2,
  // AVX-512), whose float results differ in the last bits, so that a build with mesh depth
  // differed between machines (docs/GROUND_TRUTH.md "Depth sources").
  auto store = [&](const RTCRayHit& rh, int u, int v, const Eigen::Vector3d& d) {
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
    const double t = PlanarDepthOnTriangle(rh.hit.primID, d, origin);
    if (!(t >= near) || !(t <= options.far_m)) return;
    out.depth_m(v, u) = static_cast<float>(t);
    if (options.triangle_ids) out.triangle_id(v, u) = static_cast<int>(rh.hit.primID);
  };

  if (!scene || num_triangles == 0) return out;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, tiles_x * tiles_y), [&](const tbb::blocked_range<int>& r) {
        alignas(64) RTCRayHit rays[kTile * kTile];
        int pixel_u[kTile * kTile], pixel_v[kTile * kTile];
        Eigen::Vector3d direction_of[kTile * kTile];  // each ray's d, in double
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        if (options.batching == RayBatching::kCoherent)
          context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        for (int tile = r.begin(); tile != r.end(); ++tile) {
          const int u0 = (tile % tiles_x) * kTile, v0 = (tile / tiles_x) * kTile;
          int n = 0;
          for (int v = v0; v < std::min(v0 + kTile, height); ++v) {
            for (int u = u0; u < std::min(u0 + kTile, width); ++u) {
              double x = 0, y = 0;
              if (!direction(u, v, &x, &y)) continue;
              direction_of[n] = rotation * Eigen::Vector3d(x, y, 1.0);
              make_ray(&rays[n], direction_of[n]);
              pixel_u[n] = u;
              pixel_v[n] = v;
              ++n;
            }
          }
          if (options.batching == RayBatching::kCoherent) {
            rtcIntersect1M(scene, &context, rays, static_cast<unsigned>(n), sizeof(RTCRayHit));
          } else {
            for (int i = 0; i < n; ++i) rtcIntersect1(scene, &context, &rays[i]);
          }
          for (int i = 0; i < n; ++i) store(rays[i], pixel_u[i], pixel_v[i], direction_of[i]);
        }
      });
  return out;
}

namespace {
void CheckRenderInputs(const Rigid3d& world_from_cam, const RenderOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("render options", error);
  if (!world_from_cam.matrix().allFinite()) throw InputError("world_from_cam", "non-finite pose");
}
}  // namespace

RenderedDepth MeshRenderer::Render(const Camera& camera, const Rigid3d& world_from_cam,
                                   const RenderOptions& options) const {
  std::string error;
  if (!camera.Check(&error)) throw InputError("camera", error);
  CheckRenderInputs(world_from_cam, options);
  const double fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
  return impl_->Cast(camera.width, camera.height, world_from_cam, options,
                     [&](int u, int v, double* x, double* y) {
                       *x = (u - cx) / fx;
                       *y = (v - cy) / fy;
                       return true;
                     });
}

RenderedDepth MeshRenderer::Render(const LensCamera& camera, const Rigid3d& world_from_cam,
                                   const RenderOptions& options) const {
  std::string error;
  if (!camera.Check(&error)) throw InputError("camera", error);
  if (camera.model == LensModel::kPinhole) return Render(camera.pinhole, world_from_cam, options);
  CheckRenderInputs(world_from_cam, options);
  const int width = camera.pinhole.width, height = camera.pinhole.height;
  // The rays of every pixel first (the inverse of the distortion is iterative), NaN where a
  // pixel has none.
  std::vector<double> rays(static_cast<size_t>(width) * height * 2);
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v != r.end(); ++v) {
      for (int u = 0; u < width; ++u) {
        const auto xy = UndistortPixel(camera, u, v);
        double* out = &rays[(static_cast<size_t>(v) * width + u) * 2];
        out[0] = xy ? xy->x() : std::numeric_limits<double>::quiet_NaN();
        out[1] = xy ? xy->y() : std::numeric_limits<double>::quiet_NaN();
      }
    }
  });
  return impl_->Cast(width, height, world_from_cam, options,
                     [&](int u, int v, double* x, double* y) {
                       const double* in = &rays[(static_cast<size_t>(v) * width + u) * 2];
                       *x = in[0];
                       *y = in[1];
                       return std::isfinite(in[0]) && std::isfinite(in[1]);
                     });
}

}  // namespace gt::render

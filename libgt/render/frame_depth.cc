#include "libgt/render/frame_depth.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <mutex>

#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"

namespace gt::render {

const char* DepthSourceModeName(DepthSourceMode mode) {
  switch (mode) {
    case DepthSourceMode::kSensor:
      return "sensor";
    case DepthSourceMode::kMesh:
      return "mesh";
    case DepthSourceMode::kFused:
      return "fused";
  }
  return "?";
}

DepthSourceMode ParseDepthSourceMode(std::string_view name, const std::string& field) {
  for (DepthSourceMode m :
       {DepthSourceMode::kSensor, DepthSourceMode::kMesh, DepthSourceMode::kFused}) {
    if (name == DepthSourceModeName(m)) return m;
  }
  throw InputError(
      field, "unknown depth source '" + std::string(name) + "', expected sensor, mesh or fused");
}

bool FusedDepthOptions::Check(std::string* error) const {
  // Each message names its field first (the CLI names the flag from it).
  for (const auto& [name, value] : {std::pair<const char*, double>{"abs_tol_m", abs_tol_m},
                                    std::pair<const char*, double>{"rel_tol", rel_tol}}) {
    if (!std::isfinite(value) || value < 0) {
      *error = std::string(name) + ": expected a finite number >= 0 (fused depth), got " +
               std::to_string(value);
      return false;
    }
  }
  return true;
}

bool FrameDepthOptions::Check(std::string* error) const {
  if (!fused.Check(error)) return false;
  RenderOptions render;
  render.near_m = near_m;
  render.far_m = far_m;
  return render.Check(error);
}

DepthAgreement& DepthAgreement::operator+=(const DepthAgreement& o) {
  sensor_only += o.sensor_only;
  mesh_only += o.mesh_only;
  agree += o.agree;
  disagree += o.disagree;
  neither += o.neither;
  return *this;
}

namespace {

// The class of one pixel: 0 neither, 1 sensor only, 2 mesh only, 3 agree, 4 disagree.
inline int Classify(float s, float m, double min_depth_m, double max_depth_m,
                    const FusedDepthOptions& o) {
  const bool has_s = IsValidDepth(s, min_depth_m, max_depth_m);
  const bool has_m = m > 0 && std::isfinite(m);
  if (!has_s) return has_m ? 2 : 0;
  if (!has_m) return 1;
  return std::abs(static_cast<double>(s) - m) <= o.abs_tol_m + o.rel_tol * m ? 3 : 4;
}

void CheckSameSize(const DepthImage& sensor, const DepthImage& mesh) {
  GT_ASSERT_MSG(sensor.width == mesh.width && sensor.height == mesh.height,
                "sensor and rendered depth of different sizes");
}

void Count(int c, DepthAgreement* a) {
  switch (c) {
    case 0:
      ++a->neither;
      break;
    case 1:
      ++a->sensor_only;
      break;
    case 2:
      ++a->mesh_only;
      break;
    case 3:
      ++a->agree;
      break;
    default:
      ++a->disagree;
      break;
  }
}

}  // namespace

DepthImage FuseSensorAndMesh(const DepthImage& sensor, const DepthImage& mesh, double min_depth_m,
                             double max_depth_m, const FusedDepthOptions& options,
                             DepthAgreement* agreement) {
  CheckSameSize(sensor, mesh);
  DepthImage fused(sensor.width, sensor.height, 0.0f);
  DepthAgreement counts;
  for (size_t i = 0; i < sensor.values_m.size(); ++i) {
    const float s = sensor.values_m[i], m = mesh.values_m[i];
    const int c = Classify(s, m, min_depth_m, max_depth_m, options);
    Count(c, &counts);
    // Sensor only: kept (the mesh may miss a surface the sensor sees, e.g. a thin object or
    // one added after the scan).
    fused.values_m[i] = c == 1 || c == 3 ? s : c == 2 ? m : 0.0f;
  }
  if (agreement) *agreement += counts;
  return fused;
}

DepthAgreement CompareSensorAndMesh(const DepthImage& sensor, const DepthImage& mesh,
                                    double min_depth_m, double max_depth_m,
                                    const FusedDepthOptions& options) {
  CheckSameSize(sensor, mesh);
  DepthAgreement counts;
  for (size_t i = 0; i < sensor.values_m.size(); ++i) {
    Count(Classify(sensor.values_m[i], mesh.values_m[i], min_depth_m, max_depth_m, options),
          &counts);
  }
  return counts;
}

std::shared_ptr<const MeshRenderer> SharedMeshRenderer(const std::string& path) {
  // One entry per path, built once under the entry's own flag (outside the map's lock). The
  // map holds entries weakly; the kKeep most recently asked-for meshes are also held
  // strongly, so that the frames of a scene reuse its BVH while a build over thousands of
  // scenes does not keep every one.
  constexpr size_t kKeep = 4;
  struct Entry {
    std::once_flag once;
    std::shared_ptr<const MeshRenderer> renderer;
  };
  static std::mutex mutex;
  static std::map<std::string, std::weak_ptr<Entry>> cache;
  static std::deque<std::shared_ptr<Entry>> recent;
  std::shared_ptr<Entry> entry;
  {
    std::lock_guard<std::mutex> lock(mutex);
    entry = cache[path].lock();
    if (!entry) {
      entry = std::make_shared<Entry>();
      cache[path] = entry;
    }
    const auto it = std::find(recent.begin(), recent.end(), entry);
    if (it != recent.end()) recent.erase(it);
    recent.push_front(entry);
    if (recent.size() > kKeep) recent.pop_back();
    for (auto c = cache.begin(); c != cache.end();)
      c = c->second.expired() ? cache.erase(c) : std::next(c);
  }
  std::call_once(entry->once, [&] {
    entry->renderer = std::make_shared<const MeshRenderer>(ReadPlyMesh(path));
  });
  if (!entry->renderer)
    throw InputError(path, "the mesh could not be read before (see the first error)");
  return entry->renderer;
}

DepthImage RenderFrameDepth(const Scene& scene, const Frame& frame, const Camera& camera,
                            const FrameDepthOptions& options) {
  if (scene.mesh_path.empty()) {
    throw InputError(scene.name, "depth source '" +
                                     std::string(DepthSourceModeName(options.source)) +
                                     "' needs a mesh, and the scene has none" +
                                     scene.MissingMeshNote() + " (dataset.mesh_path)");
  }
  const auto renderer = SharedMeshRenderer(scene.mesh_path);
  RenderOptions render;
  render.near_m = options.near_m;
  render.far_m = options.far_m;
  const RenderedDepth rendered = renderer->Render(camera, frame.world_from_cam, render);
  DepthImage depth(camera.width, camera.height);
  depth.values_m.assign(rendered.depth_m.begin(), rendered.depth_m.end());
  io::ApplyFrameMask(frame, &depth);  // anonymised pixels (ScanNet++) have no depth
  return depth;
}

DepthImage LoadFrameDepth(const Scene& scene, const Frame& frame, const Camera& camera,
                          const FrameDepthOptions& options, DepthAgreement* agreement,
                          const DepthImage* sensor) {
  std::string error;
  if (!options.Check(&error)) throw InputError("depth source", error);
  auto read_sensor = [&] {
    if (sensor) return *sensor;
    // A frame without a depth file (ScanNet++ DSLR) has no sensor depth anywhere.
    if (frame.depth.path.empty()) return DepthImage(camera.width, camera.height);
    // Undistorted and masked as the frame says (io::ReadFrameDepth).
    DepthImage full = io::ReadFrameDepth(frame);
    if (full.width == camera.width && full.height == camera.height) return full;
    return ResizeDepthNearest(full, camera.width, camera.height);
  };
  switch (options.source) {
    case DepthSourceMode::kSensor:
      return read_sensor();
    case DepthSourceMode::kMesh: {
      DepthImage mesh = RenderFrameDepth(scene, frame, camera, options);
      if (agreement) {
        *agreement += CompareSensorAndMesh(read_sensor(), mesh, scene.min_depth_m,
                                           scene.max_depth_m, options.fused);
      }
      return mesh;
    }
    case DepthSourceMode::kFused:
      return FuseSensorAndMesh(read_sensor(), RenderFrameDepth(scene, frame, camera, options),
                               scene.min_depth_m, scene.max_depth_m, options.fused, agreement);
  }
  return {};
}

}  // namespace gt::render

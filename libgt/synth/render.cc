// Ray casting and shading of synthetic rooms (render.h).
#include "libgt/synth/render.h"

#include <algorithm>
#include <cmath>

#include "libgt/synth/random.h"

namespace gt::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMinT = 1e-9;

// Object in its own frame, precomputed once per render.
struct LocalBox {
  Eigen::Vector3d center;
  Eigen::Vector3d half;
  double c = 1.0, s = 0.0;  // cos / sin of yaw
};

LocalBox MakeLocal(const OrientedBox& b) {
  return {b.center_in_world, b.half_size_m, std::cos(b.yaw_rad), std::sin(b.yaw_rad)};
}

// box_from_world rotation (Rz(-yaw)) applied to a vector.
inline Eigen::Vector3d ToBox(const LocalBox& b, const Eigen::Vector3d& v) {
  return Eigen::Vector3d(b.c * v.x() + b.s * v.y(), -b.s * v.x() + b.c * v.y(), v.z());
}
inline Eigen::Vector3d FromBox(const LocalBox& b, const Eigen::Vector3d& v) {
  return Eigen::Vector3d(b.c * v.x() - b.s * v.y(), b.s * v.x() + b.c * v.y(), v.z());
}

// Entry of a ray (o, d in the box frame) into the box [-h, h]^3 from outside: t of entry
// and the entry axis, or t = inf when it misses or starts inside.
inline double EnterBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& h,
                       int* axis) {
  double t_near = -kInf, t_far = kInf;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      if (o[i] < -h[i] || o[i] > h[i]) return kInf;
      continue;
    }
    const double inv = 1.0 / d[i];
    double t0 = (-h[i] - o[i]) * inv, t1 = (h[i] - o[i]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      *axis = i;
    }
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return kInf;
  }
  return t_near > kMinT ? t_near : kInf;
}

// Texture coordinates on a face whose normal is along `axis`: the two other coordinates.
inline Eigen::Vector2d FaceUv(const Eigen::Vector3d& p, int axis) {
  switch (axis) {
    case 0:
      return {p.y(), p.z()};
    case 1:
      return {p.x(), p.z()};
    default:
      return {p.x(), p.y()};
  }
}

RayHit CastWithLocal(const SynthScene& scene, const std::vector<LocalBox>& boxes,
                     const std::vector<Eigen::Vector3d>& origins_in_box, const Eigen::Vector3d& o,
                     const Eigen::Vector3d& d) {
  RayHit best;
  // Room, seen from inside: the exit through the nearest face.
  const Eigen::Vector3d& size = scene.room_size_m;
  bool inside = true;
  for (int i = 0; i < 3; ++i) inside = inside && o[i] > 0.0 && o[i] < size[i];
  if (inside) {
    for (int i = 0; i < 3; ++i) {
      if (d[i] == 0.0) continue;
      const double t = d[i] > 0.0 ? (size[i] - o[i]) / d[i] : -o[i] / d[i];
      if (t < best.t) {
        best.t = t;
        best.surface_id = 2 * i + (d[i] > 0.0 ? 1 : 0);
        best.normal_in_world = Eigen::Vector3d::Zero();
        best.normal_in_world[i] = d[i] > 0.0 ? -1.0 : 1.0;
      }
    }
    if (best.hit()) best.uv_m = FaceUv(o + best.t * d, best.surface_id / 2);
  }
  for (size_t k = 0; k < boxes.size(); ++k) {
    const LocalBox& b = boxes[k];
    const Eigen::Vector3d d_b = ToBox(b, d);
    int axis = 0;
    const double t = EnterBox(origins_in_box[k], d_b, b.half, &axis);
    if (t < best.t) {
      best.t = t;
      best.surface_id = kFirstObjectId + static_cast<int>(k);
      Eigen::Vector3d n_b = Eigen::Vector3d::Zero();
      n_b[axis] = d_b[axis] > 0.0 ? -1.0 : 1.0;
      best.normal_in_world = FromBox(b, n_b);
      best.uv_m = FaceUv(origins_in_box[k] + t * d_b + b.half, axis);
    }
  }
  return best;
}

// Value noise in [0, 1]: a hash per integer lattice point, smoothstep-interpolated.
double LatticeValue(int64_t x, int64_t y, uint64_t seed) {
  const uint64_t h = Mix64(
      seed ^ Mix64(static_cast<uint64_t>(x) * 0x9e3779b1ull ^ (static_cast<uint64_t>(y) << 32)));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}
double ValueNoise(double x, double y, uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  const double a = LatticeValue(ix, iy, seed), b = LatticeValue(ix + 1, iy, seed);
  const double c = LatticeValue(ix, iy + 1, seed), e = LatticeValue(ix + 1, iy + 1, seed);
  return (a + (b - a) * tx) + ((c + (e - c) * tx) - (a + (b - a) * tx)) * ty;
}

const Material& MaterialOf(const SynthScene& scene, int surface_id) {
  return surface_id < kFirstObjectId ? scene.room_materials[surface_id]
                                     : scene.objects[surface_id - kFirstObjectId].material;
}

}  // namespace

RayHit CastRay(const SynthScene& scene, const Eigen::Vector3d& origin_in_world,
               const Eigen::Vector3d& direction_in_world) {
  std::vector<LocalBox> boxes;
  std::vector<Eigen::Vector3d> origins;
  for (const auto& b : scene.objects) {
    boxes.push_back(MakeLocal(b));
    origins.push_back(ToBox(boxes.back(), origin_in_world - b.center_in_world));
  }
  return CastWithLocal(scene, boxes, origins, origin_in_world, direction_in_world);
}

Eigen::Vector3d ShadeHit(const SynthScene& scene, const Eigen::Vector3d& p_in_world,
                         const RayHit& hit) {
  const Material& m = MaterialOf(scene, hit.surface_id);
  const double u = hit.uv_m.x() / m.scale_m, v = hit.uv_m.y() / m.scale_m;
  double pattern = 0.5;
  switch (m.pattern) {
    case Pattern::kChecker:
      pattern = ((static_cast<int64_t>(std::floor(u)) + static_cast<int64_t>(std::floor(v))) & 1)
                    ? 1.0
                    : 0.0;
      break;
    case Pattern::kStripes:
      pattern = (static_cast<int64_t>(std::floor(u)) & 1) ? 1.0 : 0.0;
      break;
    case Pattern::kNoise:
      pattern = ValueNoise(u, v, m.noise_seed);
      break;
  }
  // Fine noise everywhere (periods scale/4 and a fixed 2.5 cm) so that every patch has
  // texture, as real surfaces do for a matcher.
  const double fine =
      0.5 * ValueNoise(4.0 * u, 4.0 * v, m.noise_seed + 1) +
      0.5 * ValueNoise(hit.uv_m.x() / 0.025, hit.uv_m.y() / 0.025, m.noise_seed + 2);
  const double texture = (1.0 - m.contrast) + m.contrast * (0.5 * pattern + 0.5 * fine);
  const Eigen::Vector3d to_light = scene.light_in_world - p_in_world;
  const double dist2 = std::max(to_light.squaredNorm(), 1e-6);
  const double lambert = std::max(0.0, hit.normal_in_world.dot(to_light) / std::sqrt(dist2));
  const double light = 0.3 + 0.9 * lambert * (9.0 / (9.0 + dist2));
  return (m.albedo_rgb * (texture * light)).cwiseMax(0.0).cwiseMin(1.0);
}

RenderedView RenderView(const SynthScene& scene, const Camera& camera,
                        const Rigid3d& world_from_cam) {
  RenderedView view;
  const int w = camera.width, h = camera.height;
  view.depth = DepthImage(w, h, 0.0f);
  view.color.width = w;
  view.color.height = h;
  view.color.rgb.assign(static_cast<size_t>(w) * h * 3, 0);
  view.surface_ids.assign(static_cast<size_t>(w) * h, kNoSurface);

  const Eigen::Matrix3d R = world_from_cam.linear();
  const Eigen::Vector3d o = world_from_cam.translation();
  std::vector<LocalBox> boxes;
  std::vector<Eigen::Vector3d> origins;
  for (const auto& b : scene.objects) {
    boxes.push_back(MakeLocal(b));
    origins.push_back(ToBox(boxes.back(), o - b.center_in_world));
  }
  for (int v = 0; v < h; ++v) {
    const double y = (v - camera.cy) / camera.fy;
    for (int u = 0; u < w; ++u) {
      const double x = (u - camera.cx) / camera.fx;
      const Eigen::Vector3d d = R * Eigen::Vector3d(x, y, 1.0);
      const RayHit hit = CastWithLocal(scene, boxes, origins, o, d);
      const size_t i = static_cast<size_t>(v) * w + u;
      if (!hit.hit()) continue;
      view.depth.values_m[i] = static_cast<float>(hit.t);
      view.surface_ids[i] = hit.surface_id;
      const Eigen::Vector3d rgb = ShadeHit(scene, o + hit.t * d, hit);
      for (int c = 0; c < 3; ++c) {
        view.color.rgb[3 * i + c] = static_cast<uint8_t>(std::lround(255.0 * rgb[c]));
      }
    }
  }
  return view;
}

DepthImage RenderDepth(const SynthScene& scene, const Camera& camera,
                       const Rigid3d& world_from_cam) {
  return RenderView(scene, camera, world_from_cam).depth;
}

io::ColorImage RenderColor(const SynthScene& scene, const Camera& camera,
                           const Rigid3d& world_from_cam) {
  return RenderView(scene, camera, world_from_cam).color;
}

}  // namespace gt::synth

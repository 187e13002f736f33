// Seeded room generator (scene.h).
#include "libgt/synth/scene.h"

#include <cmath>

#include "libgt/synth/random.h"

namespace gt::synth {
namespace {

Material RandomMaterial(SplitMix64& rng, double lo, double hi, double min_scale_m,
                        double max_scale_m) {
  Material m;
  m.albedo_rgb = Eigen::Vector3d(rng.Uniform(lo, hi), rng.Uniform(lo, hi), rng.Uniform(lo, hi));
  const int p = rng.Int(0, 2);
  m.pattern = p == 0 ? Pattern::kChecker : (p == 1 ? Pattern::kStripes : Pattern::kNoise);
  m.scale_m = rng.Uniform(min_scale_m, max_scale_m);
  m.contrast = rng.Uniform(0.45, 0.75);
  m.noise_seed = rng.Next();
  return m;
}

// Radius in the xy plane of a circle holding the box footprint.
double FootprintRadius(const OrientedBox& b) {
  return std::hypot(b.half_size_m.x(), b.half_size_m.y());
}

// True when the footprint circle stays inside the room (with `margin_m`), outside the
// grown walk ellipse, and apart from every placed object.
bool Fits(const SynthScene& scene, const OrientedBox& b, const RoomOptions& o, double margin_m) {
  const double r = FootprintRadius(b);
  const Eigen::Vector3d& c = b.center_in_world;
  // Exact footprint extent along x and y for the wall test (a yawed rectangle).
  const double cy = std::abs(std::cos(b.yaw_rad)), sy = std::abs(std::sin(b.yaw_rad));
  const double ex = cy * b.half_size_m.x() + sy * b.half_size_m.y();
  const double ey = sy * b.half_size_m.x() + cy * b.half_size_m.y();
  if (c.x() - ex < margin_m || c.x() + ex > scene.room_size_m.x() - margin_m) return false;
  if (c.y() - ey < margin_m || c.y() + ey > scene.room_size_m.y() - margin_m) return false;
  const double ax = scene.walk_semi_axes_m.x() + o.walk_clearance_m + r;
  const double ay = scene.walk_semi_axes_m.y() + o.walk_clearance_m + r;
  const double dx = (c.x() - scene.walk_center_xy.x()) / ax;
  const double dy = (c.y() - scene.walk_center_xy.y()) / ay;
  if (dx * dx + dy * dy < 1.0) return false;
  for (const auto& other : scene.objects) {
    const double d =
        std::hypot(c.x() - other.center_in_world.x(), c.y() - other.center_in_world.y());
    if (d < r + FootprintRadius(other) + 0.05) return false;
  }
  return true;
}

// A point at distance `offset_m` in front of a random wall, somewhere along it; returns the
// wall-normal axis (0 for walls x = const, 1 for y = const).
int PointInFrontOfWall(SplitMix64& rng, const SynthScene& scene, double offset_m,
                       Eigen::Vector2d* xy) {
  const int wall = rng.Int(0, 3);
  const double sx = scene.room_size_m.x(), sy = scene.room_size_m.y();
  if (wall < 2) {
    const double along = rng.Uniform(0.6, sy - 0.6);
    *xy = Eigen::Vector2d(wall == 0 ? offset_m : sx - offset_m, along);
    return 0;
  }
  const double along = rng.Uniform(0.6, sx - 0.6);
  *xy = Eigen::Vector2d(along, wall == 2 ? offset_m : sy - offset_m);
  return 1;
}

}  // namespace

bool RoomOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error != nullptr) *error = m;
    return false;
  };
  if (!(min_room_size_m >= 4.0 && max_room_size_m >= min_room_size_m && max_room_size_m <= 50))
    return fail("room size: expected 4 <= min_room_size_m <= max_room_size_m <= 50");
  if (!(min_height_m >= 2.0 && max_height_m >= min_height_m && max_height_m <= 20))
    return fail("room height: expected 2 <= min_height_m <= max_height_m <= 20");
  if (min_boxes < 0 || max_boxes < min_boxes || min_poles < 0 || max_poles < min_poles ||
      min_panels < 0 || max_panels < min_panels || max_boxes + max_poles + max_panels > 100)
    return fail("object counts: expected 0 <= min <= max and at most 100 objects");
  if (!(walk_fraction > 0.0 && walk_fraction <= 0.3))
    return fail("walk_fraction: expected (0, 0.3]");
  if (!(walk_clearance_m >= 0.3 && walk_clearance_m <= 2.0))
    return fail("walk_clearance_m: expected [0.3, 2]");
  return true;
}

SynthScene MakeRoomScene(uint64_t seed, const RoomOptions& o) {
  SplitMix64 rng(Mix64(seed));
  SynthScene scene;
  scene.room_size_m = Eigen::Vector3d(rng.Uniform(o.min_room_size_m, o.max_room_size_m),
                                      rng.Uniform(o.min_room_size_m, o.max_room_size_m),
                                      rng.Uniform(o.min_height_m, o.max_height_m));
  const Eigen::Vector3d& size = scene.room_size_m;
  for (int f = 0; f < 6; ++f) {
    // Pale walls and ceiling, a darker floor; large patterns on the room surfaces.
    scene.room_materials[f] = f == kFloor ? RandomMaterial(rng, 0.25, 0.6, 0.3, 0.6)
                                          : RandomMaterial(rng, 0.5, 0.9, 0.2, 0.7);
  }
  scene.light_in_world = Eigen::Vector3d(rng.Uniform(0.35, 0.65) * size.x(),
                                         rng.Uniform(0.35, 0.65) * size.y(), size.z() - 0.3);
  scene.walk_center_xy = Eigen::Vector2d(0.5 * size.x(), 0.5 * size.y());
  scene.walk_semi_axes_m = o.walk_fraction * size.head<2>();
  scene.eye_height_m = rng.Uniform(1.3, 1.6);
  scene.walk_phase_rad = rng.Uniform(0.0, 2.0 * kPi);

  constexpr int kTries = 200;
  const int n_boxes = rng.Int(o.min_boxes, o.max_boxes);
  for (int i = 0; i < n_boxes; ++i) {
    for (int t = 0; t < kTries; ++t) {
      OrientedBox b;
      b.kind = ObjectKind::kBox;
      b.half_size_m =
          Eigen::Vector3d(rng.Uniform(0.15, 0.45), rng.Uniform(0.15, 0.45), rng.Uniform(0.15, 0.6));
      b.yaw_rad = rng.Coin() ? 0.0 : rng.Uniform(0.0, 0.5 * kPi);
      b.center_in_world = Eigen::Vector3d(rng.Uniform(0.0, size.x()), rng.Uniform(0.0, size.y()),
                                          b.half_size_m.z());
      b.material = RandomMaterial(rng, 0.15, 0.95, 0.05, 0.2);
      if (Fits(scene, b, o, 0.1)) {
        scene.objects.push_back(b);
        break;
      }
    }
  }
  const int n_poles = rng.Int(o.min_poles, o.max_poles);
  for (int i = 0; i < n_poles; ++i) {
    for (int t = 0; t < kTries; ++t) {
      OrientedBox b;
      b.kind = ObjectKind::kPole;
      const double half_width = rng.Uniform(0.04, 0.07);
      b.half_size_m = Eigen::Vector3d(half_width, half_width, 0.5 * size.z() - 0.001);
      Eigen::Vector2d xy;
      PointInFrontOfWall(rng, scene, rng.Uniform(0.35, 0.9), &xy);
      b.center_in_world = Eigen::Vector3d(xy.x(), xy.y(), 0.5 * size.z());
      b.material = RandomMaterial(rng, 0.1, 0.9, 0.04, 0.1);
      if (Fits(scene, b, o, 0.1)) {
        scene.objects.push_back(b);
        break;
      }
    }
  }
  const int n_panels = rng.Int(o.min_panels, o.max_panels);
  for (int i = 0; i < n_panels; ++i) {
    for (int t = 0; t < kTries; ++t) {
      OrientedBox b;
      b.kind = ObjectKind::kPanel;
      const double half_width = rng.Uniform(0.25, 0.6), half_height = rng.Uniform(0.5, 0.9);
      const double bottom = rng.Uniform(0.0, 0.4);
      Eigen::Vector2d xy;
      const int axis = PointInFrontOfWall(rng, scene, rng.Uniform(0.3, 0.7), &xy);
      // Thin along the wall normal.
      b.half_size_m = axis == 0 ? Eigen::Vector3d(0.015, half_width, half_height)
                                : Eigen::Vector3d(half_width, 0.015, half_height);
      b.center_in_world = Eigen::Vector3d(xy.x(), xy.y(), bottom + half_height);
      b.material = RandomMaterial(rng, 0.2, 0.95, 0.05, 0.15);
      if (Fits(scene, b, o, 0.1)) {
        scene.objects.push_back(b);
        break;
      }
    }
  }
  return scene;
}

}  // namespace gt::synth

// Procedural indoor scenes for the synthetic dataset (docs/SYNTH.md): plain data describing
// a closed room and the objects standing in it, plus the seeded generator MakeRoomScene.
//
// World frame: metres, z up (gravity along -z). The room is the axis-aligned box
// [0, size.x] x [0, size.y] x [0, size.z]; the floor is z = 0. Every object is an oriented
// box: a centre, half extents along its own axes, and a yaw (rotation about +z), so that
// p_in_world = center + Rz(yaw) * p_in_box. Poles and panels are thin boxes placed in
// front of the walls so that nearby views occlude different parts of the walls.
// Colours are linear RGB albedos in [0, 1].
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace gt::synth {

inline constexpr double kPi = 3.14159265358979323846;

enum class Pattern {
  kChecker,  // squares of side scale_m
  kStripes,  // stripes of width scale_m along the surface's first axis
  kNoise,    // value noise only
};

// Surface appearance; texture coordinates are in metres on the surface, so a pattern is
// the same in every view (what a matcher needs).
struct Material {
  Eigen::Vector3d albedo_rgb = Eigen::Vector3d::Constant(0.7);  // linear, [0, 1]
  Pattern pattern = Pattern::kChecker;
  double scale_m = 0.25;    // pattern period (metres)
  double contrast = 0.35;   // [0, 1]: 0 = flat colour
  uint64_t noise_seed = 0;  // seed of the value-noise layer
};

enum class ObjectKind { kBox, kPole, kPanel };

struct OrientedBox {
  ObjectKind kind = ObjectKind::kBox;
  Eigen::Vector3d center_in_world = Eigen::Vector3d::Zero();  // metres
  Eigen::Vector3d half_size_m = Eigen::Vector3d::Constant(0.5);
  double yaw_rad = 0.0;  // about world +z
  Material material;
};

// Faces of the room, indexed as in SynthScene::room_materials.
enum RoomFace { kWallX0 = 0, kWallX1 = 1, kWallY0 = 2, kWallY1 = 3, kFloor = 4, kCeiling = 5 };

struct SynthScene {
  std::string name;
  Eigen::Vector3d room_size_m = Eigen::Vector3d(6.0, 5.0, 2.8);
  std::array<Material, 6> room_materials;  // by RoomFace
  std::vector<OrientedBox> objects;
  Eigen::Vector3d light_in_world = Eigen::Vector3d(3.0, 2.5, 2.5);  // point light
  // Where cameras may walk: an ellipse at eye height kept free of objects (Trajectory).
  Eigen::Vector2d walk_center_xy = Eigen::Vector2d(3.0, 2.5);
  Eigen::Vector2d walk_semi_axes_m = Eigen::Vector2d(0.9, 0.75);
  double eye_height_m = 1.4;
  double walk_phase_rad = 0.0;  // start angle on the ellipse
};

struct RoomOptions {
  double min_room_size_m = 5.0;  // x and y extents drawn in [min, max]
  double max_room_size_m = 7.0;
  double min_height_m = 2.6;  // ceiling height drawn in [min, max]
  double max_height_m = 3.0;
  int min_boxes = 4;  // boxes standing on the floor
  int max_boxes = 6;
  int min_poles = 2;  // floor-to-ceiling poles in front of walls
  int max_poles = 4;
  int min_panels = 1;  // thin standing panels parallel to a wall
  int max_panels = 3;
  double walk_fraction = 0.15;    // walk ellipse semi-axes = fraction * room extents
  double walk_clearance_m = 0.5;  // free space kept around the walk ellipse

  bool Check(std::string* error) const;
};

// A room with objects, entirely determined by `seed` (SplitMix64, portable). Objects never
// intersect each other, the walls, or the walk ellipse grown by walk_clearance_m.
SynthScene MakeRoomScene(uint64_t seed, const RoomOptions& options = {});

}  // namespace gt::synth

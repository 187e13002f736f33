// Closed-form meshes for the render tests and benchmarks: quads, boxes and tessellated
// spheres, with their exact depth along a ray.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <utility>

#include "libgt/render/mesh.h"

namespace gt::render::test {

inline uint32_t AddVertex(TriangleMesh* mesh, const Eigen::Vector3d& p) {
  mesh->vertices_m.push_back(static_cast<float>(p.x()));
  mesh->vertices_m.push_back(static_cast<float>(p.y()));
  mesh->vertices_m.push_back(static_cast<float>(p.z()));
  return static_cast<uint32_t>(mesh->NumVertices() - 1);
}

// The quad a, b, c, d (in order around it) as triangles (a, b, c), (a, c, d).
inline void AddQuad(TriangleMesh* mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                    const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const uint32_t ia = AddVertex(mesh, a), ib = AddVertex(mesh, b), ic = AddVertex(mesh, c),
                 id = AddVertex(mesh, d);
  for (uint32_t i : {ia, ib, ic, ia, ic, id}) mesh->triangles.push_back(i);
}

// The six faces of the box [lo, hi] (12 triangles; faces share vertices, as a closed mesh
// does). Face order: -x, +x, -y, +y, -z, +z (triangles 2f and 2f + 1).
inline void AddBox(TriangleMesh* mesh, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  uint32_t corner[8];
  for (int i = 0; i < 8; ++i) {
    corner[i] = AddVertex(mesh, Eigen::Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                                                i & 4 ? hi.z() : lo.z()));
  }
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                           {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& f : faces) {
    for (int k : {0, 1, 2, 0, 2, 3}) mesh->triangles.push_back(corner[f[k]]);
  }
}

// Distance along o + t d to the first face of box [lo, hi]: from outside the entry, from
// inside the exit; nullopt when the ray misses it.
inline std::optional<double> BoxDistance(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                         const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t_in = -INFINITY, t_out = INFINITY;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {
      if (o[i] < lo[i] || o[i] > hi[i]) return std::nullopt;
      continue;
    }
    double a = (lo[i] - o[i]) / d[i], b = (hi[i] - o[i]) / d[i];
    if (a > b) std::swap(a, b);
    t_in = std::max(t_in, a);
    t_out = std::min(t_out, b);
  }
  if (t_in > t_out || t_out <= 0) return std::nullopt;
  return t_in > 0 ? t_in : t_out;
}

// An icosahedron subdivided `levels` times, vertices projected onto the sphere (centre,
// radius_m): 20 * 4^levels triangles.
inline TriangleMesh IcoSphere(const Eigen::Vector3d& centre, double radius_m, int levels) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                    {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                    {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto middle = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<uint32_t>(v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& t : f) {
      const uint32_t a = middle(t[0], t[1]), b = middle(t[1], t[2]), c = middle(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  TriangleMesh mesh;
  for (const auto& p : v) AddVertex(&mesh, centre + radius_m * p);
  for (const auto& t : f) mesh.triangles.insert(mesh.triangles.end(), t.begin(), t.end());
  return mesh;
}

// Distance along o + t d (t > 0) to the sphere (centre, radius); nullopt when missed.
inline std::optional<double> SphereDistance(const Eigen::Vector3d& centre, double radius,
                                            const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d oc = o - centre;
  const double a = d.squaredNorm(), b = oc.dot(d), c = oc.squaredNorm() - radius * radius;
  const double disc = b * b - a * c;
  if (disc < 0) return std::nullopt;
  const double t = (-b - std::sqrt(disc)) / a;
  if (t <= 0) return std::nullopt;
  return t;
}

}  // namespace gt::render::test

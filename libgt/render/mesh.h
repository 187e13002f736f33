// Triangle meshes and the PLY reader (the meshes that depth is rendered from:
// ScanNet's <scene>_vh_clean_2.ply, ScanNet++'s scans/mesh_aligned_0.05.ply, occgt's TSDF
// meshes). Coordinates are in the mesh's own frame, metres (for a dataset: the frames' world
// frame, docs/GROUND_TRUTH.md "Depth sources").
//
// PLY (Turk's format, as written by MeshLab, Open3D, ScanNet and ScanNet++): `format ascii`,
// `binary_little_endian` or `binary_big_endian`, version 1.0. Read: element `vertex` with
// properties x, y, z of type float or double (other vertex properties - colours, normals,
// labels - are skipped), element `face` with a list property `vertex_indices` (or
// `vertex_index`) whose count type is an 8/16/32-bit integer and whose index type is int or
// uint (other face properties skipped). Faces of more than three vertices are split into a
// fan (0, i, i+1). Other elements are skipped. Every count is checked against the bytes the
// file has before anything is allocated; every index against the vertex count; every
// coordinate must be finite. Any problem is one InputError naming the file.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace gt::render {

struct TriangleMesh {
  // Vertex positions, row-major [num_vertices, 3] (x, y, z), metres, float32 (what the ray
  // caster stores; a double PLY is rounded once, ~1e-7 relative).
  std::vector<float> vertices_m;
  // Vertex indices, row-major [num_triangles, 3]; triangle t is the t-th triangle of the
  // file's faces after fan splitting (the id a render returns).
  std::vector<uint32_t> triangles;

  size_t NumVertices() const { return vertices_m.size() / 3; }
  size_t NumTriangles() const { return triangles.size() / 3; }
};

// The mesh of a PLY file (rules above). Throws InputError("<path>", "...") on any problem:
// unreadable, not a PLY, unsupported format or property type, no x/y/z or no face list, a
// count larger than the file's bytes allow, truncated data, an index out of range, a
// non-finite coordinate, no triangle at all (no face element: a point cloud; or no face in it).
TriangleMesh ReadPlyMesh(const std::string& path);

// The same from the file's bytes in memory; `where` names them in errors.
TriangleMesh ParsePlyMesh(std::string_view bytes, const std::string& where);

// The bytes of a binary little-endian PLY of the mesh (float x, y, z; faces
// `list uchar int vertex_indices`): for tests, benchmarks and synthetic scenes.
std::string EncodePlyMesh(const TriangleMesh& mesh);

}  // namespace gt::render

// PLY bytes -> gt::render::ParsePlyMesh (libgt/render/mesh.h): ASCII, binary little- and
// big-endian headers, vertex and face properties of every type, extra elements. A mesh that
// parses has every index below the vertex count and every coordinate finite, and it survives
// EncodePlyMesh -> ParsePlyMesh unchanged.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "libgt/render/mesh.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "mesh.ply";
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const gt::render::TriangleMesh mesh =
        gt::render::ParsePlyMesh(gt::fuzz::Bytes(data, size), name);
    if (mesh.vertices_m.size() % 3 != 0 || mesh.triangles.size() % 3 != 0) std::abort();
    for (const float x : mesh.vertices_m) {
      if (!std::isfinite(x)) std::abort();
    }
    for (const uint32_t i : mesh.triangles) {
      if (i >= mesh.NumVertices()) std::abort();
    }
    const gt::render::TriangleMesh again =
        gt::render::ParsePlyMesh(gt::render::EncodePlyMesh(mesh), "encoded");
    if (again.vertices_m != mesh.vertices_m || again.triangles != mesh.triangles) {
      std::fprintf(stderr, "EncodePlyMesh -> ParsePlyMesh changed the mesh\n");
      std::abort();
    }
  });
  return 0;
}

// PLY reader: every encoding (ASCII, binary little/big endian), float and double vertices,
// the face list types, extra properties and elements skipped, polygons split into fans,
// and bad files (truncated, wrong counts, bad property types, huge counts, bad indices)
// refused with one error naming the file. The shared TSDF mesh is read and its counts
// checked against its header, read here independently.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/render/mesh.h"
#include "tests/support/test_support.h"

namespace gt::render {
namespace {

// Binary values in either byte order.
template <typename T>
void Put(std::string* out, T value, bool big_endian) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));
  out->append(raw, sizeof(T));
}

// Two triangles sharing an edge, plus a quad: 6 vertices, 3 faces -> 4 triangles.
const double kVertices[6][3] = {{0, 0, 0}, {1, 0, 0},   {1, 1, 0},
                                {0, 1, 0}, {0, 0, 2.5}, {-1.25, 3, 7}};

std::string BinaryPly(bool big_endian, bool double_vertices) {
  std::string s =
      std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\ncomment made by a test\nelement vertex 6\n" +
      (double_vertices ? "property double x\nproperty double y\nproperty double z\n"
                       : "property float x\nproperty float y\nproperty float z\n") +
      "property uchar red\nproperty float nx\n"
      "element face 3\nproperty list int uint vertex_indices\nproperty uchar label\n"
      "element extra 2\nproperty list uchar float values\nproperty short s\nend_header\n";
  for (const auto& v : kVertices) {
    for (double c : v) {
      if (double_vertices) {
        Put<double>(&s, c, big_endian);
      } else {
        Put<float>(&s, static_cast<float>(c), big_endian);
      }
    }
    Put<uint8_t>(&s, 200, big_endian);
    Put<float>(&s, 0.5f, big_endian);
  }
  const std::vector<std::vector<uint32_t>> faces = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5, 3}};
  for (const auto& f : faces) {
    Put<int32_t>(&s, static_cast<int32_t>(f.size()), big_endian);
    for (uint32_t i : f) Put<uint32_t>(&s, i, big_endian);
    Put<uint8_t>(&s, 7, big_endian);
  }
  for (int e = 0; e < 2; ++e) {
    Put<uint8_t>(&s, 2, big_endian);
    Put<float>(&s, 1.0f, big_endian);
    Put<float>(&s, 2.0f, big_endian);
    Put<int16_t>(&s, -3, big_endian);
  }
  return s;
}

void ExpectSample(const TriangleMesh& mesh) {
  ASSERT_EQ(mesh.NumVertices(), 6u);
  for (int i = 0; i < 6; ++i) {
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(mesh.vertices_m[3 * i + c], static_cast<float>(kVertices[i][c]));
  }
  const std::vector<uint32_t> expected = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 3};
  EXPECT_EQ(mesh.triangles, expected);
  EXPECT_EQ(mesh.NumTriangles(), 4u);
}

TEST(Ply, BinaryLittleAndBigEndianFloatAndDouble) {
  for (bool big : {false, true}) {
    for (bool dbl : {false, true}) {
      SCOPED_TRACE(std::string(big ? "big" : "little") + (dbl ? " double" : " float"));
      ExpectSample(ParsePlyMesh(BinaryPly(big, dbl), "sample.ply"));
    }
  }
}

TEST(Ply, AsciiWithExtraPropertiesAndCrLf) {
  const std::string s =
      "ply\r\nformat ascii 1.0\r\nelement vertex 6\r\nproperty float nx\r\nproperty double x\r\n"
      "property double y\r\nproperty double z\r\nproperty uchar red\r\n"
      "element face 3\r\nproperty list uchar int vertex_index\r\nend_header\r\n"
      "9 0 0 0 1\r\n9 1 0 0 2\r\n9 1 1 0 3\r\n9 0 1 0 4\r\n9 0 0 2.5 5\r\n9 -1.25 3 7 6\r\n"
      "3 0 1 2\r\n3 0 2 3\r\n4 1 4 5 3\r\n";
  ExpectSample(ParsePlyMesh(s, "ascii.ply"));
}

TEST(Ply, EncodeRoundTripsAndFileRead) {
  TriangleMesh mesh;
  for (const auto& v : kVertices) {
    for (double c : v) mesh.vertices_m.push_back(static_cast<float>(c));
  }
  mesh.triangles = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 3};
  const std::string path = test::ScratchDir("ply_roundtrip") + "/m.ply";
  io::WriteFileAtomic(path, EncodePlyMesh(mesh));
  ExpectSample(ReadPlyMesh(path));
}

// The error of a bad file: one line naming it.
std::string ErrorOf(const std::string& bytes) {
  try {
    ParsePlyMesh(bytes, "bad.ply");
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bad.ply: ", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    return what;
  }
  ADD_FAILURE() << "no error";
  return "";
}

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

TEST(Ply, TruncatedFilesAreRefused) {
  const std::string good = BinaryPly(false, false);
  const size_t data = good.find("end_header\n") + 11;
  // Cut anywhere in the data or the header.
  for (size_t cut :
       {good.size() - 1, good.size() - 20, data + 30, data + 1, data, data - 5, size_t{10}}) {
    SCOPED_TRACE(cut);
    ErrorOf(good.substr(0, cut));
  }
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n\n\n\n";  // enough bytes, one index short
  EXPECT_NE(ErrorOf(ascii).find("ends early"), std::string::npos);
}

TEST(Ply, WrongCountsAreRefused) {
  const std::string good = BinaryPly(false, false);
  // More vertices or faces than the data holds.
  ErrorOf(Replace(good, "element vertex 6", "element vertex 7"));
  ErrorOf(Replace(good, "element face 3", "element face 5"));
  // A face listing more indices than there are.
  std::string long_face = good;
  const size_t data = long_face.find("end_header\n") + 11;
  const size_t first_face = data + 6 * (12 + 1 + 4);
  int32_t n = 200;
  std::memcpy(&long_face[first_face], &n, 4);
  ErrorOf(long_face);
  // An index out of range.
  std::string bad_index = good;
  uint32_t index = 6;
  std::memcpy(&bad_index[first_face + 4], &index, 4);
  EXPECT_NE(ErrorOf(bad_index).find("vertex index 6 outside [0, 6)"), std::string::npos);
  // A face with two vertices.
  std::string two = good;
  n = 2;
  std::memcpy(&two[first_face], &n, 4);
  EXPECT_NE(ErrorOf(two).find("has 2 vertices"), std::string::npos);
  // Negative count / index in ASCII.
  const std::string neg =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n";
  EXPECT_NE(ErrorOf(neg).find("vertex index -1"), std::string::npos);
  // ASCII: a vertex count larger than the vertex rows reads the first face line as a vertex;
  // the message names the count (it was "face 0 has 2 vertices").
  const std::string more =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0.000000 0.000000 0.000000\n1.000000 0.000000 0.000000\n"
      "0.000000 1.000000 0.000000\n3 0 1 2\n";
  EXPECT_NE(ErrorOf(more).find("vertex 3: more values on its line than the header's properties "
                               "(a vertex count in the header larger than the file's vertex "
                               "rows?)"),
            std::string::npos)
      << ErrorOf(more);
  // Fewer faces in the header than in the data, or bytes after the last element: refused
  // (the rows past the count were dropped without a word). ASCII may end in white space.
  EXPECT_NE(ErrorOf(Replace(good, "element face 3", "element face 2"))
                .find("bytes of data after the last element"),
            std::string::npos);
  EXPECT_NE(ErrorOf(good + "garbage").find("7 bytes of data after the last element"),
            std::string::npos);
  const std::string ascii_extra =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(ParsePlyMesh(ascii_extra + "\n \r\n", "a.ply").NumTriangles(), 1u);
  EXPECT_NE(ErrorOf(ascii_extra + "3 0 1 2\n").find("after the last element"), std::string::npos);
}

// Found by fuzz_ply: a PLY whose face element has no face ("element face 0") was read as an
// empty mesh, which renders "no depth" everywhere; and EncodePlyMesh of an empty mesh
// passed a null pointer to memcpy (UBSan). Now: one error naming the file (as for a PLY
// without a face element, a point cloud); the encoder writes an empty mesh's header alone.
TEST(Ply, NoTriangleIsRefusedAndAnEmptyMeshEncodes) {
  const std::string cloud =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n1 0 0\n";
  EXPECT_NE(ErrorOf(cloud).find("without a face element (a point cloud"), std::string::npos);
  const std::string no_face =
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_NE(ErrorOf(no_face).find("no triangles (0 vertices, no face)"), std::string::npos);
  const std::string empty = EncodePlyMesh(TriangleMesh{});
  EXPECT_NE(empty.find("element vertex 0\n"), std::string::npos);
  EXPECT_EQ(empty.substr(empty.size() - 11), "end_header\n");
  EXPECT_NE(ErrorOf(empty).find("no triangles"), std::string::npos);
}

TEST(Ply, BadPropertyTypesAreRefused) {
  const std::string good = BinaryPly(false, false);
  EXPECT_NE(ErrorOf(Replace(good, "property float x", "property uchar x")).find("float or double"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf(Replace(good, "property float y", "property quad y")).find("unknown property type"),
      std::string::npos);
  EXPECT_NE(ErrorOf(Replace(good, "list int uint vertex_indices", "list int float vertex_indices"))
                .find("list of int or uint"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(good, "list int uint vertex_indices", "list float uint vertex_indices"))
                .find("bad list property"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(good, "property float z\n", "")).find("without x, y and z"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(good, "vertex_indices", "corners")).find("without a vertex_indices"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf(Replace(good, "binary_little_endian", "binary_middle_endian")).find("unknown format"),
      std::string::npos);
  EXPECT_NE(ErrorOf(Replace(good, "ply\n", "plx\n")).find("not a PLY"), std::string::npos);
  EXPECT_NE(ErrorOf(Replace(good, "end_header", "end_headr")).find("unknown header keyword"),
            std::string::npos);
  const std::string points =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n";
  EXPECT_NE(ErrorOf(points).find("without a face element"), std::string::npos);
  const std::string nan =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n";
  EXPECT_NE(ErrorOf(nan).find("vertex 1: non-finite"), std::string::npos);
  const std::string word =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n";
  EXPECT_NE(ErrorOf(word).find("bad number"), std::string::npos);
}

TEST(Ply, HugeCountsAreRefusedBeforeAllocating) {
  const std::string good = BinaryPly(false, false);
  const auto start = std::chrono::steady_clock::now();
  for (const std::string count : {"1000000000000", "18446744073709551615", "4294967296"}) {
    EXPECT_NE(ErrorOf(Replace(good, "element vertex 6", "element vertex " + count)).find("claims"),
              std::string::npos);
    EXPECT_NE(ErrorOf(Replace(good, "element face 3", "element face " + count)).find("claims"),
              std::string::npos);
  }
  ErrorOf(Replace(good, "element face 3", "element face 99999999999999999999999"));  // > uint64
  ErrorOf(Replace(good, "element face 3", "element face -3"));
  // Refused from the header: no allocation of the claimed size (which would throw
  // std::bad_alloc, not InputError, or take seconds).
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

TEST(Ply, SharedTsdfMeshMatchesItsHeader) {
  const std::string path = test::SharedData("meshes/sevenscenes-rgbd-frames-tsdf.ply");
  ASSERT_FALSE(path.empty());
  // The header read here with a plain stream.
  std::ifstream in(path, std::ios::binary);
  std::string line;
  uint64_t vertices = 0, faces = 0;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream ls(line);
    std::string a, b;
    uint64_t n = 0;
    if (ls >> a >> b >> n && a == "element") (b == "vertex" ? vertices : faces) = n;
  }
  ASSERT_GT(vertices, 100000u);
  ASSERT_GT(faces, 200000u);
  const TriangleMesh mesh = ReadPlyMesh(path);
  EXPECT_EQ(mesh.NumVertices(), vertices);
  EXPECT_EQ(mesh.NumTriangles(), faces);
  // Every coordinate in a room-sized box around the 7-Scenes poses' origin.
  for (float c : mesh.vertices_m) ASSERT_LT(std::abs(c), 20.0f);
}

TEST(Ply, MissingFileNamesIt) {
  try {
    ReadPlyMesh("/nonexistent/mesh.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/mesh.ply"), std::string::npos);
  }
}

}  // namespace
}  // namespace gt::render

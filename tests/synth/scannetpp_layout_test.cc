// The ScanNet++-layout fixture (synth/scannetpp_layout.h): its mesh is the scene's exact
// geometry (a brute-force ray-triangle caster over the PLY's triangles agrees with the
// analytic ray caster), its COLMAP files hold the cameras and poses it renders with, and
// reruns are byte-identical.
#include "libgt/synth/scannetpp_layout.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/datasets/colmap.h"
#include "libgt/io/file_read.h"
#include "libgt/synth/dataset.h"
#include "libgt/synth/render.h"

namespace gt::synth {
namespace {
namespace fs = std::filesystem;

struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> faces;
};

// The fixture's PLY as it writes it (float x y z, uchar r g b; list uchar int), parsed here
// independently of any reader in libgt.
Mesh ReadFixturePly(const std::string& path) {
  const std::string bytes = io::ReadFileBytes(path);
  const size_t end = bytes.find("end_header\n");
  EXPECT_NE(end, std::string::npos);
  std::istringstream header(bytes.substr(0, end));
  std::string line;
  size_t nv = 0, nf = 0;
  while (std::getline(header, line)) {
    std::istringstream l(line);
    std::string a, b;
    size_t n = 0;
    if (l >> a >> b >> n && a == "element") (b == "vertex" ? nv : nf) = n;
  }
  Mesh m;
  size_t at = end + std::strlen("end_header\n");
  for (size_t i = 0; i < nv; ++i) {
    float xyz[3];
    std::memcpy(xyz, bytes.data() + at, 12);
    m.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
    at += 15;
  }
  for (size_t i = 0; i < nf; ++i) {
    EXPECT_EQ(bytes[at], 3);
    std::array<int, 3> f;
    std::memcpy(f.data(), bytes.data() + at + 1, 12);
    m.faces.push_back(f);
    at += 13;
  }
  EXPECT_EQ(at, bytes.size());
  return m;
}

// Nearest hit t > 0 of o + t d over every triangle (Moller-Trumbore, no culling).
double BruteForceHit(const Mesh& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : m.faces) {
    const Eigen::Vector3d& a = m.vertices[f[0]];
    const Eigen::Vector3d e1 = m.vertices[f[1]] - a, e2 = m.vertices[f[2]] - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(p) / det;
    if (u < -1e-9 || u > 1 + 1e-9) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < -1e-9 || u + v > 1 + 1e-9) continue;
    const double t = e2.dot(q) / det;
    if (t > 1e-9 && t < best) best = t;
  }
  return best;
}

ScanNetPPSynthOptions Small() {
  ScanNetPPSynthOptions o;
  o.frames = 3;
  o.dslr_width = 64;
  o.dslr_height = 48;
  o.iphone_width = 64;
  o.iphone_height = 48;
  o.seed = 5;
  return o;
}

TEST(ScanNetPPLayout, MeshIsTheExactSceneAndFilesHoldTheTruth) {
  const fs::path out =
      fs::temp_directory_path() / ("occgt_spp_layout_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const ScanNetPPSynthOptions o = Small();
  const ScanNetPPSynthSummary summary = WriteScanNetPPSynth(out.string(), o);
  ASSERT_EQ(summary.scene_names, std::vector<std::string>{"synthpp_000"});
  const fs::path scene_dir = out / "data" / "synthpp_000";
  const ScanNetPPSynthScene truth = MakeScanNetPPSynthScene(o, 0);
  const Mesh mesh = ReadFixturePly((scene_dir / "scans" / "mesh_aligned_0.05.ply").string());
  EXPECT_EQ(mesh.faces.size(), 12 * (1 + truth.scene.objects.size()));
  // Rays of every posed DSLR pixel on a coarse grid, through the fisheye lens.
  const LensCamera lens = ScanNetPPSynthDslrLens(o);
  int checked = 0;
  for (const Rigid3d& pose : truth.dslr_poses) {
    for (int v = 0; v < o.dslr_height; v += 5) {
      for (int u = 0; u < o.dslr_width; u += 5) {
        const auto ab = UndistortPixel(lens, u, v);
        ASSERT_TRUE(ab.has_value());
        const Eigen::Vector3d d = pose.linear() * Eigen::Vector3d(ab->x(), ab->y(), 1.0);
        const RayHit hit = CastRay(truth.scene, pose.translation(), d);
        ASSERT_TRUE(hit.hit());
        // float vertices: a few micrometres.
        ASSERT_NEAR(BruteForceHit(mesh, pose.translation(), d), hit.t, 2e-5) << u << "," << v;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);

  // COLMAP: the lens (with COLMAP's +0.5) and the poses the images were rendered with.
  const datasets::ColmapModel model =
      datasets::ReadColmapModel((scene_dir / "dslr" / "colmap").string());
  ASSERT_EQ(model.images.size(), static_cast<size_t>(o.frames));
  const LensCamera read = datasets::ColmapLensCamera(model.cameras.at(1), model.cameras_path);
  EXPECT_NEAR(read.pinhole.cx, lens.pinhole.cx, 1e-12);
  EXPECT_NEAR(read.pinhole.fy, lens.pinhole.fy, 1e-12);
  for (int i = 0; i < o.frames; ++i) {
    EXPECT_EQ(model.images[i].name, ScanNetPPSynthDslrName(i));
    const Rigid3d got = datasets::ColmapWorldFromCam(model.images[i]);
    EXPECT_LT((got.matrix() - truth.dslr_poses[i].matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }

  // Byte-identical rerun.
  const fs::path again = out.string() + "_again";
  fs::remove_all(again);
  WriteScanNetPPSynth(again.string(), o);
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    if (!e.is_regular_file()) continue;
    const fs::path other = again / fs::relative(e.path(), out);
    ASSERT_EQ(io::ReadFileBytes(e.path().string()), io::ReadFileBytes(other.string())) << e.path();
  }
  // Other options into the same folder (fewer frames, another size: stale images and a
  // scene of the other run would stay beside the new ones), or into a folder of the generic
  // layout: refused, naming the claim or the folder, nothing written.
  ScanNetPPSynthOptions fewer = o;
  fewer.frames = 2;
  fewer.dslr_width = 48;
  fewer.dslr_height = 32;
  fewer.seed = 3;
  const std::string count_before = std::to_string(
      std::distance(fs::recursive_directory_iterator(again), fs::recursive_directory_iterator()));
  try {
    WriteScanNetPPSynth(again.string(), fewer);
    ADD_FAILURE() << "other options into the same folder";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (again / ".occgt-synth.json").string());
    EXPECT_NE(std::string(e.what()).find("holds a synthetic dataset of other options"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(std::to_string(std::distance(fs::recursive_directory_iterator(again),
                                         fs::recursive_directory_iterator())),
            count_before);
  WriteScanNetPPSynth(again.string(), o);  // the same options: a re-run
  const fs::path generic = out.string() + "_generic";
  fs::remove_all(generic);
  SynthOptions g;
  g.scenes = 1;
  g.frames_per_scene = 2;
  g.width = 32;
  g.height = 24;
  WriteSyntheticDataset(generic.string(), g);
  EXPECT_THROW(WriteScanNetPPSynth(generic.string(), o), InputError);
  EXPECT_THROW(WriteSyntheticDataset(again.string(), g), InputError);
  fs::remove_all(out);
  fs::remove_all(again);
  fs::remove_all(generic);
  EXPECT_THROW(WriteScanNetPPSynth(out.string(), ScanNetPPSynthOptions{1, 1}), InputError);
}

}  // namespace
}  // namespace gt::synth

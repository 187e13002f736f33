// MeshRenderer against closed-form depth (a tilted plane, a room-sized box seen from inside,
// a box seen from outside with rays grazing its edges, a tessellated sphere checked facet by
// facet and against the spheres that bound it), the near/far rule, thread safety and
// determinism, a brute-force reference renderer on the shared TSDF mesh, and that mesh
// rendered at the 7-Scenes sample's poses against the sensor depth it was fused from.
#include "libgt/render/mesh_renderer.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <functional>
#include <opencv2/calib3d.hpp>
#include <random>
#include <thread>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/depth_io.h"
#include "tests/render/reference_renderer.h"
#include "tests/render/scenes.h"
#include "tests/support/test_support.h"

namespace gt::render {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kDepthTolM = 1e-4;

// A camera model under test: its size, the normalised direction (x, y) of the ray of pixel
// (u, v) as the test computes it, and the renderer's call.
struct Rig {
  std::string name;
  int width = 0, height = 0;
  std::function<std::optional<Vector2d>(int u, int v)> ray;
  std::function<RenderedDepth(const MeshRenderer&, const Rigid3d&, const RenderOptions&)> render;
};

Rig PinholeRig(int width, int height, double fx, double fy, double cx, double cy) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = fx;
  camera.fy = fy;
  camera.cx = cx;
  camera.cy = cy;
  Rig rig;
  rig.name = "pinhole";
  rig.width = width;
  rig.height = height;
  rig.ray = [=](int u, int v) {
    return std::optional<Vector2d>(Vector2d((u - cx) / fx, (v - cy) / fy));
  };
  rig.render = [=](const MeshRenderer& r, const Rigid3d& pose, const RenderOptions& o) {
    return r.Render(camera, pose, o);
  };
  return rig;
}

// A distorted camera: the ray of each pixel is UndistortPixel's, checked here against
// OpenCV's own projection (cv::projectPoints, cv::fisheye::projectPoints): the direction
// projects back onto the pixel's centre.
Rig LensRig(LensModel model, int width, int height, double f, std::array<double, 5> coeffs) {
  LensCamera lens;
  lens.pinhole = Camera::FromK(
      (Eigen::Matrix3d() << f, 0, 0.5 * width - 0.3, 0, 1.05 * f, 0.5 * height + 0.2, 0, 0, 1)
          .finished(),
      width, height);
  lens.model = model;
  lens.coeffs = coeffs;
  Rig rig;
  rig.name = LensModelName(model);
  rig.width = width;
  rig.height = height;
  rig.ray = [=](int u, int v) -> std::optional<Vector2d> {
    const auto xy = UndistortPixel(lens, u, v);
    if (!xy) return std::nullopt;
    std::vector<cv::Point3d> object = {cv::Point3d(xy->x(), xy->y(), 1.0)};
    std::vector<cv::Point2d> image;
    const cv::Matx33d K(lens.pinhole.fx, 0, lens.pinhole.cx, 0, lens.pinhole.fy, lens.pinhole.cy, 0,
                        0, 1);
    const cv::Vec3d zero(0, 0, 0);
    if (model == LensModel::kOpenCvFisheye) {
      cv::fisheye::projectPoints(object, image, zero, zero, K,
                                 cv::Vec4d(coeffs[0], coeffs[1], coeffs[2], coeffs[3]));
    } else {
      cv::projectPoints(object, zero, zero, K, std::vector<double>(coeffs.begin(), coeffs.end()),
                        image);
    }
    EXPECT_NEAR(image[0].x, u, 1e-6) << rig.name << " ray of pixel " << u << "," << v;
    EXPECT_NEAR(image[0].y, v, 1e-6) << rig.name << " ray of pixel " << u << "," << v;
    return xy;
  };
  rig.render = [=](const MeshRenderer& r, const Rigid3d& pose, const RenderOptions& o) {
    return r.Render(lens, pose, o);
  };
  return rig;
}

std::vector<Rig> Rigs() {
  return {
      // A wide pinhole (~100 degrees across) with an off-centre principal point and fx != fy.
      PinholeRig(97, 61, 40.0, 43.0, 47.3, 29.1),
      // Barrel distortion with tangential terms (an iPhone-like OPENCV camera, wide).
      LensRig(LensModel::kOpenCv, 97, 61, 45.0, {-0.12, 0.02, 0.001, -0.0015, 0.0}),
      // A ScanNet++-like fisheye, ~150 degrees across its width.
      LensRig(LensModel::kOpenCvFisheye, 97, 61, 22.0, {0.03, -0.01, 0.004, -0.0007, 0.0}),
  };
}

Rigid3d Pose(const Vector3d& axis, double angle, const Vector3d& t) {
  Rigid3d pose = Rigid3d::Identity();
  pose.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  pose.translation() = t;
  return pose;
}

// World direction of the ray (x, y, 1): its planar z is the distance along it.
Vector3d WorldRay(const Rigid3d& pose, const Vector2d& xy) {
  return pose.linear() * Vector3d(xy.x(), xy.y(), 1);
}

// Compares every pixel of a render with expected(u, v, direction): the expected depth,
// 0 for none, or nullopt for a pixel too close to a boundary to call. Returns the number of
// pixels compared.
int CompareAll(const Rig& rig, const RenderedDepth& got, const Rigid3d& pose,
               const std::function<std::optional<double>(int, int, const Vector3d&)>& expected,
               const RenderOptions& range = RenderOptions{}) {
  int compared = 0;
  for (int v = 0; v < rig.height; ++v) {
    for (int u = 0; u < rig.width; ++u) {
      const auto xy = rig.ray(u, v);
      if (!xy) {
        EXPECT_EQ(got.depth_m(v, u), 0.0f) << rig.name << " pixel without a ray " << u << "," << v;
        continue;
      }
      auto want = expected(u, v, WorldRay(pose, *xy));
      if (!want) continue;
      // The first surface outside [near, far] gives 0 (a fisheye's rays near 90 degrees meet
      // surfaces at a small planar z); within 1e-4 of a limit either is right.
      if (std::abs(*want - range.near_m) < kDepthTolM || std::abs(*want - range.far_m) < kDepthTolM)
        continue;
      if (*want < range.near_m || *want > range.far_m) want = 0.0;
      ++compared;
      EXPECT_NEAR(got.depth_m(v, u), *want, kDepthTolM) << rig.name << " pixel " << u << "," << v;
    }
  }
  return compared;
}

TEST(MeshRenderer, TiltedPlaneAnalytic) {
  // The plane n.p = c, a 40 m square around the point the camera looks at.
  const Vector3d n = Vector3d(0.2, -0.3, 1).normalized();
  const Vector3d centre(0.5, -0.2, 3.0);
  const Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  TriangleMesh mesh;
  const double half = 20;
  test::AddQuad(&mesh, centre - half * e1 - half * e2, centre + half * e1 - half * e2,
                centre + half * e1 + half * e2, centre - half * e1 + half * e2);
  const MeshRenderer renderer(mesh);
  for (const Rig& rig : Rigs()) {
    for (int k = 0; k < 3; ++k) {
      const Rigid3d pose =
          Pose(Vector3d(0.3, 1, -0.2 + k), 0.15 * k, Vector3d(0.1 * k, 0.05, -0.4 * k));
      RenderOptions options;
      options.far_m = 30;
      const RenderedDepth got = rig.render(renderer, pose, options);
      ASSERT_EQ(got.depth_m.rows, rig.height);
      ASSERT_EQ(got.depth_m.cols, rig.width);
      const int compared = CompareAll(
          rig, got, pose,
          [&](int, int, const Vector3d& d) -> std::optional<double> {
            const double denom = n.dot(d);
            if (denom == 0) return 0.0;
            const double t = (n.dot(centre) - n.dot(pose.translation())) / denom;
            if (t <= 0) return 0.0;
            const Vector3d q = pose.translation() + t * d - centre;
            const double a = std::abs(q.dot(e1)), b = std::abs(q.dot(e2));
            if (std::abs(a - half) < 1e-3 || std::abs(b - half) < 1e-3)
              return std::nullopt;  // the quad's edge
            if (a > half || b > half) return 0.0;
            return t;
          },
          options);
      int with_ray = 0;
      for (int v = 0; v < rig.height; ++v) {
        for (int u = 0; u < rig.width; ++u) with_ray += rig.ray(u, v).has_value();
      }
      EXPECT_GT(compared, with_ray * 9 / 10) << rig.name;
      EXPECT_TRUE(got.triangle_id.empty());
    }
  }
}

TEST(MeshRenderer, BoxFromInsideEveryPixelHitsAndIdsNameTheFace) {
  const Vector3d lo(-2, -1.5, -2.5), hi(3, 1.2, 4);
  TriangleMesh mesh;
  test::AddBox(&mesh, lo, hi);
  const MeshRenderer renderer(mesh);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (const Rig& rig : Rigs()) {
    for (int k = 0; k < 6; ++k) {
      const Rigid3d pose = Pose(Vector3d(unit(rng), unit(rng), unit(rng)), 3 * unit(rng),
                                Vector3d(unit(rng), 0.5 * unit(rng), unit(rng)));
      RenderOptions options;
      options.triangle_ids = true;
      const RenderedDepth got = rig.render(renderer, pose, options);
      const int compared =
          CompareAll(rig, got, pose, [&](int u, int v, const Vector3d& d) -> std::optional<double> {
            const double t = *test::BoxDistance(lo, hi, pose.translation(), d);
            // The face the ray leaves through: the axis whose exit distance is t.
            int face = -1, ties = 0;
            for (int i = 0; i < 3; ++i) {
              if (d[i] == 0) continue;
              const double ti = ((d[i] > 0 ? hi[i] : lo[i]) - pose.translation()[i]) / d[i];
              if (std::abs(ti - t) < 1e-6 * t) {
                face = 2 * i + (d[i] > 0 ? 1 : 0);
                ++ties;
              }
            }
            if (ties == 1 && t > options.near_m + kDepthTolM) {
              EXPECT_EQ(got.triangle_id(v, u) / 2, face) << rig.name << " pixel " << u << "," << v;
            }
            return t;
          });
      int with_ray = 0;
      for (int v = 0; v < rig.height; ++v) {
        for (int u = 0; u < rig.width; ++u) with_ray += rig.ray(u, v).has_value();
      }
      EXPECT_GT(with_ray, rig.width * rig.height / 2) << rig.name;  // the fisheye: 65 %
      EXPECT_EQ(compared, with_ray)
          << rig.name;  // every ray compared (none leaks out of a closed box)
    }
  }
}

TEST(MeshRenderer, RaysGrazingBoxEdges) {
  // Box x, y in [-1, 1], z in [4, 6]; camera at x = 1, on the plane of the +x face, looking
  // along +z: the rays of column u0 (x = 0) run inside that face's plane and meet the front
  // face exactly on its edge (z = 4); the rays of row v0 (y = 0.25 z) hit the front face's
  // top edge at y = 1 exactly. Both edges belong to the box: depth 4.
  const Vector3d lo(-1, -1, 4), hi(1, 1, 6);
  TriangleMesh mesh;
  test::AddBox(&mesh, lo, hi);
  const MeshRenderer renderer(mesh);
  Camera camera;
  camera.width = 64;
  camera.height = 48;
  camera.fx = camera.fy = 64;
  camera.cx = 40;  // u0 = 40: x = 0
  camera.cy = 0;   // v0 = 16: y = 0.25
  Rigid3d pose = Rigid3d::Identity();
  pose.translation() = Vector3d(1, 0, 0);
  const RenderedDepth got = renderer.Render(camera, pose, RenderOptions{});
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Vector3d d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1);
      const auto t = test::BoxDistance(lo, hi, pose.translation(), d);
      const double want = t ? *t : 0.0;  // the slab test counts a box's edges in
      EXPECT_NEAR(got.depth_m(v, u), want, kDepthTolM) << u << "," << v;
    }
  }
  // The grazing column and the edge row are hits; one pixel beyond each is a miss.
  EXPECT_NEAR(got.depth_m(0, 40), 4.0, kDepthTolM);   // along the +x face's plane
  EXPECT_NEAR(got.depth_m(16, 20), 4.0, kDepthTolM);  // through the top edge (y = 1, z = 4)
  EXPECT_NEAR(got.depth_m(16, 40), 4.0, kDepthTolM);  // both: the front face's corner
  EXPECT_EQ(got.depth_m(0, 41), 0.0f);
  EXPECT_EQ(got.depth_m(17, 20), 0.0f);
}

TEST(MeshRenderer, TessellatedSphereFacetExactAndBounded) {
  const Vector3d centre(0.3, -0.2, 0.0);
  const double radius = 1.5;
  const TriangleMesh mesh = test::IcoSphere(centre, radius, 4);  // 5120 triangles
  ASSERT_EQ(mesh.NumTriangles(), 5120u);
  // The inscribed radius: the nearest facet plane to the centre.
  double r_in = radius;
  for (size_t t = 0; t < mesh.NumTriangles(); ++t) {
    Vector3d p[3];
    for (int k = 0; k < 3; ++k) {
      const float* q = &mesh.vertices_m[3 * mesh.triangles[3 * t + k]];
      p[k] = Vector3d(q[0], q[1], q[2]);
    }
    const Vector3d nrm = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    r_in = std::min(r_in, std::abs(nrm.dot(p[0] - centre)));
  }
  ASSERT_GT(r_in, radius * 0.99);  // level 4: facets within 1 % of the sphere
  const MeshRenderer renderer(mesh);
  for (const Rig& rig : Rigs()) {
    for (int k = 0; k < 4; ++k) {
      // Looking at the sphere from 3-4 m away, from several sides.
      const Rigid3d look = Pose(Vector3d(0, 1, 0.2 * k), 1.3 * k, Vector3d::Zero());
      Rigid3d pose = look;
      pose.translation() = centre - look.linear() * Vector3d(0.1 * k, -0.05, 3.0 + 0.3 * k);
      RenderOptions options;
      options.triangle_ids = true;
      const RenderedDepth got = rig.render(renderer, pose, options);
      int hits = 0;
      CompareAll(rig, got, pose, [&](int u, int v, const Vector3d& d) -> std::optional<double> {
        const auto outer = test::SphereDistance(centre, radius, pose.translation(), d);
        const auto inner = test::SphereDistance(centre, r_in, pose.translation(), d);
        const float depth = got.depth_m(v, u);
        const int id = got.triangle_id(v, u);
        if (!outer) {
          EXPECT_EQ(depth, 0.0f) << "outside the circumscribed sphere " << u << "," << v;
          return std::nullopt;
        }
        if (inner) {
          EXPECT_GT(depth, 0.0f) << "inside the inscribed sphere " << u << "," << v;
          EXPECT_GE(depth, *outer - kDepthTolM);
          EXPECT_LE(depth, *inner + kDepthTolM);
        }
        if (id < 0) return std::nullopt;
        ++hits;
        // The exact depth of the facet the renderer names: the ray meets its plane at the
        // returned depth, inside the triangle.
        Vector3d p[3];
        for (int c = 0; c < 3; ++c) {
          const float* q = &mesh.vertices_m[3 * mesh.triangles[3 * id + c]];
          p[c] = Vector3d(q[0], q[1], q[2]);
        }
        const Vector3d nrm = (p[1] - p[0]).cross(p[2] - p[0]);
        const double t = nrm.dot(p[0] - pose.translation()) / nrm.dot(d);
        const Vector3d x = pose.translation() + t * d;
        const double area = nrm.norm();
        for (int c = 0; c < 3; ++c) {
          const double w = (p[(c + 1) % 3] - x).cross(p[(c + 2) % 3] - x).dot(nrm) / (area * area);
          EXPECT_GT(w, -1e-4) << "hit outside its facet " << u << "," << v;
        }
        return t;
      });
      EXPECT_GT(hits, 200) << rig.name;
    }
  }
}

TEST(MeshRenderer, NearAndFarLimitsGiveZeroWithoutSeeingThrough) {
  TriangleMesh mesh;
  test::AddQuad(&mesh, Vector3d(-50, -50, 5), Vector3d(50, -50, 5), Vector3d(50, 50, 5),
                Vector3d(-50, 50, 5));
  // A small card 3 cm in front of the camera, covering the image's centre.
  test::AddQuad(&mesh, Vector3d(-0.01, -0.01, 0.03), Vector3d(0.01, -0.01, 0.03),
                Vector3d(0.01, 0.01, 0.03), Vector3d(-0.01, 0.01, 0.03));
  const MeshRenderer renderer(mesh);
  Camera camera =
      Camera::FromK((Eigen::Matrix3d() << 50, 0, 31.5, 0, 50, 23.5, 0, 0, 1).finished(), 64, 48);
  RenderOptions options;
  options.triangle_ids = true;
  RenderedDepth got = renderer.Render(camera, Rigid3d::Identity(), options);
  EXPECT_EQ(got.depth_m(24, 32), 0.0f);  // the card is nearer than near_m: 0, not the wall
  EXPECT_EQ(got.triangle_id(24, 32), -1);
  EXPECT_NEAR(got.depth_m(0, 0), 5.0, kDepthTolM);  // the wall around it
  options.near_m = 0.01;
  got = renderer.Render(camera, Rigid3d::Identity(), options);
  EXPECT_NEAR(got.depth_m(24, 32), 0.03, kDepthTolM);
  EXPECT_GE(got.triangle_id(24, 32), 2);
  options.far_m = 4.9;
  got = renderer.Render(camera, Rigid3d::Identity(), options);
  EXPECT_EQ(got.depth_m(0, 0), 0.0f);
  options.far_m = 5.1;
  got = renderer.Render(camera, Rigid3d::Identity(), options);
  EXPECT_NEAR(got.depth_m(0, 0), 5.0, kDepthTolM);
  // Bad options and cameras are refused.
  options.far_m = 0.001;
  EXPECT_THROW(renderer.Render(camera, Rigid3d::Identity(), options), InputError);
  options = RenderOptions{};
  camera.fx = 0;
  EXPECT_THROW(renderer.Render(camera, Rigid3d::Identity(), options), InputError);
}

TEST(MeshRenderer, BadMeshIsRefusedAndEmptyMeshRendersNothing) {
  TriangleMesh bad;
  bad.vertices_m = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bad.triangles = {0, 1, 3};
  EXPECT_THROW(MeshRenderer{bad}, InputError);
  bad.triangles = {0, 1, 2};
  bad.vertices_m[4] = NAN;
  EXPECT_THROW(MeshRenderer{bad}, InputError);
  const MeshRenderer empty(TriangleMesh{});
  const Camera camera = Camera::FromK(Eigen::Matrix3d::Identity() * 10, 8, 8);
  const RenderedDepth got = empty.Render(camera, Rigid3d::Identity(), RenderOptions{});
  EXPECT_EQ(cv::countNonZero(got.depth_m), 0);
}

const std::string kTsdfMesh = "meshes/sevenscenes-rgbd-frames-tsdf.ply";

Scene SevenScenesSample() {
  const std::string parent = gt::test::SharedData("sevenscenes");
  if (parent.empty()) return {};
  return datasets::MakeReader(DatasetFormat::kSevenScenes)->ReadScene(parent, "rgbd-frames");
}

TEST(MeshRenderer, ThreadsShareOneRendererAndAgreeBitForBit) {
  const std::string path = gt::test::SharedData(kTsdfMesh);
  ASSERT_FALSE(path.empty());
  const MeshRenderer renderer(ReadPlyMesh(path));
  const Scene scene = SevenScenesSample();
  ASSERT_EQ(scene.frames.size(), 50u);
  RenderOptions options;
  options.triangle_ids = true;
  // Serial renders of 4 frames, then the same frames from 4 threads at once, twice each.
  std::vector<RenderedDepth> serial;
  for (int i = 0; i < 4; ++i) {
    const Frame& f = scene.frames[12 * i];
    serial.push_back(renderer.Render(f.depth_camera, f.world_from_cam, options));
  }
  std::vector<RenderedDepth> parallel(8);
  std::vector<std::thread> threads;
  for (int i = 0; i < 8; ++i) {
    threads.emplace_back([&, i] {
      const Frame& f = scene.frames[12 * (i % 4)];
      parallel[i] = renderer.Render(f.depth_camera, f.world_from_cam, options);
    });
  }
  for (auto& t : threads) t.join();
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(cv::norm(parallel[i].depth_m, serial[i % 4].depth_m, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::countNonZero(parallel[i].triangle_id != serial[i % 4].triangle_id), 0);
  }
  // One ray at a time gives the same depth.
  options.batching = RayBatching::kSingleRay;
  const Frame& f = scene.frames[0];
  const RenderedDepth single = renderer.Render(f.depth_camera, f.world_from_cam, options);
  EXPECT_LE(cv::norm(single.depth_m, serial[0].depth_m, cv::NORM_INF), 1e-5);
  EXPECT_LE(cv::countNonZero(single.triangle_id != serial[0].triangle_id), 10);
}

TEST(MeshRenderer, MatchesBruteForceReferenceOnTsdfMesh) {
  const std::string path = gt::test::SharedData(kTsdfMesh);
  ASSERT_FALSE(path.empty());
  const TriangleMesh mesh = ReadPlyMesh(path);
  const MeshRenderer renderer(mesh);
  const Scene scene = SevenScenesSample();
  ASSERT_EQ(scene.frames.size(), 50u);
  std::mt19937 rng(33);
  RenderOptions options;
  options.triangle_ids = true;
  int compared = 0, hits = 0, ambiguous = 0;
  for (int i : {0, 17, 33, 49}) {
    const Frame& f = scene.frames[i];
    const Camera& c = f.depth_camera;
    const RenderedDepth got = renderer.Render(c, f.world_from_cam, options);
    std::vector<std::pair<int, int>> pixels = {
        {0, 0}, {c.width - 1, 0}, {0, c.height - 1}, {c.width - 1, c.height - 1}};
    for (int k = 0; k < 60; ++k) {
      pixels.emplace_back(std::uniform_int_distribution<int>(0, c.width - 1)(rng),
                          std::uniform_int_distribution<int>(0, c.height - 1)(rng));
    }
    for (const auto& [u, v] : pixels) {
      const auto ref = test::ReferenceCast(mesh, f.world_from_cam, (u - c.cx) / c.fx,
                                           (v - c.cy) / c.fy, options.near_m, options.far_m);
      if (ref.ambiguous) {
        ++ambiguous;
        continue;
      }
      ++compared;
      hits += ref.triangle >= 0;
      EXPECT_NEAR(got.depth_m(v, u), ref.depth_m, kDepthTolM)
          << "frame " << i << " pixel " << u << "," << v;
      EXPECT_EQ(got.triangle_id(v, u), ref.triangle) << "frame " << i << " pixel " << u << "," << v;
    }
  }
  // 256 pixels; those whose ray passes within a hair of an edge of the 1 cm facets are
  // set aside (about 7 %).
  EXPECT_GE(compared, 220);
  EXPECT_GT(hits, compared / 2);
  EXPECT_LE(ambiguous, 36);
}

// The depth of every hit is the float nearest to the exact (double) distance from the
// camera centre to the hit triangle's plane along the pixel's ray (x, y, 1), computed here
// with Moller-Trumbore's formula: a function of the triangle and the ray alone. Embree's own
// float distance comes from a kernel picked by the CPU's instruction set (AVX-512 here, AVX2
// or SSE elsewhere), and its last bits differed between machines: it was within 1e-4 m of
// this distance, but not its nearest float (and a build with mesh depth was not the same on
// every machine).
TEST(MeshRenderer, DepthIsTheNearestFloatToTheHitTrianglesPlane) {
  const std::string path = gt::test::SharedData(kTsdfMesh);
  ASSERT_FALSE(path.empty());
  const TriangleMesh mesh = ReadPlyMesh(path);
  const MeshRenderer renderer(mesh);
  const Scene scene = SevenScenesSample();
  RenderOptions options;
  options.triangle_ids = true;
  int64_t hits = 0, midpoints = 0;
  for (int i : {0, 25, 49}) {
    const Frame& f = scene.frames[i];
    const Camera& c = f.depth_camera;
    const RenderedDepth got = renderer.Render(c, f.world_from_cam, options);
    const Vector3d o = f.world_from_cam.translation();
    for (int v = 0; v < c.height; ++v) {
      for (int u = 0; u < c.width; ++u) {
        const int t = got.triangle_id(v, u);
        if (t < 0) {
          EXPECT_EQ(got.depth_m(v, u), 0.0f);
          continue;
        }
        ++hits;
        const Vector3d d =
            f.world_from_cam.linear() * Vector3d((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1);
        auto vertex = [&](int k) {
          const float* p = &mesh.vertices_m[3 * mesh.triangles[3 * t + k]];
          return Vector3d(p[0], p[1], p[2]);
        };
        const Vector3d a = vertex(0), e1 = vertex(1) - a, e2 = vertex(2) - a;
        const Vector3d s = o - a, q = s.cross(e1);
        const double exact = e2.dot(q) / e1.dot(d.cross(e2));
        const float nearest = static_cast<float>(exact);
        if (got.depth_m(v, u) == nearest) continue;
        // Only where the exact distance lies on a rounding midpoint of two floats, within the
        // double rounding of two formulas of the same plane.
        const float other = got.depth_m(v, u);
        const double midpoint = (static_cast<double>(nearest) + other) / 2;
        EXPECT_LE(std::abs(exact - midpoint), 1e-12 * exact)
            << "frame " << i << " pixel " << u << "," << v << ": " << other << " vs " << nearest;
        ++midpoints;
      }
    }
  }
  EXPECT_GT(hits, 300000);
  EXPECT_LE(midpoints, 3);
}

TEST(MeshRenderer, TsdfMeshAtSevenScenesPosesReproducesSensorDepth) {
  const std::string path = gt::test::SharedData(kTsdfMesh);
  ASSERT_FALSE(path.empty());
  const MeshRenderer renderer(ReadPlyMesh(path));
  const Scene scene = SevenScenesSample();
  ASSERT_EQ(scene.frames.size(), 50u);
  std::vector<float> abs_diff;
  int64_t sensor_valid = 0, both = 0, sensor_holes = 0, holes_filled = 0;
  for (const Frame& f : scene.frames) {
    const DepthImage sensor = io::ReadDepth(f.depth, f.depth_camera.width, f.depth_camera.height);
    const RenderedDepth got = renderer.Render(f.depth_camera, f.world_from_cam, RenderOptions{});
    for (int v = 0; v < sensor.height; ++v) {
      for (int u = 0; u < sensor.width; ++u) {
        const float s = sensor.at(u, v), m = got.depth_m(v, u);
        const bool s_ok = s > scene.min_depth_m && s < scene.max_depth_m;
        sensor_valid += s_ok;
        sensor_holes += !s_ok;
        holes_filled += !s_ok && m > 0;
        if (s_ok && m > 0) {
          ++both;
          abs_diff.push_back(std::abs(s - m));
        }
      }
    }
  }
  ASSERT_GT(sensor_valid, 0);
  std::nth_element(abs_diff.begin(), abs_diff.begin() + abs_diff.size() / 2, abs_diff.end());
  const double median = abs_diff[abs_diff.size() / 2];
  const double coverage = static_cast<double>(both) / sensor_valid;
  const double filled = static_cast<double>(holes_filled) / std::max<int64_t>(1, sensor_holes);
  std::printf(
      "7-Scenes sample, TSDF mesh vs sensor: median |diff| %.4f m, coverage %.4f, holes filled "
      "%.4f\n",
      median, coverage, filled);
  // Stated in docs/GROUND_TRUTH.md "Depth sources".
  EXPECT_LT(median, 0.01);
  EXPECT_GT(coverage, 0.95);
  EXPECT_GT(filled, 0.2);
}

}  // namespace
}  // namespace gt::render

// Ray-cast depth against closed-form answers (a wall, a box in front of a wall) and against
// a slow reference written here (intersect each face plane, keep points inside the face),
// on random generated rooms and random poses; colour has texture everywhere.
#include "libgt/synth/render.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "libgt/synth/scene.h"
#include "libgt/synth/trajectory.h"

namespace gt::synth {
namespace {

Camera TestCamera(int w = 640, int h = 480) {
  Camera c;
  c.width = w;
  c.height = h;
  c.fx = c.fy = 525.0 * w / 640.0;
  c.cx = (w - 1) / 2.0;
  c.cy = (h - 1) / 2.0;
  return c;
}

SynthScene EmptyRoom(const Eigen::Vector3d& size) {
  SynthScene s;
  s.room_size_m = size;
  s.light_in_world = Eigen::Vector3d(size.x() / 2, size.y() / 2, size.z() - 0.2);
  return s;
}

// Camera at `c` looking along world +x, image x along world -y, image y along world -z.
Rigid3d FacingPlusX(const Eigen::Vector3d& c) {
  Rigid3d t = Rigid3d::Identity();
  t.linear() << 0, 0, 1,  //
      -1, 0, 0,           //
      0, -1, 0;
  t.translation() = c;
  return t;
}

TEST(Render, WallHeadOnHasConstantDepth) {
  const SynthScene room = EmptyRoom({10, 8, 6});
  const Camera cam = TestCamera();
  const RenderedView view = RenderView(room, cam, FacingPlusX({5, 4, 3}));
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      ASSERT_EQ(view.depth.at(u, v), 5.0f) << u << "," << v;
      ASSERT_EQ(view.surface_ids[v * cam.width + u], kWallX1);
    }
  }
}

TEST(Render, YawedCameraSeesWallAtDOverCosine) {
  // Camera rotated by alpha about the vertical: a pixel whose ray makes the angle beta with
  // the wall normal in the horizontal plane... planar depth = D / (n . R d) in general.
  const SynthScene room = EmptyRoom({10, 8, 6});
  const Camera cam = TestCamera();
  const double alpha = 0.3, D = 5.0;
  Rigid3d pose = FacingPlusX({5, 4, 3});
  pose.linear() =
      Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitZ()).toRotationMatrix() * pose.linear();
  const DepthImage depth = RenderDepth(room, cam, pose);
  int checked = 0;
  for (int v = 0; v < cam.height; v += 3) {
    for (int u = 0; u < cam.width; u += 3) {
      // Ray in camera: x = (u - cx)/f, y = (v - cy)/f, z = 1. Its horizontal angle to the
      // optical axis is atan(x) to the right (world -y side), so to the wall normal +x it is
      // alpha - atan(x); along the axis the ray advances cos(alpha - atan(x)) * hypot(1, x)
      // per unit of planar depth.
      const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
      const double advance = std::cos(alpha - std::atan(x)) * std::hypot(1.0, x);
      const double expected = D / advance;
      // Where it lands on the wall: skip rays that reach a side wall first.
      const double lateral = 4.0 + std::tan(alpha - std::atan(x)) * D;
      const double height = 3.0 - y * expected;
      if (lateral <= 0.01 || lateral >= 7.99 || height <= 0.01 || height >= 5.99) continue;
      ASSERT_NEAR(depth.at(u, v), expected, 2e-6 * expected) << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 20000);
}

TEST(Render, BoxInFrontOfWallFillsItsSilhouette) {
  SynthScene scene = EmptyRoom({10, 8, 6});
  OrientedBox box;
  box.center_in_world = {7.0, 4.1, 3.05};
  box.half_size_m = {0.5, 0.3, 0.25};
  scene.objects.push_back(box);
  const Camera cam = TestCamera();
  const RenderedView view = RenderView(scene, cam, FacingPlusX({5, 4, 3}));
  // Front face x = 6.5 at planar depth 1.5; y in [3.8, 4.4] maps to camera x = 4 - y,
  // z in [2.8, 3.3] to camera y = 3 - z. The box straddles the optical axis, so its
  // silhouette is exactly the front face.
  const double u0 = cam.cx + cam.fx * (4.0 - 4.4) / 1.5, u1 = cam.cx + cam.fx * (4.0 - 3.8) / 1.5;
  const double v0 = cam.cy + cam.fy * (3.0 - 3.3) / 1.5, v1 = cam.cy + cam.fy * (3.0 - 2.8) / 1.5;
  int inside = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const bool in = u > u0 && u < u1 && v > v0 && v < v1;
      inside += in;
      ASSERT_NEAR(view.depth.at(u, v), in ? 1.5f : 5.0f, 1e-6) << u << "," << v;
      ASSERT_EQ(view.surface_ids[v * cam.width + u], in ? kFirstObjectId : kWallX1);
    }
  }
  EXPECT_EQ(inside, 210 * 175);  // u in 180..389, v in 135..309
}

// ---- Slow reference: every face of every box as a bounded plane. ----
struct RefHit {
  double t = std::numeric_limits<double>::infinity();
  int id = kNoSurface;
};

// Faces of a box with rotation R and centre c: the ray hits face (axis k, side s) where
// the plane n.(p - c) = h_k is met and the other two local coordinates are within bounds.
void RefBox(const Eigen::Vector3d& c, const Eigen::Matrix3d& R, const Eigen::Vector3d& h,
            const Eigen::Vector3d& o, const Eigen::Vector3d& d, int id, bool from_inside,
            RefHit* best) {
  for (int k = 0; k < 3; ++k) {
    for (int s : {-1, 1}) {
      const Eigen::Vector3d n = s * R.col(k);
      const double denom = n.dot(d);
      if (std::abs(denom) < 1e-15) continue;
      const double t = (h[k] - n.dot(o - c)) / denom;
      if (t <= 1e-9 || t >= best->t) continue;
      if (!from_inside && denom >= 0) continue;  // entering faces face the ray
      const Eigen::Vector3d q = R.transpose() * (o + t * d - c);
      bool ok = true;
      for (int j = 0; j < 3; ++j) {
        if (j != k && std::abs(q[j]) > h[j] + 1e-12) ok = false;
      }
      if (ok) {
        best->t = t;
        best->id = id;
      }
    }
  }
}

RefHit ReferenceCast(const SynthScene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  RefHit best;
  const Eigen::Vector3d half = scene.room_size_m / 2;
  RefBox(half, Eigen::Matrix3d::Identity(), half, o, d, 0, true, &best);
  if (best.id != kNoSurface) {
    // Room face id from the hit point.
    const Eigen::Vector3d p = o + best.t * d;
    double err = 1e9;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(p[k]) < err) err = std::abs(p[k]), best.id = 2 * k;
      if (std::abs(p[k] - scene.room_size_m[k]) < err)
        err = std::abs(p[k] - scene.room_size_m[k]), best.id = 2 * k + 1;
    }
  }
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const auto& b = scene.objects[i];
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(b.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    RefBox(b.center_in_world, R, b.half_size_m, o, d, kFirstObjectId + static_cast<int>(i), false,
           &best);
  }
  return best;
}

bool InsideAnObject(const SynthScene& scene, const Eigen::Vector3d& p) {
  for (const auto& b : scene.objects) {
    const Eigen::Vector3d q =
        Eigen::AngleAxisd(-b.yaw_rad, Eigen::Vector3d::UnitZ()) * (p - b.center_in_world);
    if ((q.cwiseAbs() - b.half_size_m).maxCoeff() < 0.0) return true;
  }
  return false;
}

TEST(Render, MatchesSlowReferenceOnRandomRoomsAndPoses) {
  const Camera cam = TestCamera(96, 72);
  std::mt19937 rng(3);
  int compared = 0, same_id = 0;
  for (uint64_t seed = 0; seed < 6; ++seed) {
    const SynthScene scene = MakeRoomScene(seed);
    ASSERT_GT(scene.objects.size(), 4u);
    std::uniform_real_distribution<double> ux(0.3, scene.room_size_m.x() - 0.3),
        uy(0.3, scene.room_size_m.y() - 0.3), uz(0.2, scene.room_size_m.z() - 0.2),
        angle(-3.14159, 3.14159), pitch(-1.2, 1.2);
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d c(ux(rng), uy(rng), uz(rng));
      const double yaw = angle(rng), p = pitch(rng);
      const Rigid3d pose =
          LookAlong(c, {std::cos(p) * std::cos(yaw), std::cos(p) * std::sin(yaw), std::sin(p)});
      if (InsideAnObject(scene, c)) continue;
      const RenderedView view = RenderView(scene, cam, pose);
      for (int v = 0; v < cam.height; ++v) {
        for (int u = 0; u < cam.width; ++u) {
          const Eigen::Vector3d d =
              pose.linear() * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
          const RefHit ref = ReferenceCast(scene, c, d);
          const float got = view.depth.at(u, v);
          ASSERT_TRUE(std::isfinite(ref.t));  // the room is closed
          ASSERT_NEAR(got, ref.t, 1e-5 * ref.t) << "seed " << seed << " pixel " << u << "," << v;
          same_id += view.surface_ids[v * cam.width + u] == ref.id;
          ++compared;
        }
      }
    }
  }
  EXPECT_GT(compared, 100000);
  // Ids differ only on edges where two faces are at the same depth.
  EXPECT_GT(same_id, compared - compared / 200);
}

TEST(Render, ColourHasTextureInEveryRegion) {
  const SynthScene scene = MakeRoomScene(11);
  const Camera cam = TestCamera();
  TrajectoryOptions t;
  t.frames = 4;
  for (const Rigid3d& pose : Trajectory(scene, t)) {
    const io::ColorImage img = RenderColor(scene, cam, pose);
    ASSERT_EQ(img.width, 640);
    ASSERT_EQ(img.rgb.size(), 640u * 480 * 3);
    // Fraction of 16x16 blocks whose grey values vary (std > 2 levels).
    int textured = 0, blocks = 0;
    for (int by = 0; by < 480; by += 16) {
      for (int bx = 0; bx < 640; bx += 16) {
        double s = 0, s2 = 0;
        for (int v = by; v < by + 16; ++v) {
          for (int u = bx; u < bx + 16; ++u) {
            const uint8_t* p = img.pixel(u, v);
            const double g = (p[0] + p[1] + p[2]) / 3.0;
            s += g;
            s2 += g * g;
          }
        }
        const double mean = s / 256, var = s2 / 256 - mean * mean;
        textured += var > 4.0;
        ++blocks;
      }
    }
    EXPECT_GT(textured, blocks * 9 / 10);
  }
}

}  // namespace
}  // namespace gt::synth

// Camera: projection/back-projection round trips, cheirality, pixel area, resize rule.
#include "libgt/core/camera.h"

#include <gtest/gtest.h>

#include <random>

namespace gt {
namespace {

Camera ScanNetDepthCamera() {
  Camera c;
  c.width = 640;
  c.height = 480;
  c.fx = 577.59;
  c.fy = 578.73;
  c.cx = 319.5;
  c.cy = 239.5;
  return c;
}

TEST(Camera, UnprojectThenProjectReturnsPixel) {
  const Camera cam = ScanNetDepthCamera();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> du(-0.5, 639.49), dv(-0.5, 479.49), dz(0.1, 20.0);
  for (int i = 0; i < 1000; ++i) {
    const double u = du(rng), v = dv(rng), z = dz(rng);
    const auto x = cam.ImgFromCam(cam.CamFromImg(u, v, z));
    ASSERT_TRUE(x.has_value());
    EXPECT_NEAR(x->x(), u, 1e-9);
    EXPECT_NEAR(x->y(), v, 1e-9);
  }
}

TEST(Camera, PointsBehindOrAtTheCameraDoNotProject) {
  const Camera cam = ScanNetDepthCamera();
  EXPECT_FALSE(cam.ImgFromCam({0.1, 0.2, -1.0}).has_value());
  EXPECT_FALSE(cam.ImgFromCam({0.1, 0.2, 0.0}).has_value());
  EXPECT_FALSE(cam.ImgFromCam({0.1, 0.2, 0.05}, 0.1).has_value());
  EXPECT_FALSE(cam.ImgFromCam({0.1, 0.2, std::nan("")}).has_value());
}

TEST(Camera, PixelAreaBounds) {
  const Camera cam = ScanNetDepthCamera();
  EXPECT_TRUE(cam.InPixelArea(-0.5, -0.5));
  EXPECT_FALSE(cam.InPixelArea(-0.5001, 0));
  EXPECT_TRUE(cam.InPixelArea(639.49, 479.49));
  EXPECT_FALSE(cam.InPixelArea(639.5, 0));
  EXPECT_FALSE(cam.InPixelArea(0, 479.5));
}

TEST(Camera, ResizeKeepsPixelAreasAligned) {
  Camera c;
  c.width = 1296;
  c.height = 968;
  c.fx = 1170.0;
  c.fy = 1170.0;
  c.cx = 647.5;
  c.cy = 483.5;
  const Camera r = c.Resized(640, 480);
  const double sx = 640.0 / 1296, sy = 480.0 / 968;
  EXPECT_DOUBLE_EQ(r.fx, sx * 1170.0);
  EXPECT_DOUBLE_EQ(r.cx, sx * (647.5 + 0.5) - 0.5);
  EXPECT_DOUBLE_EQ(r.cy, sy * (483.5 + 0.5) - 0.5);
  // The image's left edge (-0.5) and right edge (W-0.5) map onto the new edges.
  const Eigen::Vector3d left = c.CamFromImg(-0.5, 100, 2.0);
  const Eigen::Vector3d right = c.CamFromImg(1295.5, 100, 2.0);
  EXPECT_NEAR(r.ImgFromCam(left)->x(), -0.5, 1e-9);
  EXPECT_NEAR(r.ImgFromCam(right)->x(), 639.5, 1e-9);
  // Resizing back gives the original K.
  const Camera back = r.Resized(1296, 968);
  EXPECT_NEAR(back.cx, c.cx, 1e-9);
  EXPECT_NEAR(back.fy, c.fy, 1e-9);
}

TEST(Camera, CheckRejectsBadIntrinsics) {
  std::string err;
  Camera c = ScanNetDepthCamera();
  EXPECT_TRUE(c.Check(&err));
  c.fx = 0;
  EXPECT_FALSE(c.Check(&err));
  EXPECT_NE(err.find("focal"), std::string::npos);
  c.fx = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(c.Check(&err));
  c = ScanNetDepthCamera();
  c.width = 0;
  EXPECT_FALSE(c.Check(&err));
}

TEST(Camera, HalfGridRaysPassThroughEvenPixels) {
  const Camera cam = ScanNetDepthCamera();
  const Camera half = cam.HalfGrid();
  EXPECT_EQ(half.width, 320);
  // Ray of half-grid pixel (u, v) equals the ray of full pixel (2u, 2v).
  const Eigen::Vector3d a = half.CamFromImg(37, 81, 1.0);
  const Eigen::Vector3d b = cam.CamFromImg(74, 162, 1.0);
  EXPECT_NEAR((a - b).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace gt

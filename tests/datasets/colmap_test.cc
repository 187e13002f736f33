// COLMAP sparse models (libgt/datasets/colmap.h): one tiny model written here in both COLMAP
// forms (binary byte by byte, text as COLMAP's model_converter writes it) gives the same
// cameras and poses; K follows occgt's pixel-centre convention (cx = COLMAP cx - 0.5);
// cut files, absurd counts and unsupported models are one clear error.
#include "libgt/datasets/colmap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "libgt/core/error.h"
#include "tests/support/test_support.h"

namespace gt::datasets {

namespace {
namespace fs = std::filesystem;

template <typename T>
void Put(std::string* out, T v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

const double kS = std::sqrt(0.5);  // qw = qz = sqrt(1/2): 90 degrees about z

// Two cameras (PINHOLE 64x48, SIMPLE_PINHOLE 40x30) and two images, the second with two 2D
// points (skipped by the reader).
std::string CamerasBin(int32_t second_model = 0) {
  std::string b;
  Put<uint64_t>(&b, 2);
  Put<int32_t>(&b, 1);
  Put<int32_t>(&b, 1);  // PINHOLE
  Put<uint64_t>(&b, 64);
  Put<uint64_t>(&b, 48);
  for (double p : {50.0, 52.0, 32.0, 24.0}) Put<double>(&b, p);
  Put<int32_t>(&b, 7);
  Put<int32_t>(&b, second_model);  // SIMPLE_PINHOLE (0), or SIMPLE_RADIAL (2): 4 params
  Put<uint64_t>(&b, 40);
  Put<uint64_t>(&b, 30);
  for (double p : {30.0, 20.0, 15.0}) Put<double>(&b, p);
  if (second_model == 2) Put<double>(&b, 0.01);
  return b;
}

std::string ImagesBin() {
  std::string b;
  Put<uint64_t>(&b, 2);
  Put<int32_t>(&b, 3);
  for (double v : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}) Put<double>(&b, v);
  Put<int32_t>(&b, 1);
  b += std::string("a/0001.jpg") + '\0';
  Put<uint64_t>(&b, 0);
  Put<int32_t>(&b, 9);
  for (double v : {kS, 0.0, 0.0, kS, 1.0, 2.0, 3.0}) Put<double>(&b, v);
  Put<int32_t>(&b, 7);
  b += std::string("0002.png") + '\0';
  Put<uint64_t>(&b, 2);
  for (int k = 0; k < 2; ++k) {
    Put<double>(&b, 10.5);
    Put<double>(&b, 20.5);
    Put<int64_t>(&b, k == 0 ? -1 : 42);
  }
  return b;
}

const char* kCamerasTxt =
    "# Camera list with one line of data per camera:\n"
    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
    "# Number of cameras: 2\n"
    "1 PINHOLE 64 48 50 52 32 24\n"
    "7 SIMPLE_PINHOLE 40 30 30 20 15\n";

std::string ImagesTxt() {
  char line[256];
  std::snprintf(line, sizeof(line), "9 %.17g 0 0 %.17g 1 2 3 7 0002.png\n", kS, kS);
  return std::string(
             "# Image list with two lines of data per image:\n"
             "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
             "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
             "3 1 0 0 0 0 0 0 1 a/0001.jpg\n"
             "\n") +
         line + "10.5 20.5 -1 10.5 20.5 42\n";
}

std::string WriteModel(const std::string& name, const std::string& cameras,
                       const std::string& images, const std::string& ext) {
  const fs::path dir = test::ScratchDir("colmap_" + name);
  std::ofstream((dir / ("cameras." + ext)).string(), std::ios::binary) << cameras;
  std::ofstream((dir / ("images." + ext)).string(), std::ios::binary) << images;
  return dir.string();
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void CheckModel(const ColmapModel& m) {
  ASSERT_EQ(m.cameras.size(), 2u);
  ASSERT_EQ(m.images.size(), 2u);
  const Camera c1 = ColmapPinholeCamera(m.cameras.at(1), m.cameras_path);
  EXPECT_EQ(c1.width, 64);
  EXPECT_EQ(c1.height, 48);
  EXPECT_DOUBLE_EQ(c1.fx, 50);
  EXPECT_DOUBLE_EQ(c1.fy, 52);
  EXPECT_DOUBLE_EQ(c1.cx, 31.5);  // COLMAP's centre of the top-left pixel is (0.5, 0.5)
  EXPECT_DOUBLE_EQ(c1.cy, 23.5);
  const Camera c7 = ColmapPinholeCamera(m.cameras.at(7), m.cameras_path);
  EXPECT_EQ(c7.width, 40);
  EXPECT_DOUBLE_EQ(c7.fx, 30);
  EXPECT_DOUBLE_EQ(c7.fy, 30);
  EXPECT_DOUBLE_EQ(c7.cx, 19.5);
  EXPECT_DOUBLE_EQ(c7.cy, 14.5);

  EXPECT_EQ(m.images[0].id, 3);
  EXPECT_EQ(m.images[0].name, "a/0001.jpg");
  EXPECT_EQ(m.images[0].camera_id, 1);
  EXPECT_TRUE(ColmapWorldFromCam(m.images[0]).isApprox(Rigid3d::Identity()));
  const ColmapImage& im = m.images[1];
  EXPECT_EQ(im.id, 9);
  EXPECT_EQ(im.name, "0002.png");
  EXPECT_EQ(im.camera_id, 7);
  EXPECT_FALSE(ColmapPoseDefect(im).has_value());
  // cam_from_world: R = 90 degrees about z (x -> y), t = (1, 2, 3). The camera centre in
  // the world is -R^T t = -(2, -1, 3); the world x axis is the camera's y axis.
  const Rigid3d world_from_cam = ColmapWorldFromCam(im);
  EXPECT_TRUE(world_from_cam.translation().isApprox(Eigen::Vector3d(-2, 1, -3), 1e-12));
  const Eigen::Vector3d x_in_cam =
      world_from_cam.inverse(Eigen::Isometry).linear() * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(x_in_cam.isApprox(Eigen::Vector3d::UnitY(), 1e-12));
}

TEST(Colmap, BinaryAndTextGiveTheSameModel) {
  const ColmapModel bin = ReadColmapModel(WriteModel("bin", CamerasBin(), ImagesBin(), "bin"));
  EXPECT_NE(bin.images_path.find("images.bin"), std::string::npos);
  CheckModel(bin);
  const ColmapModel txt = ReadColmapModel(WriteModel("txt", kCamerasTxt, ImagesTxt(), "txt"));
  EXPECT_NE(txt.images_path.find("images.txt"), std::string::npos);
  CheckModel(txt);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(bin.images[i].qvec_wxyz, txt.images[i].qvec_wxyz);
    EXPECT_EQ(bin.images[i].tvec, txt.images[i].tvec);
  }
}

TEST(Colmap, EveryCutOfABinaryFileIsOneError) {
  for (const bool cameras : {true, false}) {
    const std::string whole = cameras ? CamerasBin() : ImagesBin();
    for (size_t n = 0; n < whole.size(); ++n) {
      const std::string cut = whole.substr(0, n);
      const std::string e = ErrorOf([&] {
        if (cameras) {
          ParseColmapCamerasBinary(cut, "cameras.bin");
        } else {
          ParseColmapImagesBinary(cut, "images.bin");
        }
      });
      ASSERT_EQ(e.rfind(cameras ? "cameras.bin: " : "images.bin: ", 0), 0u) << n << ": " << e;
    }
  }
  EXPECT_EQ(ErrorOf([] { ParseColmapImagesBinary(ImagesBin() + "x", "images.bin"); }),
            "images.bin: 1 bytes after the last image (not an images.bin?)");
}

TEST(Colmap, AbsurdCountsAreRefusedBeforeAllocating) {
  std::string b = ImagesBin();
  const uint64_t huge = uint64_t{1} << 60;
  std::memcpy(b.data(), &huge, 8);
  EXPECT_EQ(ErrorOf([&] { ParseColmapImagesBinary(b, "images.bin"); }),
            "images.bin: image count: 1152921504606846976, but the file holds at most 2 records "
            "of 73 bytes after it (truncated file?)");
  // num_points2D of the second image.
  b = ImagesBin();
  const size_t at = 8 + 64 + 11 + 8 + 64 + 9;
  std::memcpy(b.data() + at, &huge, 8);
  EXPECT_EQ(ErrorOf([&] { ParseColmapImagesBinary(b, "images.bin"); }),
            "images.bin: image 1 (0002.png) num_points2D: 1152921504606846976, but only 48 bytes "
            "are left (truncated file?)");
  std::string c = CamerasBin();
  const uint64_t wide = 100000;
  std::memcpy(c.data() + 8 + 8, &wide, 8);
  EXPECT_EQ(ErrorOf([&] { ParseColmapCamerasBinary(c, "cameras.bin"); }),
            "cameras.bin: camera 0 width: 65537, expected an image size in 1..65536");
}

TEST(Colmap, DistortedModelsAreNamed) {
  const ColmapModel m = ReadColmapModel(WriteModel("radial", CamerasBin(2), ImagesBin(), "bin"));
  const std::string e = ErrorOf([&] { ColmapPinholeCamera(m.cameras.at(7), m.cameras_path); });
  EXPECT_NE(e.find("cameras.bin: camera 7: model SIMPLE_RADIAL is not supported (expected "
                   "PINHOLE or SIMPLE_PINHOLE"),
            std::string::npos)
      << e;
  EXPECT_EQ(ErrorOf([] { ParseColmapCamerasText("1 PINHOLE 64 48 50 52 32\n", "cameras.txt"); }),
            "cameras.txt:1: model PINHOLE has 4 parameters, found 3");
  EXPECT_EQ(ErrorOf([] { ParseColmapCamerasText("1 PINHOL 64 48 1 2 3 4\n", "cameras.txt"); }),
            "cameras.txt:1: MODEL: unknown COLMAP camera model 'PINHOL'");
  EXPECT_EQ(ErrorOf([] { ParseColmapImagesText("3 1 0 0 0 0 0 0 1\n", "images.txt"); }),
            "images.txt:1: expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (10 fields, a "
            "name without spaces), found 9 fields");
  // An image whose camera is not in cameras.txt.
  const std::string dir = WriteModel("nocam", "1 PINHOLE 64 48 50 52 32 24\n", ImagesTxt(), "txt");
  EXPECT_NE(ErrorOf([&] {
              ReadColmapModel(dir);
            }).find("images.txt: image 9 (0002.png): camera_id 7 is not in "),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ReadColmapModel("/nonexistent"); }).find("no COLMAP model"),
            std::string::npos);
  // A comma inside a field is not a separator: the field is refused, not split into two
  // numbers (a lone "," read past the fields and gave a pose of other numbers).
  EXPECT_EQ(ErrorOf([] { ParseColmapImagesText("3 1 0 0 0 , 0 0 1 a.jpg\n", "images.txt"); }),
            "images.txt:1: field 6: expected one number, found ','");
  EXPECT_EQ(ErrorOf([] { ParseColmapImagesText("3 1 0 0 0 0.5,0.5 0 0 1 a.jpg\n", "i.txt"); }),
            "i.txt:1: field 6: expected one number, found '0.5,0.5'");
  EXPECT_EQ(ErrorOf([] { ParseColmapCamerasText("1 PINHOLE 64 48 50 52 , 24\n", "c.txt"); }),
            "c.txt:1: field 7: expected one number, found ','");
}

// COLMAP writes a POINTS2D line (possibly empty) after every image line; a model written
// without them has the images' lines one after the other, and every one of them is read.
TEST(Colmap, ImagesWithoutPointLinesAreAllRead) {
  const std::string with_points =
      "1 1 0 0 0 0 0 0 1 a.jpg\n"
      "\n"
      "2 1 0 0 0 1 0 0 1 b.jpg\n"
      "1.5 2.5 -1 3 4 7\n"
      "3 1 0 0 0 2 0 0 1 c.jpg\n"
      "\n";
  const std::string without =
      "# no POINTS2D lines\n"
      "1 1 0 0 0 0 0 0 1 a.jpg\n"
      "2 1 0 0 0 1 0 0 1 b.jpg\n"
      "3 1 0 0 0 2 0 0 1 c.jpg\n"
      "4 1 0 0 0 3 0 0 1 d.jpg\n";
  const std::vector<ColmapImage> a = ParseColmapImagesText(with_points, "images.txt");
  const std::vector<ColmapImage> b = ParseColmapImagesText(without, "images.txt");
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 4u);
  for (size_t k = 0; k < b.size(); ++k) {
    EXPECT_EQ(b[k].id, static_cast<int64_t>(k + 1));
    EXPECT_EQ(b[k].name, std::string(1, static_cast<char>('a' + k)) + ".jpg");
    EXPECT_EQ(b[k].tvec.x(), static_cast<double>(k));
    if (k < a.size()) EXPECT_EQ(a[k].name, b[k].name);
  }
  // A damaged POINTS2D line (not triples) is not taken for an image line silently.
  EXPECT_EQ(ErrorOf([] { ParseColmapImagesText("1 1 0 0 0 0 0 0 1 a.jpg\n1.5 2.5\n", "i.txt"); }),
            "i.txt:2: expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (10 fields, a "
            "name without spaces), found 2 fields");
}

// An image id given twice names both lines of images.txt (it named the file only).
TEST(Colmap, RepeatedImageIdNamesBothLines) {
  const std::string dir = WriteModel("repeated_id", "1 PINHOLE 64 48 50 50 32 24\n",
                                     "# images\n"
                                     "1 1 0 0 0 0 0 0 1 a.jpg\n"
                                     "\n"
                                     "2 1 0 0 0 1 0 0 1 b.jpg\n"
                                     "\n"
                                     "1 1 0 0 0 2 0 0 1 c.jpg\n"
                                     "\n",
                                     "txt");
  EXPECT_EQ(ErrorOf([&] { ReadColmapModel(dir); }),
            dir + "/images.txt:6: image id 1 repeats line 2");
}

}  // namespace
}  // namespace gt::datasets

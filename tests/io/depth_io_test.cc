// Depth and image files: EXR channel matching (files written here with OpenEXR), invalid
// markers, png16 scale and invalid value, .npy depth, size checks, image headers, and
// colour resizing against a slow bilinear reference.
#include "libgt/io/depth_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"
#include "tests/support/test_support.h"

namespace gt::io {
namespace {
namespace fs = std::filesystem;

// Writes a w x h float EXR whose channel c holds value(c, u, v).
void WriteExr(const std::string& path, int w, int h, const std::vector<std::string>& channels,
              float (*value)(size_t, int, int)) {
  Imf::Header header(w, h);
  for (const auto& c : channels) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  std::vector<std::vector<float>> planes(channels.size(), std::vector<float>(size_t(w) * h));
  Imf::FrameBuffer fb;
  for (size_t c = 0; c < channels.size(); ++c) {
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) planes[c][size_t(v) * w + u] = value(c, u, v);
    }
    fb.insert(channels[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[c].data()),
                                      sizeof(float), sizeof(float) * w));
  }
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(fb);
  file.writePixels(h);
}

// Channel c holds 10 * (c + 1) + u + 0.5 * v, except a few markers in channel 0 and 1.
float ChannelValue(size_t c, int u, int v) {
  if (u == 0 && v == 0) return 1e10f;  // Blender background
  if (u == 1 && v == 0) return std::numeric_limits<float>::infinity();
  if (u == 2 && v == 0) return std::numeric_limits<float>::quiet_NaN();
  if (u == 3 && v == 0) return -1.0f;
  return 10.0f * (c + 1) + u + 0.5f * v;
}

DepthSource Exr(const std::string& path, const std::string& channel) {
  DepthSource s;
  s.path = path;
  s.format = DepthFormat::kExr;
  s.exr_channel = channel;
  return s;
}

TEST(DepthExr, ChannelMatchingExactSuffixAndAuto) {
  const std::string dir = test::ScratchDir("exr");
  // EXR stores channels sorted by name.
  const std::vector<std::string> ch = {"View Layer.Combined.R", "View Layer.Depth.Z", "Z"};
  WriteExr(dir + "/a.exr", 8, 6, ch, ChannelValue);
  auto value_of_channel = [&](const std::string& wanted) {
    const DepthImage d = ReadDepth(Exr(dir + "/a.exr", wanted), 8, 6);
    return d.at(5, 4) - 5.0f - 2.0f;  // 10 * (c + 1)
  };
  EXPECT_FLOAT_EQ(value_of_channel("Z"), 30.0f);                   // exact beats suffix
  EXPECT_FLOAT_EQ(value_of_channel("Depth.Z"), 20.0f);             // suffix
  EXPECT_FLOAT_EQ(value_of_channel("View Layer.Depth.Z"), 20.0f);  // exact
  EXPECT_FLOAT_EQ(value_of_channel("R"), 10.0f);                   // suffix ".R"
  EXPECT_FLOAT_EQ(value_of_channel(""), 30.0f);                    // auto: "Z" first
  // Auto with only a Blender depth channel and a colour channel.
  WriteExr(dir + "/b.exr", 8, 6, {"RenderLayer.Depth.Z", "RenderLayer.Combined.G"}, ChannelValue);
  const DepthImage b = ReadDepth(Exr(dir + "/b.exr", ""));
  EXPECT_FLOAT_EQ(b.at(5, 4), 10.0f + 5.0f + 2.0f);  // Depth.Z holds the c = 0 values
}

TEST(DepthExr, MarkersBecomeZero) {
  const std::string dir = test::ScratchDir("exr_markers");
  WriteExr(dir + "/a.exr", 8, 6, {"Z"}, ChannelValue);
  const DepthImage d = ReadDepth(Exr(dir + "/a.exr", ""));
  ASSERT_EQ(d.width, 8);
  ASSERT_EQ(d.height, 6);
  for (int u = 0; u < 4; ++u) EXPECT_EQ(d.at(u, 0), 0.0f) << u;
  EXPECT_FLOAT_EQ(d.at(4, 0), 14.0f);
  EXPECT_FLOAT_EQ(d.at(7, 5), 19.5f);
}

TEST(DepthExr, UnknownChannelListsChannelsAndNamesFile) {
  const std::string dir = test::ScratchDir("exr_unknown");
  WriteExr(dir + "/a.exr", 4, 4, {"Depth.Z", "Combined.R"}, ChannelValue);
  try {
    ReadDepth(Exr(dir + "/a.exr", "Mist"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/a.exr");
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'Mist' not found"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'Combined.R'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'Depth.Z'"), std::string::npos) << msg;
  }
  WriteExr(dir + "/c.exr", 4, 4, {"R", "G"}, ChannelValue);
  EXPECT_THROW(ReadDepth(Exr(dir + "/c.exr", "")), InputError);  // no Z/Y/V, two channels
  WriteFileAtomic(dir + "/junk.exr", "not an exr");
  try {
    ReadDepth(Exr(dir + "/junk.exr", ""));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/junk.exr");
  }
}

TEST(DepthPng16, ScaleInvalidValueAndWrongSize) {
  const std::string dir = test::ScratchDir("png16");
  cv::Mat raw(5, 7, CV_16UC1);
  std::mt19937 rng(3);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u) raw.at<uint16_t>(v, u) = static_cast<uint16_t>(rng() % 65536);
  }
  raw.at<uint16_t>(0, 0) = 0;
  raw.at<uint16_t>(0, 1) = 65535;
  raw.at<uint16_t>(0, 2) = 4000;
  ASSERT_TRUE(cv::imwrite(dir + "/d.png", raw));
  DepthSource s;
  s.path = dir + "/d.png";
  s.format = DepthFormat::kPng16;
  s.scale_m_per_unit = 0.001;
  s.invalid_value = 65535;
  const DepthImage d = ReadDepth(s, 7, 5);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u) {
      const uint16_t r = raw.at<uint16_t>(v, u);
      const float expected = (r == 0 || r == 65535) ? 0.0f : static_cast<float>(r * 0.001);
      EXPECT_EQ(d.at(u, v), expected) << u << "," << v;
    }
  }
  EXPECT_FLOAT_EQ(d.at(2, 0), 4.0f);
  try {
    ReadDepth(s, 640, 480);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/d.png: depth is 7x5, expected 640x480");
  }
  // An 8-bit PNG is not depth.
  ASSERT_TRUE(cv::imwrite(dir + "/g.png", cv::Mat(5, 7, CV_8UC1, cv::Scalar(9))));
  s.path = dir + "/g.png";
  EXPECT_THROW(ReadDepth(s), InputError);
  s.path = dir + "/missing.png";
  try {
    ReadDepth(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/missing.png");
  }
}

TEST(DepthNpy, Float32WithMarkersAndBadDtype) {
  const std::string dir = test::ScratchDir("npy_depth");
  std::vector<float> v = {1.5f,
                          0.0f,
                          -2.0f,
                          std::numeric_limits<float>::quiet_NaN(),
                          std::numeric_limits<float>::infinity(),
                          2e9f};
  WriteFileAtomic(dir + "/d.npy", EncodeNpy("<f4", {2, 3}, v.data(), v.size() * 4));
  DepthSource s;
  s.path = dir + "/d.npy";
  const DepthImage d = ReadDepth(s, 3, 2);
  EXPECT_EQ(d.values_m, (std::vector<float>{1.5f, 0, 0, 0, 0, 0}));
  std::vector<int32_t> ints(6, 1);
  WriteFileAtomic(dir + "/i.npy", EncodeNpy("<i4", {2, 3}, ints.data(), ints.size() * 4));
  s.path = dir + "/i.npy";
  try {
    ReadDepth(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/i.npy");
  }
  WriteFileAtomic(dir + "/v.npy", EncodeNpy("<f4", {6}, v.data(), v.size() * 4));
  s.path = dir + "/v.npy";
  EXPECT_THROW(ReadDepth(s), InputError);
}

TEST(ImageSize, HeadersMatchDecodedSize) {
  const std::string dir = test::ScratchDir("imgsize");
  const cv::Mat img(37, 53, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const char* name : {"a.png", "a.jpg", "a.pgm"}) {
    const std::string p = dir + "/" + name;
    ASSERT_TRUE(cv::imwrite(p, std::string(name) == "a.pgm" ? cv::Mat(37, 53, CV_16UC1) : img));
    const ImageSize s = ReadImageSize(p);
    EXPECT_EQ(s.width, 53) << name;
    EXPECT_EQ(s.height, 37) << name;
  }
  const std::string sample = test::SharedData("scannet_posed_color/scene_sample/color/0048.png");
  if (!sample.empty()) {
    const cv::Mat m = cv::imread(sample);
    const ImageSize s = ReadImageSize(sample);
    EXPECT_EQ(s.width, m.cols);
    EXPECT_EQ(s.height, m.rows);
  }
  EXPECT_THROW(ReadImageSize(dir + "/none.png"), InputError);
}

// The in-memory variant gives the same sizes; damaged, cut and unknown files are one
// InputError naming the file (nothing is decoded).
TEST(ImageSize, FromMemoryAndBadHeaders) {
  const std::string dir = test::ScratchDir("imgsize_mem");
  const cv::Mat img(21, 34, CV_8UC3, cv::Scalar(1, 2, 3));
  for (const char* name : {"b.png", "b.jpg", "b.ppm"}) {
    const std::string p = dir + "/" + name;
    ASSERT_TRUE(cv::imwrite(p, img));
    const ImageSize s = DecodeImageSize(ReadFileBytes(p), p);
    EXPECT_EQ(s.width, 34) << name;
    EXPECT_EQ(s.height, 21) << name;
  }
  // Netpbm with a comment between the tokens.
  const ImageSize pgm = DecodeImageSize("P5\n# made by hand\n7 5\n255\n", "c.pgm");
  EXPECT_EQ(pgm.width, 7);
  EXPECT_EQ(pgm.height, 5);
  const std::string png = ReadFileBytes(dir + "/b.png");
  const std::string jpg = ReadFileBytes(dir + "/b.jpg");
  auto expect_error = [](const std::string& bytes, const std::string& path, const char* what) {
    try {
      DecodeImageSize(bytes, path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_error(png.substr(0, 20), "cut.png", "IHDR");
  std::string zero = png;
  for (int i = 16; i < 20; ++i) zero[i] = 0;  // width 0
  expect_error(zero, "zero.png", "IHDR");
  expect_error(jpg.substr(0, 40), "cut.jpg", "SOF");
  expect_error("BM\x36\0\0\0", "a.bmp", "unsupported image format");
  expect_error("", "empty.png", "unsupported image format");
  expect_error("P6\n-3 4\n255\n", "neg.ppm", "unsupported image format");
  // The same through the file reader.
  WriteFileAtomic(dir + "/cut.jpg", jpg.substr(0, 40));
  EXPECT_THROW(ReadImageSize(dir + "/cut.jpg"), InputError);
}

// Bilinear sample of an RGB image at continuous (x, y) under the pixel-centre convention,
// clamping at the borders.
double BilinearReference(const ColorImage& im, double x, double y, int c) {
  auto at = [&](int u, int v) {
    u = std::clamp(u, 0, im.width - 1);
    v = std::clamp(v, 0, im.height - 1);
    return static_cast<double>(im.pixel(u, v)[c]);
  };
  const int u0 = static_cast<int>(std::floor(x)), v0 = static_cast<int>(std::floor(y));
  const double a = x - u0, b = y - v0;
  return (1 - a) * (1 - b) * at(u0, v0) + a * (1 - b) * at(u0 + 1, v0) +
         (1 - a) * b * at(u0, v0 + 1) + a * b * at(u0 + 1, v0 + 1);
}

TEST(ColorImage, ReadsRgbOrderAndResizesBilinearWithRescaledK) {
  const std::string dir = test::ScratchDir("color");
  cv::Mat bgr(30, 40, CV_8UC3);
  std::mt19937 rng(5);
  for (int v = 0; v < 30; ++v) {
    for (int u = 0; u < 40; ++u) {
      bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(rng() % 256, rng() % 256, rng() % 256);
    }
  }
  ASSERT_TRUE(cv::imwrite(dir + "/c.png", bgr));
  const ColorImage im = ReadColor(dir + "/c.png");
  ASSERT_EQ(im.width, 40);
  ASSERT_EQ(im.height, 30);
  EXPECT_EQ(im.pixel(7, 3)[0], bgr.at<cv::Vec3b>(3, 7)[2]);  // R
  EXPECT_EQ(im.pixel(7, 3)[2], bgr.at<cv::Vec3b>(3, 7)[0]);  // B

  Camera cam;
  cam.width = 40, cam.height = 30, cam.fx = 50, cam.fy = 40, cam.cx = 19.5, cam.cy = 14.5;
  Camera resized;
  const ColorImage up = ReadColorResized(dir + "/c.png", cam, 100, 75, &resized);
  ASSERT_EQ(up.width, 100);
  ASSERT_EQ(up.height, 75);
  EXPECT_DOUBLE_EQ(resized.fx, 125.0);
  EXPECT_DOUBLE_EQ(resized.cx, 2.5 * 20.0 - 0.5);
  EXPECT_DOUBLE_EQ(resized.fy, 100.0);
  // Each target pixel u' samples the source at (u' + 0.5) / s - 0.5 (pixel areas aligned).
  int worst = 0;
  for (int v = 0; v < 75; ++v) {
    for (int u = 0; u < 100; ++u) {
      for (int c = 0; c < 3; ++c) {
        const double ref = BilinearReference(im, (u + 0.5) / 2.5 - 0.5, (v + 0.5) / 2.5 - 0.5, c);
        worst = std::max(worst, static_cast<int>(std::abs(up.pixel(u, v)[c] - ref) + 0.5));
      }
    }
  }
  EXPECT_LE(worst, 1);  // OpenCV's fixed-point weights round within one grey level
  try {
    Camera wrong = cam;
    wrong.width = 41;
    ReadColorResized(dir + "/c.png", wrong, 20, 15);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir + "/c.png");
  }
}

}  // namespace
}  // namespace gt::io

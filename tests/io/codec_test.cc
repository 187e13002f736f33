// Image codecs (libgt/io/codec.h) against independent implementations: OpenCV's imgcodecs
// (linked by the tests only) decodes and encodes the same images, and PNG layouts OpenCV
// cannot write (palette, tRNS, 2/4-bit grey, grey+alpha, Adam7) are written here with
// libpng's own API and compared with closed-form pixels. Netpbm files are written by hand.
#include "libgt/io/codec.h"

#include <gtest/gtest.h>
#include <png.h>
#include <zlib.h>

#include <csetjmp>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

// clang-format off
#include <jpeglib.h>
// clang-format on

#include "libgt/core/error.h"

namespace gt::io {
namespace {

cv::Mat RandomMat(int rows, int cols, int type, uint32_t seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  if (CV_MAT_DEPTH(type) == CV_16U) {
    rng.fill(m, cv::RNG::UNIFORM, 0, 65536);
  } else {
    rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  }
  return m;
}

// A smooth colour image (JPEG-friendly): gradients plus a disc.
cv::Mat SmoothBgr(int rows, int cols) {
  cv::Mat m(rows, cols, CV_8UC3);
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) {
      const bool disc = (u - cols / 2) * (u - cols / 2) + (v - rows / 2) * (v - rows / 2) < 100;
      m.at<cv::Vec3b>(v, u) =
          cv::Vec3b(static_cast<uint8_t>(u * 255 / cols), static_cast<uint8_t>(v * 255 / rows),
                    static_cast<uint8_t>(disc ? 220 : 40));
    }
  }
  return m;
}

std::string ToString(const std::vector<uchar>& b) { return std::string(b.begin(), b.end()); }

bool SameMat(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  return cv::norm(a, b, cv::NORM_INF) == 0;
}

cv::Mat SwapRb(const cv::Mat& m) {
  cv::Mat out = m.clone();
  std::vector<cv::Mat> planes;
  cv::split(m, planes);
  std::swap(planes[0], planes[2]);
  cv::merge(planes, out);
  return out;
}

// ---- a classic-API libpng writer for the layouts OpenCV cannot write -------------------
struct PngOut {
  std::string bytes;
};
void Append(png_structp png, png_bytep data, size_t n) {
  static_cast<PngOut*>(png_get_io_ptr(png))->bytes.append(reinterpret_cast<char*>(data), n);
}
void NoFlush(png_structp) {}

// rows: packed samples as PNG stores them (bit depth `depth`, `colour_type`).
bool WritePngRaw(PngOut* out, int width, int height, int depth, int colour_type, bool adam7,
                 const std::vector<png_color>* palette, const std::vector<png_byte>* trns,
                 png_bytepp rows) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, out, Append, NoFlush);
  png_set_IHDR(png, info, width, height, depth, colour_type,
               adam7 ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (palette) png_set_PLTE(png, info, palette->data(), static_cast<int>(palette->size()));
  if (trns) png_set_tRNS(png, info, trns->data(), static_cast<int>(trns->size()), nullptr);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

std::string WritePng(int width, int height, int depth, int colour_type, bool adam7,
                     std::vector<std::vector<png_byte>> rows,
                     const std::vector<png_color>* palette = nullptr,
                     const std::vector<png_byte>* trns = nullptr) {
  std::vector<png_bytep> ptrs;
  for (auto& r : rows) ptrs.push_back(r.data());
  PngOut out;
  EXPECT_TRUE(
      WritePngRaw(&out, width, height, depth, colour_type, adam7, palette, trns, ptrs.data()));
  return out.bytes;
}

// Packs `values` (each < 2^bits) into a PNG row of `bits`-bit samples, MSB first.
std::vector<png_byte> Pack(const std::vector<int>& values, int bits) {
  std::vector<png_byte> row((values.size() * bits + 7) / 8, 0);
  for (size_t i = 0; i < values.size(); ++i) {
    const size_t bit = i * bits;
    row[bit / 8] |= static_cast<png_byte>(values[i] << (8 - bits - bit % 8));
  }
  return row;
}

// ---- PNG ---------------------------------------------------------------------------------

TEST(Png, RoundTripsEveryEncodableLayoutExactly) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3}) {
    for (int level : {0, 1, 6, 9}) {
      const cv::Mat m = RandomMat(17, 23, type, 7 + type + level);
      const std::string png = EncodePngBytes(m, ChannelOrder::kBgr, level, "t");
      EXPECT_TRUE(SameMat(DecodeImageBytes(png, ChannelOrder::kBgr, "t"), m)) << type;
      // OpenCV reads our file as we wrote it (BGR in, BGR out).
      const cv::Mat cv_read =
          cv::imdecode(std::vector<uchar>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
      EXPECT_TRUE(SameMat(cv_read, m)) << type << " level " << level;
    }
  }
}

// The filter byte of every row of a PNG (8-bit, not interlaced): its IDAT data inflated.
std::vector<int> RowFilters(const std::string& png, int rows, size_t row_bytes) {
  std::string idat;
  for (size_t p = 8; p + 12 <= png.size();) {
    const auto* b = reinterpret_cast<const unsigned char*>(png.data() + p);
    const size_t length = (size_t{b[0]} << 24) | (size_t{b[1]} << 16) | (size_t{b[2]} << 8) | b[3];
    if (png.compare(p + 4, 4, "IDAT") == 0) idat += png.substr(p + 8, length);
    p += 12 + length;
  }
  std::vector<unsigned char> raw(static_cast<size_t>(rows) * (row_bytes + 1));
  uLongf size = raw.size();
  EXPECT_EQ(uncompress(raw.data(), &size, reinterpret_cast<const Bytef*>(idat.data()), idat.size()),
            Z_OK);
  EXPECT_EQ(size, raw.size());
  std::vector<int> filters;
  for (int r = 0; r < rows; ++r) filters.push_back(raw[r * (row_bytes + 1)]);
  return filters;
}

TEST(Png, SubFilterOnEveryRowRoundTripsExactly) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4}) {
    for (int level : {0, 1, 9}) {
      const cv::Mat m = RandomMat(17, 23, type, 11 + type + level);
      const std::string png = EncodePngBytes(m, ChannelOrder::kBgr, level, "t", PngFilter::kSub);
      EXPECT_TRUE(SameMat(DecodeImageBytes(png, ChannelOrder::kBgr, "t"), m)) << type;
      const cv::Mat cv_read =
          cv::imdecode(std::vector<uchar>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
      EXPECT_TRUE(SameMat(cv_read, m)) << type << " level " << level;
      EXPECT_EQ(RowFilters(png, m.rows, m.cols * m.elemSize()), std::vector<int>(m.rows, 1))
          << type << " level " << level;
    }
  }
  // The adaptive default picks other filters on a smooth image (so the option matters).
  const cv::Mat smooth = SmoothBgr(32, 48);
  const std::vector<int> adaptive =
      RowFilters(EncodePngBytes(smooth, ChannelOrder::kBgr, 1, "t"), 32, 48 * 3);
  EXPECT_NE(adaptive, std::vector<int>(32, 1));
}

TEST(Png, ChannelOrderSwapsRedAndBlueOnly) {
  const cv::Mat bgr = RandomMat(9, 11, CV_8UC3, 3);
  const std::string png = EncodePngBytes(bgr, ChannelOrder::kBgr, 1, "t");
  EXPECT_TRUE(SameMat(DecodeImageBytes(png, ChannelOrder::kRgb, "t"), SwapRb(bgr)));
  // Writing in RGB order what is RGB gives the same file as writing BGR in BGR order.
  EXPECT_EQ(EncodePngBytes(SwapRb(bgr), ChannelOrder::kRgb, 1, "t"), png);
  const cv::Mat grey = RandomMat(9, 11, CV_8UC1, 4);
  EXPECT_TRUE(SameMat(
      DecodeImageBytes(EncodePngBytes(grey, ChannelOrder::kRgb, 1, "t"), ChannelOrder::kBgr, "t"),
      grey));
}

TEST(Png, DecodesWhatOpenCvWritesLikeOpenCv) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    const cv::Mat m = RandomMat(31, 19, type, 11 + type);
    std::vector<uchar> buf;
    ASSERT_TRUE(cv::imencode(".png", m, buf));
    const cv::Mat ours = DecodeImageBytes(ToString(buf), ChannelOrder::kBgr, "t");
    EXPECT_TRUE(SameMat(ours, cv::imdecode(buf, cv::IMREAD_UNCHANGED))) << type;
    EXPECT_TRUE(SameMat(ours, m)) << type;
  }
  // 1-bit grey (OpenCV's bilevel option): 0 and 255.
  cv::Mat bits(8, 13, CV_8UC1);
  for (int v = 0; v < bits.rows; ++v) {
    for (int u = 0; u < bits.cols; ++u)
      bits.at<uint8_t>(v, u) = ((u * 7 + v * 3) % 5 < 2) ? 255 : 0;
  }
  std::vector<uchar> buf;
  ASSERT_TRUE(cv::imencode(".png", bits, buf, {cv::IMWRITE_PNG_BILEVEL, 1}));
  EXPECT_TRUE(SameMat(DecodeImageBytes(ToString(buf), ChannelOrder::kRgb, "t"), bits));
}

TEST(Png, LowBitGreyExpandsToFullRange) {
  for (int bits : {1, 2, 4}) {
    const int levels = 1 << bits;
    std::vector<std::vector<png_byte>> rows;
    cv::Mat expected(3, 10, CV_8UC1);
    for (int v = 0; v < 3; ++v) {
      std::vector<int> values;
      for (int u = 0; u < 10; ++u) {
        values.push_back((u + v) % levels);
        expected.at<uint8_t>(v, u) = static_cast<uint8_t>((u + v) % levels * 255 / (levels - 1));
      }
      rows.push_back(Pack(values, bits));
    }
    const std::string png = WritePng(10, 3, bits, PNG_COLOR_TYPE_GRAY, false, rows);
    EXPECT_TRUE(SameMat(DecodeImageBytes(png, ChannelOrder::kRgb, "t"), expected)) << bits;
  }
}

TEST(Png, PaletteBecomesRgbOrRgbaWithTrns) {
  const std::vector<png_color> palette = {{10, 20, 30}, {200, 100, 50}, {0, 255, 7}};
  const std::vector<png_byte> trns = {255, 128};  // entry 2 stays opaque
  std::vector<std::vector<png_byte>> rows;
  for (int v = 0; v < 4; ++v) {
    std::vector<int> idx;
    for (int u = 0; u < 6; ++u) idx.push_back((u + 2 * v) % 3);
    rows.push_back(Pack(idx, 4));
  }
  const std::string plain = WritePng(6, 4, 4, PNG_COLOR_TYPE_PALETTE, false, rows, &palette);
  const std::string alpha = WritePng(6, 4, 4, PNG_COLOR_TYPE_PALETTE, false, rows, &palette, &trns);
  const cv::Mat rgb = DecodeImageBytes(plain, ChannelOrder::kRgb, "t");
  const cv::Mat bgr = DecodeImageBytes(plain, ChannelOrder::kBgr, "t");
  const cv::Mat rgba = DecodeImageBytes(alpha, ChannelOrder::kRgb, "t");
  ASSERT_EQ(rgb.type(), CV_8UC3);
  ASSERT_EQ(rgba.type(), CV_8UC4);
  for (int v = 0; v < 4; ++v) {
    for (int u = 0; u < 6; ++u) {
      const int k = (u + 2 * v) % 3;
      const png_color c = palette[k];
      EXPECT_EQ(rgb.at<cv::Vec3b>(v, u), cv::Vec3b(c.red, c.green, c.blue));
      EXPECT_EQ(bgr.at<cv::Vec3b>(v, u), cv::Vec3b(c.blue, c.green, c.red));
      EXPECT_EQ(rgba.at<cv::Vec4b>(v, u), cv::Vec4b(c.red, c.green, c.blue, k < 2 ? trns[k] : 255));
    }
  }
}

TEST(Png, GreyAlphaLosesAlphaAndAdam7EqualsProgressiveFree) {
  std::vector<std::vector<png_byte>> ga_rows, grey_rows;
  cv::Mat expected(9, 13, CV_8UC1);
  for (int v = 0; v < 9; ++v) {
    std::vector<png_byte> ga, g;
    for (int u = 0; u < 13; ++u) {
      const auto value = static_cast<png_byte>((u * 19 + v * 31) % 256);
      ga.push_back(value);
      ga.push_back(static_cast<png_byte>(u * 10));
      g.push_back(value);
      expected.at<uint8_t>(v, u) = value;
    }
    ga_rows.push_back(ga);
    grey_rows.push_back(g);
  }
  const std::string ga = WritePng(13, 9, 8, PNG_COLOR_TYPE_GRAY_ALPHA, false, ga_rows);
  EXPECT_TRUE(SameMat(DecodeImageBytes(ga, ChannelOrder::kRgb, "t"), expected));
  const std::string adam7 = WritePng(13, 9, 8, PNG_COLOR_TYPE_GRAY, true, grey_rows);
  EXPECT_TRUE(SameMat(DecodeImageBytes(adam7, ChannelOrder::kRgb, "t"), expected));
}

TEST(Png, DamageIsOneInputErrorAndNothingOnStderr) {
  const std::string png = EncodePngBytes(RandomMat(40, 40, CV_8UC3, 5), ChannelOrder::kRgb, 1, "t");
  std::vector<std::string> bad;
  for (size_t keep : {size_t{9}, size_t{40}, png.size() / 2, png.size() - 13, png.size() - 1}) {
    bad.push_back(png.substr(0, keep));
  }
  std::string crc = png;
  crc[png.size() / 2] = static_cast<char>(crc[png.size() / 2] ^ 0x55);  // inside IDAT
  bad.push_back(crc);
  testing::internal::CaptureStderr();
  for (const std::string& b : bad) {
    try {
      (void)DecodeImageBytes(b, ChannelOrder::kRgb, "cut.png");
      ADD_FAILURE() << "decoded a damaged PNG of " << b.size() << " bytes";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cut.png: "), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

// ---- JPEG --------------------------------------------------------------------------------

TEST(Jpeg, DecodesLikeOpenCvBitForBit) {
  const cv::Mat bgr = SmoothBgr(48, 64);
  cv::Mat grey;
  cv::extractChannel(bgr, grey, 1);
  for (const cv::Mat* m : {&bgr, static_cast<const cv::Mat*>(&grey)}) {
    for (bool progressive : {false, true}) {
      std::vector<uchar> buf;
      ASSERT_TRUE(cv::imencode(
          ".jpg", *m, buf,
          {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0}));
      const cv::Mat theirs = cv::imdecode(buf, cv::IMREAD_UNCHANGED);
      EXPECT_TRUE(SameMat(DecodeImageBytes(ToString(buf), ChannelOrder::kBgr, "t"), theirs));
      if (m->channels() == 3) {
        EXPECT_TRUE(
            SameMat(DecodeImageBytes(ToString(buf), ChannelOrder::kRgb, "t"), SwapRb(theirs)));
      }
    }
  }
}

TEST(Jpeg, EncodesCloseToTheInputAndOpenCvReadsIt) {
  const cv::Mat bgr = SmoothBgr(48, 64);
  for (int quality : {85, 95}) {
    const std::string jpg = EncodeJpegBytes(bgr, ChannelOrder::kBgr, quality, "t");
    const cv::Mat ours = DecodeImageBytes(jpg, ChannelOrder::kBgr, "t");
    EXPECT_TRUE(SameMat(
        ours, cv::imdecode(std::vector<uchar>(jpg.begin(), jpg.end()), cv::IMREAD_UNCHANGED)));
    // As close to the input as OpenCV's own encoder at the same quality (4:2:0 chroma on
    // the disc's sharp edge caps both near 30 dB).
    std::vector<uchar> theirs;
    ASSERT_TRUE(cv::imencode(".jpg", bgr, theirs, {cv::IMWRITE_JPEG_QUALITY, quality}));
    const double their_psnr = cv::PSNR(cv::imdecode(theirs, cv::IMREAD_UNCHANGED), bgr);
    EXPECT_GT(cv::PSNR(ours, bgr), their_psnr - 0.25) << quality;
    EXPECT_GT(cv::PSNR(ours, bgr), 28.0) << quality;
    // RGB order in = the same file for the swapped image.
    EXPECT_EQ(EncodeJpegBytes(SwapRb(bgr), ChannelOrder::kRgb, quality, "t"), jpg);
  }
  cv::Mat grey;
  cv::extractChannel(bgr, grey, 0);
  const cv::Mat back =
      DecodeImageBytes(EncodeJpegBytes(grey, ChannelOrder::kRgb, 90, "t"), ChannelOrder::kRgb, "t");
  ASSERT_EQ(back.type(), CV_8UC1);
  EXPECT_GT(cv::PSNR(back, grey), 35.0);
}

struct JpegErr {
  jpeg_error_mgr mgr;
  jmp_buf jump;
};
void JumpOut(j_common_ptr c) { std::longjmp(reinterpret_cast<JpegErr*>(c->err)->jump, 1); }

// A 16x16 CMYK JPEG written with libjpeg.
bool WriteCmykJpeg(unsigned char** buffer, unsigned long* size) {
  jpeg_compress_struct c;
  JpegErr err;
  c.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = JumpOut;
  if (setjmp(err.jump)) {
    jpeg_destroy_compress(&c);
    return false;
  }
  jpeg_create_compress(&c);
  jpeg_mem_dest(&c, buffer, size);
  c.image_width = 16;
  c.image_height = 16;
  c.input_components = 4;
  c.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&c);
  jpeg_start_compress(&c, TRUE);
  std::vector<unsigned char> row(16 * 4, 100);
  while (c.next_scanline < 16) {
    unsigned char* r = row.data();
    jpeg_write_scanlines(&c, &r, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  return true;
}

TEST(Jpeg, CmykCorruptAndCutAreRefusedQuietly) {
  unsigned char* cmyk_buf = nullptr;
  unsigned long cmyk_size = 0;
  ASSERT_TRUE(WriteCmykJpeg(&cmyk_buf, &cmyk_size));
  const std::string cmyk(reinterpret_cast<char*>(cmyk_buf), cmyk_size);
  std::free(cmyk_buf);

  const std::string jpg =
      EncodeJpegBytes(RandomMat(64, 64, CV_8UC3, 9), ChannelOrder::kRgb, 90, "t");
  // Corrupt entropy-coded data: replace a stretch in the middle of the scan with a restart
  // marker that is not expected there.
  std::string corrupt = jpg;
  const size_t mid = jpg.size() * 2 / 3;
  corrupt[mid] = static_cast<char>(0xFF);
  corrupt[mid + 1] = static_cast<char>(0xD3);
  const std::string cut = jpg.substr(0, jpg.size() / 2);

  testing::internal::CaptureStderr();
  const auto message = [](const std::string& bytes) {
    try {
      (void)DecodeImageBytes(bytes, ChannelOrder::kRgb, "x.jpg");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("decoded");
  };
  EXPECT_NE(message(cmyk).find("x.jpg: CMYK JPEG is not supported"), std::string::npos);
  EXPECT_NE(message(corrupt).find("x.jpg: corrupt JPEG data"), std::string::npos)
      << message(corrupt);
  EXPECT_NE(message(cut).find("x.jpg: truncated JPEG"), std::string::npos) << message(cut);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

// ---- Netpbm ------------------------------------------------------------------------------

TEST(Netpbm, EveryKindMatchesItsHandWrittenPixels) {
  // 3x2 images; the expected grey/RGB values are written out.
  const cv::Mat bitmap = (cv::Mat_<uint8_t>(2, 3) << 0, 255, 0, 255, 255, 0);  // 1 = black
  EXPECT_TRUE(
      SameMat(DecodeImageBytes("P1\n# c\n3 2\n1 0 1\n001", ChannelOrder::kRgb, "t"), bitmap));
  // P4: rows padded to a byte: 101xxxxx, 001xxxxx.
  EXPECT_TRUE(SameMat(
      DecodeImageBytes(std::string("P4\n3 2\n") + "\xA0\x3F", ChannelOrder::kRgb, "t"), bitmap));
  const cv::Mat grey = (cv::Mat_<uint8_t>(2, 3) << 0, 7, 200, 15, 3, 9);
  EXPECT_TRUE(
      SameMat(DecodeImageBytes("P2 3 2 200\n0 7 200\n15 3 9\n", ChannelOrder::kRgb, "t"), grey));
  EXPECT_TRUE(SameMat(
      DecodeImageBytes(std::string("P5\n3 2\n200\n") + std::string("\0\x07\xC8\x0F\x03\x09", 6),
                       ChannelOrder::kRgb, "t"),
      grey));
  const cv::Mat wide = (cv::Mat_<uint16_t>(2, 3) << 0, 1000, 65535, 258, 1, 300);
  EXPECT_TRUE(SameMat(
      DecodeImageBytes("P2\n3 2\n65535\n0 1000 65535 258 1 300", ChannelOrder::kRgb, "t"), wide));
  EXPECT_TRUE(SameMat(
      DecodeImageBytes(std::string("P5\n3 2\n65535\n") +
                           std::string("\x00\x00\x03\xE8\xFF\xFF\x01\x02\x00\x01\x01\x2C", 12),
                       ChannelOrder::kRgb, "t"),
      wide));
  cv::Mat rgb(1, 2, CV_8UC3);
  rgb.at<cv::Vec3b>(0, 0) = {1, 2, 3};
  rgb.at<cv::Vec3b>(0, 1) = {250, 128, 0};
  EXPECT_TRUE(
      SameMat(DecodeImageBytes("P3 2 1 255  1 2 3  250 128 0", ChannelOrder::kRgb, "t"), rgb));
  EXPECT_TRUE(SameMat(
      DecodeImageBytes(std::string("P6 2 1 255\n\x01\x02\x03\xFA\x80", 16) + std::string(1, '\0'),
                       ChannelOrder::kBgr, "t"),
      SwapRb(rgb)));
}

TEST(Netpbm, AgreesWithOpenCvOnItsOwnFiles) {
  for (const auto& [ext, type] : std::vector<std::pair<std::string, int>>{
           {".pgm", CV_8UC1}, {".pgm", CV_16UC1}, {".ppm", CV_8UC3}}) {
    const cv::Mat m = RandomMat(13, 21, type, 21 + type);
    std::vector<uchar> buf;
    ASSERT_TRUE(cv::imencode(ext, m, buf));
    EXPECT_TRUE(SameMat(DecodeImageBytes(ToString(buf), ChannelOrder::kBgr, "t"), m)) << ext;
  }
}

TEST(Netpbm, BadFilesNameTheProblem) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"P5\n3 2\n255\n\x01\x02", "truncated"},
      {"P5\n3 2\n0\n123456", "maxval must be 1..65535"},
      {"P5\n3 2\n70000\n", "maxval must be 1..65535"},
      {"P2\n2 1\n10\n3 11\n", "exceeds maxval"},
      {"P2\n2 1\n10\n3 x\n", "expected a decimal sample"},
      {"P2\n2 1\n10\n3", "truncated"},
      {"P1\n2 1\n1 2\n", "expected a 0 or 1"},
      {"P5\nx 2\n255\n", "expected a decimal width"},
      {"P5\n3 2\n255x\x01\x02\x03\x04\x05\x06", "whitespace byte after the header"},
      {"P5\n0 2\n255\n", "implausible size"},
      {"P5\n70000 2\n255\n", "implausible size"},
      {"P6\n1234567890 2\n255\n", "too many digits"},
      {"GIF89a", "unsupported image format"},
  };
  for (const auto& [bytes, problem] : cases) {
    try {
      (void)DecodeImageBytes(bytes, ChannelOrder::kRgb, "f.pgm");
      ADD_FAILURE() << "accepted " << bytes;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("f.pgm: ", 0), 0u) << what;
      EXPECT_NE(what.find(problem), std::string::npos) << what << " | wanted " << problem;
    }
  }
}

TEST(Netpbm, HeaderSizeAgreesWithTheDecoder) {
  for (const std::string& bytes :
       {std::string("P1\n# c\n3 2\n1 0 1\n001"), std::string("P2 3 2 200\n0 7 200\n15 3 9\n"),
        std::string("P3 2 1 255  1 2 3  250 128 0"),
        std::string("P5\n#a\r4 1\n255\n\x01\x02\x03\x04")}) {
    int w = 0, h = 0;
    ASSERT_TRUE(NetpbmSize(bytes, &w, &h)) << bytes;
    const cv::Mat m = DecodeImageBytes(bytes, ChannelOrder::kRgb, "t");
    EXPECT_EQ(w, m.cols) << bytes;
    EXPECT_EQ(h, m.rows) << bytes;
  }
  int w = 0, h = 0;
  for (const std::string& bad : {"GIF89a", "P7\n3 2\n", "P5\nx 2\n", "P5\n3", "P5\n0 2\n255\n"}) {
    EXPECT_FALSE(NetpbmSize(bad, &w, &h)) << bad;
  }
}

TEST(Encoders, RefuseWhatTheyCannotWrite) {
  EXPECT_THROW(EncodePngBytes(cv::Mat(), ChannelOrder::kRgb, 1, "t"), InputError);
  EXPECT_THROW(EncodePngBytes(cv::Mat(2, 2, CV_32FC1), ChannelOrder::kRgb, 1, "t"), InputError);
  EXPECT_THROW(EncodePngBytes(cv::Mat(2, 2, CV_8UC2), ChannelOrder::kRgb, 1, "t"), InputError);
  EXPECT_THROW(EncodePngBytes(cv::Mat(2, 2, CV_8UC1), ChannelOrder::kRgb, 10, "t"), InputError);
  EXPECT_THROW(EncodeJpegBytes(cv::Mat(2, 2, CV_16UC1), ChannelOrder::kRgb, 90, "t"), InputError);
  EXPECT_THROW(EncodeJpegBytes(cv::Mat(2, 2, CV_8UC4), ChannelOrder::kRgb, 90, "t"), InputError);
  EXPECT_THROW(EncodeJpegBytes(cv::Mat(2, 2, CV_8UC3), ChannelOrder::kRgb, 0, "t"), InputError);
}

}  // namespace
}  // namespace gt::io

// Renderers of libgt/report/pictures.h: sizes, colours at known places (computed here from
// the geometry of the drawing, not read back from the renderer), subset determinism, and
// bad input.
#include "libgt/report/pictures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <set>

#include "libgt/core/error.h"
#include "libgt/report/canvas.h"

namespace gt::report {
namespace {

cv::Vec3b At(const cv::Mat& m, int x, int y) { return m.at<cv::Vec3b>(y, x); }

// A checkerboard image so that "not blank" is meaningful and colours differ from it.
cv::Mat Checker(int w, int h) {
  cv::Mat m(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t g = ((x / 4 + y / 4) % 2) ? 90 : 140;
      m.at<cv::Vec3b>(y, x) = cv::Vec3b(g, g, g);
    }
  }
  return m;
}

int CountColor(const cv::Mat& m, const cv::Vec3b& c) {
  int n = 0;
  for (int y = 0; y < m.rows; ++y) {
    for (int x = 0; x < m.cols; ++x) n += At(m, x, y) == c ? 1 : 0;
  }
  return n;
}

TEST(SelectMatchSubset, AllWhenFewAndDeterministicWhenMany) {
  std::vector<uint8_t> few = {0, 1, 2, 0};
  EXPECT_EQ(SelectMatchSubset(few, 200, 7), (std::vector<size_t>{0, 1, 2, 3}));

  std::mt19937 rng(3);
  std::vector<uint8_t> types(5000);
  for (auto& t : types) t = rng() % 100 < 90 ? 0 : (rng() % 2 ? 1 : 2);
  const auto a = SelectMatchSubset(types, 200, 11);
  const auto b = SelectMatchSubset(types, 200, 11);
  const auto c = SelectMatchSubset(types, 200, 12);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  ASSERT_EQ(a.size(), 200u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(std::set<size_t>(a.begin(), a.end()).size(), a.size());
  // Equal shares when every type has enough matches: 66/67 each.
  int per_type[3] = {0, 0, 0};
  for (size_t i : a) ++per_type[types[i]];
  for (int t = 0; t < 3; ++t) {
    EXPECT_GE(per_type[t], 66);
    EXPECT_LE(per_type[t], 67);
  }
}

TEST(SelectMatchSubset, RareTypeKeepsAllItsMatches) {
  std::vector<uint8_t> types(1000, 0);
  types[10] = 2;
  types[500] = 2;
  const auto s = SelectMatchSubset(types, 100, 0);
  ASSERT_EQ(s.size(), 100u);
  EXPECT_TRUE(std::binary_search(s.begin(), s.end(), size_t{10}));
  EXPECT_TRUE(std::binary_search(s.begin(), s.end(), size_t{500}));
}

TEST(RenderMatches, LinesHaveTheTypeColourAlongTheirPath) {
  const int w = 64, h = 48, s = 8;
  const cv::Mat img0 = Checker(w, h), img1 = Checker(w, h);
  gt::PatchMatches m;
  m.cells_w0 = m.cells_w1 = w / s;
  m.cells_h0 = m.cells_h1 = h / s;
  // vo: cell (1, 2) of image 0 (anchor (12, 20)) → (30, 20) in image 1: horizontal line.
  m.matches = {2 * 8 + 1, 2 * 8 + 3};
  m.match_type = {1};
  m.match_xy = {30.0f, 20.0f};
  // ov: (5, 36) in image 0 → anchor of cell (4, 4) of image 1 = (36, 36).
  m.matches.insert(m.matches.end(), {4 * 8 + 0, 4 * 8 + 4});
  m.match_type.push_back(2);
  m.match_xy.insert(m.match_xy.end(), {5.0f, 36.0f});

  MatchPictureOptions o;
  o.legend = false;
  const cv::Mat pic = RenderMatches(img0, img1, m, o);
  ASSERT_EQ(pic.cols, 2 * w + kPanelGap);
  ASSERT_EQ(pic.rows, h);
  const int x1 = w + kPanelGap;
  // Every pixel of the horizontal vo segment from (12, 20) to (x1 + 30, 20) is yellow.
  for (int x = 12; x <= x1 + 30; ++x) {
    EXPECT_EQ(At(pic, x, 20), kMatchColorVo.Bgr()) << "x=" << x;
  }
  // The ov segment from (5, 36) to (x1 + 36, 36) is red; the row above is untouched far
  // from the end points.
  for (int x = 5; x <= x1 + 36; ++x) EXPECT_EQ(At(pic, x, 36), kMatchColorOv.Bgr()) << x;
  EXPECT_EQ(At(pic, 40, 30), img0.at<cv::Vec3b>(30, 40));
  // The gap between the panels is white where no line crosses it.
  EXPECT_EQ(At(pic, w + 2, 5), cv::Vec3b(255, 255, 255));
  // No vv line was drawn.
  EXPECT_EQ(CountColor(pic, kMatchColorVv.Bgr()), 0);

  o.legend = true;
  const cv::Mat with_legend = RenderMatches(img0, img1, m, o);
  EXPECT_EQ(with_legend.cols, pic.cols);
  EXPECT_GT(with_legend.rows, pic.rows);
}

TEST(RenderMatches, CornerAnchorsAndDiagonalLine) {
  const int w = 64, h = 48, s = 8;
  const cv::Mat img = Checker(w, h);
  gt::PatchMatches m;
  m.matches = {1 * 8 + 1, 0};  // cell (1, 1): corner anchor (8, 8)
  m.match_type = {0};
  m.match_xy = {8.0f, 40.0f};
  MatchPictureOptions o;
  o.legend = false;
  o.anchor = gt::Anchor::kCorner;
  o.stride = s;
  const cv::Mat pic = RenderMatches(img, img, m, o);
  const int x1 = w + kPanelGap;
  // Points of the segment (8, 8) → (x1 + 8, 40) at integer x where y is integral.
  const double slope = 32.0 / x1;
  int checked = 0;
  for (int x = 8; x <= x1 + 8; ++x) {
    const double y = 8 + slope * (x - 8);
    if (std::abs(y - std::round(y)) < 1e-9) {
      EXPECT_EQ(At(pic, x, static_cast<int>(std::round(y))), kMatchColorVv.Bgr()) << x;
      ++checked;
    }
  }
  EXPECT_GE(checked, 2);
}

TEST(RenderMatches, ManyMatchesDrawOnlyTheSubsetAndAreDeterministic) {
  const int w = 160, h = 120, s = 8;
  const cv::Mat img = Checker(w, h);
  gt::PatchMatches m;
  std::mt19937 rng(5);
  for (int k = 0; k < 1000; ++k) {
    m.matches.push_back(static_cast<int32_t>(rng() % (20 * 15)));
    m.matches.push_back(static_cast<int32_t>(rng() % (20 * 15)));
    m.match_type.push_back(static_cast<uint8_t>(rng() % 3));
    m.match_xy.push_back(static_cast<float>(rng() % w));
    m.match_xy.push_back(static_cast<float>(rng() % h));
  }
  MatchPictureOptions o;
  o.max_lines = 50;
  o.stride = s;
  const cv::Mat a = RenderMatches(img, img, m, o);
  const cv::Mat b = RenderMatches(img, img, m, o);
  EXPECT_EQ(EncodePng(a), EncodePng(b));
  o.seed = 1;
  EXPECT_NE(EncodePng(a), EncodePng(RenderMatches(img, img, m, o)));
}

TEST(RenderMatches, BadInputThrows) {
  const cv::Mat img = Checker(64, 48);
  gt::PatchMatches m;
  m.matches = {8 * 6, 0};  // cell 48 of an 8x6 grid does not exist
  m.match_type = {0};
  m.match_xy = {1, 1};
  EXPECT_THROW(RenderMatches(img, img, m, {}), gt::InputError);
  m.matches = {0, 0};
  m.match_type = {3};
  EXPECT_THROW(RenderMatches(img, img, m, {}), gt::InputError);
  m.match_type = {0};
  m.match_xy = {NAN, 1};
  EXPECT_THROW(RenderMatches(img, img, m, {}), gt::InputError);
  m.match_xy = {1};
  EXPECT_THROW(RenderMatches(img, img, m, {}), gt::InputError);
  MatchPictureOptions o;
  o.max_lines = 0;
  std::string error;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_THROW(RenderMatches(img, img, {}, o), gt::InputError);
}

TEST(RenderLabels, EachCodeGetsItsColourBlended) {
  const int w = 60, h = 40;
  const cv::Mat img = Checker(w, h);
  LabelMap l01{w, h, std::vector<uint8_t>(w * h)};
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) l01.codes[v * w + u] = static_cast<uint8_t>(u / 10);  // 6 bands
  }
  LabelMap l10{w, h, std::vector<uint8_t>(w * h, 2)};  // all VISIBLE

  // alpha = 1: the label colour exactly.
  const cv::Mat full = OverlayLabels(img, l01, 1.0);
  for (int c = 0; c < 6; ++c) EXPECT_EQ(At(full, c * 10 + 5, 7), kLabelColors[c].Bgr()) << c;
  // alpha = 0.5: the mean of image and colour (rounded), computed here.
  const cv::Mat half = OverlayLabels(img, l01, 0.5);
  const cv::Vec3b px = img.at<cv::Vec3b>(7, 25), col = kLabelColors[2].Bgr();
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_NEAR(At(half, 25, 7)[ch], 0.5 * px[ch] + 0.5 * col[ch], 0.51);
  }

  LabelPictureOptions o;
  o.alpha = 1.0;
  const cv::Mat pic = RenderLabels(img, l01, img, l10, o);
  EXPECT_EQ(pic.cols, 2 * w + kPanelGap);
  EXPECT_GT(pic.rows, h + 22);  // title above, legend below
  // The right panel (labels 1->0) is VISIBLE everywhere, under a 22-pixel title.
  const int x1 = w + kPanelGap;
  EXPECT_EQ(At(pic, x1 + 3, 22 + 3), kLabelColors[2].Bgr());
  EXPECT_EQ(At(pic, x1 + w - 1, 22 + h - 1), kLabelColors[2].Bgr());
  EXPECT_EQ(At(pic, 55, 22 + 20), kLabelColors[5].Bgr());  // UNKNOWN band of image 0
  // The legend shows every colour as a swatch.
  const cv::Mat legend = pic(cv::Rect(0, 22 + h, pic.cols, pic.rows - 22 - h));
  for (int c = 0; c < 6; ++c) EXPECT_GT(CountColor(legend, kLabelColors[c].Bgr()), 100) << c;
}

TEST(RenderLabels, BadCodesAndSizesThrow) {
  const cv::Mat img = Checker(8, 8);
  LabelMap bad{8, 8, std::vector<uint8_t>(64, 6)};
  EXPECT_THROW(OverlayLabels(img, bad, 0.5), gt::InputError);
  LabelMap small{4, 4, std::vector<uint8_t>(16, 2)};
  EXPECT_THROW(OverlayLabels(img, small, 0.5), gt::InputError);
  LabelPictureOptions o;
  o.alpha = 1.5;
  LabelMap ok{8, 8, std::vector<uint8_t>(64, 2)};
  EXPECT_THROW(RenderLabels(img, ok, img, ok, o), gt::InputError);
}

gt::occupancy::FrustumVolume TestVolume(int w, int h, int bins) {
  gt::occupancy::FrustumVolume v;
  v.width = w;
  v.height = h;
  for (int k = 0; k <= bins; ++k) v.edges_m.push_back(0.5 + 0.1 * k);
  v.occ.assign(w * h, 0);
  v.known.assign(w * h, 0);
  return v;
}

TEST(Occupancy, FirstOccupiedBinAndSpecialRays) {
  const int w = 20, h = 10, bins = 64;
  auto v = TestVolume(w, h, bins);
  // Ray (3, 2): free 0..9, occupied 10 and 30 → first = 10.
  v.occ[2 * w + 3] = (1ULL << 10) | (1ULL << 30);
  v.known[2 * w + 3] = ((1ULL << 10) - 1) | v.occ[2 * w + 3];
  // Ray (4, 2): occupied in bin 63 only.
  v.occ[2 * w + 4] = 1ULL << 63;
  v.known[2 * w + 4] = ~0ULL;
  // Ray (5, 2): all free.
  v.known[2 * w + 5] = ~0ULL;
  const auto first = FirstOccupiedBins(v);
  EXPECT_EQ(first[2 * w + 3], 10);
  EXPECT_EQ(first[2 * w + 4], 63);
  EXPECT_EQ(first[2 * w + 5], -1);
  EXPECT_EQ(first[0], -1);

  OccupancyPictureOptions o;
  o.scale = 2;
  const cv::Mat pic = RenderFirstOccupied(v, o);
  EXPECT_GT(pic.cols, w * 2);
  EXPECT_GT(pic.rows, h * 2);
  EXPECT_EQ(At(pic, 5 * 2, 2 * 2), kNoOccupiedSeenColor.Bgr());
  EXPECT_EQ(At(pic, 5 * 2 + 1, 2 * 2 + 1), kNoOccupiedSeenColor.Bgr());
  EXPECT_EQ(At(pic, 0, 0), kNothingKnownColor.Bgr());
  // Near bins are warm (red > blue), far bins cold (blue > red), on the turbo map.
  const cv::Vec3b near = At(pic, 3 * 2, 2 * 2), far = At(pic, 4 * 2, 2 * 2);
  EXPECT_GT(near[2], near[0]);
  EXPECT_GT(far[0], far[2]);
  EXPECT_NE(near, far);
}

TEST(Occupancy, SliceShowsThreeStatesWhereTheBitsSayIt) {
  const int w = 12, h = 6, bins = 16;
  auto v = TestVolume(w, h, bins);
  const int row = 4;
  // Column 7 of row 4: bins 0..4 free, 5 occupied, rest unknown.
  v.known[row * w + 7] = (1ULL << 6) - 1;
  v.occ[row * w + 7] = 1ULL << 5;
  OccupancyPictureOptions o;
  o.slice_row = row;
  o.scale = 3;
  o.slice_bin_px = 4;
  const cv::Mat pic = RenderOccupancySlice(v, o);
  // Layout: 22-pixel title, then a 70-pixel depth axis and the slice.
  auto bin_px = [&](int u, int k) { return At(pic, 70 + u * 3 + 1, 22 + k * 4 + 1); };
  EXPECT_EQ(bin_px(7, 0), kFreeColor.Bgr());
  EXPECT_EQ(bin_px(7, 4), kFreeColor.Bgr());
  EXPECT_EQ(bin_px(7, 5), kOccupiedColor.Bgr());
  EXPECT_EQ(bin_px(7, 6), kUnknownColor.Bgr());
  EXPECT_EQ(bin_px(0, 0), kUnknownColor.Bgr());
  EXPECT_GE(pic.rows, 22 + bins * 4);
  EXPECT_EQ(pic.cols, 70 + w * 3);
  o.slice_row = h;
  EXPECT_THROW(RenderOccupancySlice(v, o), gt::InputError);
}

TEST(Occupancy, DenseRoundTripAndComposite) {
  const int w = 8, h = 4, bins = 3;
  std::vector<uint8_t> dense(bins * h * w, 255);
  dense[0 * h * w + 5] = 0;
  dense[1 * h * w + 5] = 1;
  std::vector<double> edges = {1, 2, 3, 4};
  const auto v = VolumeFromDense(dense, bins, h, w, edges);
  EXPECT_EQ(v.occ[5], 2u);
  EXPECT_EQ(v.known[5], 3u);
  EXPECT_EQ(v.known[4], 0u);
  dense[0] = 7;
  EXPECT_THROW(VolumeFromDense(dense, bins, h, w, edges), gt::InputError);
  EXPECT_THROW(VolumeFromDense(dense, bins, h, w + 1, edges), gt::InputError);

  const cv::Mat both = RenderOccupancy(v, &v, {});
  const cv::Mat one = RenderOccupancy(v, nullptr, {});
  EXPECT_GT(both.cols, one.cols);
  EXPECT_EQ(both.rows, one.rows);
  auto bad = v;
  bad.occ.pop_back();
  EXPECT_THROW(RenderOccupancy(bad, nullptr, {}), gt::InputError);
}

TEST(Png, EncodesAndDecodesToTheSamePixels) {
  const cv::Mat img = Checker(33, 17);
  const std::string png = EncodePng(img);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  const cv::Mat back = cv::imdecode(std::vector<uint8_t>(png.begin(), png.end()), cv::IMREAD_COLOR);
  ASSERT_EQ(back.size(), img.size());
  EXPECT_EQ(cv::norm(back, img, cv::NORM_INF), 0.0);
}

TEST(PrepareImage, ResizesConvertsAndFillsPlaceholder) {
  const cv::Mat gray(10, 20, CV_8UC1, cv::Scalar(77));
  const cv::Mat out = PrepareImage(gray, 40, 20);
  EXPECT_EQ(out.type(), CV_8UC3);
  EXPECT_EQ(out.cols, 40);
  EXPECT_EQ(At(out, 13, 7), cv::Vec3b(77, 77, 77));
  const cv::Mat placeholder = PrepareImage(cv::Mat(), 8, 6);
  EXPECT_EQ(placeholder.rows, 6);
  EXPECT_EQ(At(placeholder, 0, 0), cv::Vec3b(128, 128, 128));
}

TEST(RenderPredictedMatches, VerdictColoursAlongTheLinesOverTheLabels) {
  const int w = 64, h = 48;
  const cv::Mat img0 = Checker(w, h), img1 = Checker(w, h);
  LabelMap l01{w, h, std::vector<uint8_t>(w * h, 2)}, l10{w, h, std::vector<uint8_t>(w * h, 3)};
  // Correct: (4, 10) -> (20, 10); wrong: (4, 30) -> (50, 30); unscored: (4, 44) -> (10, 44).
  const std::vector<float> k0{4, 10, 4, 30, 4, 44}, k1{20, 10, 50, 30, 10, 44};
  const std::vector<PredictionVerdict> v{PredictionVerdict::kCorrect, PredictionVerdict::kWrong,
                                         PredictionVerdict::kUnscored};
  PredictionPictureOptions o;
  o.alpha = 1.0;  // pure label colours under the lines
  const cv::Mat pic = RenderPredictedMatches(img0, l01, img1, l10, k0, k1, v, o);
  ASSERT_EQ(pic.cols, 2 * w + kPanelGap);
  ASSERT_GT(pic.rows, h);  // legend strip below
  const int x1 = w + kPanelGap;
  for (int x = 4; x <= x1 + 20; ++x) EXPECT_EQ(At(pic, x, 10), kPredictionCorrectColor.Bgr()) << x;
  for (int x = 4; x <= x1 + 50; ++x) EXPECT_EQ(At(pic, x, 30), kPredictionWrongColor.Bgr()) << x;
  for (int x = 8; x <= x1 + 8; ++x) {
    if (x >= w && x < x1) continue;  // the white gap
    EXPECT_EQ(At(pic, x, 44), kPredictionUnscoredColor.Bgr()) << x;
  }
  // Away from the lines: the labels (VISIBLE in image 0, OCCLUDED in image 1).
  EXPECT_EQ(At(pic, 40, 20), kLabelColors[2].Bgr());
  EXPECT_EQ(At(pic, x1 + 40, 20), kLabelColors[3].Bgr());

  // Many matches: at most max_lines drawn, deterministic; bad input is an InputError.
  std::vector<float> m0, m1;
  std::vector<PredictionVerdict> mv;
  for (int i = 0; i < 500; ++i) {
    m0.insert(m0.end(), {static_cast<float>(i % w), static_cast<float>(i % h)});
    m1.insert(m1.end(), {static_cast<float>((i * 7) % w), static_cast<float>((i * 3) % h)});
    mv.push_back(static_cast<PredictionVerdict>(i % 3));
  }
  o.max_lines = 20;
  const cv::Mat a = RenderPredictedMatches(img0, l01, img1, l10, m0, m1, mv, o);
  const cv::Mat b = RenderPredictedMatches(img0, l01, img1, l10, m0, m1, mv, o);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_THROW(RenderPredictedMatches(img0, l01, img1, l10, {1, 2}, {}, {v[0]}, o), InputError);
  EXPECT_THROW(RenderPredictedMatches(img0, l01, img1, l10, {NAN, 2}, {1, 2}, {v[0]}, o),
               InputError);
  o.max_lines = 0;
  EXPECT_THROW(RenderPredictedMatches(img0, l01, img1, l10, k0, k1, v, o), InputError);
}

TEST(Legends, TextScaleEnlargesTitlesAndLegendsForDownscaledPictures) {
  // The split report draws its gallery pictures with text_scale = 1 / gallery_scale: after
  // the downscale the legend has the size of an unscaled one (rows of 22 px, 0.45 font).
  const int w = 64, h = 48;
  const cv::Mat img0 = Checker(w, h), img1 = Checker(w, h);
  const LabelMap labels{w, h, std::vector<uint8_t>(w * h, 2)};
  LabelPictureOptions o;
  const cv::Mat one = RenderLabels(img0, labels, img1, labels, o);
  o.text_scale = 2.0;
  const cv::Mat two = RenderLabels(img0, labels, img1, labels, o);
  EXPECT_EQ(one.cols, two.cols);
  // Title strip 22 -> 44 px; legend 6 rows (one per entry at this width, and the note)
  // of 22 -> 44 px plus 6 -> 12 px of margin.
  const int legend_rows = (one.rows - h - 22 - 6) / 22;
  EXPECT_EQ(one.rows, h + 22 + legend_rows * 22 + 6);
  EXPECT_EQ(two.rows - h, 2 * (one.rows - h));
  o.text_scale = 5.0;
  EXPECT_THROW(RenderLabels(img0, labels, img1, labels, o), InputError);
}

// Dark pixels in the last `margin` columns of rows [y0, y1) of columns [x0, x1): text that
// ran past the panel's right edge and was cut there.
int DarkAtRightEdge(const cv::Mat& m, int x0, int x1, int y0, int y1, int margin = 6) {
  int n = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x1 - margin; x < x1; ++x) {
      const cv::Vec3b p = At(m, x, y);
      n += (p[0] < 200 || p[1] < 200 || p[2] < 200) ? 1 : 0;
    }
  }
  (void)x0;
  return n;
}

TEST(Legends, TitlesAndLegendsFitTheirPanelsAt320x240InTheGallery) {
  // The demo recipe's 320x240, drawn at twice the text size for the gallery's half size.
  const double ts = 2.0;
  const int title_h = static_cast<int>(std::lround(22 * ts));
  // A title wider than the panel is drawn at a smaller scale whose measured width fits.
  for (const std::string title : {"image 1: labels 1->0", "camera 0: first occupied bin",
                                  "row v=60: depth (down) x u", "no occupied bin, free seen"}) {
    const int width = 250;
    const double font = FittingFontScale(title, 0.45 * ts, width);
    int baseline = 0;
    EXPECT_LE(cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline).width, width)
        << title;
    EXPECT_GT(cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, font / 0.9, 1, &baseline).width,
              width)
        << title << ": shrunk more than needed";
  }
  EXPECT_EQ(FittingFontScale("short", 0.9, 300), 0.9);  // fits: unchanged

  const int w = 320, h = 240;
  const cv::Mat img = Checker(w, h);
  LabelMap labels{w, h, std::vector<uint8_t>(w * h, 2)};
  for (int k = 0; k < w * h; ++k) labels.codes[k] = static_cast<uint8_t>(k % 6);
  LabelPictureOptions lo;
  lo.text_scale = ts;
  const cv::Mat lab = RenderLabels(img, labels, img, labels, lo);
  // Both titles end inside their panel; the legend inside the picture.
  EXPECT_EQ(DarkAtRightEdge(lab, 0, w, 0, title_h), 0);
  EXPECT_EQ(DarkAtRightEdge(lab, w + kPanelGap, 2 * w + kPanelGap, 0, title_h), 0);
  EXPECT_EQ(DarkAtRightEdge(lab, 0, lab.cols, title_h + h, lab.rows), 0);
  // Each title is drawn: dark pixels in its strip.
  EXPECT_GT(DarkAtRightEdge(lab, 0, w, 0, title_h, w / 2), 0);

  // The occupancy of the half grid (160x120 rays, 2 pixels each) of both cameras.
  auto v = TestVolume(w / 2, h / 2, 64);
  for (size_t r = 0; r < v.occ.size(); ++r) {
    v.known[r] = (r % 3 == 0) ? ~0ULL : 0;
    v.occ[r] = (r % 3 == 0 && r % 2 == 0) ? 1ULL << (r % 64) : 0;
  }
  OccupancyPictureOptions oo;
  oo.text_scale = ts;
  const cv::Mat first = RenderFirstOccupied(v, oo), slice = RenderOccupancySlice(v, oo);
  const cv::Mat occ = RenderOccupancy(v, &v, oo);
  // Top row: "camera k: first occupied bin" over the depth picture with its colour bar and
  // legend (white right margin from top to bottom); bottom row: "camera k: slice" over the
  // slice, whose own title and legend end inside it.
  for (int k = 0; k < 2; ++k) {
    const int x0 = k * (first.cols + kPanelGap), top = title_h + first.rows;
    EXPECT_EQ(DarkAtRightEdge(occ, x0, x0 + first.cols, 0, top), 0) << "camera " << k;
    const int s0 = k * (slice.cols + kPanelGap);
    EXPECT_EQ(DarkAtRightEdge(occ, s0, s0 + slice.cols, top, top + 2 * title_h), 0);
    EXPECT_EQ(DarkAtRightEdge(occ, s0, s0 + slice.cols, top + 2 * title_h + 64 * 4, occ.rows), 0);
  }
}

}  // namespace
}  // namespace gt::report

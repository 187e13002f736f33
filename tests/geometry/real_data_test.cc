// Labels on real samples (../shared/data) through the io readers: sane metric ranges,
// fast metrics equal to the label maps, and the slow reference on a pixel subsample.
#include <gtest/gtest.h>

#include "libgt/geometry/pair.h"
#include "libgt/io/depth_io.h"
#include "libgt/datasets/reader.h"
#include "tests/geometry/reference.h"
#include "tests/support/test_support.h"

namespace gt {
namespace {

struct RealPair {
  DepthImage d0, d1;
  Camera c0, c1;
  Rigid3d w0, w1;
  LabelOptions options;
};

RealPair Load(const std::string& format, const std::string& root, const std::string& id0,
              const std::string& id1) {
  const auto reader = datasets::MakeReader(ParseDatasetFormat(format));
  const auto names = reader->ListScenes(root);
  EXPECT_EQ(names.size(), 1u);
  const Scene scene = reader->ReadScene(root, names.at(0));
  RealPair p;
  p.options = LabelPreset("default");
  p.options.min_depth_m = scene.min_depth_m;
  p.options.max_depth_m = scene.max_depth_m;
  for (const auto& f : scene.frames) {
    if (f.id != id0 && f.id != id1) continue;
    EXPECT_TRUE(f.usable) << f.id;
    const DepthImage d = ResizeDepthNearest(io::ReadDepth(f.depth), 640, 480);
    const Camera c = f.depth_camera.Resized(640, 480);
    (f.id == id0 ? p.d0 : p.d1) = d;
    (f.id == id0 ? p.c0 : p.c1) = c;
    (f.id == id0 ? p.w0 : p.w1) = f.world_from_cam;
  }
  EXPECT_FALSE(p.d0.empty());
  EXPECT_FALSE(p.d1.empty());
  return p;
}

void CheckSane(const RealPair& p) {
  const PairLabels l = LabelPair(p.d0, p.c0, p.w0, p.d1, p.c1, p.w1, p.options, PatchOptions{});
  for (const DirectionMetrics* m : {&l.m01, &l.m10}) {
    const auto c = [&](PixelLabel k) { return m->counts[static_cast<int>(k)]; };
    const int64_t overlapping = m->valid - c(PixelLabel::kOutOfView);
    EXPECT_GT(overlapping, 10000);
    EXPECT_GT(c(PixelLabel::kVisible), overlapping / 2) << "VISIBLE must be the majority";
    EXPECT_LT(c(PixelLabel::kInconsistent), overlapping / 20) << "INCONSISTENT must be small";
    EXPECT_GT(m->overlap, 0.0);
    EXPECT_LE(m->overlap, 1.0);
  }
  EXPECT_GT(std::max(l.m01.overlap, l.m10.overlap), 0.2);
  EXPECT_GT(0.5 * (l.m01.overlap + l.m10.overlap), 0.2);
  EXPECT_GT(l.patches.size(), 100u);
  // Fast metrics equal the label maps; slow reference on every 7th pixel.
  const Rigid3d b_from_a = RelativePose(p.w0, p.w1);
  const DirectionMetrics fast = ScoreDirection(p.d0, p.c0, p.d1, p.c1, b_from_a, p.options, 1);
  EXPECT_EQ(fast.counts, l.m01.counts);
  int differ = 0;
  for (int v = 0; v < 480; v += 7) {
    for (int u = 0; u < 640; u += 7) {
      const auto ref = test::ReferenceLabel(p.d0, p.c0, p.d1, p.c1, b_from_a, p.options, u, v);
      differ += ref.label != l.l01.at(u, v);
    }
  }
  EXPECT_EQ(differ, 0);
}

TEST(RealData, TartanAirFrame0To20) {
  const std::string root = test::SharedData("tartanair/hospital_sample");
  ASSERT_FALSE(root.empty());
  CheckSane(Load("tartanair", root, "000000", "000020"));
}

TEST(RealData, SevenScenes150To190) {
  const std::string root = test::SharedData("sevenscenes");
  ASSERT_FALSE(root.empty());
  CheckSane(Load("sevenscenes", root, "000150", "000190"));
}

}  // namespace
}  // namespace gt

// eval::LoftrPairName / NormalizeLoftrPairName: the identifier LoFTR's test loop forms
// ('#'.join(pair_names), "<folder>/color/<n>.jpg" per side) and the forms a user's dump may
// hold (a data-root prefix, another image extension, zero-padded numbers), and what is
// not such a name. ReadPredictions' use of them is tested end to end in eval/cli.
#include <gtest/gtest.h>

#include "libgt/eval/predictions.h"

namespace gt::eval {
namespace {

TEST(LoftrPairName, IsLoftrsIdentifier) {
  EXPECT_EQ(LoftrPairName("scene0707_00", 15, 585),
            "scene0707_00/color/15.jpg#scene0707_00/color/585.jpg");
}

TEST(LoftrPairName, NormalizedForms) {
  const std::string want = "scene0707_00/color/15.jpg#scene0707_00/color/585.jpg";
  EXPECT_EQ(NormalizeLoftrPairName(want), want);
  EXPECT_EQ(NormalizeLoftrPairName("scans_test/scene0707_00/color/15.jpg#"
                                   "/data/scannet/scans_test/scene0707_00/color/585.png"),
            want);
  EXPECT_EQ(NormalizeLoftrPairName("scene0707_00/color/000015.jpg#scene0707_00/color/585"), want);
}

TEST(LoftrPairName, OtherNamesAreNotLoftrNames) {
  for (const char* name :
       {"scene0707_00/000015_000585", "a#b", "scene/color/1.jpg",
        "scene/color/1.jpg#scene/color/2.jpg#scene/color/3.jpg",
        "scene/depth/1.png#scene/depth/2.png", "scene/color/x.jpg#scene/color/2.jpg",
        "scene/color/.jpg#scene/color/2.jpg", "/color/1.jpg#scene/color/2.jpg",
        "scene/color/1234567890123456789.jpg#scene/color/2.jpg"}) {
    EXPECT_EQ(NormalizeLoftrPairName(name), "") << name;
  }
}

}  // namespace
}  // namespace gt::eval

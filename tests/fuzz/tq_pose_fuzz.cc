// Quaternion pose lines: TartanAir pose_left.txt ("tx ty tz qx qy qz qw") and TUM
// groundtruth.txt ("timestamp tx ty tz qx qy qz qw", '#' comments), then the pose check
// and the rigid transform for every line that passes it.
#include <cstdint>

#include "libgt/core/pose.h"
#include "libgt/datasets/text_parsing.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

void CheckPose(const Eigen::Vector3d& t, const Eigen::Vector4d& q) {
  if (!gt::PoseProblemTQ(t, q)) {
    const gt::Rigid3d r = gt::RigidFromTQ(t, q);
    if (!r.matrix().allFinite()) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = gt::fuzz::Bytes(data, size);
  const std::string tartan = "pose_left.txt";
  gt::fuzz::ExpectValueOrInputError(tartan, [&] {
    for (const auto& line : gt::datasets::ParseTQLines(text, tartan)) {
      CheckPose(line.translation, line.q_xyzw);
    }
  });
  const std::string tum = "groundtruth.txt";
  gt::fuzz::ExpectValueOrInputError(tum, [&] {
    const auto poses = gt::datasets::ParseTimedPoses(text, tum);
    for (size_t i = 0; i < poses.size(); ++i) {
      if (i > 0 && poses[i].t < poses[i - 1].t) std::abort();  // sorted by time
      CheckPose(poses[i].translation, poses[i].q_xyzw);
    }
  });
  return 0;
}

// Quaternion pose lines: TartanAir pose_left.txt ("tx ty tz qx qy qz qw") and TUM
// groundtruth.txt ("timestamp tx ty tz qx qy qz qw", '#' comments), then the pose check the
// readers make (SetTQPose): the rigid transform of every line that passes it, or an
// unusable frame whose detail names the file and the line.
#include <cstdint>

#include "libgt/core/pose.h"
#include "libgt/datasets/text_parsing.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

void CheckPose(const Eigen::Vector3d& t, const Eigen::Vector4d& q, const std::string& name,
               int line_no) {
  const std::string where = gt::datasets::LineWhere(name, line_no);
  gt::Frame f;
  if (gt::datasets::SetTQPose(t, q, gt::datasets::PoseLocator::Whole(where), &f)) {
    if (!f.world_from_cam.matrix().allFinite()) std::abort();
  } else if (f.usable || f.unusable_detail.rfind(where + ": ", 0) != 0) {
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = gt::fuzz::Bytes(data, size);
  const std::string tartan = "pose_left.txt";
  gt::fuzz::ExpectValueOrInputError(tartan, [&] {
    for (const auto& line : gt::datasets::ParseTQLines(text, tartan)) {
      CheckPose(line.translation, line.q_xyzw, tartan, line.line_no);
    }
  });
  const std::string tum = "groundtruth.txt";
  gt::fuzz::ExpectValueOrInputError(tum, [&] {
    const auto poses = gt::datasets::ParseTimedPoses(text, tum);
    for (size_t i = 0; i < poses.size(); ++i) {
      if (i > 0 && poses[i].t < poses[i - 1].t) std::abort();  // sorted by time
      CheckPose(poses[i].translation, poses[i].q_xyzw, tum, poses[i].line_no);
    }
  });
  return 0;
}

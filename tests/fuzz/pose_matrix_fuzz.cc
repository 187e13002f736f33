// 4x4 pose text (ScanNet pose/<n>.txt and 7-Scenes frame-NNNNNN.pose.txt share this
// parser: ReadPoseText) and intrinsics text (3x3 or 4x4), then the pose check the readers
// make (SetMatrixPose): the rigid transform of a valid matrix, or an unusable frame whose
// detail names the file and a line.
#include <cstdint>

#include "libgt/core/pose.h"
#include "libgt/datasets/text_parsing.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "pose/0.txt";
  const std::string_view text = gt::fuzz::Bytes(data, size);
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const gt::datasets::PoseText pose = gt::datasets::ParsePoseText(text, name);
    gt::Frame f;
    if (gt::datasets::SetMatrixPose(pose.world_from_cam, pose.where, &f)) {
      if (!f.world_from_cam.matrix().allFinite()) std::abort();
    } else if (f.usable || f.unusable_detail.rfind(name + ":", 0) != 0) {
      std::abort();
    }
  });
  const std::string k_name = "intrinsic/intrinsic_depth.txt";
  gt::fuzz::ExpectValueOrInputError(k_name, [&] {
    const Eigen::Matrix3d K = gt::datasets::ParseIntrinsicsText(text, k_name);
    if (!K.allFinite() || !(K(0, 0) > 0)) std::abort();
  });
  return 0;
}

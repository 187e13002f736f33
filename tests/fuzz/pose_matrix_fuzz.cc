// 4x4 pose text (ScanNet pose/<n>.txt and 7-Scenes frame-NNNNNN.pose.txt share this
// parser: ReadMatrixText) and intrinsics text (3x3 or 4x4), then the pose validity check
// and the rigid transform the readers build from a valid matrix.
#include <cstdint>

#include "libgt/core/pose.h"
#include "libgt/datasets/text_parsing.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string name = "pose/0.txt";
  const std::string_view text = gt::fuzz::Bytes(data, size);
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const Eigen::Matrix4d m = gt::datasets::ParseMatrixText(text, name, 4, 4);
    if (!gt::PoseProblem(m)) {
      const gt::Rigid3d r = gt::RigidFromMatrix(m);
      if (!r.matrix().allFinite()) std::abort();
    }
  });
  const std::string k_name = "intrinsic/intrinsic_depth.txt";
  gt::fuzz::ExpectValueOrInputError(k_name, [&] {
    const Eigen::Matrix3d K = gt::datasets::ParseIntrinsicsText(text, k_name);
    if (!K.allFinite() || !(K(0, 0) > 0)) std::abort();
  });
  return 0;
}

// The occupancy map fused over a scope of a scene (truth::FuseScope: the pair, a window of
// neighbouring frames or the whole scene at a stride), as Python holds it: made by
// Scene.fuse (io.cc), passed to pair_ground_truth(scope_map=...) (truth.cc), shared by every
// pair that uses it. It keeps the options it was fused with, so that a pair computed with
// other fusion options is refused instead of silently mixing the two.
#pragma once

#include <memory>
#include <string>

#include "libgt/truth/pair_truth.h"

namespace occgt_py {

struct PyScopeMap {
  std::shared_ptr<const gt::truth::ScopeMap> fused;
  std::string scene;
  std::string scope;  // FusionScopeName: "pair", "window:N", "scene:S"
  double voxel_m = 0.0, max_range_m = 0.0, min_depth_m = 0.0, max_depth_m = 0.0;
  gt::occupancy::FusionOptions fusion;  // the options it was fused with (its point filters)
  int width = 0, height = 0;            // working resolution of the fused depth maps
};

}  // namespace occgt_py

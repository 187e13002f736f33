// Pair facade (pair_occupancy.h).
#include "libgt/occupancy/pair_occupancy.h"

#include <tbb/parallel_invoke.h>

#include "libgt/core/error.h"

namespace gt::occupancy {

OccupancyMode ParseOccupancyMode(const std::string& text) {
  if (text == "octomap") return OccupancyMode::kOctomap;
  if (text == "two_point") return OccupancyMode::kTwoPoint;
  throw InputError("--mode", "expected octomap or two_point, got '" + text + "'");
}

std::string OccupancyModeName(OccupancyMode mode) {
  return mode == OccupancyMode::kTwoPoint ? "two_point" : "octomap";
}

PairOccupancy ComputePairOccupancy(const FusionInput& frame0, const FusionInput& frame1,
                                   const FusionOptions& fusion_options,
                                   const BinOptions& bin_options, OccupancyMode mode,
                                   const OccupancyMap* shared_map) {
  PairOccupancy out;
  if (mode == OccupancyMode::kTwoPoint) {
    tbb::parallel_invoke([&] { out.cam0 = TwoPointVolume(frame0, frame1, bin_options); },
                         [&] { out.cam1 = TwoPointVolume(frame1, frame0, bin_options); });
    return out;
  }
  OccupancyMap fused;
  const OccupancyMap* map = shared_map;
  if (map == nullptr) {
    fused = FuseOccupancy({frame0, frame1}, fusion_options);
    map = &fused;
  }
  out.fusion_stats = map->stats();
  // The two cameras' volumes are independent reads of the map: two tasks (a pair's
  // occupancy is often the last work of a build, when no other sample is left to run
  // beside it).
  tbb::parallel_invoke(
      [&] { out.cam0 = ProjectToFrustum(*map, frame0.camera, frame0.world_from_cam, bin_options); },
      [&] {
        out.cam1 = ProjectToFrustum(*map, frame1.camera, frame1.world_from_cam, bin_options);
      });
  return out;
}

}  // namespace gt::occupancy

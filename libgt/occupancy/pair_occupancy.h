// Occupancy targets of both cameras of a pair: the facade the pair pipeline calls
// (GROUND_TRUTH.md §5). Mode `octomap` fuses (or reuses) an OccupancyMap and bins it in each
// camera's frustum; mode `two_point` reproduces the released Occ²Net target
// (frustum.h TwoPointVolume). Layouts as in frustum.h.
#pragma once

#include <optional>
#include <string>

#include "libgt/occupancy/frustum.h"
#include "libgt/occupancy/fusion.h"

namespace gt::occupancy {

enum class OccupancyMode { kOctomap, kTwoPoint };           // "octomap" | "two_point"
OccupancyMode ParseOccupancyMode(const std::string& text);  // InputError("--mode", ...)
std::string OccupancyModeName(OccupancyMode mode);

struct PairOccupancy {
  FrustumVolume cam0;  // in frame0's camera (frame0.camera.HalfGrid())
  FrustumVolume cam1;
  // kOctomap: what happened to the points of the map binned (the pair's own fusion, or the
  // shared map's, summed over its frames): pixels, invalid and out-of-key-range points
  // dropped, points inserted. Unset for kTwoPoint (no fusion).
  std::optional<FusionStats> fusion_stats;
};

// frame0/frame1: the pair (depth at each camera's resolution). kOctomap: when shared_map is
// null the pair is fused with fusion_options (scope kPair); pass the map of a window or scene
// scope to reuse it. kTwoPoint ignores fusion_options and shared_map.
PairOccupancy ComputePairOccupancy(const FusionInput& frame0, const FusionInput& frame1,
                                   const FusionOptions& fusion_options,
                                   const BinOptions& bin_options, OccupancyMode mode,
                                   const OccupancyMap* shared_map = nullptr);

}  // namespace gt::occupancy

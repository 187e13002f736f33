// The ground truth of one pair of frames in one call: the per-pair entry point that the
// build, `occgt pair`, `occgt occupancy`, `inspect pair` and the Python module all use
// (GROUND_TRUTH.md §2–5).
//
// Inputs are plain arrays at the working resolution (WorkingFrame: depth [H, W] planar
// metres, K at W×H, world_from_cam) and one Options struct; outputs are the labels of both
// directions (uint8 [H, W] PixelLabel codes), their metrics at stride 1, the coarse patch
// matches (geometry/patches.h layouts) and, when asked, the occupancy volumes of both
// cameras (occupancy/frustum.h: uint64 occ/known words [H/2, W/2]).
//
// Occupancy scopes (GROUND_TRUTH.md §5): `pair` fuses the two frames here; `window` and
// `scene` fuse more frames of the scene (FuseScope below) into a map the caller passes in,
// so that a scene map is computed once and shared by every pair of the scene.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "libgt/core/frame.h"
#include "libgt/geometry/pair.h"
#include "libgt/occupancy/pair_occupancy.h"
#include "libgt/truth/working_frame.h"

namespace gt::truth {

struct PairTruthOptions {
  LabelOptions labels;   // preset `default` unless set (geometry/labels.h LabelPreset); its
                         // depth range is also the occupancy fusion's validity range
  PatchOptions patches;  // stride 8, centre anchors, mutual vv
  bool labels_and_matches = true;   // compute the labels, metrics and patch matches
  bool occupancy = true;            // compute the two occupancy volumes
  occupancy::FusionOptions fusion;  // voxel 5 cm, range 10 m, scope pair
  occupancy::BinOptions bins;       // 64 linear bins in [0.1, 10] m, exact traversal
  occupancy::OccupancyMode mode = occupancy::OccupancyMode::kOctomap;

  bool Check(std::string* error) const;
};

// "" or why options.mode cannot use options.fusion's scope or point filters (two_point fuses
// nothing, so a window or scene scope, downsample or remove_outliers would be recorded and
// not applied); part of Check, and of a recipe's check for occupancy that is enabled.
std::string ModeScopeProblem(const PairTruthOptions& options);

struct PairTruth {
  PairLabels labels;  // l01/l10, m01/m10, patches, cam1_from_cam0 (when labels_and_matches)
  std::optional<occupancy::PairOccupancy> occupancy;  // when options.occupancy
};

// frame0/frame1 at the working resolution. scope_map: the fused map of a window or scene
// scope (FuseScope) for mode octomap, else null (the pair is fused here). Labels and
// occupancy are computed as parallel TBB tasks; an error of either is rethrown (labels
// first), so the one reported never depends on timing. Throws InputError for options that
// fail Check and for inputs of the wrong size.
PairTruth ComputePairTruth(const WorkingFrame& frame0, const WorkingFrame& frame1,
                           const PairTruthOptions& options,
                           const occupancy::OccupancyMap* scope_map = nullptr);

// The fused map of a window or scene scope (options.fusion.scope) for the pair (i0, i1) of
// `scene`, its frames loaded with `load` (an index into scene.frames → the working frame).
// Every frame of the scope is fused or listed in `skipped`, in scene order: a frame the
// reader marked unusable (occupancy::ScopeFrameIndices's `unusable`; not read), and a frame
// other than the pair's that cannot be read; an error of the pair's own frames propagates;
// a scope with no frame left to fuse (no usable frame, or none readable) is an InputError
// naming the scene, not an all-unknown map.
struct ScopeMap {
  occupancy::OccupancyMap map;
  std::vector<std::string> fused_ids;  // frame ids, in fusion order
  struct Skipped {
    std::string frame_id;
    // "unusable: <Frame::UnusableMessage()>", or the error reading the frame
    std::string reason;
    bool unusable = false;  // the reader's unusable frame (else: it could not be read)
  };
  std::vector<Skipped> skipped;
};
using FrameLoader = std::function<WorkingFrame(size_t frame_index)>;
ScopeMap FuseScope(const Scene& scene, size_t i0, size_t i1, const PairTruthOptions& options,
                   const FrameLoader& load);

// The validity range of the options as the FusionInput of a frame.
occupancy::FusionInput FusionInputOf(const WorkingFrame& frame, const LabelOptions& labels);

}  // namespace gt::truth

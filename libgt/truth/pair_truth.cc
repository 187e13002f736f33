#include "libgt/truth/pair_truth.h"

#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <exception>
#include <utility>

#include "libgt/core/error.h"

namespace gt::truth {

bool PairTruthOptions::Check(std::string* error) const {
  if (!labels.Check(error)) return *error = "labels: " + *error, false;
  if (labels_and_matches && !patches.Check(error)) return *error = "patches: " + *error, false;
  if (!occupancy) return true;
  if (!fusion.Check(error)) return *error = "occupancy: " + *error, false;
  if (!bins.Check(error)) return *error = "occupancy: " + *error, false;
  if (std::string why = ModeScopeProblem(*this); !why.empty()) {
    return *error = "occupancy: " + why, false;
  }
  return true;
}

std::string ModeScopeProblem(const PairTruthOptions& options) {
  // two_point fuses nothing: a scope of more frames would be recorded and not applied.
  if (options.mode == occupancy::OccupancyMode::kTwoPoint &&
      options.fusion.scope != occupancy::FusionScope::kPair) {
    return "scope " + occupancy::FusionScopeName(options.fusion) +
           " fuses frames for mode octomap only (mode two_point uses the pair's depth alone): "
           "use scope pair";
  }
  if (options.mode == occupancy::OccupancyMode::kTwoPoint &&
      (options.fusion.downsample || options.fusion.remove_outliers)) {
    return std::string(options.fusion.downsample ? "downsample" : "remove_outliers") +
           " filters the fused points for mode octomap only (mode two_point fuses nothing)";
  }
  return "";
}

occupancy::FusionInput FusionInputOf(const WorkingFrame& frame, const LabelOptions& labels) {
  return {frame.depth.get(), frame.camera, frame.world_from_cam, labels.min_depth_m,
          labels.max_depth_m};
}

PairTruth ComputePairTruth(const WorkingFrame& frame0, const WorkingFrame& frame1,
                           const PairTruthOptions& options,
                           const occupancy::OccupancyMap* scope_map) {
  std::string error;
  if (!options.Check(&error)) throw InputError("pair options", error);
  GT_ASSERT(frame0.depth && frame1.depth);
  PairTruth out;
  std::exception_ptr failed[2];
  auto guarded = [](std::exception_ptr* e, auto&& f) {
    try {
      f();
    } catch (...) {
      *e = std::current_exception();
    }
  };
  // Its own context: a cancellation of the caller's work (another sample of a build
  // failing) must not silently skip these tasks and leave the results empty.
  tbb::task_group_context own(tbb::task_group_context::isolated);
  tbb::parallel_invoke(
      [&] {
        guarded(&failed[1], [&] {
          if (!options.occupancy) return;
          out.occupancy = occupancy::ComputePairOccupancy(
              FusionInputOf(frame0, options.labels), FusionInputOf(frame1, options.labels),
              options.fusion, options.bins, options.mode, scope_map);
        });
      },
      [&] {
        guarded(&failed[0], [&] {
          if (!options.labels_and_matches) return;
          out.labels =
              LabelPair(*frame0.depth, frame0.camera, frame0.world_from_cam, *frame1.depth,
                        frame1.camera, frame1.world_from_cam, options.labels, options.patches);
        });
      },
      own);
  for (const std::exception_ptr& e : failed) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

ScopeMap FuseScope(const Scene& scene, size_t i0, size_t i1, const PairTruthOptions& options,
                   const FrameLoader& load) {
  std::vector<size_t> indices = {i0, i1}, unusable;
  if (options.fusion.scope != occupancy::FusionScope::kPair) {
    indices = occupancy::ScopeFrameIndices(scene, i0, i1, options.fusion, &unusable);
    indices.insert(indices.end(), unusable.begin(), unusable.end());
    std::sort(indices.begin(), indices.end());  // scene order
  }
  ScopeMap out;
  std::vector<WorkingFrame> frames;
  frames.reserve(indices.size());
  size_t unreadable = 0;
  for (size_t i : indices) {
    const Frame& frame = scene.frames[i];
    if (std::binary_search(unusable.begin(), unusable.end(), i)) {  // listed, never read
      out.skipped.push_back({frame.id, "unusable: " + frame.UnusableMessage(), true});
      continue;
    }
    try {
      frames.push_back(load(i));
    } catch (const InputError& e) {
      if (i == i0 || i == i1) throw;
      out.skipped.push_back({frame.id, e.what(), false});
      ++unreadable;
      continue;
    }
    out.fused_ids.push_back(frame.id);
  }
  if (frames.empty()) {  // an empty map: every bin unknown
    const auto first_unreadable =
        std::find_if(out.skipped.begin(), out.skipped.end(),
                     [](const ScopeMap::Skipped& s) { return !s.unusable; });
    throw InputError(
        scene.name,
        "occupancy scope " + occupancy::FusionScopeName(options.fusion) + ": no frame to fuse" +
            (unreadable == 0
                 ? std::string(" (the scene has no usable frame)")
                 : ": none of its " + std::to_string(unreadable) +
                       " frames could be read, the first: " + first_unreadable->reason));
  }
  std::vector<occupancy::FusionInput> inputs;
  inputs.reserve(frames.size());
  for (const WorkingFrame& f : frames) inputs.push_back(FusionInputOf(f, options.labels));
  out.map = occupancy::FuseOccupancy(inputs, options.fusion);
  return out;
}

}  // namespace gt::truth

// Re-opening the dataset of a build (`occgt build` DIR) from DIR/recipe.json, the resolved
// recipe the build wrote (Recipe::ToJson), for commands that read its frames again; and the
// depth-source shares of a split for its report (`occgt inspect split`, docs/INSPECT.md).
//
// recipe.json records what re-opening needs: dataset.format ("synthetic": the generic data
// the build generated into DIR/data), dataset.root (as the build's working folder saw it),
// dataset.device (ScanNet++: the camera whose frames were read), dataset.mesh_path,
// dataset.depth_source and fused_depth (absent: sensor), resolution.
#pragma once

#include <optional>
#include <string>

#include "libgt/core/frame.h"
#include "libgt/datasets/reader.h"
#include "libgt/render/frame_depth.h"
#include "libgt/report/split_report.h"
#include "libgt/truth/working_frame.h"

namespace gt::pipeline {

struct BuildDataset {
  DatasetFormat format = DatasetFormat::kGeneric;
  std::string root;  // recipe.json's dataset.root, or the override; synthetic: DIR/data
  // dataset.device (scannetpp), dataset.tum_max_dt_s (tum), as RecipeReaderOptions reads them
  datasets::ReaderOptions reader;
  std::string mesh_path;            // dataset.mesh_path ("" = the reader's own)
  render::FrameDepthOptions depth;  // dataset.depth_source, fused_depth
  truth::Resolution resolution;     // resolution
};

// Reads DIR/recipe.json. A missing or malformed field is an InputError naming
// "DIR/recipe.json: <field>"; a ScanNet++ build without dataset.device is refused (every
// build of the ScanNet++ reader records it). root_override ("" = none) replaces the root.
BuildDataset ReadBuildDataset(const std::string& dir, const std::string& root_override = "");

// The split's depth-source shares when its build's depth source is mesh or fused (nullopt
// for sensor, or when DIR has no recipe.json): every distinct frame of DIR/pairs.jsonl compared at
// the build's resolution with truth::CompareWorkingDepthWithMesh, frames in parallel (TBB), summed
// in a fixed order. Throws InputError when the dataset or a mesh cannot be read (naming it; the
// root may be given again with root_override).
std::optional<report::SplitDepthShares> ComputeSplitDepthShares(
    const std::string& dir, const std::string& root_override = "");

}  // namespace gt::pipeline

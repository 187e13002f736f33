// The synthetic dataset of a recipe with `dataset: {format: synthetic}`: the procedural
// sample of libgt/synth (exact ray-cast depth, generic manifests) generated into a folder
// when it is missing, so that `occgt build recipes/demo.yaml --out DIR` needs no download.
// The folder holds one generic manifest per scene (docs/DATASETS.md "Generic") and a
// completion marker `.complete` holding the generator options; a folder without the marker
// is regenerated, one whose marker names other options is an error.
#pragma once

#include <string>

#include "libgt/pipeline/recipe.h"

namespace gt::pipeline {

void EnsureSyntheticDataset(const std::string& root, const SyntheticDatasetOptions& options);

}  // namespace gt::pipeline

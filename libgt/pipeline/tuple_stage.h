// `occgt tuples`: seeded N-view tuples of every scene of a recipe, sampled on the covisibility
// graphs of `occgt covis` (pairs/tuples.h for the walk, pipeline/covisibility.h for the
// graphs; docs/MULTIVIEW.md "Tuples").
//
// Reads DIR/covisibility/<scene>.npz of every scene (written under the same
// CovisibilityDigest; a missing or other graph is an error naming it), samples
// recipe.tuples->quota tuples per scene with the seed SceneSeed(recipe.seed, scene), and
// writes DIR/tuples.jsonl (atomically), one JSON object per tuple in scene order then draw
// order (schemas/tuples_line.schema.json):
//   {"scene", "frame_ids": [N ids, in the order the walk added them],
//    "covisibility": N×N, [a][b] = the graph's visible overlap of frame a → frame b
//                    (c_ij / c_ji; 0 for a pair the pruning dropped), [a][a] = self}
// No threads: the file depends on the graphs, the options and the seed only. A run holds
// DIR/.tuples.lock (AcquireTaskLock, build.h): a second `occgt tuples` into DIR is refused
// while it runs.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "libgt/pairs/tuples.h"
#include "libgt/pipeline/recipe.h"

namespace gt::pipeline {

// Returns the summary {scenes, tuples, views: {N: count}, drops}. With write_shards, every
// view's depth is checked first (CheckGraphFramesDepth, before anything is written), then the
// N-view shards of the tuples are written (views_write.h, DIR/views/) and their summary added
// as "shards".
nlohmann::json RunTuples(const Recipe& recipe, const std::string& out_dir,
                         bool write_shards = false);

}  // namespace gt::pipeline

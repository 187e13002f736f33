// The write stage of `occgt build`: the selected pairs, in the global order (scenes sorted,
// pairs in selection order), are cut into shards of the plan; a task computes the samples
// of its incomplete shards (sample.h ComputeSample over truth::ComputePairTruth) and writes
// them with the shard writer of libgt/shards; when every shard is complete, the indices
// (index.json, pairs.jsonl: shards::MergeSplit trusting the recorded digests) and the
// LoFTR-family export (DIR/loftr/) are published.
//
// Pipeline (TBB parallel_pipeline, one per task, no barrier at shard ends):
//   1. serial, in order: the next sample; reads its scene when first needed;
//   2. parallel: ComputeSample (ground truth, images, encoding);
//   3. serial, in order: adds the sample to its shard's writer; when the shard is complete,
//      its Finish (close, fsync, rename, part record) runs on a thread of its own while the
//      pipeline goes on (at most one in flight), so shards are published in order and byte
//      for byte as with any thread count.
// At most 2 × threads samples are in flight; a scene's data is released when its last
// sample is computed. An error in any stage cancels the pipeline: the shard being filled
// is dropped (its temporary removed), nothing later is published.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libgt/datasets/reader.h"
#include "libgt/pipeline/build.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/sample.h"

namespace gt::pipeline {

struct WriteResult {
  int64_t shards_written = 0;   // this run
  int64_t shards_skipped = 0;   // found complete (resume)
  int64_t samples_written = 0;  // this run
  int64_t bytes_written = 0;    // shard bytes of this run
};

// Sizes of the shards of `total` samples under the recipe's shards options.
std::vector<int64_t> PlanShards(const Recipe& recipe, int64_t total);

// The sample key of every pair (shards::MakeSampleKey); two pairs with one key after
// sanitising are an InputError naming both scenes, and so is a key whose longest member
// (LongestPairField under `compression`) would not fit a tar member path, so that the build
// stops before it computes any sample (and its dry run says so).
std::vector<std::string> SampleKeys(const std::vector<const SelectedPair*>& all,
                                    SampleCompression compression);

// Refuses, before anything is written, an export the recipe asks for whose folders the
// selected scenes cannot all have: two scenes mapping to one LoFTR folder
// (shards::LoftrSceneFolders) or to one glue-factory/DUSt3R folder
// (shards::PosedSceneFolders). The same InputError the export would throw.
void CheckExportFolders(const Recipe& recipe, const std::vector<const SelectedPair*>& all);

// Publishes the plan (DIR/parts/<split>.plan.json) once, under the folder lock; refuses a
// different existing plan.
void WritePlan(const BuildOptions& options, const std::string& split,
               const std::vector<int64_t>& shard_sizes);

// Writes this task's incomplete shards of the plan.
WriteResult WriteShards(const Recipe& recipe, const datasets::DatasetReader& reader,
                        const BuildOptions& options, const std::vector<const SelectedPair*>& all,
                        const std::vector<std::string>& keys,
                        const std::vector<int64_t>& shard_sizes, const ProgressFn& progress);

// True when every shard of the plan is complete.
bool AllShardsComplete(const BuildOptions& options, const std::string& split, int64_t nshards);

// Writes index.json, pairs.jsonl and, with recipe.loftr_export, the LoFTR-family index.
void PublishIndices(const Recipe& recipe, const datasets::DatasetReader& reader,
                    const BuildOptions& options, const std::vector<const SelectedPair*>& all);

}  // namespace gt::pipeline

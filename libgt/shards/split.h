// The on-disk layout of one split and the steps that publish it: per-shard part records
// written by `occgt build` tasks, and the merge / validate steps (SHARDS.md "Index files",
// SCALE.md rules 2-4).
//
// Layout of an output folder DIR holding split S (names come from the input, never from a
// task id, so any task layout gives the same files):
//   DIR/parts/S.plan.json         written ONCE before shards are written (select stage or
//                                 task 0): {"split": S, "nshards": N,
//                                 "nsamples": [n_0, ..., n_{N-1}]}
//   DIR/S-000000.tar ...          shard s = "S-{s:06d}.tar" (TarShardWriter)
//   DIR/parts/S-000000.json       part record of shard s, written right after the shard is
//                                 published; it is the shard's completion marker, and
//                                 its md5sum / filesize (computed while writing) are what
//                                 the merge trusts and copies into index.json:
//                                 {"split", "shard_index", "url", "nsamples", "md5sum",
//                                  "filesize", "keys": [...], "pairs": [{...}, ...]}
//   DIR/index.json                (merge) wids index: {"__kind__": "wids-shard-index-v1",
//                                 "wids_version": 1, "name": S, "shardlist": [{"url":
//                                 "S-000000.tar", "nsamples", "md5sum", "filesize"}, ...]}
//   DIR/pairs.jsonl               (merge) one compact JSON object per sample, shards in
//                                 order, samples in shard order; each line is the
//                                 caller's pair line plus "shard" (url) and "key".
//   DIR/summary.json              (occgt merge) MergeSummaryJson below.
// URLs in index.json are relative to DIR. All JSON is written with sorted keys and
// atomically (gt::io::WriteFileAtomic), so outputs are byte-deterministic.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "libgt/shards/sample.h"
#include "libgt/shards/tar_shard.h"

namespace gt::shards {

// "S-{s:06d}.tar", "DIR/S-{s:06d}.tar", "DIR/parts/S-{s:06d}.json", "DIR/parts/S.plan.json".
std::string ShardFileName(const std::string& split, int64_t shard_index);
std::string ShardPath(const std::string& dir, const std::string& split, int64_t shard_index);
std::string PartRecordPath(const std::string& dir, const std::string& split, int64_t shard_index);
std::string PlanPath(const std::string& dir, const std::string& split);
// "" when `split` is usable in file names ([A-Za-z0-9_-]+, not starting with "__").
std::string CheckSplitName(const std::string& split);

// How many shards a split has and how many samples each holds.
struct SplitPlan {
  std::string split;
  std::vector<int64_t> shard_nsamples;  // one entry per shard, in shard order
};
// Equal cut of `total_samples` into shards of `samples_per_shard` (last one shorter).
SplitPlan PlanEqualShards(const std::string& split, int64_t total_samples,
                          int64_t samples_per_shard);
void WritePlan(const std::string& dir, const SplitPlan& plan);         // atomic
SplitPlan ReadPlan(const std::string& dir, const std::string& split);  // InputError if bad
// Splits that have a plan in DIR/parts, sorted.
std::vector<std::string> ListPlannedSplits(const std::string& dir);

// Record of one finished shard (the parsed part record).
struct PartRecord {
  std::string split;
  int64_t shard_index = 0;
  std::string url;  // shard file name relative to DIR
  ShardInfo info;
  std::vector<std::string> keys;        // sample keys in tar order
  std::vector<std::string> pair_lines;  // compact JSON objects, one per key, same order
  // The options digest of the build that wrote the shard (its samples' "options_digest");
  // "" in records written before it was recorded. The merge refuses a split whose records
  // name two digests, or another than DIR/recipe.json's.
  std::string options_digest;
};
// Parses DIR/parts/S-{s:06d}.json; throws InputError("<record path>", ...) unless it names
// shard s of the split, has a 32-digit lower-case hex md5sum, non-negative sizes, and one
// key and one pair line per sample, each line's "key" and "shard" naming its key and url.
PartRecord ReadPartRecord(const std::string& dir, const std::string& split, int64_t shard_index);

// Writes shard s of a split and then its part record. Usage (one per shard, any thread):
//   SplitShardWriter w(dir, split, s, recipe.Digest());
//   for (...) w.Add(sample, pair_line_json);
//   PartRecord r = w.Finish();
// `pair_line_json` must be one JSON object (the pairs.jsonl line of this sample: scene,
// frame ids, directional metrics); the writer sets its "shard" and "key" members.
class SplitShardWriter {
 public:
  SplitShardWriter(const std::string& dir, const std::string& split, int64_t shard_index,
                   const std::string& options_digest = "");
  ~SplitShardWriter();
  void Add(const Sample& sample, const std::string& pair_line_json);
  // The same, taking the sample (its buffers are released when Add returns).
  void Add(Sample&& sample, const std::string& pair_line_json);
  // Publishes the tar (TarShardWriter::Finish), then writes its part record with the size
  // and the MD5 computed while writing; returns the record.
  PartRecord Finish();

 private:
  nlohmann::json ParsePairLine(const std::string& key, const std::string& text) const;
  void Record(const std::string& key, nlohmann::json* line);
  PartRecord record_;
  std::string dir_;
  std::unique_ptr<TarShardWriter> tar_;
};

// True when shard s was completed earlier: its part record parses and the tar exists
// with the recorded size (and MD5 when `verify_md5`). `occgt build` uses it to skip work
// on a re-run.
bool IsShardComplete(const std::string& dir, const std::string& split, int64_t shard_index,
                     bool verify_md5 = false);

// wids index.json text (sorted keys, 2-space indent, trailing newline).
std::string IndexJson(const std::string& name, const std::vector<PartRecord>& parts);

// One entry of index.json's shardlist.
struct IndexedShard {
  std::string url;  // the shard's file name, in the split folder
  int64_t nsamples = 0;
  int64_t filesize = 0;
  std::string md5sum;  // "" when the entry has none (ValidateSplit requires it)
};
struct ShardIndex {
  std::string path;  // DIR/index.json
  std::string name;  // "" when the index has none
  std::vector<IndexedShard> shards;
};
// DIR/index.json as every reader of a published split needs it (ShardDataset, `occgt eval`;
// ValidateSplit checks each entry the same way): an object with a shardlist whose entries
// have a url that is a file name in DIR (no folder part, so an edited index cannot point a
// reader outside the split), nsamples and filesize integers >= 0, md5sum a string when
// present. Throws InputError naming index.json (and shardlist[i]); the shards themselves
// are not opened.
ShardIndex ReadShardIndex(const std::string& dir);
// Writes lines (each without '\n') as a JSONL file atomically.
void WriteJsonLines(const std::string& path, const std::vector<std::string>& lines);

struct MergeOptions {
  std::string split;        // "" = the only split planned in DIR/parts (error if several)
  bool verify = false;      // also re-hash every shard and read every tar back (keys,
                            // member names, .npy headers), and check sample JSON and
                            // pair lines against the schemas; shards in parallel; reads
                            // every byte
  std::string schemas_dir;  // the schemas `verify` checks against, as ValidateOptions'
                            // ("" = built in); the default merge checks no JSON Schema
  bool Check(std::string* error) const;
};

struct MergeResult {
  std::string split;
  int64_t nshards = 0;
  int64_t nsamples = 0;
  int64_t total_bytes = 0;
  std::vector<PartRecord> parts;  // in shard order; pair_lines left empty (in pairs.jsonl)
  std::map<std::string, int64_t> samples_per_scene;  // lines' "scene" (else key folder)
  bool tuples = false;  // the lines are N-view samples' (they have "tuple_index")
};

// Publishes a split whose shards the tasks have written: checks every shard of the plan
// and then writes DIR/pairs.jsonl and DIR/index.json atomically (index.json second).
// By default the digests and sizes the tasks recorded while writing are TRUSTED: the merge
// reads the plan and every part record (ReadPartRecord's checks), stats every tar (present,
// the recorded size) and checks sample count = plan = record, valid keys, and that no key
// repeats in the split. It never opens a tar: its cost is one small-file read and parse
// per shard (JSON of its pair lines, records parsed in parallel) and one stat, whatever
// the shards' bytes; pairs.jsonl is streamed, so memory is a few chunks of records plus
// the split's keys. A shard whose bytes changed with its size kept is therefore not caught
// here; ValidateSplit and `verify` (MD5 of every shard, tars read back) catch it.
// The first missing or corrupt shard throws InputError("<shard path>", reason) (a pair line
// breaking pairs_line.schema.json: "<record path>: pairs[i]: ..."), the first in shard
// order whatever the thread count and whatever the kind of problem (with `verify`, a
// truncated shard 2 found by the record checks does not hide an MD5 mismatch of shard 0:
// the shards before the first record problem are read through before it is reported);
// nothing is published then.
MergeResult MergeSplit(const std::string& dir, const MergeOptions& options);
// summary.json content of a merge: {"kind": "occgt-merge-summary", "split", "shards",
// "samples" (the build summary's name), "bytes", "pairs_per_scene": {scene: n} (from the pair
// lines' "scene" field; "tuples_per_scene" for the N-view shards of `occgt tuples`)}.
std::string MergeSummaryJson(const MergeResult& result);
// Writes DIR/summary.json (MergeSummaryJson) atomically unless DIR/summary.json already
// holds another document (the richer summary of `occgt build`, schemas/summary.schema.json),
// which is left untouched. Returns true when it wrote.
bool WriteMergeSummary(const std::string& dir, const MergeResult& result);

struct ValidateOptions {
  std::string schemas_dir;  // the JSON Schemas' folder (index, sample, views_sample,
                            // pairs_line, views_line .schema.json, all required); "" = the
                            // copies of schemas/ built into the binary
  // Each sample's members and values against its json and each other (pair samples:
  // sample_check.h; N-view samples: views_sample_check.h), and each pairs.jsonl line's
  // values against its sample's json; false: the
  // structure only (tars, names, .npy headers, schemas, counts, keys), for a split whose
  // samples are not occgt build's.
  bool values = true;
  bool Check(std::string* error) const;
};

// Re-checks a published split from DIR/index.json: schema of index.json, every shard's
// size and MD5, sample counts and member names read back from the tars, every .npy
// member's header, every .json member parses (and matches sample.schema.json), pairs.jsonl
// has one line per sample naming an existing shard/key; with options.values, each sample's
// values (sample_check.h, views_sample_check.h) and each line's values against its sample's
// json. Reads every
// byte of every shard; shards are checked in parallel (TBB, as many threads as tbb::global_control
// allows) and their problems collected by shard index, so the lines and their order do not depend
// on the thread count. Returns one line per problem ("<file>: <problem>"); empty = valid. Never
// throws for bad content.
std::vector<std::string> ValidateSplit(const std::string& dir, const ValidateOptions& options);

// Validates `document` (JSON text) against the JSON Schema file `schema_path` (valijson;
// draft-7 keywords, which the draft 2020-12 schemas of schemas/ keep to). Returns one line
// per violation, "" entries never; throws InputError when the schema itself is unreadable.
std::vector<std::string> ValidateJsonAgainstSchema(const std::string& document,
                                                   const std::string& schema_path);

}  // namespace gt::shards

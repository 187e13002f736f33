// occgt merge DIR: checks every shard a split's plan lists (part record, size, MD5, sample
// count, keys and member names, sample JSON against schemas/ when present) and writes
// DIR/index.json, DIR/pairs.jsonl and DIR/summary.json (unless `occgt build` wrote its
// own summary there; libgt/shards/split.h).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "libgt/core/error.h"
#include "libgt/shards/split.h"

namespace occgt {

void AddMergeCommand(CLI::App& app) {
  struct Args {
    std::string dir;
    gt::shards::MergeOptions options;
    bool no_md5 = false;
    bool no_read = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "merge", "Check every shard of a split and write index.json, pairs.jsonl, summary.json");
  cmd->add_option("dir", args->dir, "Output folder of `occgt build` (holds parts/)")->required();
  cmd->add_option("--split", args->options.split, "Split name (default: the only one planned)");
  cmd->add_option("--schemas", args->options.schemas_dir,
                  "Folder with sample.schema.json / pairs_line.schema.json "
                  "(default: $OCCGT_SCHEMAS or the source tree's schemas/, when found)");
  cmd->add_flag("--no-md5", args->no_md5, "Do not recompute shard MD5s (sizes still checked)");
  cmd->add_flag("--no-read", args->no_read, "Do not read the tars back");
  cmd->callback([args] {
    gt::shards::MergeOptions options = args->options;
    options.verify_md5 = !args->no_md5;
    options.read_tars = !args->no_read;
    if (options.schemas_dir.empty()) options.schemas_dir = DefaultSchemasDir();
    std::string error;
    if (!options.Check(&error)) throw gt::InputError("occgt merge", error);
    const gt::shards::MergeResult result = gt::shards::MergeSplit(args->dir, options);
    const bool wrote_summary = gt::shards::WriteMergeSummary(args->dir, result);
    std::printf("merged split %s: %lld shards, %lld samples, %lld bytes -> %s/index.json\n",
                result.split.c_str(), static_cast<long long>(result.nshards),
                static_cast<long long>(result.nsamples), static_cast<long long>(result.total_bytes),
                args->dir.c_str());
    if (!wrote_summary) {
      std::printf("kept the existing %s/summary.json (written by occgt build)\n",
                  args->dir.c_str());
    }
  });
}

}  // namespace occgt

// occgt merge DIR [--verify]: publishes a split the build tasks have written. By default it
// trusts the MD5s and sizes the tasks recorded in their part records while writing: it
// checks that every shard of the plan has its part record, that the tar exists with the
// recorded size, that sample counts agree (plan = record) and that keys and pair lines are
// consistent, without reading the tars; then it writes DIR/index.json, DIR/pairs.jsonl and
// DIR/summary.json (unless `occgt build` wrote its own summary there). Part records are
// parsed in parallel (--threads). --verify also re-hashes and reads back every shard, in
// parallel, as `occgt validate` does (libgt/shards/split.h, docs/SCALE.md).
#include <tbb/global_control.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "apps/job_flags.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/io/folder_lock.h"
#include "libgt/shards/split.h"

namespace occgt {

void AddMergeCommand(CLI::App& app) {
  struct Args {
    std::string dir;
    gt::shards::MergeOptions options;
    int threads = 0;
    bool no_md5 = false;
    bool no_read = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "merge", "Check every shard's part record and write index.json, pairs.jsonl, summary.json");
  cmd->add_option("dir", args->dir, "Output folder of `occgt build` (holds parts/)")->required();
  cmd->add_option("--split", args->options.split, "Split name (default: the only one planned)");
  cmd->add_option("--schemas", args->options.schemas_dir,
                  "Folder of the split's JSON Schemas for --verify (default: the copies of "
                  "schemas/ built into occgt)");
  auto* verify = cmd->add_flag("--verify", args->options.verify,
                               "Also re-hash every shard and read every tar back (reads every "
                               "byte; default: trust the digests recorded while writing)");
  AddThreadsFlag(cmd, &args->threads,
                 "Threads parsing part records and, with --verify, checking shards");
  // Deprecated: the checks they turned off are off by default now.
  cmd->add_flag("--no-md5", args->no_md5, "Deprecated, ignored: MD5s are not recomputed by default")
      ->excludes(verify);
  cmd->add_flag("--no-read", args->no_read, "Deprecated, ignored: tars are not read by default")
      ->excludes(verify);
  cmd->callback([args] {
    gt::shards::MergeOptions options = args->options;
    const bool schemas_given = !options.schemas_dir.empty();
    const std::unique_ptr<tbb::global_control> limit = LimitThreads(args->threads);
    std::string error;
    if (!options.Check(&error)) {
      ThrowOptionsError(error, "occgt merge",
                        {{"split", "--split", true}, {"schemas_dir", "--schemas", schemas_given}});
    }
    for (const char* flag :
         {args->no_md5 ? "--no-md5" : nullptr, args->no_read ? "--no-read" : nullptr}) {
      if (flag != nullptr) {
        std::fprintf(stderr,
                     "occgt merge: note: %s is ignored (the default now trusts the recorded "
                     "digests and reads no tar); use --verify for the full check\n",
                     flag);
      }
    }
    // The indices and summary.json are files a build task may write too: written under
    // the folder's lock, as the tasks do (io/folder_lock.h). A missing DIR is not created.
    std::optional<gt::io::FolderLock> lock;
    if (std::filesystem::is_directory(args->dir)) lock.emplace(args->dir);
    const gt::shards::MergeResult result = gt::shards::MergeSplit(args->dir, options);
    const bool wrote_summary = gt::shards::WriteMergeSummary(args->dir, result);
    std::printf("merged split %s: %lld shards, %lld samples, %lld bytes -> %s/index.json%s\n",
                result.split.c_str(), static_cast<long long>(result.nshards),
                static_cast<long long>(result.nsamples), static_cast<long long>(result.total_bytes),
                args->dir.c_str(), options.verify ? " (verified)" : "");
    if (!wrote_summary) {
      std::printf("kept the existing %s/summary.json (written by occgt build)\n",
                  args->dir.c_str());
    }
  });
}

}  // namespace occgt

// occgt validate DIR [--threads N]: re-checks a published split from DIR/index.json (MD5
// and size of every shard, sample counts and member names read back from the tars, .npy
// headers, JSON against the schemas built in from schemas/, each pair sample's values against
// its json unless --structure-only) and prints one line per problem; exit
// code 1 when any. Reads every byte; shards are checked in parallel on N threads (0 = all cores),
// and the output is the same for every N.
#include <tbb/global_control.h>

#include <cstdio>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/job_flags.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/shards/split.h"

namespace occgt {

void AddValidateCommand(CLI::App& app) {
  struct Args {
    std::string dir;
    gt::shards::ValidateOptions options;
    int threads = 0;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("validate", "Re-check the shards and indices of a split");
  cmd->add_option("dir", args->dir, "Folder holding index.json")->required();
  cmd->add_option("--schemas", args->options.schemas_dir,
                  "Folder of the split's JSON Schemas (default: the copies of schemas/ built "
                  "into occgt)");
  cmd->add_flag("--structure-only{false}", args->options.values,
                "Check the tars, names, .npy headers, schemas, counts and keys, not the pair "
                "samples' values against their json (a split of other WebDataset samples)");
  AddThreadsFlag(cmd, &args->threads, "Threads checking shards");
  cmd->callback([args] {
    gt::shards::ValidateOptions options = args->options;
    const bool schemas_given = !options.schemas_dir.empty();
    const std::unique_ptr<tbb::global_control> limit = LimitThreads(args->threads);
    std::string error;
    if (!options.Check(&error)) {
      ThrowOptionsError(error, "occgt validate", {{"schemas_dir", "--schemas", schemas_given}});
    }
    const std::vector<std::string> problems = gt::shards::ValidateSplit(args->dir, options);
    for (const std::string& p : problems) std::printf("%s\n", p.c_str());
    std::fflush(stdout);  // the lines before the error line on stderr, also through one pipe
    if (!problems.empty()) {
      throw gt::InputError(args->dir, std::to_string(problems.size()) + " problem(s) found");
    }
    std::printf("%s: valid\n", args->dir.c_str());
  });
}

}  // namespace occgt

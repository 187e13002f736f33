// occgt: ground truth and datasets for occlusion-aware image matching.
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <exception>
#include <opencv2/core/utility.hpp>

#include "apps/commands.h"
#include "gt/core/version.h"
#include "libgt/core/error.h"

int main(int argc, char** argv) {
  // occgt runs its own work in parallel (TBB tasks over scenes, samples and a sample's
  // parts, --threads); OpenCV's loops (cv::resize, colour conversions) stay sequential
  // inside them instead of opening a second level of parallelism in a task arena of
  // OpenCV's own. (That arena's TBB code is inlined into Debian's uninstrumented
  // libopencv_core, whose synchronisation ThreadSanitizer cannot see.)
  cv::setNumThreads(1);
  // Past a file-size limit (ulimit -f) write(2) raises SIGXFSZ, whose default action kills
  // the process and leaves its *.tmp behind. Ignored, the write fails with EFBIG instead:
  // the writers remove their temporary file and report one line naming it.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"occgt: ground truth and datasets for occlusion-aware image matching"};
  app.set_version_flag("--version", std::string("occgt ") + gt::kVersion);
  app.require_subcommand(1);
  occgt::AddScanCommand(app);
  occgt::AddSynthCommand(app);
  occgt::AddPairCommand(app);
  occgt::AddOccupancyCommand(app);
  occgt::AddMergeCommand(app);
  occgt::AddValidateCommand(app);
  occgt::AddBuildCommand(app);
  occgt::AddInspectCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const gt::InputError& e) {
    std::fprintf(stderr, "occgt: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "occgt: error: %s\n", e.what());
    return 1;
  }
  return 0;
}

// occgt: ground truth and datasets for occlusion-aware image matching.
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <opencv2/core/utility.hpp>
#include <optional>
#include <string>
#include <vector>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/usage.h"
#include "gt/core/version.h"
#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/core/interrupted.h"

namespace {

// glibc's defaults hand every freed block of 128 KiB and more (depth maps, label maps,
// occupancy volumes, encoded tar members) back to the kernel, and the next sample faults
// fresh zeroed pages in again. Kept in the process instead (never more than the process's
// own peak, which the depth cache bounds), a --threads 1 build on one CPU of the
// tartanair-sample bench variant spends half the system time and ~8 % less wall time
// (docs/PERFORMANCE.md, "Redesign check"). A user's own GLIBC_TUNABLES malloc settings win.
void KeepFreedMemory() {
#if defined(__GLIBC__)
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.") != nullptr) return;
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest (half a 64 MiB arena heap)
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  KeepFreedMemory();
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
  CLI::App app{"occgt: ground truth and datasets for occlusion-aware image matching", "occgt"};
  app.set_version_flag("--version", std::string("occgt ") + gt::kVersion);
  app.require_subcommand(1);
  occgt::AddScanCommand(app);
  occgt::AddSynthCommand(app);
  occgt::AddPairCommand(app);
  occgt::AddOccupancyCommand(app);
  occgt::AddMergeCommand(app);
  occgt::AddValidateCommand(app);
  occgt::AddRenderCommand(app);
  occgt::AddBuildCommand(app);
  occgt::AddInspectCommand(app);
  occgt::AddEvalCommand(app);
  occgt::AddCovisCommand(app);
  occgt::AddTuplesCommand(app);
  occgt::CheckFlagValues(app, {"--scene"});
  // Usage errors (docs/CLI.md): one line, exit 2. Bad input (files, data): one line, exit 1.
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (const std::optional<int> code = occgt::RefuseDanglingEquals(args)) return *code;
  if (const std::optional<int> code = occgt::HandleHelpOrUnknownCommand(app, args)) return *code;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return occgt::UsageError(occgt::DescribeParseError(app, args, e));
  } catch (const gt::Interrupted& e) {  // a child process (gnuplot) ended by Ctrl-C, SIGTERM
    occgt::EndInterrupted(e.signal_number(), e.what());
  } catch (const gt::InputError& e) {
    std::fprintf(stderr, "occgt: error: %s\n", gt::OneLine(e.what()).c_str());
    return e.where().rfind("--", 0) == 0 ? occgt::kUsageExit : 1;  // a flag's value
  } catch (const std::exception& e) {
    std::fprintf(stderr, "occgt: error: %s\n", gt::OneLine(e.what()).c_str());
    return 1;
  }
  return 0;
}

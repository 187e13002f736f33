// occgt scan: placeholder registration; replaced by the implementation.
#include "apps/commands.h"
#include "libgt/core/error.h"

namespace occgt {

void AddScanCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("scan", "(not available yet)");
  cmd->callback([] { throw gt::InputError("occgt scan", "not implemented in this build"); });
}

}  // namespace occgt

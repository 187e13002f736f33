// occgt occupancy: placeholder registration; replaced by the implementation.
#include "apps/commands.h"
#include "libgt/core/error.h"

namespace occgt {

void AddOccupancyCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("occupancy", "(not available yet)");
  cmd->callback([] { throw gt::InputError("occgt occupancy", "not implemented in this build"); });
}

}  // namespace occgt

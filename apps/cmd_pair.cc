// occgt pair: placeholder registration; replaced by the implementation.
#include "apps/commands.h"
#include "libgt/core/error.h"

namespace occgt {

void AddPairCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("pair", "(not available yet)");
  cmd->callback([] { throw gt::InputError("occgt pair", "not implemented in this build"); });
}

}  // namespace occgt

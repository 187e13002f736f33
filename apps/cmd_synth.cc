// occgt synth: placeholder registration; replaced by the implementation.
#include "apps/commands.h"
#include "libgt/core/error.h"

namespace occgt {

void AddSynthCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("synth", "(not available yet)");
  cmd->callback([] { throw gt::InputError("occgt synth", "not implemented in this build"); });
}

}  // namespace occgt

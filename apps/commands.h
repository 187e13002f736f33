// Subcommands of the occgt binary. Each Add*Command registers its CLI11 subcommand with
// a callback; callbacks throw gt::InputError for bad input, which main() turns into one
// line on stderr and exit code 1, or 2 when it names a flag (a usage error, apps/usage.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace occgt {

void AddScanCommand(CLI::App& app);       // cmd_scan.cc
void AddSynthCommand(CLI::App& app);      // cmd_synth.cc
void AddPairCommand(CLI::App& app);       // cmd_pair.cc
void AddOccupancyCommand(CLI::App& app);  // cmd_occupancy.cc
void AddMergeCommand(CLI::App& app);      // cmd_merge.cc
void AddValidateCommand(CLI::App& app);   // cmd_validate.cc
void AddRenderCommand(CLI::App& app);     // cmd_render.cc
// Folder of the JSON Schemas: $OCCGT_SCHEMAS, else schemas/ found next to the binary
// (../schemas, ../../schemas, ../share/occgt/schemas); "" when none (cmd_validate.cc).
std::string DefaultSchemasDir();
void AddBuildCommand(CLI::App& app);    // cmd_build.cc
void AddInspectCommand(CLI::App& app);  // cmd_inspect.cc
void AddEvalCommand(CLI::App& app);     // cmd_eval.cc

}  // namespace occgt

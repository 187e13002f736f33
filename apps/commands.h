// Subcommands of the occgt binary. Each Add*Command registers its CLI11 subcommand with
// a callback; callbacks throw gt::InputError for bad input, which main() turns into one
// line on stderr and exit code 1.
#pragma once

#include <CLI/CLI.hpp>

namespace occgt {

void AddScanCommand(CLI::App& app);       // cmd_scan.cc
void AddSynthCommand(CLI::App& app);      // cmd_synth.cc
void AddPairCommand(CLI::App& app);       // cmd_pair.cc
void AddOccupancyCommand(CLI::App& app);  // cmd_occupancy.cc

}  // namespace occgt

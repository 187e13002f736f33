// Subcommands of the occgt binary. Each Add*Command registers its CLI11 subcommand with
// a callback; callbacks throw gt::InputError for bad input, which main() turns into one
// line on stderr and exit code 1, or 2 when it names a flag (a usage error, apps/usage.h).
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace occgt {

void AddScanCommand(CLI::App& app);       // cmd_scan.cc
void AddSynthCommand(CLI::App& app);      // cmd_synth.cc
void AddPairCommand(CLI::App& app);       // cmd_pair.cc
void AddOccupancyCommand(CLI::App& app);  // cmd_occupancy.cc
void AddMergeCommand(CLI::App& app);      // cmd_merge.cc
void AddValidateCommand(CLI::App& app);   // cmd_validate.cc
void AddRenderCommand(CLI::App& app);     // cmd_render.cc
void AddBuildCommand(CLI::App& app);    // cmd_build.cc
void AddInspectCommand(CLI::App& app);  // cmd_inspect.cc
void AddEvalCommand(CLI::App& app);     // cmd_eval.cc
void AddCovisCommand(CLI::App& app);    // cmd_covis.cc
void AddTuplesCommand(CLI::App& app);   // cmd_tuples.cc
// Task layout of a Slurm array task (SLURM_ARRAY_TASK_ID - MIN of COUNT; cmd_build.cc): false
// when not in an array job; InputError naming the variable for an inconsistent array.
bool TaskFromSlurm(int* task, int* tasks);
// "  dropped: <reason> <n>, ...\n" of a summary's "drops" object ("" when it has none): the
// drops by reason of the text summaries of build, covis and tuples (cmd_build.cc).
std::string DropsText(const nlohmann::json& summary);

}  // namespace occgt

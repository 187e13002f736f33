// The command line's contract for usage errors (docs/CLI.md): every one is a single line
// `occgt: error: <flag or command>: <problem>` on stderr and exit code 2; `occgt help [CMD]`
// prints the help of the binary or of a subcommand; an unknown subcommand is named with
// the nearest known one.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "libgt/core/error.h"

namespace occgt {

inline constexpr int kUsageExit = 2;

// The items of a comma list flag (eval's lists, render's --frames); an empty item (",5",
// "5,,10", a trailing "5,10,") is a usage error naming the flag, as is an item given twice:
// "<flag>: expected comma-separated <what>, got '<text>'".
std::vector<std::string> SplitList(const std::string& text, const std::string& flag,
                                   const std::string& what);

// Prints `occgt: error: <message>` and returns kUsageExit.
int UsageError(const std::string& message);

// Checks every option of every subcommand that takes a value:
// - an empty value is refused (`--failure-error ''` parsed as 0 and changed the results): a
//   usage error "<flag>: expected a value, got ''"; but the flags in `empty_allowed`, for
//   which "" means something (`--scene ""`: the root is the scene's own folder);
// - an integer flag's digits beyond 64 bits are refused: "<flag>: integer out of range, got
//   '...'" (CLI11 saturated them: `--seed 99999999999999999999` ran with 2^64 - 1).
void CheckFlagValues(CLI::App& app, const std::set<std::string>& empty_allowed);

// `--flag=` with nothing after '=' (CLI11 would take the next argument as its value, so
// `--auc= --out x` read "--out" as the AUC list): a usage error "--flag=: expected a value
// after '='". Arguments after a lone `--` are positionals and are not looked at.
std::optional<int> RefuseDanglingEquals(const std::vector<std::string>& args);

// `occgt help`, `occgt help CMD` (exit 0) and an unknown first word (exit 2); nullopt when
// the arguments are for CLI11 to parse.
std::optional<int> HandleHelpOrUnknownCommand(CLI::App& app, const std::vector<std::string>& args);

// One line for a CLI11 parse error that names the flag: an unknown flag of a subcommand is
// reported first (CLI11 reports a missing required argument before it), with the nearest
// known flag.
std::string DescribeParseError(const CLI::App& app, const std::vector<std::string>& args,
                               const CLI::ParseError& error);

// An Options::Check failure "<field> ...": a usage error naming the flag (exit 2) when the
// field leading the message was set by a flag given on the command line (`given`), else bad
// input under `what` (exit 1: the value came from a recipe, a dataset or a default).
struct FieldFlag {
  const char* field;  // the Options field, e.g. "voxel_m"
  const char* flag;   // its flag, e.g. "--voxel-m"
  bool given;         // the flag is on the command line
};
// An unsigned flag (a seed, a size in MB) refuses a negative value, which CLI11 would wrap
// around to a huge one (`--seed -1` = 2^64 - 1), and one below `min`: a usage error
// "<flag>: expected an integer >= <min>, got '-1'". A value that is not a number is left to
// CLI11's conversion error. Returns the option.
CLI::Option* AtLeast(CLI::Option* option, unsigned long long min);
// AtLeast(option, 0).
CLI::Option* NonNegative(CLI::Option* option);

// A default value as help text shows it ("0.05", "10", "64").
std::string Num(double value);

// A path as a word of a suggested command line that a shell reads back as that path: as is
// when it holds only [A-Za-z0-9_./:@%+,=-], else in single quotes; "./" before one that starts
// with '-', which would read as a flag ("out/demo", "'my out'", "./-x").
std::string ShellWord(const std::string& path);

[[noreturn]] void ThrowOptionsError(const std::string& error, const std::string& what,
                                    const std::vector<FieldFlag>& fields);

// An InputError of the work whose where() is an option's name (e.g. "voxel_m" of
// occupancy::CheckKeyRange, which needs the frames to tell): rethrown under the flag of the
// matching `fields` entry (its `field` is that name) when the flag was given (a usage
// error, exit 2), else as it is.
[[noreturn]] void RethrowNamingFlag(const gt::InputError& error,
                                    const std::vector<FieldFlag>& fields);

}  // namespace occgt

// Shared helpers for the tests: where the real samples and the occgt binary are, a
// scratch folder per test, and running the CLI.
#pragma once

#include <string>

namespace gt::test {

// ../shared/data of the source tree. Fails the current test loudly (ADD_FAILURE + returns
// "") when the folder is missing, so a test never passes vacuously without the data.
std::string SharedData(const std::string& relative);
// A fresh, empty folder under the build tree for this test (removed on the next run).
std::string ScratchDir(const std::string& name);
// Path of the occgt binary under test.
std::string OccgtBinary();

struct CommandResult {
  int exit_code = -1;
  std::string stdout_text;
  std::string stderr_text;
};
// Runs `occgt <args>` (args are shell-quoted by the caller) and captures both streams.
CommandResult RunOccgt(const std::string& args);
// Runs an arbitrary shell command and captures both streams.
CommandResult RunShell(const std::string& command);

}  // namespace gt::test

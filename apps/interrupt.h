// Ctrl-C (SIGINT) and SIGTERM during a long command (build, render, covis, tuples, ...):
// one line on stderr, "occgt: interrupted; <advice>", the temporary files the command
// registered removed, then the process ends by the signal as if it had not been caught
// (exit status 130 for Ctrl-C in a shell, 143 for SIGTERM). One mechanism for every
// command (docs/CLI.md "Interrupts"). Nothing here allocates or locks in the handler: the
// message and the names to remove are fixed before the handler can read them.
#pragma once

#include <string>
#include <vector>

namespace occgt {

// Files of one folder that a command names while it writes them and removes on an
// interrupt (and that its next run removes as stale): names ending with one of `suffixes`
// (with at least one byte before it) or equal to one of `names`. A folder is removed only
// when named in `folders` (a scratch folder of dir, removed with every file in it, one
// level) or, on an interrupt, `dir` itself when `remove_dir_if_empty` (a folder the command
// created) and nothing is left in it.
struct TemporaryNames {
  std::string dir;
  std::vector<std::string> suffixes;
  std::vector<std::string> names;
  std::vector<std::string> folders;
  bool remove_dir_if_empty = false;
};

// Installs the SIGINT/SIGTERM handler that prints "\noccgt: interrupted; <advice>\n". Call
// once per process, before the work starts.
void ExitOnInterrupt(const std::string& advice);
// From now on the handler also removes what `names` matches in `names.dir` (the folder
// need not exist yet: the handler opens it by its path; call once, after ExitOnInterrupt).
void RemoveOnInterrupt(const TemporaryNames& names);
// Removes the files of names.dir that `names` matches now, and its `folders` (a crashed or
// killed earlier run's temporaries); a folder that does not exist has none. Returns how
// many files and folders were removed.
int RemoveTemporaries(const TemporaryNames& names);

// While one of these lives, SIGINT/SIGTERM wait: a batch of renames that publishes a
// command's files completes (or does not start) as a whole; a signal that came meanwhile
// is acted on when it ends (the handler's line, cleanup, end by the signal).
class HoldInterrupts {
 public:
  HoldInterrupts();
  ~HoldInterrupts();
  HoldInterrupts(const HoldInterrupts&) = delete;
  HoldInterrupts& operator=(const HoldInterrupts&) = delete;
};

// The end of a command whose child process was interrupted (gt::Interrupted, `detail` its
// what()): the handler's line when ExitOnInterrupt was called, else "occgt: interrupted
// (<detail>)"; then the registered temporaries are removed and the process ends by
// `signal_number`.
[[noreturn]] void EndInterrupted(int signal_number, const std::string& detail);

}  // namespace occgt

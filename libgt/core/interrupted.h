// A run cut short by a signal (Ctrl-C, SIGTERM) that reached a child process occgt waited
// for (gnuplot through std::system, which ignores SIGINT and SIGQUIT in occgt meanwhile):
// not an input error. The CLI (apps/main.cc) prints the one line of an interrupted command,
// "occgt: interrupted; ...", and ends by the same signal (exit status 130 for SIGINT in a
// shell), after the stack is unwound, so that temporary files and folders are removed.
#pragma once

#include <csignal>
#include <stdexcept>
#include <string>

namespace gt {

// "SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT", else "signal N".
inline std::string SignalName(int signal_number) {
  switch (signal_number) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    case SIGQUIT:
      return "SIGQUIT";
    default:
      return "signal " + std::to_string(signal_number);
  }
}

class Interrupted : public std::runtime_error {
 public:
  // `who` was interrupted ("gnuplot"; what() is "gnuplot ended by SIGINT");
  // `signal_number`: SIGINT, SIGTERM, ...
  Interrupted(const std::string& who, int signal_number)
      : std::runtime_error(who + " ended by " + SignalName(signal_number)),
        signal_number_(signal_number) {}
  int signal_number() const { return signal_number_; }

 private:
  int signal_number_;
};

}  // namespace gt

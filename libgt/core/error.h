// Errors in three tiers (docs/ARCHITECTURE.md):
//  - a broken internal invariant is a bug: GT_ASSERT aborts with file and line;
//  - bad input at a file or API boundary throws gt::InputError whose message names the
//    file (or field) and what was expected; the CLI prints it as one line, exit code 1;
//  - option validation returns false with a message (Options::Check), before any work.
#pragma once

#include <stdexcept>
#include <string>

namespace gt {

// Bad input at a boundary. what() is one line: "<where>: <problem>".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& where, const std::string& problem)
      : std::runtime_error(where + ": " + problem), where_(where) {}
  const std::string& where() const { return where_; }

 private:
  std::string where_;
};

[[noreturn]] void AssertFail(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace gt

// Internal invariant; never for input validation.
#define GT_ASSERT(cond)                                         \
  do {                                                          \
    if (!(cond)) ::gt::AssertFail(#cond, __FILE__, __LINE__, ""); \
  } while (0)
#define GT_ASSERT_MSG(cond, msg)                                   \
  do {                                                             \
    if (!(cond)) ::gt::AssertFail(#cond, __FILE__, __LINE__, (msg)); \
  } while (0)

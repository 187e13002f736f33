#include "libgt/core/error.h"

#include <cstdio>
#include <cstdlib>

namespace gt {

void AssertFail(const char* expr, const char* file, int line, const std::string& msg) {
  std::fprintf(stderr, "occgt internal error (a bug): %s:%d: assertion '%s' failed%s%s\n", file,
               line, expr, msg.empty() ? "" : ": ", msg.c_str());
  std::abort();
}

}  // namespace gt

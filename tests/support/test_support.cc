#include "tests/support/test_support.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace gt::test {
namespace fs = std::filesystem;

std::string SharedData(const std::string& relative) {
  const fs::path p = fs::path(OCCGT_SHARED_DATA) / relative;
  if (!fs::exists(p)) {
    ADD_FAILURE() << "real sample data missing: " << p
                  << " (the tests read ../shared/data next to the project; it is required)";
    return "";
  }
  return p.string();
}

std::string ScratchDir(const std::string& name) {
  const fs::path p = fs::current_path() / "scratch" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string OccgtBinary() { return OCCGT_BINARY; }

static std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult RunShell(const std::string& command) {
  static int counter = 0;
  const fs::path dir = fs::current_path() / "scratch" / "_cmd";
  fs::create_directories(dir);
  const std::string base = (dir / ("c" + std::to_string(::getpid()) + "_" +
                                    std::to_string(counter++))).string();
  const std::string full = command + " >" + base + ".out 2>" + base + ".err";
  const int status = std::system(full.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.stdout_text = Slurp(base + ".out");
  r.stderr_text = Slurp(base + ".err");
  fs::remove(base + ".out");
  fs::remove(base + ".err");
  return r;
}

CommandResult RunOccgt(const std::string& args) {
  return RunShell("'" + OccgtBinary() + "' " + args);
}

}  // namespace gt::test

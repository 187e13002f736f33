// Shared by the libFuzzer targets (tests/fuzz/*_fuzz.cc). The invariant every target
// checks: a parser of outside bytes either returns a value or throws gt::InputError whose
// message names the source. Any other exception aborts (libFuzzer reports a crash with
// the input); crashes, leaks and undefined behaviour are caught by ASan/UBSan.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include "libgt/core/error.h"

namespace gt::fuzz {

inline std::string_view Bytes(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Runs `parse`; returns normally for a value or an InputError that names `source`,
// aborts for anything else.
template <typename F>
void ExpectValueOrInputError(const std::string& source, F&& parse) {
  try {
    parse();
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.find(source) == std::string::npos) {
      std::fprintf(stderr, "InputError does not name the source '%s': %s\n", source.c_str(),
                   what.c_str());
      std::abort();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unexpected exception (not gt::InputError) from '%s': %s\n",
                 source.c_str(), e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "unexpected non-std exception from '%s'\n", source.c_str());
    std::abort();
  }
}

}  // namespace gt::fuzz

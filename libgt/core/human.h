// Values for people: byte counts in decimal units ("79.2 MB"), strings quoted for one-line
// messages, counts with their noun ("1 scene").
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace gt {

inline std::string HumanBytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1000 && u < 5) bytes /= 1000, ++u;
  char text[32];
  std::snprintf(text, sizeof(text), u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
  return text;
}

// s with its control bytes (below 0x20, DEL) as \xNN, and with `non_ascii` its bytes >= 0x80
// too; every other byte as it is.
inline std::string EscapedBytes(std::string_view s, bool non_ascii) {
  static const char* kHex = "0123456789abcdef";
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f || (non_ascii && u > 0x7f)) {
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 15];
    } else {
      out += c;
    }
  }
  return out;
}

// s in double quotes for a one-line message, its bytes outside printable ASCII (controls,
// DEL, non-ASCII) as \xNN: "a\x0ab".
inline std::string Quoted(std::string_view s) { return "\"" + EscapedBytes(s, true) + "\""; }

// s on one line: control bytes (a newline in a file name) as \xNN; UTF-8 kept as it is.
inline std::string OneLine(std::string_view s) { return EscapedBytes(s, false); }

// "1 scene", "2 scenes", "0 scenes": a count with its noun, plural by adding "s".
inline std::string Counted(long long n, std::string_view noun) {
  return std::to_string(n) + " " + std::string(noun) + (n == 1 ? "" : "s");
}

}  // namespace gt

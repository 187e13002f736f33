// Pieces shared by the HTML pages of libgt/report (the split report and its eval section):
// embedded images, HTML and gnuplot text escaping, number formatting, one gnuplot run.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "libgt/core/hash.h"

namespace gt::report {

struct NamedImage {
  std::string name;   // file name ("overlap_hist.png") or caption
  std::string mime;   // "image/png" | "image/jpeg"
  std::string bytes;  // encoded image
};

// Seeded choices of the galleries (pictures' match subsets, the split report's pairs and
// tuples): gt::Mix64 (core/hash.h, SplitMix64's output function) and FNV-1a 64 of a string.
uint64_t Fnv1a64(std::string_view s);

// The JSON objects of a .jsonl file (blank lines skipped), each with "<path>:<line>" for
// errors; a line that is not one JSON object is an InputError naming it.
std::vector<std::pair<std::string, nlohmann::json>> ReadJsonLines(const std::string& path);

// RFC 4648 base64 (with padding).
std::string Base64(std::string_view bytes);
// &, <, >, " escaped.
std::string HtmlEscape(const std::string& s);
// printf "%.<digits>g".
std::string Num(double v, int digits = 4);
// A string inside gnuplot double quotes (noenhanced text: quotes and backslashes become ',
// control characters are dropped).
std::string GnuplotString(const std::string& s);
// <img> with the image embedded as a data URI.
std::string ImgTag(const NamedImage& image, const std::string& alt);
// The alt text of a report plot: what it shows, by its file name (the name itself for one
// not listed).
std::string PlotAlt(const std::string& name);

// Runs `gnuplot script` inside scratch_dir (the script and its data files written there
// by the caller) and reads back `outputs` (PNG files it wrote) in that order. Throws
// InputError("gnuplot", ...) when gnuplot is missing or fails (its last error line) or an
// output is missing.
std::vector<NamedImage> RunGnuplot(const std::string& gnuplot, const std::string& scratch_dir,
                                   const std::string& script,
                                   const std::vector<std::string>& outputs);

}  // namespace gt::report

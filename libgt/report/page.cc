#include "libgt/report/page.h"

#include <sys/wait.h>

#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>

#include "libgt/core/error.h"
#include "libgt/core/interrupted.h"
#include "libgt/io/file_read.h"

namespace gt::report {

namespace fs = std::filesystem;

namespace {

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

}  // namespace

std::vector<std::pair<std::string, nlohmann::json>> ReadJsonLines(const std::string& path) {
  std::vector<std::pair<std::string, nlohmann::json>> out;
  const std::vector<std::string> lines = io::ReadLines(path);
  for (size_t n = 0; n < lines.size(); ++n) {
    if (lines[n].find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path + ":" + std::to_string(n + 1);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(lines[n]);
    } catch (const nlohmann::json::exception&) {
      throw InputError(where, "expected one JSON object per line");
    }
    if (!j.is_object()) throw InputError(where, "expected one JSON object per line");
    out.emplace_back(where, std::move(j));
  }
  return out;
}

uint64_t Fnv1a64(std::string_view s) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

// A string inside gnuplot double quotes (noenhanced text: only quotes and backslashes).
std::string GnuplotString(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\'';
    } else if (static_cast<unsigned char>(c) >= 32) {
      out += c;
    }
  }
  return "\"" + out + "\"";
}

std::string Num(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
  return buf;
}

std::string HtmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string ImgTag(const NamedImage& im, const std::string& alt) {
  return "<img alt=\"" + HtmlEscape(alt) + "\" src=\"data:" + im.mime + ";base64," +
         Base64(im.bytes) + "\">";
}

std::string PlotAlt(const std::string& name) {
  static const std::map<std::string, std::string> kAlt = {
      {"overlap_hist.png", "Histogram of the selected pairs' overlap"},
      {"occlusion_hist.png", "Histogram of the selected pairs' occlusion ratio"},
      {"occlusion_cumulative.png", "Cumulative share of pairs by occlusion ratio"},
      {"overlap_vs_occlusion.png",
       "Scatter plot of overlap against occlusion ratio, one point a pair"},
      {"pairs_per_scene.png", "Bar chart of the selected pairs per scene"},
      {"eval_cumulative.png", "Mean pose error of the pairs up to each occlusion ratio"},
      {"eval_auc_by_occlusion.png", "Pose AUC per occlusion-ratio bin, one bar a prediction set"},
      {"eval_auc_by_overlap.png", "Pose AUC per overlap bin, one bar a prediction set"},
      {"eval_estimator_disagreement.png", "Pose error of two estimators on each pair"},
      {"tuple_sizes.png", "Bar chart of the tuples by number of views"},
      {"tuple_covisibility_hist.png", "Histogram of the covisibility of the tuples' view pairs"},
      {"tuple_occlusion_hist.png", "Histogram of the tuples' occlusion ratio"}};
  const auto it = kAlt.find(name);
  return it == kAlt.end() ? name : it->second;
}

std::string Base64(std::string_view bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (static_cast<uint8_t>(bytes[i]) << 16) |
                       (static_cast<uint8_t>(bytes[i + 1]) << 8) |
                       static_cast<uint8_t>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = static_cast<uint8_t>(bytes[i]) << 16;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const uint32_t v =
        (static_cast<uint8_t>(bytes[i]) << 16) | (static_cast<uint8_t>(bytes[i + 1]) << 8);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::vector<NamedImage> RunGnuplot(const std::string& gnuplot, const std::string& scratch_dir,
                                   const std::string& script,
                                   const std::vector<std::string>& outputs) {
  const std::string err_path = (fs::path(scratch_dir) / "gnuplot.err").string();
  const std::string cmd = "cd " + ShellQuote(scratch_dir) + " && " + ShellQuote(gnuplot) + " " +
                          ShellQuote(script) + " > /dev/null 2> gnuplot.err";
  const int rc = std::system(cmd.c_str());
  if (rc != 0) {
    std::string first;
    if (gt::io::FileExists(err_path)) {
      const auto lines = gt::io::ReadLines(err_path);
      for (const auto& l : lines) {
        if (!l.empty() && l.rfind("Warning", 0) != 0 && l.find('^') == std::string::npos &&
            l.rfind(' ', 0) != 0) {
          first = l;  // the last error line wins ("plots.gp" line N: ...)
        }
      }
    }
    // gnuplot (or its shell) ended by a signal: Ctrl-C reaches the whole process group, and
    // std::system ignores SIGINT in occgt meanwhile. Interrupted, not a script's fault; the
    // shell reports a child killed by signal S as exit status 128 + S.
    const int signal_number = WIFSIGNALED(rc) ? WTERMSIG(rc)
                              : WIFEXITED(rc) && WEXITSTATUS(rc) > 128 && WEXITSTATUS(rc) < 160
                                  ? WEXITSTATUS(rc) - 128
                                  : 0;
    if (signal_number == SIGINT || signal_number == SIGTERM || signal_number == SIGHUP ||
        signal_number == SIGQUIT) {
      throw Interrupted("gnuplot", signal_number);
    }
    if (signal_number != 0) {
      throw InputError("gnuplot", "'" + gnuplot + "' was killed by signal " +
                                      std::to_string(signal_number) + " (" +
                                      strsignal(signal_number) + ")");
    }
    if (WIFEXITED(rc) && WEXITSTATUS(rc) == 127) {
      throw InputError("gnuplot",
                       "'" + gnuplot + "' not found: install gnuplot-nox (scripts/setup.sh)");
    }
    // The script and its folder are removed with the scratch folder: not named as a path.
    throw InputError("gnuplot", "failed on the generated " + script + " script" +
                                    (first.empty() ? "" : ": " + first));
  }
  std::vector<NamedImage> plots;
  for (const std::string& name : outputs) {
    const std::string path = (fs::path(scratch_dir) / name).string();
    if (!gt::io::FileExists(path)) throw InputError("gnuplot", "did not write " + name);
    plots.push_back({name, "image/png", gt::io::ReadFileBytes(path)});
  }
  return plots;
}

}  // namespace gt::report

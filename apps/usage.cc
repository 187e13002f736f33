#include "apps/usage.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "libgt/core/error.h"
#include "libgt/core/human.h"

namespace occgt {
namespace {

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// " (did you mean 'x'?)" for the nearest candidate within a third of the word, else "".
std::string Nearest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_distance = std::max<size_t>(2, word.size() / 3) + 1;
  for (const std::string& c : candidates) {
    const size_t d = EditDistance(word, c);
    if (d < best_distance) best = c, best_distance = d;
  }
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

std::vector<std::string> CommandNames(const CLI::App& app) {
  std::vector<std::string> names{"help"};
  for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
  return names;
}

// The flags (long and short names with their dashes) of a subcommand and its own
// subcommands' names.
std::vector<std::string> FlagNames(const CLI::App* sub) {
  std::vector<std::string> names;
  for (const CLI::Option* o : sub->get_options({})) {
    for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
    for (const std::string& n : o->get_snames()) names.push_back("-" + n);
  }
  return names;
}

// Whether `value` is a decimal integer: an optional sign, then digits only.
bool IsDecimalInteger(const std::string& value) {
  const size_t sign = !value.empty() && (value[0] == '-' || value[0] == '+') ? 1 : 0;
  return value.size() > sign && value.find_first_not_of("0123456789", sign) == std::string::npos;
}

}  // namespace

CLI::Option* NonNegative(CLI::Option* option) { return AtLeast(option, 0); }

CLI::Option* AtLeast(CLI::Option* option, unsigned long long min) {
  return option->check(CLI::Validator(
      [min](std::string& value) {
        const size_t first = value.find_first_not_of(" \t");
        const bool negative = first != std::string::npos && value[first] == '-';
        char* end = nullptr;
        errno = 0;
        const unsigned long long v = negative ? 0 : std::strtoull(value.c_str(), &end, 10);
        const bool parsed = negative || (end != value.c_str() && *end == '\0' && errno == 0);
        if (parsed && (negative || v < min)) {
          return "expected an integer >= " + std::to_string(min) + ", got '" + value + "'";
        }
        return std::string();  // not a number: CLI11's own conversion error follows
      },
      "", "at-least"));
}

std::string Num(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::string ShellWord(const std::string& path) {
  const std::string word = !path.empty() && path[0] == '-' ? "./" + path : path;
  const bool plain = !word.empty() && std::all_of(word.begin(), word.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_./:@%+,=-", c) != nullptr;
  });
  if (plain) return word;
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

void ThrowOptionsError(const std::string& error, const std::string& what,
                       const std::vector<FieldFlag>& fields) {
  // PairTruthOptions::Check names the section first ("labels: max_depth_m ...").
  std::string body = error;
  for (const std::string section : {"labels: ", "patches: ", "occupancy: "}) {
    if (body.rfind(section, 0) == 0) body = body.substr(section.size());
  }
  for (const FieldFlag& f : fields) {
    const std::string field = f.field;
    const bool leads =
        body.rfind(field, 0) == 0 &&
        (body.size() == field.size() || body[field.size()] == ' ' || body[field.size()] == ':');
    if (leads && f.given) throw gt::InputError(f.flag, body);
  }
  // A value that conflicts with one the user did not give (--min-depth-m 50 above the
  // dataset's max_depth_m 20): named after the given flag the message mentions.
  for (const FieldFlag& f : fields) {
    const std::string field = f.field;
    for (size_t at = body.find(field); at != std::string::npos; at = body.find(field, at + 1)) {
      const size_t end = at + field.size();
      const bool word =
          (at == 0 ||
           !(std::isalnum(static_cast<unsigned char>(body[at - 1])) || body[at - 1] == '_')) &&
          (end == body.size() ||
           !(std::isalnum(static_cast<unsigned char>(body[end])) || body[end] == '_'));
      if (word && f.given) throw gt::InputError(f.flag, body);
    }
  }
  throw gt::InputError(what, error);
}

void RethrowNamingFlag(const gt::InputError& error, const std::vector<FieldFlag>& fields) {
  for (const FieldFlag& f : fields) {
    if (f.given && error.where() == f.field) {
      const std::string prefix = error.where() + ": ";
      std::string problem = error.what();
      if (problem.rfind(prefix, 0) == 0) problem.erase(0, prefix.size());
      throw gt::InputError(f.flag, problem);
    }
  }
  throw error;
}

std::vector<std::string> SplitList(const std::string& text, const std::string& flag,
                                   const std::string& what) {
  std::vector<std::string> items;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    items.push_back(text.substr(start, comma - start));
    if (items.back().empty()) {
      throw gt::InputError(flag, "expected comma-separated " + what + ", got '" + text + "'");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  for (size_t i = 0; i < items.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (items[i] == items[j]) {
        throw gt::InputError(flag, "'" + items[i] + "' given twice in '" + text + "'");
      }
    }
  }
  return items;
}

int UsageError(const std::string& message) {
  std::fprintf(stderr, "occgt: error: %s\n", gt::OneLine(message).c_str());
  return kUsageExit;
}

void CheckFlagValues(CLI::App& app, const std::set<std::string>& empty_allowed) {
  const CLI::Validator non_empty(
      [](std::string& value) {
        return value.empty() ? std::string("expected a value, got ''") : std::string();
      },
      "", "non-empty");
  const CLI::Validator within_64_bits(
      [](std::string& value) {
        if (!IsDecimalInteger(value)) {
          return std::string();  // not an integer: CLI11's own conversion error follows
        }
        errno = 0;
        if (value[0] == '-') {
          (void)std::strtoll(value.c_str(), nullptr, 10);
        } else {
          (void)std::strtoull(value.c_str(), nullptr, 10);
        }
        return errno == ERANGE ? "integer out of range, got '" + value + "'" : std::string();
      },
      "", "within-64-bits");
  // Every command and nested command (`inspect pair`, `inspect split`).
  std::vector<CLI::App*> commands = app.get_subcommands([](CLI::App*) { return true; });
  for (size_t c = 0; c < commands.size(); ++c) {
    CLI::App* sub = commands[c];
    for (CLI::App* nested : sub->get_subcommands([](CLI::App*) { return true; })) {
      commands.push_back(nested);
    }
    for (CLI::Option* o : sub->get_options([](CLI::Option*) { return true; })) {
      const bool allowed =
          std::any_of(empty_allowed.begin(), empty_allowed.end(),
                      [o](const std::string& name) { return o->check_name(name); });
      if (o->get_type_size_max() > 0 && !allowed) o->check(non_empty);
      const std::string type = o->get_type_name();
      if (type == "INT" || type == "UINT") o->check(within_64_bits);
    }
  }
}

std::optional<int> RefuseDanglingEquals(const std::vector<std::string>& args) {
  for (const std::string& a : args) {
    if (a == "--") break;
    if (a.size() > 3 && a.rfind("--", 0) == 0 && a.back() == '=' && a.find('=') == a.size() - 1) {
      return UsageError(a + ": expected a value after '='");
    }
  }
  return std::nullopt;
}

std::optional<int> HandleHelpOrUnknownCommand(CLI::App& app, const std::vector<std::string>& args) {
  if (args.empty() || args[0].empty() || args[0][0] == '-') return std::nullopt;
  const std::vector<std::string> names = CommandNames(app);
  if (args[0] == "help") {
    if (args.size() == 1) {
      std::cout << app.help();
      return 0;
    }
    CLI::App* sub = nullptr;
    try {
      sub = app.get_subcommand(args[1]);
    } catch (const CLI::OptionNotFound&) {
      const std::vector<std::string> commands(names.begin() + 1, names.end());  // not "help"
      return UsageError("help " + args[1] + ": unknown command" + Nearest(args[1], commands));
    }
    // `occgt help inspect pair`: the nested command's own help.
    std::string path = "occgt " + args[1];
    for (size_t i = 2; i < args.size(); ++i) {
      std::vector<std::string> nested;
      CLI::App* next = nullptr;
      for (CLI::App* child : sub->get_subcommands({})) {
        nested.push_back(child->get_name());
        if (child->get_name() == args[i]) next = child;
      }
      if (next == nullptr) {
        return UsageError("help " + args[i] + ": unknown command of `" + path + "`" +
                          Nearest(args[i], nested));
      }
      sub = next;
      path += " " + args[i];
    }
    // "Usage: occgt inspect pair [OPTIONS]", as `occgt inspect pair --help` prints it.
    std::cout << sub->help(path.substr(0, path.rfind(' ')));
    return 0;
  }
  if (std::find(names.begin(), names.end(), args[0]) != names.end()) return std::nullopt;
  return UsageError(args[0] + ": unknown command" + Nearest(args[0], names) +
                    "; `occgt help` lists the commands");
}

std::string DescribeParseError(const CLI::App& app, const std::vector<std::string>& args,
                               const CLI::ParseError& error) {
  // The subcommand chain named by the arguments, and the first unknown flag after it.
  const CLI::App* sub = &app;
  std::string path = "occgt";
  for (const std::string& a : args) {
    // A negative number is a flag's value (`--seed -1`), not a flag: no flag name starts
    // with a digit.
    const bool number =
        a.size() > 1 && (std::isdigit(static_cast<unsigned char>(a[1])) != 0 || a[1] == '.');
    if (!a.empty() && a[0] == '-' && !number) {
      const std::string flag = a.substr(0, a.find('='));
      const std::vector<std::string> known = FlagNames(sub);
      if (flag != "--help" && flag != "-h" &&
          std::find(known.begin(), known.end(), flag) == known.end()) {
        return flag + ": unknown flag of `" + path + "`" + Nearest(flag, known);
      }
      continue;
    }
    const std::vector<const CLI::App*> children = sub->get_subcommands({});
    const CLI::App* next = nullptr;
    std::vector<std::string> child_names;
    for (const CLI::App* child : children) {
      child_names.push_back(child->get_name());
      if (child->get_name() == a) next = child;
    }
    if (next != nullptr) {
      sub = next;
      path += " " + a;
    } else if (!children.empty()) {
      return a + ": unknown command of `" + path + "`" + Nearest(a, child_names);
    }
  }
  std::string what = error.what();
  if (const size_t newline = what.find('\n'); newline != std::string::npos) what.resize(newline);
  // CLI11: "A subcommand is required" (`occgt`, `occgt inspect` alone).
  if (dynamic_cast<const CLI::RequiredError*>(&error) != nullptr &&
      what.find("subcommand") != std::string::npos) {
    std::string list;
    for (const CLI::App* child : sub->get_subcommands({})) {
      list += (list.empty() ? "" : ", ") + child->get_name();
    }
    return "a command is required after `" + path + "` (one of " + list + "; `" + path +
           " --help` describes them)";
  }
  // CLI11: "Could not convert: --threads = abc".
  const std::string convert = "Could not convert: ";
  if (what.rfind(convert, 0) == 0) {
    const std::string rest = what.substr(convert.size());
    const size_t eq = rest.find(" = ");
    if (eq != std::string::npos) {
      const std::string name = rest.substr(0, eq);
      const std::string value = rest.substr(eq + 3);
      const CLI::Option* option = sub->get_option_no_throw(name);
      const std::string type = option != nullptr ? option->get_type_name() : "";
      if (type == "INT" || type == "UINT") {
        // Digits that did not convert are out of the flag's integer range.
        what = name +
               (IsDecimalInteger(value) ? ": integer out of range, got '"
                                        : ": expected an integer, got '") +
               value + "'";
      } else {
        what = name + ": expected a number, got '" + value + "'";
      }
    }
  }
  // CLI11: "--frames: At Most 1 required but received 2" (a flag given twice).
  const std::string at_most = ": At Most 1 required but received ";
  if (const size_t at = what.find(at_most); at != std::string::npos) {
    what = what.substr(0, at) + ": given " + what.substr(at + at_most.size()) +
           " times (expected once)";
  }
  return what + " (`" + path + " --help` lists the flags)";
}

}  // namespace occgt

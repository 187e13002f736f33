#include "libgt/datasets/json_input.h"

#include <set>
#include <vector>

#include "libgt/core/error.h"

namespace gt::datasets {
namespace {

// One open object or array while parsing: its field path, and what it has seen so far.
struct OpenContainer {
  bool is_object = false;
  std::string field;           // "" at the top level, "frames[3]" below it
  std::set<std::string> keys;  // objects: the keys so far
  std::string last_key;        // objects: the key whose value comes next
  int64_t next_index = 0;      // arrays: the index of the next element
};

std::string FieldOf(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

}  // namespace

nlohmann::json ParseJsonInput(std::string_view text, const std::string& path) {
  using nlohmann::json;
  std::vector<OpenContainer> open;
  // The field path of the value that starts now (element of an array, or value of a key).
  const auto next_field = [&open]() -> std::string {
    if (open.empty()) return "";
    OpenContainer& top = open.back();
    if (top.is_object) return FieldOf(top.field, top.last_key);
    return top.field + "[" + std::to_string(top.next_index++) + "]";
  };
  const json::parser_callback_t callback = [&](int /*depth*/, json::parse_event_t event,
                                               json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start: {
        OpenContainer c;
        c.is_object = event == json::parse_event_t::object_start;
        c.field = next_field();
        open.push_back(std::move(c));
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!open.empty()) open.pop_back();
        break;
      case json::parse_event_t::key: {
        OpenContainer& top = open.back();
        top.last_key = parsed.get<std::string>();
        if (!top.keys.insert(top.last_key).second) {
          throw InputError(path, FieldOf(top.field, top.last_key) +
                                     ": duplicate key (a key may appear once in an object)");
        }
        break;
      }
      case json::parse_event_t::value:
        if (!open.empty() && !open.back().is_object) ++open.back().next_index;
        break;
    }
    return true;
  };
  try {
    return json::parse(text, callback);
  } catch (const json::exception& e) {
    // parse_error, and out_of_range for a number beyond double's range (found by fuzzing).
    throw InputError(path, std::string("not valid JSON: ") + e.what());
  }
}

}  // namespace gt::datasets

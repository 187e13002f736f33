#include "libgt/pipeline/recipe.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validator.hpp>

#include "libgt/core/error.h"
#include "libgt/io/file_read.h"
#include "libgt/io/md5.h"

namespace gt::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const char kSchemaText[] =
#include "gt/pipeline/recipe_schema.inc"
    ;

// ---- YAML -> JSON -------------------------------------------------------------------

bool ParseInt(const std::string& s, int64_t* out) {
  if (s.empty()) return false;
  size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
  if (i == s.size()) return false;
  for (size_t k = i; k < s.size(); ++k) {
    if (s[k] < '0' || s[k] > '9') return false;
  }
  try {
    *out = std::stoll(s);
  } catch (...) {
    return false;
  }
  return true;
}

bool ParseFloat(const std::string& s, double* out) {
  if (s == ".inf" || s == ".Inf" || s == "+.inf") return *out = INFINITY, true;
  if (s == "-.inf" || s == "-.Inf") return *out = -INFINITY, true;
  if (s.empty()) return false;
  // YAML 1.2 core: [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?
  size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
  bool digits = false;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, digits = true;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, digits = true;
  }
  if (!digits) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
    bool exp_digits = false;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, exp_digits = true;
    if (!exp_digits) return false;
  }
  if (i != s.size()) return false;
  *out = std::strtod(s.c_str(), nullptr);
  return true;
}

// Strict UTF-8 (no overlongs, surrogates or code points above U+10FFFF): YAML text is
// Unicode, and nlohmann::json refuses to serialise anything else (the recipe digest).
bool IsValidUtf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    int n = 0;
    uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xC2 && c <= 0xDF) {
      n = 1, cp = c & 0x1F;
    } else if (c >= 0xE0 && c <= 0xEF) {
      n = 2, cp = c & 0x0F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      n = 3, cp = c & 0x07;
    } else {
      return false;
    }
    if (s.size() - i <= static_cast<size_t>(n)) return false;
    for (int k = 1; k <= n; ++k) {
      const auto cc = static_cast<unsigned char>(s[i + k]);
      if ((cc & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (cc & 0x3F);
    }
    if ((n == 2 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) ||
        (n == 3 && (cp < 0x10000 || cp > 0x10FFFF))) {
      return false;
    }
    i += n + 1;
  }
  return true;
}

// Limits of the YAML -> JSON conversion. Aliases are expanded, so a few lines of anchors
// can stand for billions of nodes ("billion laughs"); a recipe has a few hundred.
constexpr int kMaxYamlDepth = 64;
constexpr int64_t kMaxYamlNodes = 100000;

json NodeToJson(const YAML::Node& node, const std::string& file, int depth, int64_t* nodes) {
  const std::string line = "line " + std::to_string(node.Mark().line + 1);
  if (depth > kMaxYamlDepth) {
    throw InputError(file,
                     line + ": nested deeper than " + std::to_string(kMaxYamlDepth) + " levels");
  }
  if (++*nodes > kMaxYamlNodes) {
    throw InputError(file, "more than " + std::to_string(kMaxYamlNodes) +
                               " YAML nodes (after expanding aliases)");
  }
  switch (node.Type()) {
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      return nullptr;
    case YAML::NodeType::Sequence: {
      json a = json::array();
      for (const auto& item : node) a.push_back(NodeToJson(item, file, depth + 1, nodes));
      return a;
    }
    case YAML::NodeType::Map: {
      json o = json::object();
      for (const auto& kv : node) {
        const std::string key_line = "line " + std::to_string(kv.first.Mark().line + 1);
        if (!kv.first.IsScalar()) {
          throw InputError(file, key_line + ": expected a plain key, found a sequence or mapping");
        }
        const std::string key = kv.first.Scalar();
        if (!IsValidUtf8(key)) throw InputError(file, key_line + ": key is not valid UTF-8");
        if (o.contains(key)) {
          throw InputError(file, "duplicate key '" + key + "' (" + key_line + ")");
        }
        o[key] = NodeToJson(kv.second, file, depth + 1, nodes);
      }
      return o;
    }
    case YAML::NodeType::Scalar: {
      const std::string s = node.Scalar();
      if (!IsValidUtf8(s)) throw InputError(file, line + ": text is not valid UTF-8");
      if (node.Tag() == "!") return s;  // quoted: always a string
      if (s == "~" || s == "null" || s == "Null" || s == "NULL") return nullptr;
      if (s == "true" || s == "True" || s == "TRUE") return true;
      if (s == "false" || s == "False" || s == "FALSE") return false;
      int64_t i = 0;
      if (ParseInt(s, &i)) return i;
      double d = 0;
      if (ParseFloat(s, &d)) return d;
      return s;
    }
  }
  return nullptr;
}

// ---- schema validation ------------------------------------------------------------

// Dotted path of a valijson context: ["<root>", "[selection]", "[overlap]", "[0]"] ->
// "selection.overlap[0]".
std::string DottedPath(const std::vector<std::string>& context) {
  std::string out;
  for (const auto& c : context) {
    if (c == "<root>") continue;
    std::string part = c;
    if (part.size() >= 2 && part.front() == '[' && part.back() == ']') {
      part = part.substr(1, part.size() - 2);
    }
    bool index = !part.empty() && std::all_of(part.begin(), part.end(), ::isdigit);
    if (index) {
      out += "[" + part + "]";
    } else {
      if (part.size() >= 2 && part.front() == '"' && part.back() == '"') {
        part = part.substr(1, part.size() - 2);
      }
      out += (out.empty() ? "" : ".") + part;
    }
  }
  return out;
}

// The subschema of the recipe schema at a dotted path (following $ref and items), or null.
const json* SubschemaAt(const json& schema, const std::vector<std::string>& context) {
  const json* node = &schema;
  auto deref = [&](const json* n) {
    while (n && n->is_object() && n->contains("$ref")) {
      std::string ref = (*n)["$ref"].get<std::string>();
      if (ref.rfind("#/", 0) != 0) return static_cast<const json*>(nullptr);
      n = &schema.at(json::json_pointer(ref.substr(1)));
    }
    return n;
  };
  for (const auto& c : context) {
    if (c == "<root>") continue;
    node = deref(node);
    if (!node) return nullptr;
    std::string part = c;
    if (part.size() >= 2 && part.front() == '[') part = part.substr(1, part.size() - 2);
    if (part.size() >= 2 && part.front() == '"') part = part.substr(1, part.size() - 2);
    bool index = !part.empty() && std::all_of(part.begin(), part.end(), ::isdigit);
    if (index) {
      if (!node->contains("items")) return nullptr;
      node = &(*node)["items"];
    } else {
      if (!node->contains("properties") || !(*node)["properties"].contains(part)) return nullptr;
      node = &(*node)["properties"][part];
    }
  }
  return deref(node);
}

const json& SchemaJson() {
  static const json schema = json::parse(kSchemaText);
  return schema;
}

// ---- JSON -> structs --------------------------------------------------------------

// An integer field as T: the schema checks "integer" and the ranges it states, but not
// that the value fits T (frame_stride: 4294967297 became 1 through get<int>()).
template <typename T>
T CheckedInteger(const json& v, const std::string& field, const std::string& file) {
  // The side the value is past (the schema's own bounds were checked before: a field with
  // minimum 0 said "expected an integer in [-2147483648, 2147483647]" of 2147483648).
  const auto fail = [&]() -> T {
    const bool negative = v.is_number_integer() ? v.get<int64_t>() < 0
                          : v.is_number_float() ? v.get<double>() < 0
                                                : false;
    const std::string expected =
        !v.is_number() || (v.is_number_float() && v.get<double>() != std::floor(v.get<double>()))
            ? "an integer"
        : negative ? "an integer >= " + std::to_string(std::numeric_limits<T>::min())
                   : "an integer <= " + std::to_string(std::numeric_limits<T>::max());
    throw InputError(file, field + ": expected " + expected + ", got " + v.dump());
  };
  if (v.is_number_unsigned()) {
    const uint64_t u = v.get<uint64_t>();
    if (u > static_cast<uint64_t>(std::numeric_limits<T>::max())) return fail();
    return static_cast<T>(u);
  }
  if (v.is_number_integer()) {
    const int64_t i = v.get<int64_t>();
    if (std::is_unsigned_v<T> ? i < 0
                              : (i < static_cast<int64_t>(std::numeric_limits<T>::min()) ||
                                 i > static_cast<int64_t>(std::numeric_limits<T>::max()))) {
      return fail();
    }
    return static_cast<T>(i);
  }
  if (v.is_number_float()) {  // 3.0 is an integer to JSON Schema
    const double d = v.get<double>();
    // Both bounds exact in double: min is 0 or -2^k, max + 1 is 2^k.
    const double lo = static_cast<double>(std::numeric_limits<T>::min());
    const double hi = static_cast<double>(std::numeric_limits<T>::max()) + 1.0;
    if (!(d >= lo && d < hi) || d != std::floor(d)) return fail();
    return static_cast<T>(d);
  }
  return fail();
}

// The key of `field` ("dataset.frame_stride") in its section's object `o`, if present.
template <typename T>
void Get(const json& o, std::string_view field, T* out, const std::string& file) {
  const std::string key(field.substr(field.rfind('.') + 1));  // npos + 1 = 0: no section
  if (!o.contains(key) || o[key].is_null()) return;
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    *out = CheckedInteger<T>(o[key], std::string(field), file);
  } else {
    *out = o[key].get<T>();
  }
}
template <typename T>
void GetOpt(const json& o, std::string_view field, std::optional<T>* out, const std::string& file) {
  const std::string key(field.substr(field.rfind('.') + 1));
  if (!o.contains(key) || o[key].is_null()) return;
  T value{};
  Get(o, field, &value, file);
  *out = value;
}

// occupancy.scope: the kind only; window and scene_stride are their own keys.
const char* ScopeName(occupancy::FusionScope scope) {
  switch (scope) {
    case occupancy::FusionScope::kWindow:
      return "window";
    case occupancy::FusionScope::kScene:
      return "scene";
    case occupancy::FusionScope::kPair:
      break;
  }
  return "pair";
}

occupancy::FusionScope ParseScope(const std::string& text, const std::string& file) {
  if (text == "window") return occupancy::FusionScope::kWindow;
  if (text == "scene") return occupancy::FusionScope::kScene;
  if (text == "pair") return occupancy::FusionScope::kPair;
  throw InputError(file + ": occupancy.scope", "expected pair, window or scene");
}

std::string ResolvePath(const std::string& raw, const std::string& field,
                        const std::string& base_dir) {
  std::string p = ExpandEnv(raw, field);
  fs::path path(p);
  if (path.is_relative()) path = fs::path(base_dir) / path;
  return path.lexically_normal().string();
}

}  // namespace

const char* LoftrExportKindName(LoftrExportKind kind) {
  switch (kind) {
    case LoftrExportKind::kTrain:
      return "train";
    case LoftrExportKind::kTest:
      return "test";
    case LoftrExportKind::kMegaDepth:
      return "megadepth";
    case LoftrExportKind::kNone:
      break;
  }
  return "";
}

const std::string& RecipeSchemaText() {
  static const std::string text(kSchemaText);
  return text;
}

json YamlToJson(const std::string& yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw InputError(file,
                     "invalid YAML at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  int64_t nodes = 0;
  return NodeToJson(root, file, 0, &nodes);
}

std::string ValidateRecipeJson(const json& recipe) {
  static const std::unique_ptr<valijson::Schema> schema = [] {
    auto s = std::make_unique<valijson::Schema>();
    valijson::SchemaParser parser(valijson::SchemaParser::kDraft7);
    valijson::adapters::NlohmannJsonAdapter adapter(SchemaJson());
    parser.populateSchema(adapter, *s);
    return s;
  }();
  if (!recipe.is_object()) return "(top level): expected a mapping of recipe keys";
  valijson::Validator validator;
  valijson::ValidationResults results;
  valijson::adapters::NlohmannJsonAdapter target(recipe);
  if (validator.validate(*schema, target, &results)) return "";
  // Report the deepest error: the most specific field.
  valijson::ValidationResults::Error best;
  size_t best_depth = 0;
  bool have = false;
  valijson::ValidationResults::Error e;
  while (results.popError(e)) {
    if (!have || e.context.size() > best_depth) {
      best = e;
      best_depth = e.context.size();
      have = true;
    }
  }
  std::string path = DottedPath(best.context);
  const std::string unknown_marker = "additionalProperties' constraints: '";
  size_t pos = best.description.find(unknown_marker);
  if (pos != std::string::npos) {
    std::string key = best.description.substr(pos + unknown_marker.size());
    key = key.substr(0, key.find('\''));
    std::string allowed;
    if (const json* sub = SubschemaAt(SchemaJson(), best.context);
        sub && sub->contains("properties")) {
      for (const auto& [k, v] : (*sub)["properties"].items())
        allowed += (allowed.empty() ? "" : ", ") + k;
    }
    return (path.empty() ? key : path + "." + key) + ": unknown key (expected one of " + allowed +
           ")";
  }
  const std::string missing_marker = "Missing required property '";
  pos = best.description.find(missing_marker);
  if (pos != std::string::npos) {
    std::string key = best.description.substr(pos + missing_marker.size());
    key = key.substr(0, key.find('\''));
    return (path.empty() ? key : path + "." + key) + ": missing (required)";
  }
  // Index inside an array: describe the array.
  std::vector<std::string> context = best.context;
  while (!context.empty()) {
    const std::string& last = context.back();
    std::string p = last.size() >= 2 ? last.substr(1, last.size() - 2) : last;
    if (!p.empty() && std::all_of(p.begin(), p.end(), ::isdigit)) {
      context.pop_back();
    } else {
      break;
    }
  }
  const json* sub = SubschemaAt(SchemaJson(), context);
  std::string expected = (sub && sub->contains("description"))
                             ? (*sub)["description"].get<std::string>()
                             : best.description;
  return (context.size() > 1 ? DottedPath(context) : std::string("(top level)")) + ": expected " +
         expected;
}

std::string ExpandEnv(const std::string& text, const std::string& field) {
  std::string out;
  size_t i = 0;
  while (i < text.size()) {
    if (text[i] == '$' && i + 1 < text.size() && text[i + 1] == '{') {
      size_t end = text.find('}', i);
      if (end == std::string::npos)
        throw InputError(field, "unterminated ${...} in '" + text + "'");
      std::string body = text.substr(i + 2, end - i - 2);
      std::string name = body, fallback;
      bool has_default = false;
      size_t dash = body.find(":-");
      if (dash != std::string::npos) {
        name = body.substr(0, dash);
        fallback = body.substr(dash + 2);
        has_default = true;
      }
      if (name.empty()) throw InputError(field, "empty variable name in '" + text + "'");
      const char* value = std::getenv(name.c_str());
      if (value && *value) {
        out += value;
      } else if (has_default) {
        out += fallback;
      } else {
        throw InputError(field, "environment variable " + name + " is not set (use ${" + name +
                                    ":-default} or set it)");
      }
      i = end + 1;
    } else {
      out += text[i++];
    }
  }
  return out;
}

bool DatasetOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) { return *error = m, false; };
  if (!is_synthetic && root.empty()) return fail("dataset.root: expected a folder path");
  if (frame_stride < 1) return fail("dataset.frame_stride: expected an integer >= 1");
  if (!(min_valid_depth_fraction >= 0 && min_valid_depth_fraction <= 1)) {
    return fail("dataset.min_valid_depth_fraction: expected a number in [0, 1]");
  }
  if (min_depth_m && !(*min_depth_m >= 0 && std::isfinite(*min_depth_m))) {
    return fail("dataset.min_depth_m: expected a finite number >= 0 (metres)");
  }
  if (max_depth_m && !(*max_depth_m > 0)) {
    return fail("dataset.max_depth_m: expected a number > 0 (metres)");
  }
  if (min_depth_m && max_depth_m && !(*min_depth_m < *max_depth_m)) {
    return fail("dataset.max_depth_m: expected a number > dataset.min_depth_m");
  }
  if (!fused_depth.Check(error)) return fail("dataset.fused_depth: " + *error);
  if (!scenes.empty() && !split_file.empty()) {
    return fail(
        "dataset.split_file: expected either dataset.scenes or dataset.split_file, not both");
  }
  return true;
}

namespace {

// The occupancy keys, checked on the options they resolve to (defaults included).
bool CheckOccupancy(const truth::PairTruthOptions& t, bool max_range_given, std::string* error) {
  const occupancy::BinOptions& b = t.bins;
  if (!(t.fusion.voxel_m > 0) || !std::isfinite(t.fusion.voxel_m))
    return *error = "occupancy.voxel_m: expected a number > 0 (metres)", false;
  if (b.num_bins < 1 || b.num_bins > 64)
    return *error = "occupancy.bins: expected an integer in [1, 64]", false;
  if (!(b.near_m > 0)) return *error = "occupancy.near_m: expected a number > 0 (metres)", false;
  if (!(b.far_m > b.near_m) || !std::isfinite(b.far_m))
    return *error = "occupancy.far_m: expected a number > occupancy.near_m", false;
  if (max_range_given && !std::isfinite(t.fusion.max_range_m))
    return *error = "occupancy.max_range_m: expected a finite number (<= 0: unlimited)", false;
  std::string why;
  if (!t.fusion.Check(&why)) return *error = "occupancy: " + why, false;
  if (!t.occupancy) return true;
  if (!t.bins.Check(&why)) return *error = "occupancy: " + why, false;
  if (why = truth::ModeScopeProblem(t); !why.empty()) return *error = "occupancy: " + why, false;
  return true;
}

}  // namespace

bool ShardOptions::Check(std::string* error) const {
  if (samples_per_shard < 1)
    return *error = "shards.samples_per_shard: expected an integer >= 1", false;
  if (!(target_mb >= 0) || !std::isfinite(target_mb)) {
    return *error = "shards.target_mb: expected a finite number >= 0", false;
  }
  return true;
}

bool TupleTrackOptions::Check(std::string* error) const {
  if (num_tracks < 0) {
    return *error = "selection.tuples.num_tracks: expected an integer >= 0", false;
  }
  if (query_view < 0) {
    return *error = "selection.tuples.query_view: expected an integer >= 0", false;
  }
  return true;
}

bool Recipe::Check(std::string* error) const {
  if (name.empty()) return *error = "name: expected a non-empty name", false;
  if (width < 8 || height < 8)
    return *error = "resolution: expected [W, H] with 8 <= W, H <= 8192", false;
  const truth::PairTruthOptions resolved =
      truth::ResolvePairTruthOptions(RecipePairSettings(*this));
  if (!dataset.Check(error) || !selection.Check(error) ||
      !CheckOccupancy(resolved, occupancy.settings.max_range_m.has_value(), error) ||
      !shards.Check(error)) {
    return false;
  }
  // The labels: the preset with labels.overrides (the scene's depth range comes with the
  // scene), so that a bad override fails here, naming its key, before anything is written.
  if (std::string why; !resolved.labels.Check(&why)) {
    // Named after the override the message mentions first ("max_depth_m must be >
    // min_depth_m (2000)" after min_depth_m: 2000).
    const std::pair<const char*, bool> keys[] = {{"abs_tol_m", labels.abs_tol_m.has_value()},
                                                 {"rel_tol", labels.rel_tol.has_value()},
                                                 {"min_depth_m", labels.min_depth_m.has_value()},
                                                 {"max_depth_m", labels.max_depth_m.has_value()}};
    const char* named = nullptr;
    size_t first = std::string::npos;
    for (const auto& [key, set] : keys) {
      if (const size_t at = why.find(key); set && at < first) first = at, named = key;
    }
    return *error = (named ? std::string("labels.overrides.") + named : "labels") + ": " + why,
           false;
  }
  if (tuples) {
    if (!tuple_tracks.Check(error)) return false;
    if (tuple_tracks.query_view >= tuples->min_views) {
      return *error =
                 "selection.tuples.query_view: expected a view index below selection.views' "
                 "smallest N (" +
                 std::to_string(tuples->min_views) + ")",
             false;
    }
  }
  if (width % patches.stride != 0 || height % patches.stride != 0) {
    return *error = "patches.stride: expected a divisor of both resolution W and H", false;
  }
  if (occupancy.enabled() && (width % 2 != 0 || height % 2 != 0)) {
    return *error = "resolution: expected even W and H when occupancy.enabled (H/2 x W/2 rays)",
           false;
  }
  if (loftr_export == LoftrExportKind::kMegaDepth &&
      (dataset.is_synthetic || dataset.format != DatasetFormat::kMegaDepth || loftr_tree)) {
    return *error =
               "loftr_export.kind: megadepth (LoFTR's MegaDepth index) expects dataset.format "
               "megadepth and no tree",
           false;
  }
  if (loftr_export == LoftrExportKind::kTest && !sample.depth) {
    return *error =
               "sample.depth: expected true for loftr_export.kind test (Occ2Net's test step reads "
               "depth)",
           false;
  }
  return true;
}

namespace {

// A number of the normalised recipe. JSON has no infinity (nlohmann writes null, the value of
// a key not given), so a YAML `.inf` — no upper limit, for a depth range or a camera distance —
// is the string "inf": recipe.json keeps it, and the digest tells it from an unset key.
json NumberJson(double v) { return std::isinf(v) && v > 0 ? json("inf") : json(v); }

}  // namespace

json Recipe::ToJson() const {
  json j;
  j["name"] = name;
  j["split"] = split;
  j["seed"] = seed;
  j["resolution"] = {width, height};
  json d;
  d["format"] = dataset.is_synthetic ? "synthetic" : DatasetFormatName(dataset.format);
  d["root"] = dataset.root;
  d["scenes"] = dataset.scenes;
  d["split_file"] = dataset.split_file;
  d["frame_stride"] = dataset.frame_stride;
  if (dataset.format == DatasetFormat::kScanNetPP && !dataset.is_synthetic) {
    d["device"] = datasets::ScanNetPPDeviceName(dataset.device);
  }
  // Only when given, so that the digest of existing recipes is unchanged.
  if (dataset.tum_max_dt_s) d["tum_max_dt_s"] = *dataset.tum_max_dt_s;
  d["min_valid_depth_fraction"] = dataset.min_valid_depth_fraction;
  d["min_depth_m"] = dataset.min_depth_m ? NumberJson(*dataset.min_depth_m) : json(nullptr);
  d["max_depth_m"] = dataset.max_depth_m ? NumberJson(*dataset.max_depth_m) : json(nullptr);
  // The depth source only when not the default, so that the digest of existing recipes (and
  // every file that records it) is unchanged.
  if (dataset.depth_source != render::DepthSourceMode::kSensor) {
    d["depth_source"] = render::DepthSourceModeName(dataset.depth_source);
    d["fused_depth"] = {{"abs_tol_m", dataset.fused_depth.abs_tol_m},
                        {"rel_tol", dataset.fused_depth.rel_tol}};
  }
  if (!dataset.mesh_path.empty()) d["mesh_path"] = dataset.mesh_path;
  if (dataset.is_synthetic) {
    d["synthetic"] = {{"scenes", dataset.synthetic.scenes},
                      {"frames", dataset.synthetic.frames},
                      {"width", dataset.synthetic.width},
                      {"height", dataset.synthetic.height},
                      {"seed", dataset.synthetic.seed}};
  }
  j["dataset"] = d;
  auto opt = [](const std::optional<double>& v) { return v ? NumberJson(*v) : json(nullptr); };
  j["labels"] = {{"preset", labels.preset},
                 {"overrides",
                  {{"abs_tol_m", opt(labels.abs_tol_m)},
                   {"rel_tol", opt(labels.rel_tol)},
                   {"min_depth_m", opt(labels.min_depth_m)},
                   {"max_depth_m", opt(labels.max_depth_m)}}}};
  j["patches"] = {{"stride", patches.stride},
                  {"anchor", AnchorName(patches.anchor)},
                  {"mutual", patches.mutual}};
  j["selection"] = {
      {"max_frame_gap", selection.max_frame_gap},
      {"pruning",
       {{"max_distance_m", NumberJson(selection.pruning.max_distance_m)},
        {"max_view_angle_deg", selection.pruning.max_view_angle_deg},
        {"frustum", selection.pruning.frustum}}},
      {"score_stride", selection.score_stride},
      {"overlap", {selection.overlap_lo, selection.overlap_hi}},
      {"visible_overlap", {selection.visible_overlap_lo, selection.visible_overlap_hi}},
      {"visible_aggregate", AggregateName(selection.visible_aggregate)},
      {"occlusion", {selection.occlusion_lo, selection.occlusion_hi}},
      {"occlusion_metric", OcclusionMetricName(selection.occlusion_metric)},
      {"aggregate", AggregateName(selection.aggregate)},
      {"quota_per_scene", selection.quota_per_scene},
      {"balance_bins", selection.balance_bins},
      {"import_pairs",
       {{"format", selection.import_pairs.format}, {"path", selection.import_pairs.path}}}};
  if (tuples) {  // only when set, so that recipes without tuples keep their digest
    j["selection"]["views"] = {tuples->min_views, tuples->max_views};
    j["selection"]["tuples"] = {{"edge_threshold", tuples->edge_threshold},
                                {"pair_covisibility", {tuples->pair_lo, tuples->pair_hi}},
                                {"min_spread", tuples->min_spread_score},
                                {"restarts", tuples->restarts},
                                {"quota_per_scene", tuples->quota}};
    if (tuples->balance_occlusion > 0) {  // only when set: digests of earlier recipes unchanged
      j["selection"]["tuples"]["balance_occlusion"] = tuples->balance_occlusion;
    }
    // The tracks likewise only when not the defaults (truth::ViewsTruthOptions's).
    const TupleTrackOptions default_tracks;
    if (tuple_tracks.num_tracks != default_tracks.num_tracks) {
      j["selection"]["tuples"]["num_tracks"] = tuple_tracks.num_tracks;
    }
    if (tuple_tracks.query_view != default_tracks.query_view) {
      j["selection"]["tuples"]["query_view"] = tuple_tracks.query_view;
    }
  }
  // The values the keys resolve to (defaults included); max_range_m only when set apart
  // from far_m, so that recipes without it keep their digest.
  truth::PairSettings settings = RecipePairSettings(*this);
  settings.occupancy.enabled = occupancy.enabled();
  const truth::PairTruthOptions t = truth::ResolvePairTruthOptions(settings);
  j["occupancy"] = {{"enabled", occupancy.enabled()},
                    {"voxel_m", t.fusion.voxel_m},
                    {"bins", t.bins.num_bins},
                    {"near_m", t.bins.near_m},
                    {"far_m", t.bins.far_m},
                    {"spacing", occupancy::BinSpacingName(t.bins.spacing)},
                    {"traversal", occupancy::TraversalName(t.bins.traversal)},
                    {"scope", ScopeName(t.fusion.scope)},
                    {"window", t.fusion.window},
                    {"scene_stride", t.fusion.scene_stride},
                    {"mode", occupancy::OccupancyModeName(t.mode)},
                    {"encoding", VolumeEncodingName(occupancy.encoding)}};
  if (occupancy.settings.max_range_m) j["occupancy"]["max_range_m"] = t.fusion.max_range_m;
  // The point filters only when on (recipes without them keep their digest).
  if (t.fusion.downsample) j["occupancy"]["downsample"] = true;
  if (t.fusion.remove_outliers) {
    j["occupancy"]["remove_outliers"] = true;
    j["occupancy"]["outlier_k"] = t.fusion.outlier_k;
    j["occupancy"]["outlier_stddev"] = t.fusion.outlier_stddev;
  }
  j["sample"] = {{"image", ImageFormatName(sample.image)},
                 {"depth", sample.depth},
                 {"labels", sample.labels},
                 {"occupancy", sample.occupancy},
                 {"compression", SampleCompressionName(sample.compression)}};
  j["shards"] = {{"samples_per_shard", shards.samples_per_shard}, {"target_mb", shards.target_mb}};
  j["loftr_export"] = LoftrExportKindName(loftr_export);
  // The exports' other keys only when asked for, so that recipes without them keep their
  // digest: a re-run into the same --out that adds an export is refused as another recipe
  // instead of finding every shard complete and writing no export.
  if (loftr_export != LoftrExportKind::kNone) {
    if (loftr_tree) j["loftr_tree"] = true;
    if (loftr_score == LoftrScore::kCovisible) j["loftr_score"] = "covisible";
  }
  if (gluefactory_export) j["gluefactory_export"] = true;
  if (dust3r_export) j["dust3r_export"] = true;
  return j;
}

std::string Recipe::Digest() const {
  // Paths are machine specific: the digest covers the options, not where the data is.
  json j = ToJson();
  j["dataset"].erase("root");
  j["dataset"].erase("split_file");
  j["dataset"].erase("mesh_path");
  j["selection"]["import_pairs"].erase("path");
  return io::Md5Hex(j.dump());
}

Recipe ParseRecipe(const std::string& yaml_text, const std::string& file,
                   const std::string& base_dir, const RecipeOverrides& overrides) {
  const json j = YamlToJson(yaml_text, file);
  if (std::string problem = ValidateRecipeJson(j); !problem.empty()) {
    throw InputError(file, problem);
  }
  Recipe r;
  r.file = file;
  r.base_dir = base_dir;
  r.name = j["name"].get<std::string>();
  Get(j, "split", &r.split, file);
  Get(j, "seed", &r.seed, file);
  if (j.contains("resolution")) {
    r.width = CheckedInteger<int>(j["resolution"][0], "resolution[0]", file);
    r.height = CheckedInteger<int>(j["resolution"][1], "resolution[1]", file);
  }
  const json& d = j["dataset"];
  const std::string format = d["format"].get<std::string>();
  r.dataset.is_synthetic = format == "synthetic";
  if (!r.dataset.is_synthetic) {
    r.dataset.format = ParseDatasetFormat(format, file + ": dataset.format");
  }
  if (d.contains("root"))
    r.dataset.root = ResolvePath(d["root"].get<std::string>(), file + ": dataset.root", base_dir);
  Get(d, "dataset.scenes", &r.dataset.scenes, file);
  // An empty value (e.g. an unset ${VAR:-}) means no split file: every scene.
  if (d.contains("split_file") &&
      !ExpandEnv(d["split_file"].get<std::string>(), file + ": dataset.split_file").empty()) {
    r.dataset.split_file =
        ResolvePath(d["split_file"].get<std::string>(), file + ": dataset.split_file", base_dir);
  }
  Get(d, "dataset.frame_stride", &r.dataset.frame_stride, file);
  if (d.contains("device")) {
    if (r.dataset.is_synthetic || r.dataset.format != DatasetFormat::kScanNetPP) {
      throw InputError(file,
                       "dataset.device: expected only with format scannetpp (ScanNet++'s "
                       "camera), not " +
                           format);
    }
    r.dataset.device =
        datasets::ParseScanNetPPDevice(d["device"].get<std::string>(), file + ": dataset.device");
  }
  if (d.contains("tum_max_dt_s")) {
    if (r.dataset.is_synthetic || r.dataset.format != DatasetFormat::kTum) {
      throw InputError(file,
                       "dataset.tum_max_dt_s: expected only with format tum (TUM's time "
                       "association), not " +
                           format);
    }
    GetOpt(d, "dataset.tum_max_dt_s", &r.dataset.tum_max_dt_s, file);
    if (r.dataset.tum_max_dt_s &&
        (!std::isfinite(*r.dataset.tum_max_dt_s) || *r.dataset.tum_max_dt_s < 0)) {
      throw InputError(file, "dataset.tum_max_dt_s: expected a finite number of seconds >= 0");
    }
  }
  Get(d, "dataset.min_valid_depth_fraction", &r.dataset.min_valid_depth_fraction, file);
  GetOpt(d, "dataset.min_depth_m", &r.dataset.min_depth_m, file);
  GetOpt(d, "dataset.max_depth_m", &r.dataset.max_depth_m, file);
  if (d.contains("depth_source")) {
    r.dataset.depth_source = render::ParseDepthSourceMode(d["depth_source"].get<std::string>(),
                                                          file + ": dataset.depth_source");
  }
  if (d.contains("mesh_path")) {
    r.dataset.mesh_path =
        ResolvePath(d["mesh_path"].get<std::string>(), file + ": dataset.mesh_path", base_dir);
  }
  if (d.contains("fused_depth")) {
    Get(d["fused_depth"], "dataset.fused_depth.abs_tol_m", &r.dataset.fused_depth.abs_tol_m, file);
    Get(d["fused_depth"], "dataset.fused_depth.rel_tol", &r.dataset.fused_depth.rel_tol, file);
  }
  if (d.contains("synthetic")) {
    if (!r.dataset.is_synthetic) {
      throw InputError(file,
                       "dataset.synthetic: expected only with format synthetic, not " + format);
    }
    const json& s = d["synthetic"];
    Get(s, "dataset.synthetic.scenes", &r.dataset.synthetic.scenes, file);
    Get(s, "dataset.synthetic.frames", &r.dataset.synthetic.frames, file);
    Get(s, "dataset.synthetic.width", &r.dataset.synthetic.width, file);
    Get(s, "dataset.synthetic.height", &r.dataset.synthetic.height, file);
    Get(s, "dataset.synthetic.seed", &r.dataset.synthetic.seed, file);
  }
  if (!overrides.root.empty()) {
    r.dataset.root = fs::absolute(overrides.root).lexically_normal().string();
  }
  if (overrides.depth_source) r.dataset.depth_source = *overrides.depth_source;
  if (j.contains("labels")) {
    const json& l = j["labels"];
    Get(l, "labels.preset", &r.labels.preset, file);
    if (l.contains("overrides")) {
      const json& o = l["overrides"];
      GetOpt(o, "labels.overrides.abs_tol_m", &r.labels.abs_tol_m, file);
      GetOpt(o, "labels.overrides.rel_tol", &r.labels.rel_tol, file);
      GetOpt(o, "labels.overrides.min_depth_m", &r.labels.min_depth_m, file);
      GetOpt(o, "labels.overrides.max_depth_m", &r.labels.max_depth_m, file);
    }
  }
  if (j.contains("patches")) {
    const json& p = j["patches"];
    Get(p, "patches.stride", &r.patches.stride, file);
    if (p.contains("anchor")) r.patches.anchor = ParseAnchor(p["anchor"].get<std::string>());
    Get(p, "patches.mutual", &r.patches.mutual, file);
  }
  if (j.contains("selection")) {
    const json& s = j["selection"];
    pairs::SelectionOptions& o = r.selection;
    Get(s, "selection.max_frame_gap", &o.max_frame_gap, file);
    if (s.contains("pruning")) {
      Get(s["pruning"], "selection.pruning.max_distance_m", &o.pruning.max_distance_m, file);
      Get(s["pruning"], "selection.pruning.max_view_angle_deg", &o.pruning.max_view_angle_deg,
          file);
      Get(s["pruning"], "selection.pruning.frustum", &o.pruning.frustum, file);
    }
    Get(s, "selection.score_stride", &o.score_stride, file);
    if (s.contains("overlap")) {
      o.overlap_lo = s["overlap"][0].get<double>();
      o.overlap_hi = s["overlap"][1].get<double>();
    }
    if (s.contains("visible_overlap")) {
      o.visible_overlap_lo = s["visible_overlap"][0].get<double>();
      o.visible_overlap_hi = s["visible_overlap"][1].get<double>();
    }
    if (s.contains("visible_aggregate")) {
      o.visible_aggregate = ParseAggregate(s["visible_aggregate"].get<std::string>(),
                                           file + ": selection.visible_aggregate");
    }
    if (s.contains("occlusion")) {
      o.occlusion_lo = s["occlusion"][0].get<double>();
      o.occlusion_hi = s["occlusion"][1].get<double>();
    }
    if (s.contains("occlusion_metric")) {
      o.occlusion_metric = ParseOcclusionMetric(s["occlusion_metric"].get<std::string>(),
                                                file + ": selection.occlusion_metric");
    }
    if (s.contains("aggregate")) {
      o.aggregate =
          ParseAggregate(s["aggregate"].get<std::string>(), file + ": selection.aggregate");
    }
    Get(s, "selection.quota_per_scene", &o.quota_per_scene, file);
    Get(s, "selection.balance_bins", &o.balance_bins, file);
    if (s.contains("views") || s.contains("tuples")) {
      if (!s.contains("views")) {
        throw InputError(file,
                         "selection.tuples: expected selection.views (N or [min, max]) "
                         "beside it");
      }
      pairs::TupleOptions t;
      const json& v = s["views"];
      if (v.is_array()) {
        t.min_views = v[0].get<int>();
        t.max_views = v[1].get<int>();
      } else {
        t.min_views = t.max_views = v.get<int>();
      }
      if (s.contains("tuples")) {
        const json& tj = s["tuples"];
        Get(tj, "selection.tuples.edge_threshold", &t.edge_threshold, file);
        if (tj.contains("pair_covisibility")) {
          t.pair_lo = tj["pair_covisibility"][0].get<double>();
          t.pair_hi = tj["pair_covisibility"][1].get<double>();
        }
        Get(tj, "selection.tuples.min_spread", &t.min_spread_score, file);
        Get(tj, "selection.tuples.restarts", &t.restarts, file);
        Get(tj, "selection.tuples.quota_per_scene", &t.quota, file);
        Get(tj, "selection.tuples.balance_occlusion", &t.balance_occlusion, file);
        Get(tj, "selection.tuples.num_tracks", &r.tuple_tracks.num_tracks, file);
        Get(tj, "selection.tuples.query_view", &r.tuple_tracks.query_view, file);
      }
      std::string error;
      if (!t.Check(&error)) {  // "views: ..." is selection.views, the rest selection.tuples.*
        throw InputError(
            file, (error.rfind("views:", 0) == 0 ? "selection." : "selection.tuples.") + error);
      }
      r.tuples = t;
    }
    if (s.contains("import_pairs")) {
      Get(s["import_pairs"], "selection.import_pairs.format", &o.import_pairs.format, file);
      o.import_pairs.path = ResolvePath(s["import_pairs"]["path"].get<std::string>(),
                                        file + ": selection.import_pairs.path", base_dir);
    }
  }
  if (j.contains("occupancy")) {
    const json& o = j["occupancy"];
    truth::OccupancySettings& os = r.occupancy.settings;
    Get(o, "occupancy.enabled", &os.enabled, file);
    GetOpt(o, "occupancy.voxel_m", &os.voxel_m, file);
    GetOpt(o, "occupancy.max_range_m", &os.max_range_m, file);
    GetOpt(o, "occupancy.bins", &os.bins, file);
    GetOpt(o, "occupancy.near_m", &os.near_m, file);
    GetOpt(o, "occupancy.far_m", &os.far_m, file);
    if (o.contains("spacing"))
      os.spacing = occupancy::ParseBinSpacing(o["spacing"].get<std::string>());
    if (o.contains("traversal")) {
      os.traversal = occupancy::ParseTraversal(o["traversal"].get<std::string>());
    }
    if (o.contains("scope")) os.scope = ParseScope(o["scope"].get<std::string>(), file);
    GetOpt(o, "occupancy.window", &os.window, file);
    GetOpt(o, "occupancy.scene_stride", &os.scene_stride, file);
    if (o.contains("mode")) os.mode = occupancy::ParseOccupancyMode(o["mode"].get<std::string>());
    GetOpt(o, "occupancy.downsample", &os.downsample, file);
    GetOpt(o, "occupancy.remove_outliers", &os.remove_outliers, file);
    GetOpt(o, "occupancy.outlier_k", &os.outlier_k, file);
    GetOpt(o, "occupancy.outlier_stddev", &os.outlier_stddev, file);
    if (std::string why = truth::OccupancySettingsProblem(os); !why.empty())
      throw InputError(file, "occupancy." + why);
    if (o.contains("encoding")) {
      r.occupancy.encoding =
          ParseVolumeEncoding(o["encoding"].get<std::string>(), file + ": occupancy.encoding");
    }
  }
  if (j.contains("sample")) {
    const json& s = j["sample"];
    if (s.contains("image"))
      r.sample.image = ParseImageFormat(s["image"].get<std::string>(), file + ": sample.image");
    Get(s, "sample.depth", &r.sample.depth, file);
    Get(s, "sample.labels", &r.sample.labels, file);
    Get(s, "sample.occupancy", &r.sample.occupancy, file);
    if (s.contains("compression")) {
      r.sample.compression = ParseSampleCompression(s["compression"].get<std::string>(),
                                                    file + ": sample.compression");
    }
  }
  if (j.contains("shards")) {
    Get(j["shards"], "shards.samples_per_shard", &r.shards.samples_per_shard, file);
    Get(j["shards"], "shards.target_mb", &r.shards.target_mb, file);
  }
  if (j.contains("loftr_export")) {
    const std::string kind = j["loftr_export"]["kind"].get<std::string>();
    r.loftr_export = kind == "test"        ? LoftrExportKind::kTest
                     : kind == "megadepth" ? LoftrExportKind::kMegaDepth
                                           : LoftrExportKind::kTrain;
    Get(j["loftr_export"], "loftr_export.tree", &r.loftr_tree, file);
    if (j["loftr_export"].contains("score") && r.loftr_export == LoftrExportKind::kTest) {
      throw InputError(file,
                       "loftr_export.score: expected only with kind train or megadepth "
                       "(LoFTR's test index has no score)");
    }
    if (j["loftr_export"].value("score", "overlap") == "covisible") {
      r.loftr_score = LoftrScore::kCovisible;
    }
  }
  Get(j, "gluefactory_export", &r.gluefactory_export, file);
  Get(j, "dust3r_export", &r.dust3r_export, file);
  std::string error;
  if (!r.Check(&error)) throw InputError(file, error);
  return r;
}

Recipe LoadRecipe(const std::string& path, const RecipeOverrides& overrides) {
  if (!fs::is_regular_file(path)) throw InputError(path, "recipe file not found");
  const std::string text = io::ReadFileBytes(path);
  std::string base = fs::absolute(fs::path(path)).parent_path().lexically_normal().string();
  Recipe r = ParseRecipe(text, path, base, overrides);
  // Inputs that must exist before any work starts.
  if (!r.dataset.is_synthetic && !fs::is_directory(r.dataset.root)) {
    if (!overrides.root.empty()) {  // the flag's value, not the recipe's: a usage error
      throw InputError("--root", "expected an existing folder, not found: " + r.dataset.root);
    }
    throw InputError(path,
                     "dataset.root: expected an existing folder, not found: " + r.dataset.root);
  }
  if (!r.dataset.split_file.empty() && !fs::is_regular_file(r.dataset.split_file)) {
    throw InputError(
        path, "dataset.split_file: expected an existing file, not found: " + r.dataset.split_file);
  }
  // A mesh path without "{scene}" names one file for every scene: a missing one would make
  // every frame of every scene a read error (with "{scene}", each scene's is checked there).
  if (!r.dataset.mesh_path.empty() && r.dataset.mesh_path.find("{scene}") == std::string::npos &&
      !fs::is_regular_file(r.dataset.mesh_path)) {
    throw InputError(
        path, "dataset.mesh_path: expected an existing file, not found: " + r.dataset.mesh_path);
  }
  if (!r.selection.import_pairs.path.empty() &&
      !fs::is_regular_file(r.selection.import_pairs.path)) {
    throw InputError(path, "selection.import_pairs.path: expected an existing file, not found: " +
                               r.selection.import_pairs.path);
  }
  return r;
}

truth::PairSettings RecipePairSettings(const Recipe& recipe) {
  truth::PairSettings s;
  s.labels = recipe.labels;
  s.patches = recipe.patches;
  s.occupancy = recipe.occupancy.settings;
  s.occupancy.enabled = recipe.occupancy.enabled() && recipe.sample.occupancy;
  return s;
}

truth::DatasetDepthRange RecipeDepthRange(const Recipe& recipe, const Scene& scene) {
  truth::DatasetDepthRange r = truth::DepthRangeOf(scene);
  r.set_min_depth_m = recipe.dataset.min_depth_m;
  r.set_max_depth_m = recipe.dataset.max_depth_m;
  return r;
}

truth::PairTruthOptions RecipePairTruthOptions(const Recipe& recipe, const Scene& scene) {
  const truth::PairTruthOptions o =
      truth::ResolvePairTruthOptions(RecipePairSettings(recipe), RecipeDepthRange(recipe, scene));
  std::string error;
  if (!o.Check(&error)) throw InputError(recipe.file, error);
  return o;
}

SampleOptions RecipeSampleOptions(const Recipe& recipe) {
  SampleOptions s;
  s.resolution = {recipe.width, recipe.height};
  s.score_stride = recipe.selection.score_stride;
  s.truth = truth::ResolvePairTruthOptions(RecipePairSettings(recipe));
  s.encoding = recipe.occupancy.encoding;
  s.image = recipe.sample.image;
  s.depth = recipe.sample.depth;
  s.label_maps = recipe.sample.labels;
  s.compression = recipe.sample.compression;
  s.digest = recipe.Digest();
  s.recipe_name = recipe.name;
  s.split = recipe.split;
  return s;
}

}  // namespace gt::pipeline

namespace gt::pipeline {

render::FrameDepthOptions RecipeFrameDepthOptions(const Recipe& recipe) {
  render::FrameDepthOptions o;
  o.source = recipe.dataset.depth_source;
  o.fused = recipe.dataset.fused_depth;
  return o;
}

void ApplyMeshPath(const std::string& mesh_path, Scene* scene) {
  if (mesh_path.empty()) return;
  std::string path = mesh_path;
  for (size_t at = path.find("{scene}"); at != std::string::npos; at = path.find("{scene}", at)) {
    path.replace(at, 7, scene->name);
    at += scene->name.size();
  }
  scene->mesh_path = path;
}

datasets::ReaderOptions RecipeReaderOptions(const Recipe& recipe) {
  datasets::ReaderOptions options;
  options.scannetpp_device = recipe.dataset.device;
  if (recipe.dataset.tum_max_dt_s) options.tum_max_dt_s = *recipe.dataset.tum_max_dt_s;
  return options;
}

std::unique_ptr<datasets::DatasetReader> MakeRecipeReader(const Recipe& recipe) {
  return datasets::MakeReader(recipe.dataset.format, RecipeReaderOptions(recipe));
}

void RequireSceneMesh(const Recipe& recipe, const Scene& scene) {
  if (recipe.dataset.depth_source == render::DepthSourceMode::kSensor) return;
  try {
    render::SharedMeshRenderer(scene.mesh_path);
  } catch (const InputError& e) {
    if (e.where() == scene.mesh_path) throw;      // the PLY reader names the file
    throw InputError(scene.mesh_path, e.what());  // the renderer's checks name "mesh"
  }
}

Scene ReadRecipeScene(const Recipe& recipe, const datasets::DatasetReader& reader,
                      const std::string& name) {
  Scene scene = reader.ReadScene(recipe.dataset.root, name);
  ApplyMeshPath(recipe.dataset.mesh_path, &scene);
  // Depth from the mesh needs the mesh: without it every frame would fail to read, and the
  // scene's selection would be saved empty (kept by a re-run after the recipe is fixed).
  if (recipe.dataset.depth_source != render::DepthSourceMode::kSensor) {
    const std::string source = render::DepthSourceModeName(recipe.dataset.depth_source);
    if (scene.mesh_path.empty()) {
      throw InputError(scene.name, "dataset.depth_source " + source +
                                       " needs the scene's mesh, and it has none" +
                                       scene.MissingMeshNote() +
                                       " (set dataset.mesh_path, or use --depth-source sensor)");
    }
    if (!io::FileExists(scene.mesh_path)) {
      throw InputError(scene.mesh_path, "not found: the mesh of scene " + scene.name +
                                            " (dataset.depth_source " + source + ")");
    }
  }
  return scene;
}

}  // namespace gt::pipeline

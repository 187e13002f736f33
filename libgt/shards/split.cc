#include "libgt/shards/split.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validation_results.hpp>
#include <valijson/validator.hpp>

#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/md5.h"
#include "libgt/io/npy.h"
#include "libgt/shards/sample_check.h"
#include "libgt/shards/views_sample_check.h"

namespace gt::shards {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

json ParseJsonFile(const std::string& path) {
  const std::string text = io::ReadFileBytes(path);
  json doc = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) throw InputError(path, "not valid JSON");
  return doc;
}

// Typed member access with errors naming the file and field.
const json& Member(const json& obj, const std::string& name, const std::string& path) {
  if (!obj.is_object() || !obj.contains(name)) {
    throw InputError(path, "missing field \"" + name + "\"");
  }
  return obj.at(name);
}
int64_t IntMember(const json& obj, const std::string& name, const std::string& path) {
  const json& v = Member(obj, name, path);
  if (!v.is_number_integer() || v.get<int64_t>() < 0) {
    throw InputError(path, "field \"" + name + "\": expected a non-negative integer");
  }
  return v.get<int64_t>();
}
std::string StringMember(const json& obj, const std::string& name, const std::string& path) {
  const json& v = Member(obj, name, path);
  if (!v.is_string()) throw InputError(path, "field \"" + name + "\": expected a string");
  return v.get<std::string>();
}

bool IsMd5Hex(const std::string& s) {
  return s.size() == 32 && std::all_of(s.begin(), s.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

int64_t FileSize(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return -1;
  return static_cast<int64_t>(st.st_size);
}

// The split's schemas built into the binary from schemas/ (file name, text).
struct EmbeddedSchema {
  const char* file;
  const char* text;
};
const EmbeddedSchema kEmbeddedSchemas[] = {
#include "gt/shards/split_schemas.inc"
};

// A parsed JSON Schema, reused for many documents. `where` names it in messages (its
// path, or its file name for a built-in one).
class SchemaChecker {
 public:
  SchemaChecker(const std::string& where, const json& doc) : path_(where) {
    try {
      valijson::SchemaParser parser;
      valijson::adapters::NlohmannJsonAdapter adapter(doc);
      parser.populateSchema(adapter, schema_);
    } catch (const std::exception& e) {
      throw InputError(where, std::string("unusable JSON Schema: ") + e.what());
    }
  }
  std::vector<std::string> Check(const json& doc) const {
    valijson::Validator validator;
    valijson::ValidationResults results;
    valijson::adapters::NlohmannJsonAdapter adapter(doc);
    std::vector<std::string> problems;
    if (validator.validate(schema_, adapter, &results)) return problems;
    valijson::ValidationResults::Error error;
    while (results.popError(error)) {
      std::string where;
      for (const std::string& c : error.context) where += c;
      problems.push_back(where + ": " + error.description);
    }
    if (problems.empty()) problems.push_back("does not match " + path_);
    return problems;
  }

 private:
  std::string path_;
  valijson::Schema schema_;
};

// The schema `file` of folder `dir` (which must hold it), or the built-in one when `dir`
// is "".
std::unique_ptr<SchemaChecker> LoadSchema(const std::string& dir, const std::string& file) {
  if (dir.empty()) {
    for (const EmbeddedSchema& e : kEmbeddedSchemas) {
      if (file == e.file) return std::make_unique<SchemaChecker>(file, json::parse(e.text));
    }
    GT_ASSERT_MSG(false, "schema not built in");
  }
  const std::string path = (fs::path(dir) / file).string();
  if (!io::FileExists(path))
    throw InputError(path, "missing (a --schemas folder holds every schema)");
  return std::make_unique<SchemaChecker>(path, ParseJsonFile(path));
}

// The reason of an error without its place (the caller's line names the shard and member
// already: "<shard>: <member>: <shard>:<member>: bad gzip data" said the place twice).
std::string ReasonOf(const InputError& e, const std::string& place = "") {
  const std::string what = e.what();
  if (!place.empty() && e.where() != place) return what;  // another place: keep it
  const std::string prefix = e.where() + ": ";
  return what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what;
}

std::string FirstLines(const std::vector<std::string>& problems) {
  std::string out;
  for (size_t i = 0; i < problems.size() && i < 3; ++i) out += (i ? "; " : "") + problems[i];
  if (problems.size() > 3) out += "; ...";
  return out;
}

// The schemas of a split's sample json members and pairs.jsonl lines, for both kinds of
// split: pair samples (`occgt build`: sample.schema.json, pairs_line.schema.json) and N-view
// samples (`occgt tuples --shards`: views_sample.schema.json, views_line.schema.json). Each
// document is checked against the schema of its own kind: a sample json whose "kind" is
// "occgt-views-sample", or a line with "frame_ids", is an N-view one. From a folder (which
// must hold all four), or built in when the folder is ""; default-constructed: no check.
class SplitSchemas {
 public:
  SplitSchemas() = default;
  explicit SplitSchemas(const std::string& dir)
      : pair_sample_(LoadSchema(dir, kPairSample)),
        views_sample_(LoadSchema(dir, kViewsSample)),
        pair_line_(LoadSchema(dir, kPairLine)),
        views_line_(LoadSchema(dir, kViewsLine)) {}
  // "" or "<schema file>: <its first problems>".
  std::string CheckSample(const json& doc) const {
    const bool views =
        doc.is_object() && doc.contains("kind") && doc["kind"] == "occgt-views-sample";
    return views ? Check(views_sample_.get(), kViewsSample, doc)
                 : Check(pair_sample_.get(), kPairSample, doc);
  }
  std::string CheckLine(const json& line) const {
    const bool views = line.is_object() && line.contains("frame_ids");
    return views ? Check(views_line_.get(), kViewsLine, line)
                 : Check(pair_line_.get(), kPairLine, line);
  }

 private:
  static constexpr const char* kPairSample = "sample.schema.json";
  static constexpr const char* kViewsSample = "views_sample.schema.json";
  static constexpr const char* kPairLine = "pairs_line.schema.json";
  static constexpr const char* kViewsLine = "views_line.schema.json";
  static std::string Check(const SchemaChecker* schema, const char* name, const json& doc) {
    if (schema == nullptr) return "";
    const std::vector<std::string> p = schema->Check(doc);
    return p.empty() ? "" : std::string(name) + ": " + FirstLines(p);
  }
  std::unique_ptr<SchemaChecker> pair_sample_, views_sample_, pair_line_, views_line_;
};

std::string SceneOfLine(const json& line, const std::string& key) {
  if (line.is_object() && line.contains("scene") && line["scene"].is_string()) {
    return line["scene"].get<std::string>();
  }
  const size_t slash = key.rfind('/');
  return slash == std::string::npos ? std::string() : key.substr(0, slash);
}

// The fields a pairs.jsonl line shares with its sample's json (everything but "shard"), in
// a fixed order, each as the hash of its JSON text: a pair line's fields are the json's own
// (libgt/pipeline/sample.cc); an N-view line's frame_ids are the json's frames' ids and its
// occlusion_ratio_visible the json's metrics' (views_write.cc). Kept per sample (80 bytes)
// rather than the json, so that a split of millions of samples is checked in little memory.
constexpr size_t kLineFields = 9;
using LineDigest = std::array<uint64_t, kLineFields>;
constexpr const char* kPairLineFields[kLineFields] = {"key",           "scene",   "frame0",
                                                      "frame1",        "metrics", "score_stride",
                                                      "score_metrics", "matches", "T_0to1"};
constexpr const char* kViewsLineFields[kLineFields] = {
    "key", "scene", "tuple_index", "frame_ids", "options_digest", "occlusion_ratio_visible", "",
    "",    ""};

uint64_t JsonHash(const json& j) { return std::hash<std::string>()(j.dump()); }

bool IsViewsLine(const json& line) { return line.is_object() && line.contains("frame_ids"); }

// The digest of the line a sample json implies; nullopt when the json lacks a field.
std::optional<LineDigest> LineDigestOfSample(const json& doc) {
  LineDigest d{};
  try {
    if (doc.value("kind", "") == "occgt-views-sample") {
      json ids = json::array();
      for (const json& f : doc.at("frames")) ids.push_back(f.at("id"));
      const json values[] = {
          doc.at("key"), doc.at("scene"),          doc.at("tuple_index"),
          ids,           doc.at("options_digest"), doc.at("metrics").at("occlusion_ratio_visible")};
      for (size_t i = 0; i < std::size(values); ++i) d[i] = JsonHash(values[i]);
    } else {
      for (size_t i = 0; i < kLineFields; ++i) d[i] = JsonHash(doc.at(kPairLineFields[i]));
    }
  } catch (const json::exception&) {
    return std::nullopt;
  }
  return d;
}

// The first field of `line` (a JSON object) whose value differs from its sample's, or "".
std::string LineFieldDiffering(const json& line, const LineDigest& sample) {
  const char* const* names = IsViewsLine(line) ? kViewsLineFields : kPairLineFields;
  for (size_t i = 0; i < kLineFields && *names[i] != '\0'; ++i) {
    if (!line.contains(names[i]) || JsonHash(line[names[i]]) != sample[i]) return names[i];
  }
  return "";
}

// One sample read back: what the value checks (sample_check.h) need.
struct SampleRead {
  std::string key;
  std::optional<json> doc;  // its json member, when it parsed and matched its schema
  std::set<std::string> fields;
  std::map<std::string, io::NpyArray> arrays;
  std::map<std::string, std::string> images;
};

// The value problems of a pair or N-view sample read through, each "<key>.<field>: <problem>".
void CheckSampleValues(const SampleRead& s, std::vector<std::string>* problems) {
  if (!s.doc) return;
  const std::map<std::string, std::string_view> images(s.images.begin(), s.images.end());
  const bool views = s.doc->value("kind", "") == "occgt-views-sample";
  std::vector<std::string> found =
      views ? CheckViewsSampleMembers(*s.doc, s.fields) : CheckPairSampleMembers(*s.doc, s.fields);
  for (std::string& p : views ? CheckViewsSampleValues(*s.doc, s.arrays, images)
                              : CheckPairSampleValues(*s.doc, s.arrays, images)) {
    found.push_back(std::move(p));
  }
  for (const std::string& p : found) problems->push_back(s.key + "." + p);
}

// Checks that a tar holds exactly `expected_keys` (when given) with valid member names;
// validates sample JSON with `sample_schema` (may be null), parses every .npy member and,
// when `lines_out` is given, checks each sample's values against its json
// (CheckSampleValues) and gives the line digest of each sample (nullopt: its json is
// unusable). Returns problems, each "<member>: <problem>"; `keys_out` gets the keys in order.
std::vector<std::string> CheckTarContents(
    const std::string& tar_path, const SplitSchemas& schemas, std::vector<std::string>* keys_out,
    std::set<std::string>* digests_out = nullptr,
    std::vector<std::optional<LineDigest>>* lines_out = nullptr) {
  const bool values = lines_out != nullptr;
  std::vector<std::string> problems;
  std::vector<std::string> keys;
  std::set<std::string> seen_keys;
  std::set<std::string> fields_of_key;
  std::vector<std::optional<LineDigest>> lines;
  SampleRead current;
  auto finish_sample = [&] {
    if (current.key.empty()) return;
    if (values) CheckSampleValues(current, &problems);
    current = SampleRead();
  };
  ForEachTarMember(tar_path, [&](const TarMemberInfo& info, std::string_view data) {
    const std::string& name = info.path;
    if (!info.regular_file) {
      problems.push_back(name + ": not a regular file");
      return;
    }
    if (name.size() > kMaxMemberPathBytes) {
      problems.push_back(name + ": member path longer than 100 bytes");
    }
    std::string key, field;
    if (!SplitMemberPath(name, &key, &field)) {
      problems.push_back(name + ": member name has no '.<field>' suffix");
      return;
    }
    if (key.substr(key.rfind('/') + 1).substr(0, 2) == "__") return;  // reader-skipped meta
    if (std::string e = CheckSampleKey(key); !e.empty()) problems.push_back(name + ": " + e);
    if (std::string e = CheckFieldName(field); !e.empty()) problems.push_back(name + ": " + e);
    if (keys.empty() || keys.back() != key) {
      if (!seen_keys.insert(key).second) {
        problems.push_back(name + ": members of sample " + key + " are not contiguous");
      }
      finish_sample();
      current.key = key;
      keys.push_back(key);
      lines.emplace_back();
      fields_of_key.clear();
    }
    std::string plain_field = field;
    std::string plain;  // a compressed member's bytes (DecodeMember)
    try {
      plain = DecodeMember(&plain_field, data, tar_path + ":" + name);
    } catch (const InputError& e) {
      problems.push_back(name + ": " + ReasonOf(e));
      return;
    }
    if (!fields_of_key.insert(plain_field).second) problems.push_back(name + ": duplicate member");
    current.fields.insert(plain_field);
    const std::string ext = plain_field.substr(plain_field.rfind('.') + 1);
    const std::string_view bytes = plain;
    if (ext == "npy") {
      try {
        io::NpyArray array = io::ParseNpy(bytes, tar_path + ":" + name);
        if (values) current.arrays[plain_field] = std::move(array);
      } catch (const InputError& e) {
        problems.push_back(name + ": bad .npy: " + ReasonOf(e));
      }
    } else if (values && (ext == "png" || ext == "jpg")) {
      current.images[plain_field] = std::string(bytes);
    } else if (ext == "json") {
      json doc = json::parse(plain, nullptr, false);  // a .json.gz member: its JSON
      if (doc.is_discarded()) {
        problems.push_back(name + ": not valid JSON");
      } else if (plain_field == "json") {
        const std::string p = schemas.CheckSample(doc);
        if (!p.empty()) problems.push_back(name + ": " + p);
        if (values) lines.back() = LineDigestOfSample(doc);
        if (p.empty()) current.doc = doc;
        // The sample's own key (a member renamed or moved to another sample kept its json).
        if (doc.is_object() && doc.contains("key") && doc["key"].is_string() &&
            doc["key"].get<std::string>() != key) {
          problems.push_back(name + ": its \"key\" is " + doc["key"].dump() +
                             ", not the member's " + key);
        }
        if (digests_out != nullptr && doc.is_object() && doc.contains("options_digest") &&
            doc["options_digest"].is_string()) {
          digests_out->insert(doc["options_digest"].get<std::string>());
        }
      }
    } else if (ext == "pyd" || ext == "pth" || ext == "pickle") {
      problems.push_back(name + ": pickle fields are not allowed");
    }
  });
  finish_sample();
  if (keys_out != nullptr) *keys_out = std::move(keys);
  if (lines_out != nullptr) *lines_out = std::move(lines);
  return problems;
}

}  // namespace

std::string ShardFileName(const std::string& split, int64_t shard_index) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "-%06lld.tar", static_cast<long long>(shard_index));
  return split + buf;
}
std::string ShardPath(const std::string& dir, const std::string& split, int64_t shard_index) {
  return (fs::path(dir) / ShardFileName(split, shard_index)).string();
}
std::string PartRecordPath(const std::string& dir, const std::string& split, int64_t shard_index) {
  std::string name = ShardFileName(split, shard_index);
  name.replace(name.size() - 4, 4, ".json");
  return (fs::path(dir) / "parts" / name).string();
}
std::string PlanPath(const std::string& dir, const std::string& split) {
  return (fs::path(dir) / "parts" / (split + ".plan.json")).string();
}

std::string CheckSplitName(const std::string& split) {
  if (split.empty()) return "empty split name";
  for (char c : split) {
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
          c == '_')) {
      return "split name \"" + split + "\" may contain only [A-Za-z0-9_-]";
    }
  }
  if (split.rfind("__", 0) == 0) return "split name \"" + split + "\" starts with \"__\"";
  return "";
}

SplitPlan PlanEqualShards(const std::string& split, int64_t total_samples,
                          int64_t samples_per_shard) {
  GT_ASSERT(samples_per_shard > 0 && total_samples >= 0);
  SplitPlan plan;
  plan.split = split;
  for (int64_t start = 0; start < total_samples; start += samples_per_shard) {
    plan.shard_nsamples.push_back(std::min(samples_per_shard, total_samples - start));
  }
  return plan;
}

void WritePlan(const std::string& dir, const SplitPlan& plan) {
  if (std::string e = CheckSplitName(plan.split); !e.empty()) {
    throw InputError(PlanPath(dir, plan.split), e);
  }
  json doc;
  doc["split"] = plan.split;
  doc["nshards"] = static_cast<int64_t>(plan.shard_nsamples.size());
  doc["nsamples"] = plan.shard_nsamples;
  io::WriteFileAtomic(PlanPath(dir, plan.split), doc.dump(2) + "\n");
}

SplitPlan ReadPlan(const std::string& dir, const std::string& split) {
  const std::string path = PlanPath(dir, split);
  if (!io::FileExists(path)) {
    throw InputError(path,
                     "missing split plan (the write stage of occgt build writes it before its "
                     "first shard: run it, then merge)");
  }
  const json doc = ParseJsonFile(path);
  SplitPlan plan;
  plan.split = StringMember(doc, "split", path);
  if (plan.split != split) throw InputError(path, "field \"split\": expected \"" + split + "\"");
  const int64_t nshards = IntMember(doc, "nshards", path);
  const json& counts = Member(doc, "nsamples", path);
  if (!counts.is_array() || static_cast<int64_t>(counts.size()) != nshards) {
    throw InputError(path, "field \"nsamples\": expected an array of nshards integers");
  }
  for (const json& c : counts) {
    if (!c.is_number_integer() || c.get<int64_t>() < 0) {
      throw InputError(path, "field \"nsamples\": expected non-negative integers");
    }
    plan.shard_nsamples.push_back(c.get<int64_t>());
  }
  return plan;
}

std::vector<std::string> ListPlannedSplits(const std::string& dir) {
  std::vector<std::string> splits;
  const fs::path parts = fs::path(dir) / "parts";
  std::error_code ec;
  if (!fs::is_directory(parts, ec)) return splits;
  const std::string suffix = ".plan.json";
  for (const auto& entry : fs::directory_iterator(parts, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      splits.push_back(name.substr(0, name.size() - suffix.size()));
    }
  }
  std::sort(splits.begin(), splits.end());
  return splits;
}

namespace {

// ReadPartRecord, also returning the scene of every pair line and whether a line is a
// tuple's (has "tuple_index": N-view shards) (for the merge summary).
PartRecord ReadPartRecordAndScenes(const std::string& dir, const std::string& split,
                                   int64_t shard_index, std::vector<std::string>* scenes,
                                   bool* tuple_lines = nullptr) {
  const std::string path = PartRecordPath(dir, split, shard_index);
  const json doc = ParseJsonFile(path);
  PartRecord r;
  r.split = StringMember(doc, "split", path);
  r.shard_index = IntMember(doc, "shard_index", path);
  r.url = StringMember(doc, "url", path);
  if (r.split != split || r.shard_index != shard_index ||
      r.url != ShardFileName(split, shard_index)) {
    throw InputError(path,
                     "split/shard_index/url do not name " + ShardFileName(split, shard_index));
  }
  r.info.path = ShardPath(dir, split, shard_index);
  r.info.nsamples = IntMember(doc, "nsamples", path);
  r.info.md5sum = StringMember(doc, "md5sum", path);
  if (!IsMd5Hex(r.info.md5sum)) {
    throw InputError(path, "field \"md5sum\": expected 32 lower-case hex digits");
  }
  r.info.filesize = IntMember(doc, "filesize", path);
  if (doc.contains("options_digest")) {  // records written before it have none
    r.options_digest = StringMember(doc, "options_digest", path);
    if (!IsMd5Hex(r.options_digest)) {
      throw InputError(path, "field \"options_digest\": expected 32 lower-case hex digits");
    }
  }
  const json& keys = Member(doc, "keys", path);
  const json& pairs = Member(doc, "pairs", path);
  if (!keys.is_array() || !pairs.is_array() ||
      static_cast<int64_t>(keys.size()) != r.info.nsamples ||
      static_cast<int64_t>(pairs.size()) != r.info.nsamples) {
    throw InputError(path, "fields \"keys\" and \"pairs\": expected nsamples entries each");
  }
  r.keys.reserve(keys.size());
  r.pair_lines.reserve(keys.size());
  if (scenes != nullptr) scenes->reserve(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    if (!keys[i].is_string() || !pairs[i].is_object()) {
      throw InputError(path, "keys[" + std::to_string(i) + "]/pairs[" + std::to_string(i) +
                                 "]: expected a string and an object");
    }
    const std::string& key = keys[i].get_ref<const std::string&>();
    const auto k = pairs[i].find("key");
    const auto u = pairs[i].find("shard");
    if (k == pairs[i].end() || *k != key || u == pairs[i].end() || *u != r.url) {
      throw InputError(path, "pairs[" + std::to_string(i) + "]: \"key\"/\"shard\" do not name " +
                                 key + " in " + r.url);
    }
    if (scenes != nullptr) scenes->push_back(SceneOfLine(pairs[i], key));
    if (tuple_lines != nullptr && pairs[i].contains("tuple_index")) *tuple_lines = true;
    r.keys.push_back(key);
    r.pair_lines.push_back(pairs[i].dump());
  }
  return r;
}

}  // namespace

PartRecord ReadPartRecord(const std::string& dir, const std::string& split, int64_t shard_index) {
  return ReadPartRecordAndScenes(dir, split, shard_index, nullptr);
}

SplitShardWriter::SplitShardWriter(const std::string& dir, const std::string& split,
                                   int64_t shard_index, const std::string& options_digest)
    : dir_(dir) {
  if (std::string e = CheckSplitName(split); !e.empty()) throw InputError(dir, e);
  record_.split = split;
  record_.options_digest = options_digest;
  record_.shard_index = shard_index;
  record_.url = ShardFileName(split, shard_index);
  tar_ = std::make_unique<TarShardWriter>(ShardPath(dir, split, shard_index));
}

SplitShardWriter::~SplitShardWriter() = default;

void SplitShardWriter::Add(const Sample& sample, const std::string& pair_line_json) {
  json line = ParsePairLine(sample.key, pair_line_json);
  tar_->Add(sample);
  Record(sample.key, &line);
}

void SplitShardWriter::Add(Sample&& sample, const std::string& pair_line_json) {
  json line = ParsePairLine(sample.key, pair_line_json);
  const std::string key = sample.key;
  tar_->Add(std::move(sample));
  Record(key, &line);
}

json SplitShardWriter::ParsePairLine(const std::string& key, const std::string& text) const {
  json line = json::parse(text, nullptr, false);
  if (line.is_discarded() || !line.is_object()) {
    throw InputError(ShardPath(dir_, record_.split, record_.shard_index) + ": " + key,
                     "pair line is not a JSON object");
  }
  return line;
}

void SplitShardWriter::Record(const std::string& key, json* line) {
  (*line)["shard"] = record_.url;
  (*line)["key"] = key;
  record_.keys.push_back(key);
  record_.pair_lines.push_back(line->dump());
}

PartRecord SplitShardWriter::Finish() {
  record_.info = tar_->Finish();
  json doc;
  doc["split"] = record_.split;
  doc["shard_index"] = record_.shard_index;
  doc["url"] = record_.url;
  doc["nsamples"] = record_.info.nsamples;
  doc["md5sum"] = record_.info.md5sum;
  doc["filesize"] = record_.info.filesize;
  if (!record_.options_digest.empty()) doc["options_digest"] = record_.options_digest;
  doc["keys"] = record_.keys;
  json pairs = json::array();
  for (const std::string& l : record_.pair_lines) pairs.push_back(json::parse(l));
  doc["pairs"] = std::move(pairs);
  io::WriteFileAtomic(PartRecordPath(dir_, record_.split, record_.shard_index), doc.dump(1) + "\n");
  return record_;
}

bool IsShardComplete(const std::string& dir, const std::string& split, int64_t shard_index,
                     bool verify_md5) {
  const std::string record_path = PartRecordPath(dir, split, shard_index);
  if (!io::FileExists(record_path)) return false;
  try {
    const PartRecord r = ReadPartRecord(dir, split, shard_index);
    if (FileSize(r.info.path) != r.info.filesize) return false;
    if (verify_md5 && io::Md5HexOfFile(r.info.path) != r.info.md5sum) return false;
    return true;
  } catch (const InputError&) {
    return false;
  }
}

namespace {

bool IsNonNegativeInteger(const json& j) {
  return j.is_number_unsigned() || (j.is_number_integer() && j.get<int64_t>() >= 0);
}

// index.json's shardlist[i] (`e`) into `out`: "" or the problem, "<field>: expected ...".
std::string ParseIndexEntry(const json& e, size_t i, IndexedShard* out) {
  const std::string field = "shardlist[" + std::to_string(i) + "]";
  if (!e.is_object()) return field + ": expected an object {url, nsamples, md5sum, filesize}";
  if (!e.contains("url") || !e["url"].is_string()) return field + ".url: expected a string";
  out->url = e["url"].get<std::string>();
  if (out->url.empty() || out->url == "." || out->url == ".." ||
      out->url.find('/') != std::string::npos || out->url.find('\0') != std::string::npos) {
    return field + ".url: " + Quoted(out->url) +
           " is not a file name in the split's folder (the folder holding index.json)";
  }
  for (const char* key : {"nsamples", "filesize"}) {
    if (!e.contains(key) || !IsNonNegativeInteger(e[key]) ||
        e[key].get<uint64_t>() > static_cast<uint64_t>(INT64_MAX)) {
      return field + "." + key + ": expected an integer >= 0";
    }
  }
  out->nsamples = e["nsamples"].get<int64_t>();
  out->filesize = e["filesize"].get<int64_t>();
  out->md5sum.clear();
  if (e.contains("md5sum")) {
    if (!e["md5sum"].is_string()) return field + ".md5sum: expected a string";
    out->md5sum = e["md5sum"].get<std::string>();
  }
  return "";
}

}  // namespace

namespace {
// "" the first time `url` is listed (entry i), else the problem naming the earlier entry: a
// shard listed twice was read twice.
std::string RepeatedUrl(const std::string& url, size_t i, std::map<std::string, size_t>* seen) {
  const auto [it, inserted] = seen->emplace(url, i);
  return inserted ? std::string()
                  : "shardlist[" + std::to_string(i) + "].url: \"" + url + "\" repeats shardlist[" +
                        std::to_string(it->second) + "]";
}
}  // namespace

ShardIndex ReadShardIndex(const std::string& dir) {
  ShardIndex index;
  index.path = (fs::path(dir) / "index.json").string();
  if (!io::FileExists(index.path)) {
    throw InputError(index.path,
                     "missing (expected the split's wids shard index, written by "
                     "occgt build or occgt merge)");
  }
  const json doc = ParseJsonFile(index.path);
  if (!doc.is_object() || !doc.contains("shardlist") || !doc["shardlist"].is_array()) {
    throw InputError(index.path, "expected an object with a \"shardlist\" array");
  }
  // The kind validate checks too: every reader takes the same files.
  if (!doc.contains("__kind__") || doc["__kind__"] != "wids-shard-index-v1") {
    throw InputError(index.path,
                     "__kind__: expected \"wids-shard-index-v1\", got " +
                         (doc.contains("__kind__") ? doc["__kind__"].dump() : std::string("none")));
  }
  if (doc.contains("name")) {
    if (!doc["name"].is_string()) throw InputError(index.path, "name: expected a string");
    index.name = doc["name"].get<std::string>();
  }
  const json& list = doc["shardlist"];
  index.shards.resize(list.size());
  std::map<std::string, size_t> entry_of_url;
  for (size_t i = 0; i < list.size(); ++i) {
    if (const std::string problem = ParseIndexEntry(list[i], i, &index.shards[i]);
        !problem.empty()) {
      throw InputError(index.path, problem);
    }
    if (const std::string problem = RepeatedUrl(index.shards[i].url, i, &entry_of_url);
        !problem.empty()) {
      throw InputError(index.path, problem);
    }
  }
  return index;
}

std::string IndexJson(const std::string& name, const std::vector<PartRecord>& parts) {
  json doc;
  doc["__kind__"] = "wids-shard-index-v1";
  doc["wids_version"] = 1;
  doc["name"] = name;
  json list = json::array();
  for (const PartRecord& p : parts) {
    json e;
    e["url"] = p.url;
    e["nsamples"] = p.info.nsamples;
    e["md5sum"] = p.info.md5sum;
    e["filesize"] = p.info.filesize;
    list.push_back(std::move(e));
  }
  doc["shardlist"] = std::move(list);
  return doc.dump(2) + "\n";
}

namespace {

std::string JsonLinesText(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& l : lines) {
    GT_ASSERT_MSG(l.find('\n') == std::string::npos, "JSONL line contains a newline");
    text += l;
    text += '\n';
  }
  return text;
}

}  // namespace

void WriteJsonLines(const std::string& path, const std::vector<std::string>& lines) {
  io::WriteFileAtomic(path, JsonLinesText(lines));
}

bool MergeOptions::Check(std::string* error) const {
  if (!split.empty()) {
    if (std::string e = CheckSplitName(split); !e.empty()) {
      *error = "split: " + e;
      return false;
    }
  }
  if (!schemas_dir.empty() && !fs::is_directory(schemas_dir)) {
    *error = "schemas_dir: \"" + schemas_dir + "\" is not a folder";
    return false;
  }
  return true;
}

namespace {

// The full check of one recorded shard (MergeOptions::verify): MD5 of the file against
// the record, then the tar read back (member names, .npy headers, sample JSON) and its
// keys against the record's. Returns "" or the shard's problem (one line).
std::string VerifyShard(const std::string& shard, const PartRecord& r,
                        const std::string& record_path, const SplitSchemas& schemas) {
  try {
    const std::string md5 = io::Md5HexOfFile(shard);
    if (md5 != r.info.md5sum) return "md5 " + md5 + " differs from the recorded " + r.info.md5sum;
  } catch (const InputError& e) {
    return "unreadable: " + ReasonOf(e, shard);
  }
  std::vector<std::string> keys;
  std::vector<std::string> problems;
  try {
    problems = CheckTarContents(shard, schemas, &keys);
  } catch (const InputError& e) {
    return "unreadable: " + ReasonOf(e, shard);
  }
  if (!problems.empty()) return FirstLines(problems);
  if (keys != r.keys) return "sample keys in the tar differ from " + record_path;
  return "";
}

// The options digest of the split in DIR: DIR/recipe.json's "options_digest" (the build's
// recipe), "" when the folder has none (the N-view shards of DIR/views).
std::string RecipeDigestOf(const std::string& dir) {
  const std::string path = (fs::path(dir) / "recipe.json").string();
  if (!io::FileExists(path)) return "";
  try {
    const json doc = ParseJsonFile(path);
    return doc.is_object() && doc.contains("options_digest") && doc["options_digest"].is_string()
               ? doc["options_digest"].get<std::string>()
               : "";
  } catch (const InputError&) {
    return "";  // not this check's to report: the shards are compared among themselves
  }
}

// Shards written by two builds in one folder (a shard and its record copied from another
// split of the same name): the first digest that differs from the split's, as a problem.
class DigestCheck {
 public:
  explicit DigestCheck(const std::string& dir)
      : digest_(RecipeDigestOf(dir)), from_(digest_.empty() ? "" : "recipe.json") {}
  // "" or the problem of a shard whose samples carry `digest` ("" = not recorded).
  std::string Check(const std::string& digest, const std::string& shard_name) {
    if (digest.empty()) return "";
    if (digest_.empty()) {
      digest_ = digest;
      from_ = shard_name;
      return "";
    }
    if (digest == digest_) return "";
    return "written by another build: options digest " + digest + ", the split's is " + digest_ +
           " (" + from_ +
           "); its samples are of other data or options (remove the shard and its part record "
           "and run the build again)";
  }

 private:
  std::string digest_, from_;
};

// One shard of the plan as the trusted merge reads it: its part record (parsed, its pair
// lines naming their keys and shard, against their schema in `schemas`), the stat of its
// tar, the plan's sample count. `error` holds the shard's first problem (an InputError
// naming the shard); needs no other shard, so shards load in parallel.
struct LoadedShard {
  PartRecord record;
  std::vector<std::string> scenes;  // scene of every pair line
  bool tuple_lines = false;         // some line is an N-view sample's
  std::exception_ptr error;
};

LoadedShard LoadShard(const std::string& dir, const std::string& split, int64_t idx,
                      int64_t planned_nsamples, const SplitSchemas& schemas) {
  LoadedShard out;
  try {
    const std::string shard = ShardPath(dir, split, idx);
    const std::string record_path = PartRecordPath(dir, split, idx);
    if (!io::FileExists(record_path)) {
      throw InputError(
          shard, "missing part record " + record_path + " (shard not written or not finished)");
    }
    try {
      out.record = ReadPartRecordAndScenes(dir, split, idx, &out.scenes, &out.tuple_lines);
    } catch (const InputError& e) {
      throw InputError(shard, std::string("bad part record: ") + e.what());
    }
    const PartRecord& r = out.record;
    const int64_t size = FileSize(shard);
    // What to do: the build (or `occgt tuples --shards`) writes a missing shard again.
    const std::string remedy =
        " (re-run the occgt build or tuples command that wrote the split: "
        "it writes a missing shard again)";
    if (size < 0) throw InputError(shard, "missing shard" + remedy);
    if (size != r.info.filesize) {
      throw InputError(shard, "size " + std::to_string(size) + " differs from the recorded " +
                                  std::to_string(r.info.filesize) + "; delete it" + remedy);
    }
    if (r.info.nsamples != planned_nsamples) {
      throw InputError(shard, "holds " + std::to_string(r.info.nsamples) +
                                  " samples, the plan says " + std::to_string(planned_nsamples));
    }
    for (size_t i = 0; i < r.keys.size(); ++i) {
      if (std::string e = CheckSampleKey(r.keys[i]); !e.empty()) {
        throw InputError(shard, "bad part record: keys[" + std::to_string(i) + "]: " + e);
      }
      if (const std::string p = schemas.CheckLine(json::parse(r.pair_lines[i])); !p.empty()) {
        throw InputError(record_path, "pairs[" + std::to_string(i) + "]: " + p);
      }
    }
  } catch (const InputError&) {
    out.error = std::current_exception();
  }
  return out;
}

// "<path>.tmp" written as it goes, published by Publish() (fsync, rename); removed when
// dropped unpublished, so a failed merge leaves nothing.
class StreamedFile {
 public:
  explicit StreamedFile(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw InputError(path_, std::string("cannot open: ") + std::strerror(errno));
  }
  ~StreamedFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!published_) ::unlink(tmp_.c_str());
  }
  StreamedFile(const StreamedFile&) = delete;
  StreamedFile& operator=(const StreamedFile&) = delete;
  void Append(std::string_view bytes) {
    if (!io::WriteAll(fd_, bytes)) {
      throw InputError(path_, std::string("write failed: ") + std::strerror(errno));
    }
  }
  // fsync, close and rename onto the path (the caller makes the folder durable).
  void Publish() {
    if (::fsync(fd_) != 0) {
      throw InputError(path_, std::string("fsync failed: ") + std::strerror(errno));
    }
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) {
      throw InputError(path_, std::string("close failed: ") + std::strerror(errno));
    }
    if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
      throw InputError(path_,
                       std::string("cannot rename the temporary file: ") + std::strerror(errno));
    }
    published_ = true;
  }

 private:
  std::string path_, tmp_;
  int fd_ = -1;
  bool published_ = false;
};

// Shards whose part records are loaded at once (bounds the memory to a few chunks of
// records, whatever the split's size).
constexpr size_t kMergeChunkShards = 64;

}  // namespace

MergeResult MergeSplit(const std::string& dir, const MergeOptions& options) {
  if (std::string error; !options.Check(&error)) throw InputError("merge options", error);
  MergeResult result;
  result.split = options.split;
  if (std::error_code ec; !fs::is_directory(dir, ec)) {
    throw InputError(dir, "expected a split folder (occgt build's --out)");
  }
  if (result.split.empty()) {
    const std::vector<std::string> splits = ListPlannedSplits(dir);
    if (splits.size() != 1) {
      throw InputError((fs::path(dir) / "parts").string(),
                       "expected exactly one <split>.plan.json, found " +
                           std::to_string(splits.size()) +
                           (splits.empty() ? " (the write stage of occgt build writes it before "
                                             "its first shard: run it, then merge)"
                                           : " (pass --split with one of them)"));
    }
    result.split = splits[0];
  }
  const SplitPlan plan = ReadPlan(dir, result.split);
  // Every file the merge publishes (summary.json by occgt merge or the build after it) can
  // take a new file, before any is published: a summary.json that is a folder used to fail
  // after pairs.jsonl and index.json were out, and the split looked published.
  for (const char* name : {"pairs.jsonl", "index.json", "summary.json"}) {
    const std::string path = (fs::path(dir) / name).string();
    if (const std::string problem = io::OutputFileProblem(path); !problem.empty()) {
      throw InputError(path, problem);
    }
  }
  // Lines and samples against their schemas only with `verify`: a per-line cost of its own.
  const SplitSchemas schemas = options.verify ? SplitSchemas(options.schemas_dir) : SplitSchemas();
  const size_t nshards = plan.shard_nsamples.size();
  StreamedFile pairs_jsonl((fs::path(dir) / "pairs.jsonl").string());
  std::unordered_map<std::string, int64_t> shard_of_key;
  DigestCheck digests(dir);
  // 1. Trusted checks, shards loaded in parallel by chunk, then taken in shard order: the
  //    first problem in shard order is the error, whatever the thread count. With `verify`,
  //    a problem found here at shard s is held while the shards before s are verified
  //    (step 2), so that the error is the first problem in shard order of either kind (a
  //    corrupt shard 0 before a truncated shard 2); the shards after s are not read.
  std::exception_ptr trusted_problem;
  try {
    for (size_t begin = 0; begin < nshards; begin += kMergeChunkShards) {
      const size_t end = std::min(nshards, begin + kMergeChunkShards);
      std::vector<LoadedShard> chunk(end - begin);
      tbb::parallel_for(begin, end, size_t{1}, [&](size_t s) {
        chunk[s - begin] =
            LoadShard(dir, result.split, static_cast<int64_t>(s), plan.shard_nsamples[s], schemas);
      });
      for (LoadedShard& loaded : chunk) {
        if (loaded.error) std::rethrow_exception(loaded.error);
        PartRecord& r = loaded.record;
        if (const std::string p = digests.Check(r.options_digest, r.url); !p.empty()) {
          throw InputError(r.info.path, p);
        }
        std::string text;
        for (size_t i = 0; i < r.keys.size(); ++i) {
          const std::string& key = r.keys[i];
          if (const auto [it, inserted] = shard_of_key.emplace(key, r.shard_index); !inserted) {
            throw InputError(r.info.path, "sample key " + key +
                                              (it->second == r.shard_index
                                                   ? " appears twice in the shard"
                                                   : " appears in an earlier shard, " +
                                                         ShardFileName(result.split, it->second)));
          }
          GT_ASSERT_MSG(r.pair_lines[i].find('\n') == std::string::npos,
                        "JSONL line contains a newline");
          text += r.pair_lines[i];
          text += '\n';
          ++result.samples_per_scene[loaded.scenes[i]];
        }
        result.tuples = result.tuples || loaded.tuple_lines;
        pairs_jsonl.Append(text);
        r.pair_lines.clear();  // in pairs.jsonl now
        r.pair_lines.shrink_to_fit();
        result.nsamples += r.info.nsamples;
        result.total_bytes += r.info.filesize;
        result.parts.push_back(std::move(r));
      }
    }
  } catch (const InputError&) {  // a shard's problem (not, say, pairs.jsonl's disk full)
    if (!options.verify) throw;
    trusted_problem = std::current_exception();  // result.parts: the shards before it
  }
  result.nshards = static_cast<int64_t>(result.parts.size());
  // 2. Opt-in full check of every byte, shards in parallel; the first problem in shard order.
  if (options.verify) {
    std::vector<std::string> problem(result.parts.size());
    tbb::parallel_for(size_t{0}, result.parts.size(), size_t{1}, [&](size_t s) {
      const PartRecord& r = result.parts[s];
      problem[s] =
          VerifyShard(r.info.path, r, PartRecordPath(dir, r.split, r.shard_index), schemas);
    });
    for (size_t s = 0; s < problem.size(); ++s) {
      if (!problem[s].empty()) throw InputError(result.parts[s].info.path, problem[s]);
    }
    if (trusted_problem) std::rethrow_exception(trusted_problem);
  }
  // pairs.jsonl first; index.json, which names the shards, is published second (its
  // atomic write also makes the folder, and so both renames, durable).
  pairs_jsonl.Publish();
  io::WriteFileAtomic((fs::path(dir) / "index.json").string(),
                      IndexJson(result.split, result.parts));
  return result;
}

std::string MergeSummaryJson(const MergeResult& result) {
  json doc;
  doc["kind"] = "occgt-merge-summary";
  doc["split"] = result.split;
  doc["shards"] = result.nshards;  // the names of the build's summary for the same facts
  doc["samples"] = result.nsamples;
  doc["bytes"] = result.total_bytes;
  json per_scene = json::object();
  for (const auto& [scene, n] : result.samples_per_scene) per_scene[scene] = n;
  doc[result.tuples ? "tuples_per_scene" : "pairs_per_scene"] = std::move(per_scene);
  return doc.dump(2) + "\n";
}

bool WriteMergeSummary(const std::string& dir, const MergeResult& result) {
  const std::string path = (fs::path(dir) / "summary.json").string();
  if (io::FileExists(path)) {
    const json existing = json::parse(io::ReadFileBytes(path), nullptr, false);
    if (existing.is_discarded() || !existing.is_object() ||
        existing.value("kind", "") != "occgt-merge-summary") {
      return false;
    }
  }
  io::WriteFileAtomic(path, MergeSummaryJson(result));
  return true;
}

namespace {

// What ValidateSplit finds in one shard of index.json's shardlist.
struct ShardProblems {
  std::vector<std::string> problems;  // "<file>: <problem>", in the order found
  std::set<std::string> digests;      // the options_digest of its samples
  std::string url;                    // as listed
  std::string shard;                  // DIR/url
  bool read = false;                  // the tar was read through: `keys` are its keys
  std::vector<std::string> keys;
  std::vector<std::optional<LineDigest>> lines;  // per key: the pairs.jsonl line it implies
};

// Checks shardlist[i] (`e`) against its file: size, MD5, contents (CheckTarContents) and
// sample count. Reads the whole shard twice (MD5, then libarchive); never throws.
ShardProblems CheckListedShard(const std::string& dir, const std::string& index_path, size_t i,
                               const json& e, const SplitSchemas& schemas, bool values) {
  ShardProblems out;
  auto problem = [&](const std::string& where, const std::string& what) {
    out.problems.push_back(where + ": " + what);
  };
  IndexedShard entry;
  if (const std::string p = ParseIndexEntry(e, i, &entry); !p.empty()) {
    problem(index_path, p);
    return out;
  }
  if (!e.contains("md5sum")) {
    problem(index_path, "shardlist[" + std::to_string(i) + "].md5sum: missing");
    return out;
  }
  out.url = entry.url;
  out.shard = (fs::path(dir) / out.url).string();
  const std::string& shard = out.shard;
  const int64_t size = FileSize(shard);
  if (size < 0) {
    problem(shard, "missing shard");
    return out;
  }
  if (size != entry.filesize) {
    problem(shard, "size " + std::to_string(size) + " differs from index.json's " +
                       std::to_string(entry.filesize));
  }
  try {
    const std::string md5 = io::Md5HexOfFile(shard);
    if (md5 != entry.md5sum) {
      problem(shard, "md5 " + md5 + " differs from index.json's " + entry.md5sum);
    }
  } catch (const InputError& err) {
    problem(shard, "unreadable: " + ReasonOf(err, shard));
    return out;
  }
  try {
    for (const std::string& p :
         CheckTarContents(shard, schemas, &out.keys, &out.digests, values ? &out.lines : nullptr)) {
      problem(shard, p);
    }
  } catch (const InputError& err) {
    problem(shard, "unreadable: " + ReasonOf(err, shard));
    return out;
  }
  if (static_cast<int64_t>(out.keys.size()) != entry.nsamples) {
    problem(shard, "holds " + std::to_string(out.keys.size()) + " samples, index.json says " +
                       std::to_string(entry.nsamples));
  }
  out.read = true;
  return out;
}

}  // namespace

bool ValidateOptions::Check(std::string* error) const {
  if (!schemas_dir.empty() && !fs::is_directory(schemas_dir)) {
    *error = "schemas_dir: \"" + schemas_dir + "\" is not a folder";
    return false;
  }
  return true;
}

std::vector<std::string> ValidateSplit(const std::string& dir, const ValidateOptions& options) {
  std::vector<std::string> problems;
  auto problem = [&](const std::string& where, const std::string& what) {
    problems.push_back(where + ": " + what);
  };
  if (std::string error; !options.Check(&error)) {
    problem("validate options", error);
    return problems;
  }
  const std::string index_path = (fs::path(dir) / "index.json").string();
  json index;
  std::unique_ptr<SchemaChecker> index_schema;
  std::optional<SplitSchemas> schemas;
  try {
    index = ParseJsonFile(index_path);
    index_schema = LoadSchema(options.schemas_dir, "index.schema.json");
    schemas.emplace(options.schemas_dir);
  } catch (const InputError& e) {
    // The output folder of occgt tuples --shards holds its split in views/.
    const bool views = !io::FileExists(index_path) &&
                       io::FileExists((fs::path(dir) / "views" / "index.json").string());
    problems.push_back(std::string(e.what()) +
                       (views ? " (the N-view shards of occgt tuples --shards are in " +
                                    (fs::path(dir) / "views").string() + ": validate that folder)"
                              : ""));
    return problems;
  }
  // One line for the document, as for a sample or a line (valijson gives one per level).
  if (const std::vector<std::string> p = index_schema->Check(index); !p.empty()) {
    problem(index_path, "index.schema.json: " + FirstLines(p));
  }
  if (!index.is_object() || index.value("__kind__", "") != "wids-shard-index-v1" ||
      index.value("wids_version", 0) != 1 || !index.contains("shardlist") ||
      !index["shardlist"].is_array()) {
    problem(index_path, "expected a wids-shard-index-v1 object with a shardlist");
    return problems;
  }
  // Every shard listed, in parallel: its problems and keys, by shard index.
  const json& shardlist = index["shardlist"];
  std::vector<ShardProblems> checked(shardlist.size());
  tbb::parallel_for(size_t{0}, shardlist.size(), size_t{1}, [&](size_t i) {
    checked[i] = CheckListedShard(dir, index_path, i, shardlist[i], *schemas, options.values);
  });
  // Then in shard order, the same whatever the thread count: key -> shard url, for the
  // repeat and the pairs.jsonl checks.
  std::map<std::string, std::string> shard_of_key;
  std::map<std::string, const std::optional<LineDigest>*> line_of_key;
  std::map<std::string, size_t> entry_of_url;
  std::set<std::string> unread;           // listed shards that could not be read through
  std::vector<std::string> sample_order;  // the keys of the read shards, in shard order
  int64_t total = 0;
  DigestCheck digests(dir);
  for (size_t i = 0; i < checked.size(); ++i) {
    ShardProblems& c = checked[i];
    if (const std::string repeated = c.url.empty() ? "" : RepeatedUrl(c.url, i, &entry_of_url);
        !repeated.empty()) {
      problem(index_path, repeated);
      continue;  // its samples are the first entry's, not repeats of their own
    }
    problems.insert(problems.end(), std::make_move_iterator(c.problems.begin()),
                    std::make_move_iterator(c.problems.end()));
    if (!c.read) {
      unread.insert(c.url);  // its problem is reported; its keys are unknown
      continue;
    }
    for (const std::string& d : c.digests) {
      if (const std::string p = digests.Check(d, c.url); !p.empty()) {
        problem(c.shard, p);
        break;
      }
    }
    for (size_t s = 0; s < c.keys.size(); ++s) {
      const std::string& k = c.keys[s];
      if (const auto [it, added] = shard_of_key.emplace(k, c.url); !added) {
        problem(c.shard, "sample " + k + " repeats (first in " + it->second + ")");
      } else {
        if (options.values) line_of_key.emplace(k, &c.lines[s]);
      }
      sample_order.push_back(k);
    }
    total += static_cast<int64_t>(c.keys.size());
  }
  // Shards (and leftovers) in the folder that index.json does not list: a reader globbing
  // *.tar would see samples the index does not count.
  {
    std::set<std::string> listed;
    for (const json& e : index["shardlist"]) {
      if (e.is_object() && e.contains("url") && e["url"].is_string()) {
        listed.insert(fs::path(e["url"].get<std::string>()).lexically_normal().string());
      }
    }
    std::error_code ec;
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    for (const std::string& name : names) {
      const std::string path = (fs::path(dir) / name).string();
      if (name.size() > 4 && name.compare(name.size() - 4, 4, ".tar") == 0 && !listed.count(name)) {
        problem(path, "shard not listed in index.json");
      } else if (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0) {
        problem(path, "temporary file left by an unfinished write");
      }
    }
  }
  const std::string pairs_path = (fs::path(dir) / "pairs.jsonl").string();
  if (!io::FileExists(pairs_path)) {
    problem(pairs_path, "missing");
    return problems;
  }
  int64_t nlines = 0, lines_of_unread = 0;
  size_t position = 0;  // of the next line among the samples of the read shards
  bool order_reported = false;
  for (const std::string& text : io::ReadLines(pairs_path)) {
    ++nlines;
    const std::string where = pairs_path + ":" + std::to_string(nlines);
    const json line = json::parse(text, nullptr, false);
    if (line.is_discarded() || !line.is_object()) {
      problem(where, "not a JSON object");
      ++position;  // still a sample's line
      continue;
    }
    if (const std::string p = schemas->CheckLine(line); !p.empty()) problem(where, p);
    if (!line.contains("key") || !line["key"].is_string() || !line.contains("shard") ||
        !line["shard"].is_string()) {
      problem(where, "fields \"key\" and \"shard\": expected strings");
      ++position;
      continue;
    }
    const std::string key = line["key"].get<std::string>();
    const std::string shard = line["shard"].get<std::string>();
    if (unread.count(shard)) {  // not one more line per sample of a shard already reported
      ++lines_of_unread;
      continue;
    }
    const auto it = shard_of_key.find(key);
    if (it == shard_of_key.end() || it->second != shard) {
      problem(where, "key \"" + key + "\" is not in shard \"" + shard + "\"");
    } else if (const auto l = line_of_key.find(key);
               l != line_of_key.end() && *l->second &&
               !LineFieldDiffering(line, **l->second).empty()) {
      problem(where, "field \"" + LineFieldDiffering(line, **l->second) +
                         "\" differs from the sample's json (" + shard + ", " + key + ")");
    }
    if (it != shard_of_key.end() && it->second == shard && position < sample_order.size() &&
        sample_order[position] != key && !order_reported) {
      // The first line out of order only, not every one after.
      problem(where, "key \"" + key + "\" is out of order: the shards hold \"" +
                         sample_order[position] + "\" here (one line per sample, in shard order)");
      order_reported = true;
    }
    ++position;
  }
  if (nlines - lines_of_unread != total) {
    problem(pairs_path, std::to_string(nlines - lines_of_unread) + " lines for " +
                            std::to_string(total) + " samples" +
                            (unread.empty() ? "" : " (of the shards that could be read)"));
  }
  return problems;
}

std::vector<std::string> ValidateJsonAgainstSchema(const std::string& document,
                                                   const std::string& schema_path) {
  const SchemaChecker checker(schema_path, ParseJsonFile(schema_path));
  const json doc = json::parse(document, nullptr, false);
  if (doc.is_discarded()) return {"not valid JSON"};
  return checker.Check(doc);
}

}  // namespace gt::shards

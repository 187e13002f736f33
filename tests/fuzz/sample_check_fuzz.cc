// A stored pair or N-view sample's members -> gt::shards::CheckPairSampleMembers and
// CheckPairSampleValues, CheckViewsSampleMembers and CheckViewsSampleValues (occgt validate,
// ShardDataset and TupleShardDataset run them on a split's bytes); both sets on every input.
// Input: records [name length: 1 byte][name][size: 4 bytes, little-endian][bytes], one per
// member ("json", "label01.npy", "image0.png", ...); a cut record ends the input. The json is
// parsed without exceptions, a .npy member with io::ParseNpy (a bad one is left out, as
// validate reports it before the value checks), every other member is an image. Both checks
// must return problems, never throw, whatever the json's numbers and the arrays' shapes.
// With OCCGT_FUZZ_PRINT set, the problems are printed (to check that a seed is consistent).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/npy.h"
#include "libgt/shards/sample_check.h"
#include "libgt/shards/views_sample_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  nlohmann::json meta;
  std::set<std::string> fields;
  std::map<std::string, gt::io::NpyArray> npy;
  std::map<std::string, std::string_view> images;
  size_t at = 0;
  while (at < size) {
    const size_t name_size = data[at++];
    if (size - at < name_size + 4) break;
    const std::string name(reinterpret_cast<const char*>(data + at), name_size);
    at += name_size;
    const uint32_t n = static_cast<uint32_t>(data[at]) | static_cast<uint32_t>(data[at + 1]) << 8 |
                       static_cast<uint32_t>(data[at + 2]) << 16 |
                       static_cast<uint32_t>(data[at + 3]) << 24;
    at += 4;
    if (size - at < n) break;
    const std::string_view bytes(reinterpret_cast<const char*>(data + at), n);
    at += n;
    fields.insert(name);
    if (name == "json") {
      meta = nlohmann::json::parse(bytes, nullptr, false);
    } else if (name.size() > 4 && name.compare(name.size() - 4, 4, ".npy") == 0) {
      try {
        npy[name] = gt::io::ParseNpy(bytes, name);
      } catch (const gt::InputError&) {
      }
    } else {
      images[name] = bytes;
    }
  }
  try {
    std::vector<std::string> problems = gt::shards::CheckPairSampleMembers(meta, fields);
    for (std::string& p : gt::shards::CheckPairSampleValues(meta, npy, images)) {
      problems.push_back(std::move(p));
    }
    std::vector<std::string> views = gt::shards::CheckViewsSampleMembers(meta, fields);
    for (std::string& p : gt::shards::CheckViewsSampleValues(meta, npy, images)) {
      views.push_back(std::move(p));
    }
    static const bool print = std::getenv("OCCGT_FUZZ_PRINT") != nullptr;
    for (const auto* set : {&problems, &views}) {
      for (const std::string& p : *set) {
        if (p.empty()) std::abort();
        if (print) std::fprintf(stderr, "%s: %s\n", set == &problems ? "pair" : "views", p.c_str());
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "the sample checks threw: %s\n", e.what());
    std::abort();
  }
  return 0;
}

// One stored sample of a shard as the value checks take it (shards/sample_check.h,
// shards/views_sample_check.h): its members decoded, by plain field name.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>

#include "libgt/io/npy.h"
#include "libgt/shards/sample.h"

namespace gt::test {

struct DecodedSample {
  std::string key;
  nlohmann::json meta;
  std::set<std::string> fields;                // plain names (a .npy.gz member as .npy)
  std::map<std::string, io::NpyArray> arrays;  // the .npy members
  std::map<std::string, std::string> images;   // every other member but the json

  template <typename T>
  T* Data(const std::string& field) {
    return reinterpret_cast<T*>(arrays.at(field).data.data());
  }
  std::map<std::string, std::string_view> ImageViews() const {
    return {images.begin(), images.end()};
  }
};

inline DecodedSample DecodeSample(const shards::Sample& s) {
  DecodedSample d;
  d.key = s.key;
  for (const shards::SampleField& f : s.fields) {
    std::string field = f.name;
    std::string plain = shards::DecodeMember(&field, f.bytes, f.name);
    d.fields.insert(field);
    if (field == "json") {
      d.meta = nlohmann::json::parse(plain);
    } else if (field.size() > 4 && field.substr(field.size() - 4) == ".npy") {
      d.arrays[field] = io::ParseNpy(plain, field);
    } else {
      d.images[field] = plain;
    }
  }
  return d;
}

}  // namespace gt::test

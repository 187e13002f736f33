#include "libgt/report/pair_source.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string_view>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"
#include "libgt/render/depth_picture.h"
#include "libgt/report/canvas.h"
#include "libgt/shards/sample_check.h"
#include "libgt/shards/tar_shard.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/pair_truth.h"

namespace gt::report {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kArrayFields = {
    "label01.npy", "label10.npy",    "matches.npy",   "match_type.npy", "match_xy.npy",
    "cells0.npy",  "cells1.npy",     "occ0.npy",      "known0.npy",     "occ1.npy",
    "known1.npy",  "occ0_dense.npy", "occ1_dense.npy"};

// Parsed .npy of a required field with the expected dtype and rank.
gt::io::NpyArray NeedArray(const std::map<std::string, std::string>& fields,
                           const std::string& field, const std::string& source,
                           const std::string& descr, size_t rank) {
  const auto it = fields.find(field);
  if (it == fields.end()) throw InputError(source, "missing field " + field);
  gt::io::NpyArray a = gt::io::ParseNpy(it->second, source + ":" + field);
  if (a.descr != descr || a.shape.size() != rank) {
    throw InputError(source + ":" + field,
                     "expected dtype " + descr + " with " + std::to_string(rank) + " dimensions");
  }
  return a;
}

template <typename T>
std::vector<T> Values(const gt::io::NpyArray& a, const std::string& name) {
  const T* p = a.As<T>(name);
  return std::vector<T>(p, p + a.NumElements());
}

LabelMap LabelsFrom(const gt::io::NpyArray& a, const std::string& name) {
  LabelMap m;
  m.height = static_cast<int>(a.shape[0]);
  m.width = static_cast<int>(a.shape[1]);
  m.codes = Values<uint8_t>(a, name);
  return m;
}

// Depth-first search of the json for `pred(key, value)`; objects in key order.
const nlohmann::json* FindJson(
    const nlohmann::json& j,
    const std::function<bool(const std::string&, const nlohmann::json&)>& pred) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (pred(it.key(), it.value())) return &it.value();
    }
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (const nlohmann::json* f = FindJson(it.value(), pred)) return f;
    }
  } else if (j.is_array()) {
    for (const auto& e : j) {
      if (const nlohmann::json* f = FindJson(e, pred)) return f;
    }
  }
  return nullptr;
}

// The pair's "resolution" [W, H] in its metadata (the sample json, meta.json or
// occupancy.json), or nullptr.
const nlohmann::json* FindResolution(const nlohmann::json& meta) {
  return FindJson(meta, [](const std::string& k, const nlohmann::json& v) {
    return k == "resolution" && v.is_array() && v.size() == 2 && v[0].is_number_integer() &&
           v[1].is_number_integer();
  });
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::vector<double> FindEdges(const nlohmann::json& meta, size_t count, const std::string& source) {
  const nlohmann::json* e = FindJson(meta, [&](const std::string& k, const nlohmann::json& v) {
    if (!EndsWith(k, "edges_m") || !v.is_array() || v.size() != count) return false;
    for (const auto& x : v) {
      if (!x.is_number()) return false;
    }
    return true;
  });
  if (e == nullptr) {
    throw InputError(source + ": json", "expected the occupancy bin edges (an array of " +
                                            std::to_string(count) + " numbers named *edges_m)");
  }
  std::vector<double> edges = e->get<std::vector<double>>();
  for (size_t k = 1; k < edges.size(); ++k) {
    if (!(edges[k] > edges[k - 1])) {
      throw InputError(source + ": edges_m", "expected increasing bin edges");
    }
  }
  return edges;
}

cv::Mat FieldImage(const std::map<std::string, std::string>& fields, const std::string& stem,
                   const std::string& source) {
  for (const char* ext : {".png", ".jpg", ".jpeg"}) {
    const auto it = fields.find(stem + ext);
    if (it != fields.end()) {
      return gt::io::DecodeImageBytes(it->second, gt::io::ChannelOrder::kBgr,
                                      source + ":" + it->first);
    }
  }
  return cv::Mat();
}

cv::Mat BgrFromColor(const gt::io::ColorImage& c) {
  cv::Mat rgb(c.height, c.width, CV_8UC3, const_cast<uint8_t*>(c.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

gt::occupancy::FrustumVolume VolumeFromFields(const std::map<std::string, std::string>& fields,
                                              int cam, const nlohmann::json& meta,
                                              const std::string& source) {
  const std::string c = std::to_string(cam);
  if (fields.count("occ" + c + ".npy")) {
    const auto occ = NeedArray(fields, "occ" + c + ".npy", source, "<u8", 2);
    const auto known = NeedArray(fields, "known" + c + ".npy", source, "<u8", 2);
    if (occ.shape != known.shape) {
      throw InputError(source + ":known" + c + ".npy", "expected the shape of occ" + c);
    }
    gt::occupancy::FrustumVolume v;
    v.height = static_cast<int>(occ.shape[0]);
    v.width = static_cast<int>(occ.shape[1]);
    v.occ = Values<uint64_t>(occ, source + ":occ" + c + ".npy");
    v.known = Values<uint64_t>(known, source + ":known" + c + ".npy");
    // The number of bins: the edges array decides; try 64 first (the paper), then any.
    const nlohmann::json* e = FindJson(meta, [](const std::string& k, const nlohmann::json& x) {
      return EndsWith(k, "edges_m") && x.is_array() && x.size() >= 2 && x.size() <= 65;
    });
    if (e == nullptr) {
      throw InputError(source + ": json", "expected the occupancy bin edges (*edges_m)");
    }
    v.edges_m = FindEdges(meta, e->size(), source);
    const uint64_t mask = v.num_bins() >= 64 ? ~0ULL : ((1ULL << v.num_bins()) - 1);
    for (size_t r = 0; r < v.occ.size(); ++r) {
      if ((v.occ[r] & ~v.known[r]) != 0 || (v.known[r] & ~mask) != 0) {
        throw InputError(source + ":occ" + c + ".npy",
                         "expected occ within known and bits < number of bins");
      }
    }
    return v;
  }
  const auto dense = NeedArray(fields, "occ" + c + "_dense.npy", source, "|u1", 3);
  const int bins = static_cast<int>(dense.shape[0]);
  return VolumeFromDense(Values<uint8_t>(dense, source), bins, static_cast<int>(dense.shape[1]),
                         static_cast<int>(dense.shape[2]),
                         FindEdges(meta, static_cast<size_t>(bins) + 1, source));
}

// The json member of a shard sample, or a discarded json when it has none or it does not
// parse (PairFromFields says so). InputError for an N-view sample: not a pair.
nlohmann::json PairSampleJson(const std::map<std::string, std::string>& fields,
                              const std::string& where) {
  const auto json_it = fields.find("json");
  if (json_it == fields.end()) return nlohmann::json(nlohmann::json::value_t::discarded);
  nlohmann::json meta = nlohmann::json::parse(json_it->second, nullptr, false);
  if (meta.is_object() && meta.value("kind", "") == "occgt-views-sample") {
    throw InputError(where,
                     "an N-view sample of occgt tuples --shards; inspect pair draws the "
                     "pair samples of occgt build (occgt.torch.TupleShardDataset reads "
                     "N-view samples)");
  }
  return meta;
}

// A pair sample of a build's shard, checked by the rules of `occgt validate` before it is
// drawn (shards/sample_check.h: its members, and their values against its json and each
// other), so that a damaged sample is named rather than drawn. InputError("<where>.<field>",
// ...) naming the first problem.
void CheckStoredPair(const std::map<std::string, std::string>& fields, const nlohmann::json& meta,
                     const std::string& where) {
  if (meta.is_discarded()) return;  // PairFromFields said what is wrong
  std::set<std::string> names;
  std::map<std::string, gt::io::NpyArray> arrays;
  std::map<std::string, std::string_view> images;
  for (const auto& [name, bytes] : fields) {
    names.insert(name);
    if (EndsWith(name, ".npy")) {
      arrays[name] = gt::io::ParseNpy(bytes, where + "." + name);
    } else if (EndsWith(name, ".png") || EndsWith(name, ".jpg")) {
      images[name] = bytes;
    }
  }
  std::vector<std::string> problems = gt::shards::CheckPairSampleMembers(meta, names);
  if (problems.empty()) problems = gt::shards::CheckPairSampleValues(meta, arrays, images);
  if (!problems.empty()) {
    const std::string& p = problems.front();
    const size_t colon = p.find(": ");
    throw InputError(where + "." + p.substr(0, colon), p.substr(colon + 2));
  }
}

}  // namespace

PairData PairFromFields(const std::map<std::string, std::string>& fields, const std::string& source,
                        const cv::Mat& image0, const cv::Mat& image1) {
  PairData p;
  p.name = source;
  for (const char* j : {"json", "meta.json"}) {
    const auto it = fields.find(j);
    if (it == fields.end()) continue;
    try {
      p.meta = nlohmann::json::parse(it->second);
    } catch (const nlohmann::json::exception& e) {
      throw InputError(source + ":" + j, std::string("expected JSON: ") + e.what());
    }
  }
  const bool occ0 = fields.count("occ0.npy") || fields.count("occ0_dense.npy");
  const bool occ1 = fields.count("occ1.npy") || fields.count("occ1_dense.npy");
  // One camera's volume without the other's, or some of the label fields without label01,
  // is a broken sample, not a pair without occupancy or labels: nothing is left out quietly.
  if (occ0 != occ1)
    throw InputError(source, occ0 ? "missing field occ1.npy" : "missing field occ0.npy");
  bool any_label_field = false;
  for (const char* f : {"label01.npy", "label10.npy", "matches.npy", "match_type.npy",
                        "match_xy.npy", "cells0.npy", "cells1.npy"}) {
    any_label_field = any_label_field || fields.count(f) > 0;
  }
  if (!any_label_field && occ0 && occ1) {  // occupancy only
    p.has_labels = false;
    p.occ0 = VolumeFromFields(fields, 0, p.meta, source);
    p.occ1 = VolumeFromFields(fields, 1, p.meta, source);
    p.has_occupancy = true;
    p.width = 2 * p.occ0.width;
    p.height = 2 * p.occ0.height;
    if (const nlohmann::json* r = FindResolution(p.meta)) {
      p.width = (*r)[0].get<int>();
      p.height = (*r)[1].get<int>();
    }
    return p;
  }
  // A split of sample.labels: false keeps the matches without the label maps: say so (it
  // read as a damaged sample, "missing field label01.npy").
  if (!fields.count("label01.npy") && !fields.count("label10.npy") && fields.count("matches.npy")) {
    throw InputError(source,
                     "holds no label maps (label01.npy, label10.npy): a split built with "
                     "sample.labels: false; the pictures need them: compute the pair with "
                     "occgt pair --recipe (its recipe.json's options)");
  }
  p.labels01 = LabelsFrom(NeedArray(fields, "label01.npy", source, "|u1", 2), source);
  p.labels10 = LabelsFrom(NeedArray(fields, "label10.npy", source, "|u1", 2), source);
  p.width = p.labels01.width;
  p.height = p.labels01.height;
  if (p.width <= 0 || p.height <= 0) throw InputError(source + ":label01.npy", "empty");
  // The label maps at the json's resolution (a cut label01 was blamed on cells0.npy).
  if (const nlohmann::json* r = FindResolution(p.meta)) {
    const int w = (*r)[0].get<int>(), h = (*r)[1].get<int>();
    for (const auto& [name, labels] :
         {std::pair<const char*, const LabelMap*>{"label01.npy", &p.labels01},
          std::pair<const char*, const LabelMap*>{"label10.npy", &p.labels10}}) {
      if (labels->width != w || labels->height != h) {
        throw InputError(source + ":" + name, "expected [" + std::to_string(h) + ", " +
                                                  std::to_string(w) + "] (the json's resolution " +
                                                  std::to_string(w) + "x" + std::to_string(h) +
                                                  "), got [" + std::to_string(labels->height) +
                                                  ", " + std::to_string(labels->width) + "]");
      }
    }
  }

  const auto matches = NeedArray(fields, "matches.npy", source, "<i4", 2);
  const auto types = NeedArray(fields, "match_type.npy", source, "|u1", 1);
  const auto xy = NeedArray(fields, "match_xy.npy", source, "<f4", 2);
  const auto cells0 = NeedArray(fields, "cells0.npy", source, "|u1", 2);
  const auto cells1 = NeedArray(fields, "cells1.npy", source, "|u1", 2);
  const int64_t m = types.shape[0];
  if ((matches.shape[0] != m || matches.shape[1] != 2) || (xy.shape[0] != m || xy.shape[1] != 2)) {
    throw InputError(source + ":matches.npy",
                     "expected matches [M, 2], match_type [M], match_xy [M, 2] with equal M");
  }
  p.matches.matches = Values<int32_t>(matches, source + ":matches.npy");
  p.matches.match_type = Values<uint8_t>(types, source + ":match_type.npy");
  p.matches.match_xy = Values<float>(xy, source + ":match_xy.npy");
  p.matches.cells_h0 = static_cast<int>(cells0.shape[0]);
  p.matches.cells_w0 = static_cast<int>(cells0.shape[1]);
  p.matches.cells_h1 = static_cast<int>(cells1.shape[0]);
  p.matches.cells_w1 = static_cast<int>(cells1.shape[1]);
  p.matches.cells0 = Values<uint8_t>(cells0, source + ":cells0.npy");
  p.matches.cells1 = Values<uint8_t>(cells1, source + ":cells1.npy");
  if (p.matches.cells_w0 <= 0 || p.width % p.matches.cells_w0 > p.width / p.matches.cells_w0) {
    throw InputError(source + ":cells0.npy", "expected (H/s, W/s) cells for the label size");
  }
  p.stride = p.width / p.matches.cells_w0;
  if (p.height / p.stride != p.matches.cells_h0) {
    throw InputError(source + ":cells0.npy", "expected " + std::to_string(p.height / p.stride) +
                                                 " rows of cells for stride " +
                                                 std::to_string(p.stride));
  }
  if (const nlohmann::json* a = FindJson(p.meta, [](const std::string& k, const nlohmann::json& v) {
        return k == "anchor" && v.is_string();
      })) {
    p.anchor = gt::ParseAnchor(a->get<std::string>(), source + ": anchor");
  }

  cv::Mat img0 = image0.empty() ? FieldImage(fields, "image0", source) : image0;
  cv::Mat img1 = image1.empty() ? FieldImage(fields, "image1", source) : image1;
  if (img0.empty() != img1.empty()) {  // part of a group: an error, not a silent drop
    const std::string missing = img0.empty() ? "image0" : "image1";
    throw InputError(source,
                     "missing field " + missing + ".png (or .jpg): the other image is there");
  }
  p.has_images = !img0.empty() && !img1.empty();
  p.image0 = PrepareImage(img0, p.width, p.height);
  p.image1 = PrepareImage(img1, p.labels10.width, p.labels10.height);

  if (occ0 && occ1) {
    p.occ0 = VolumeFromFields(fields, 0, p.meta, source);
    p.occ1 = VolumeFromFields(fields, 1, p.meta, source);
    p.has_occupancy = true;
  }
  return p;
}

PairData LoadPairFromShard(const std::string& tar_path, const std::string& key) {
  const gt::shards::Sample sample = gt::shards::ReadShardSample(tar_path, key);
  std::map<std::string, std::string> fields;
  for (const auto& f : sample.fields) fields[f.name] = f.bytes;
  const std::string where = tar_path + ":" + key;
  const nlohmann::json meta = PairSampleJson(fields, where);
  PairData pair = PairFromFields(fields, where);  // its own messages first
  CheckStoredPair(fields, meta, where);
  // The build's recipe.json beside its shards says where the depth came from.
  const std::string recipe_path = (fs::path(tar_path).parent_path() / "recipe.json").string();
  if (gt::io::FileExists(recipe_path)) {
    try {
      const nlohmann::json r = nlohmann::json::parse(gt::io::ReadFileBytes(recipe_path));
      pair.depth_source = "sensor";
      if (r.contains("dataset") && r["dataset"].is_object() &&
          r["dataset"].contains("depth_source") && r["dataset"]["depth_source"].is_string()) {
        pair.depth_source = r["dataset"]["depth_source"].get<std::string>();
      }
    } catch (const nlohmann::json::exception&) {
      pair.depth_source.clear();  // not a build's recipe.json: unknown
    }
  }
  return pair;
}

PairData LoadPairFromDir(const std::string& dir, const std::string& image0_path,
                         const std::string& image1_path, const std::string& dataset_root) {
  if (!fs::is_directory(dir)) throw InputError(dir, "expected an `occgt pair` output folder");
  std::map<std::string, std::string> fields;
  std::vector<std::string> names = kArrayFields;
  for (const char* extra : {"meta.json", "image0.png", "image1.png", "image0.jpg", "image1.jpg"}) {
    names.push_back(extra);
  }
  for (const std::string& name : names) {
    const std::string path = (fs::path(dir) / name).string();
    if (gt::io::FileExists(path)) fields[name] = gt::io::ReadFileBytes(path);
  }
  // A folder whose arrays no meta.json / occupancy.json names (they are written last, after
  // an earlier pair's is removed): an `occgt pair` or `occgt occupancy` run that did not
  // finish; drawn, its arrays could be another pair's than the images'.
  const auto missing_index = [&](const std::vector<std::string>& arrays, const char* index,
                                 const char* command) {
    if (gt::io::FileExists((fs::path(dir) / index).string())) return;
    for (const std::string& a : arrays) {
      if (fields.count(a)) {
        throw InputError((fs::path(dir) / index).string(),
                         "missing, while the folder holds " + a + ": an `" + command +
                             "` run into it did not finish (re-run it)");
      }
    }
  };
  missing_index({"label01.npy", "label10.npy", "matches.npy", "match_type.npy", "match_xy.npy",
                 "cells0.npy", "cells1.npy"},
                "meta.json", "occgt pair");
  missing_index({"occ0.npy", "known0.npy", "occ1.npy", "known1.npy"}, "occupancy.json",
                "occgt occupancy");
  // `occgt occupancy` files: its dense volumes (occ0/1_dense.npy, read above; a folder
  // written before they took the shard's names has occupancy0/1.npy), and occupancy.json
  // (the bin edges) as meta.json's "occupancy" entry, or as the metadata of a folder without
  // meta.json.
  for (int cam = 0; cam < 2; ++cam) {
    const std::string c = std::to_string(cam);
    const std::string path = (fs::path(dir) / ("occupancy" + c + ".npy")).string();
    if (!fields.count("occ" + c + "_dense.npy") && gt::io::FileExists(path)) {
      fields["occ" + c + "_dense.npy"] = gt::io::ReadFileBytes(path);
    }
  }
  if (const std::string occ_path = (fs::path(dir) / "occupancy.json").string();
      gt::io::FileExists(occ_path)) {
    nlohmann::json occupancy;
    try {
      occupancy = nlohmann::json::parse(gt::io::ReadFileBytes(occ_path));
    } catch (const nlohmann::json::exception& e) {
      throw InputError(occ_path, std::string("expected JSON: ") + e.what());
    }
    nlohmann::json meta = nlohmann::json::object();
    if (fields.count("meta.json")) {
      try {
        meta = nlohmann::json::parse(fields["meta.json"]);
      } catch (const nlohmann::json::exception& e) {
        throw InputError((fs::path(dir) / "meta.json").string(),
                         std::string("expected JSON: ") + e.what());
      }
      if (!meta.is_object()) {
        throw InputError((fs::path(dir) / "meta.json").string(), "expected an object");
      }
      // Both files of one pair: `occgt occupancy` of other frames or another resolution into
      // the same folder was drawn beside the labels.
      for (const char* key : {"format", "scene", "frame0", "frame1", "resolution"}) {
        if (occupancy.is_object() && meta.contains(key) && occupancy.contains(key) &&
            meta[key] != occupancy[key]) {
          throw InputError(occ_path, std::string("\"") + key + "\" " + occupancy[key].dump() +
                                         " differs from meta.json's " + meta[key].dump() +
                                         ": the folder holds two pairs (write each into its "
                                         "own --out)");
        }
      }
      meta["occupancy"] = std::move(occupancy);
    } else {
      meta = std::move(occupancy);
    }
    fields["meta.json"] = meta.dump();
  }
  cv::Mat img0, img1;
  std::string p0 = image0_path, p1 = image1_path;
  if (p0.empty() && p1.empty() && !fields.count("image0.png") && !fields.count("image0.jpg") &&
      fields.count("meta.json")) {
    // Colour paths recorded by `occgt pair` (frame 0 first: "frame0" < "frame1" in key order).
    std::vector<std::string> paths;
    std::function<void(const nlohmann::json&)> collect = [&](const nlohmann::json& j) {
      if (j.is_object()) {
        for (auto it = j.begin(); it != j.end(); ++it) {
          if (it.key() == "color_path" && it.value().is_string()) {
            paths.push_back(it.value().get<std::string>());
          } else {
            collect(it.value());
          }
        }
      } else if (j.is_array()) {
        for (const auto& e : j) collect(e);
      }
    };
    try {
      collect(nlohmann::json::parse(fields["meta.json"]));
    } catch (const nlohmann::json::exception&) {
      // PairFromFields reports the parse error with the file name.
    }
    if (paths.size() >= 2 && gt::io::FileExists(paths[0]) && gt::io::FileExists(paths[1])) {
      p0 = paths[0];
      p1 = paths[1];
    }
  }
  if (p0.empty() && p1.empty() && !dataset_root.empty() && fields.count("meta.json")) {
    const std::string meta_path = (fs::path(dir) / "meta.json").string();
    nlohmann::json meta;
    try {
      meta = nlohmann::json::parse(fields["meta.json"]);
    } catch (const nlohmann::json::exception&) {
      throw InputError(meta_path, "expected JSON");
    }
    auto frame_id = [&meta](const char* key) -> const nlohmann::json* {
      if (!meta.contains(key) || !meta[key].is_object() || !meta[key].contains("id") ||
          !meta[key]["id"].is_string()) {
        return nullptr;
      }
      return &meta[key]["id"];
    };
    if (!meta.contains("format") || !meta["format"].is_string() || !meta.contains("scene") ||
        !meta["scene"].is_string() || !frame_id("frame0") || !frame_id("frame1")) {
      throw InputError(meta_path,
                       "expected \"format\", \"scene\", \"frame0\" and \"frame1\" "
                       "({\"id\": ..., \"number\": ...}) to find the colour images under --root");
    }
    const gt::DatasetFormat format =
        gt::ParseDatasetFormat(meta["format"].get<std::string>(), meta_path + ": format");
    gt::datasets::ReaderOptions reader_options;
    if (format == gt::DatasetFormat::kScanNetPP) {
      // The device meta.json records; folders written before it did: from the frame ids.
      const std::string id0 = frame_id("frame0")->get<std::string>();
      if (meta.contains("device")) {
        if (!meta["device"].is_string())
          throw InputError(meta_path + ": device", "expected a string");
        reader_options.scannetpp_device = gt::datasets::ParseScanNetPPDevice(
            meta["device"].get<std::string>(), meta_path + ": device");
        for (const char* key : {"frame0", "frame1"}) {
          gt::datasets::CheckScanNetPPFrameId(reader_options.scannetpp_device,
                                              frame_id(key)->get<std::string>(),
                                              meta_path + ": " + key, meta_path + "'s device");
        }
      } else {
        reader_options.scannetpp_device = gt::datasets::ScanNetPPDeviceOfFrameId(id0);
      }
    }
    if (meta.contains("tum_max_dt_s")) {  // TUM: the pair's tolerance (absent: the default)
      if (!meta["tum_max_dt_s"].is_number() || !(meta["tum_max_dt_s"].get<double>() >= 0)) {
        throw InputError(meta_path + ": tum_max_dt_s", "expected a number of seconds >= 0");
      }
      reader_options.tum_max_dt_s = meta["tum_max_dt_s"].get<double>();
    }
    const auto reader = gt::datasets::MakeReader(format, reader_options);
    const gt::Scene scene = reader->ReadScene(dataset_root, meta["scene"].get<std::string>());
    for (int k = 0; k < 2; ++k) {
      const std::string id = frame_id(k == 0 ? "frame0" : "frame1")->get<std::string>();
      for (const auto& f : scene.frames) {
        if (f.id != id || f.color_path.empty()) continue;
        // A payload inside a container (.sens), or a distorted image (ScanNet++): decoded
        // through the frame.
        if (f.color_range.size > 0 || f.color_lens) {
          (k == 0 ? img0 : img1) = BgrFromColor(gt::io::ReadFrameColor(f));
        } else {
          (k == 0 ? p0 : p1) = f.color_path;
        }
      }
    }
  }
  if (!p0.empty()) img0 = BgrFromColor(gt::io::ReadColor(p0));
  if (!p1.empty()) img1 = BgrFromColor(gt::io::ReadColor(p1));
  PairData pair = PairFromFields(fields, dir, img0, img1);
  if (pair.meta.is_object() && pair.meta.contains("tool")) {
    // meta.json records a depth source other than the sensor's (absent: sensor).
    pair.depth_source = pair.meta.value("depth_source", std::string("sensor"));
  }
  return pair;
}

cv::Mat DepthSourcesPicture(const Scene& scene, const std::vector<const Frame*>& frames,
                            const truth::Resolution& resolution,
                            const render::FrameDepthOptions& depth) {
  struct Maps {
    DepthImage sensor, mesh, fused;
  };
  std::vector<Maps> maps;
  double top = 0;
  render::FrameDepthOptions mesh_options = depth;
  mesh_options.source = render::DepthSourceMode::kMesh;
  for (const Frame* f : frames) {
    Maps m;
    m.sensor = f->depth.path.empty() ? DepthImage(resolution.width, resolution.height)
                                     : truth::LoadWorkingDepth(*f, resolution);
    m.mesh = truth::LoadWorkingDepth(scene, *f, resolution, mesh_options);
    m.fused = render::FuseSensorAndMesh(m.sensor, m.mesh, scene.min_depth_m, scene.max_depth_m,
                                        depth.fused);
    for (const DepthImage* d : {&m.sensor, &m.mesh}) {
      for (float v : d->values_m) {
        if (IsValidDepth(v, scene.min_depth_m, scene.max_depth_m)) top = std::max<double>(top, v);
      }
    }
    maps.push_back(std::move(m));
  }
  if (top <= 0) top = 1;
  auto bgr = [](const cv::Mat& rgb) {
    cv::Mat out;
    cv::cvtColor(rgb, out, cv::COLOR_RGB2BGR);
    return out;
  };
  std::vector<cv::Mat> rows;
  for (size_t k = 0; k < frames.size(); ++k) {
    const Maps& m = maps[k];
    const std::string& id = frames[k]->id;
    cv::Mat row = TitleAbove(bgr(render::DepthRamp(m.sensor, top)), id + " sensor");
    row = SideBySide(row, TitleAbove(bgr(render::DepthRamp(m.mesh, top)), id + " rendered"));
    row = SideBySide(row, TitleAbove(bgr(render::DepthRamp(m.fused, top)), id + " fused"));
    row =
        SideBySide(row, TitleAbove(bgr(render::AgreementPicture(m.sensor, m.mesh, scene.min_depth_m,
                                                                scene.max_depth_m, depth.fused)),
                                   id + " sensor vs mesh"));
    rows.push_back(row);
  }
  char note[160];
  std::snprintf(note, sizeof(note),
                "depth 0 to %.2f m (bright = near, black = none); agree within %g m + %g of depth",
                top, depth.fused.abs_tol_m, depth.fused.rel_tol);
  // The colours of render::AgreementPicture (R G B).
  rows.push_back(LegendStrip({{{40, 200, 60}, "agree"},
                              {{230, 40, 40}, "disagree (fused: none)"},
                              {{50, 110, 240}, "mesh only"},
                              {{230, 210, 40}, "sensor only"}},
                             rows.front().cols, 4, note));
  return StackVertical(rows);
}

PairData ComputePairFromScene(const Scene& scene, const std::string& id0, const std::string& id1,
                              const truth::PairTruthOptions& o, const truth::Resolution& resolution,
                              const render::FrameDepthOptions& depth) {
  std::string error;
  if (!resolution.Check(&error)) throw InputError("--resolution", error);
  if (!depth.Check(&error)) throw InputError("depth source", error);
  if (!o.Check(&error)) throw InputError("pair options", error);
  const gt::Frame& f0 = scene.frames[gt::truth::FindFrame(scene, id0)];
  const gt::Frame& f1 = scene.frames[gt::truth::FindFrame(scene, id1)];
  const gt::truth::PairTruth truth =
      gt::truth::ComputePairTruth(gt::truth::LoadWorkingFrame(scene, f0, resolution, depth),
                                  gt::truth::LoadWorkingFrame(scene, f1, resolution, depth), o);
  const gt::PairLabels& pl = truth.labels;
  PairData p;
  p.name = scene.name + " " + id0 + "," + id1;
  p.width = resolution.width;
  p.height = resolution.height;
  p.labels01 = {pl.l01.width, pl.l01.height, pl.l01.labels};
  p.labels10 = {pl.l10.width, pl.l10.height, pl.l10.labels};
  p.matches = pl.patches;
  p.stride = o.patches.stride;
  p.anchor = o.patches.anchor;
  cv::Mat img0, img1;
  if (!f0.color_path.empty()) img0 = BgrFromColor(gt::io::ReadFrameColor(f0));
  if (!f1.color_path.empty()) img1 = BgrFromColor(gt::io::ReadFrameColor(f1));
  p.has_images = !img0.empty() && !img1.empty();
  p.image0 = PrepareImage(img0, p.width, p.height);
  p.image1 = PrepareImage(img1, p.width, p.height);
  if (truth.occupancy) {
    p.occ0 = truth.occupancy->cam0;
    p.occ1 = truth.occupancy->cam1;
    p.has_occupancy = true;
  }
  p.depth_source = render::DepthSourceModeName(depth.source);
  if (!scene.mesh_path.empty()) {
    p.depth_sources = DepthSourcesPicture(scene, {&f0, &f1}, resolution, depth);
  }
  return p;
}

bool PairPictureOptions::Check(std::string* error) const {
  return matches.Check(error) && labels.Check(error) && occupancy.Check(error);
}

PairPictures RenderPair(const PairData& pair, const PairPictureOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("inspect options", error);
  PairPictures out;
  MatchPictureOptions mo = options.matches;
  mo.stride = pair.stride;
  mo.anchor = pair.anchor;
  try {
    if (pair.has_labels) {
      out.matches = RenderMatches(pair.image0, pair.image1, pair.matches, mo);
      out.labels =
          RenderLabels(pair.image0, pair.labels01, pair.image1, pair.labels10, options.labels);
    }
    if (pair.has_occupancy) {
      out.occupancy = RenderOccupancy(pair.occ0, &pair.occ1, options.occupancy);
    }
  } catch (const InputError& e) {
    // A bad value of the pair's arrays ("matches: match 0: cell outside ..."): named with
    // the pair it came from (a shard sample, a folder). A flag's error stays the flag's.
    if (e.where().rfind("--", 0) == 0) throw;
    throw InputError(pair.name + ":" + e.where(),
                     std::string(e.what()).substr(e.where().size() + 2));
  }
  out.depth = pair.depth_sources;
  return out;
}

std::vector<std::string> WritePairPictures(const PairPictures& pictures,
                                           const std::string& out_dir) {
  std::vector<std::string> written;
  auto write = [&](const cv::Mat& m, const char* name) {
    const std::string path = (fs::path(out_dir) / name).string();
    if (m.empty()) {
      // A picture of an earlier pair in the same folder would pass for this pair's.
      std::error_code ec;
      fs::remove(path, ec);
      return;
    }
    gt::io::WriteFileAtomic(path, EncodePng(m));
    written.push_back(path);
  };
  write(pictures.matches, "matches.png");
  write(pictures.labels, "labels.png");
  write(pictures.occupancy, "occupancy.png");
  write(pictures.depth, "depth.png");
  return written;
}

}  // namespace gt::report

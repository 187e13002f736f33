#include "libgt/eval/predictions.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/npy.h"

namespace gt::eval {
namespace {

std::string ShapeText(const std::vector<int64_t>& shape) {
  std::string s = "[";
  for (size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

bool IsIntegerDescr(const std::string& d) {
  return d == "|i1" || d == "|u1" || d == "<i2" || d == "<u2" || d == "<i4" || d == "<u4" ||
         d == "<i8" || d == "<u8";
}

// Values of an integer array as int64 (the supported integer dtypes only).
std::vector<int64_t> IntegerValues(const io::NpyArray& a) {
  std::vector<int64_t> out(static_cast<size_t>(a.NumElements()));
  const char* p = a.data.data();
  for (size_t i = 0; i < out.size(); ++i) {
    if (a.descr == "|i1") out[i] = reinterpret_cast<const int8_t*>(p)[i];
    if (a.descr == "|u1") out[i] = reinterpret_cast<const uint8_t*>(p)[i];
    if (a.descr == "<i2") out[i] = reinterpret_cast<const int16_t*>(p)[i];
    if (a.descr == "<u2") out[i] = reinterpret_cast<const uint16_t*>(p)[i];
    if (a.descr == "<i4") out[i] = reinterpret_cast<const int32_t*>(p)[i];
    if (a.descr == "<u4") out[i] = reinterpret_cast<const uint32_t*>(p)[i];
    if (a.descr == "<i8") out[i] = reinterpret_cast<const int64_t*>(p)[i];
    if (a.descr == "<u8") {
      const uint64_t v = reinterpret_cast<const uint64_t*>(p)[i];
      out[i] = v > static_cast<uint64_t>(INT64_MAX) ? -1 : static_cast<int64_t>(v);
    }
  }
  return out;
}

// float32/float64 values as float (float64 narrowed), "" or a problem.
std::string FloatValues(const io::NpyArray& a, std::vector<float>* out) {
  if (a.descr != "<f4" && a.descr != "<f8") {
    return "expected dtype float32 (or float64), got '" + a.descr + "'";
  }
  const size_t n = static_cast<size_t>(a.NumElements());
  out->resize(n);
  if (a.descr == "<f4") {
    std::copy_n(reinterpret_cast<const float*>(a.data.data()), n, out->data());
  } else {
    const double* d = reinterpret_cast<const double*>(a.data.data());
    for (size_t i = 0; i < n; ++i) (*out)[i] = static_cast<float>(d[i]);
  }
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite((*out)[i])) {
      std::ostringstream s;
      s << "expected finite values, element " << i << " is " << (*out)[i];
      return s.str();
    }
  }
  return "";
}

// The members of one pair: name -> array.
using Members = std::map<std::string, const io::NpyArray*>;

// [W, H] per image from a resolution member; "" or a problem.
std::string ParseResolution(const io::NpyArray& a, int64_t wh[2][2]) {
  if (!IsIntegerDescr(a.descr)) {
    return "expected an integer dtype, got '" + a.descr + "'";
  }
  const bool one = a.shape == std::vector<int64_t>{2};
  const bool two = a.shape == std::vector<int64_t>{2, 2};
  if (!one && !two) {
    return "expected shape [2] ([W, H]) or [2, 2] (per image), got " + ShapeText(a.shape);
  }
  const std::vector<int64_t> v = IntegerValues(a);
  for (const int64_t x : v) {
    if (x < 1 || x > 1000000) return "expected sizes in pixels between 1 and 1000000";
  }
  for (int img = 0; img < 2; ++img) {
    wh[img][0] = one ? v[0] : v[2 * img];
    wh[img][1] = one ? v[1] : v[2 * img + 1];
  }
  return "";
}

// Checks and converts one pair. `where` is "<file>:<prefix>" (prefix "" or "<key>/").
// `default_wh`: the resolution in force (top-level member or the working resolution).
bool ReadPair(const std::string& where, const Members& members, const int64_t default_wh[2][2],
              int width, int height, PairPrediction* out, std::vector<std::string>* problems) {
  bool ok = true;
  auto problem = [&](const std::string& member, const std::string& text) {
    problems->push_back(where + member + ": " + text);
    ok = false;
  };
  for (const auto& [name, array] : members) {
    if (name != "kpts0" && name != "kpts1" && name != "confidence" && name != "resolution") {
      problem(name, "unknown member (expected kpts0, kpts1, confidence, resolution)");
    }
  }
  int64_t wh[2][2] = {{default_wh[0][0], default_wh[0][1]}, {default_wh[1][0], default_wh[1][1]}};
  if (auto it = members.find("resolution"); it != members.end()) {
    const std::string p = ParseResolution(*it->second, wh);
    if (!p.empty()) problem("resolution", p);
  }
  std::vector<float>* kpts[2] = {&out->kpts0, &out->kpts1};
  int64_t n[2] = {-1, -1};
  for (int img = 0; img < 2; ++img) {
    const std::string name = img == 0 ? "kpts0" : "kpts1";
    auto it = members.find(name);
    if (it == members.end()) {
      problem(name, "missing (expected float32 [N, 2] pixels)");
      continue;
    }
    const io::NpyArray& a = *it->second;
    if (a.shape.size() != 2 || a.shape[1] != 2) {
      problem(name, "expected shape [N, 2], got " + ShapeText(a.shape));
      continue;
    }
    const std::string p = FloatValues(a, kpts[img]);
    if (!p.empty()) {
      problem(name, p);
      continue;
    }
    n[img] = a.shape[0];
    // Inside the pixel area of the stated resolution, then rescaled to the working one.
    const double w = static_cast<double>(wh[img][0]), h = static_cast<double>(wh[img][1]);
    std::vector<float>& k = *kpts[img];
    for (int64_t i = 0; i < n[img]; ++i) {
      const float x = k[2 * i], y = k[2 * i + 1];
      if (x < -0.5 || x >= w - 0.5 || y < -0.5 || y >= h - 0.5) {
        std::ostringstream s;
        s << "point " << i << " (" << x << ", " << y << ") is outside the " << wh[img][0] << "x"
          << wh[img][1] << " image (pixel area [-0.5, W-0.5) x [-0.5, H-0.5); state the "
          << "resolution with a 'resolution' member)";
        problem(name, s.str());
        break;
      }
    }
    if (wh[img][0] != width || wh[img][1] != height) {
      const double sx = width / w, sy = height / h;
      for (int64_t i = 0; i < n[img]; ++i) {
        k[2 * i] = static_cast<float>(sx * (k[2 * i] + 0.5) - 0.5);
        k[2 * i + 1] = static_cast<float>(sy * (k[2 * i + 1] + 0.5) - 0.5);
      }
    }
  }
  if (n[0] >= 0 && n[1] >= 0 && n[0] != n[1]) {
    problem("kpts1", "expected as many points as kpts0 (" + std::to_string(n[0]) + "), got " +
                         std::to_string(n[1]));
  }
  if (auto it = members.find("confidence"); it != members.end()) {
    const io::NpyArray& a = *it->second;
    if (a.shape.size() != 1 || (n[0] >= 0 && a.shape[0] != n[0])) {
      problem("confidence", "expected shape [N] with N = " + std::to_string(n[0]) + ", got " +
                                ShapeText(a.shape));
    } else {
      const std::string p = FloatValues(a, &out->confidence);
      if (!p.empty()) problem("confidence", p);
      out->has_confidence = true;
    }
  }
  return ok;
}

// The files under `root`/`rel` (paths relative to root, '/'-separated), descending into
// subfolders and symlinks to folders; `ancestors`: the canonical paths of the folders above,
// so that a symlink back to one of them (a loop) is a problem line instead of endless
// recursion. Anything else (a file, a symlink to one, a dangling symlink) is listed: the
// caller reads or rejects each, so nothing is skipped silently.
void ListFolder(const std::string& root, const std::string& rel, std::vector<std::string> ancestors,
                std::vector<std::string>* files, std::vector<std::string>* problems) {
  namespace fs = std::filesystem;
  const fs::path dir = rel.empty() ? fs::path(root) : fs::path(root) / rel;
  std::error_code ec;
  const fs::path canonical = fs::canonical(dir, ec);
  if (ec) {
    problems->push_back(dir.string() + ": cannot resolve the folder: " + ec.message());
    return;
  }
  for (const std::string& a : ancestors) {
    if (a == canonical.string()) {
      problems->push_back(dir.string() + ": leads back to the folder " + a +
                          " above it (a symlink loop); expected <key>.npz files and folders");
      return;
    }
  }
  ancestors.push_back(canonical.string());
  std::vector<std::string> names;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    names.push_back(it->path().filename().string());
  }
  if (ec) {
    problems->push_back(dir.string() + ": cannot list the folder: " + ec.message());
    return;
  }
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) {
    const std::string child = rel.empty() ? name : rel + "/" + name;
    std::error_code child_ec;
    if (fs::is_directory(fs::path(root) / child, child_ec)) {  // follows symlinks
      ListFolder(root, child, ancestors, files, problems);
    } else {
      files->push_back(child);
    }
  }
}

}  // namespace

std::string LoftrPairName(const std::string& folder, int64_t number0, int64_t number1) {
  return folder + "/color/" + std::to_string(number0) + ".jpg#" + folder + "/color/" +
         std::to_string(number1) + ".jpg";
}

std::string DatasetPairName(const std::string& scene, const std::string& id0,
                            const std::string& id1) {
  return scene + "/" + id0 + "#" + scene + "/" + id1;
}

std::string NormalizeLoftrPairName(const std::string& name) {
  const size_t hash = name.find('#');
  if (hash == std::string::npos || name.find('#', hash + 1) != std::string::npos) return "";
  std::string out;
  for (const std::string& side : {name.substr(0, hash), name.substr(hash + 1)}) {
    // The last three components: <folder>/color/<n>.<ext>.
    std::vector<std::string> parts;
    std::string part;
    std::istringstream in(side);
    while (std::getline(in, part, '/')) parts.push_back(part);
    if (parts.size() < 3 || parts[parts.size() - 2] != "color") return "";
    const std::string& file = parts.back();
    const size_t dot = file.rfind('.');
    const std::string stem = file.substr(0, dot);
    if (stem.empty() || stem.size() > 18 ||
        !std::all_of(stem.begin(), stem.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      return "";
    }
    const std::string& folder = parts[parts.size() - 3];
    if (folder.empty()) return "";
    out +=
        (out.empty() ? "" : "#") + folder + "/color/" + std::to_string(std::stoll(stem)) + ".jpg";
  }
  return out;
}

namespace {

// The name of the pair in the other order, when the split holds that one: "s/b_a" for
// "s/a_b" (ids may hold '_': every cut is tried), "y#x" for "x#y"; "" otherwise.
std::string ReversedPairOfSplit(const std::string& name, const std::set<std::string>& split_keys,
                                const std::map<std::string, std::string>& pair_names) {
  if (const size_t hash = name.find('#'); hash != std::string::npos) {
    const std::string reversed = name.substr(hash + 1) + "#" + name.substr(0, hash);
    if (pair_names.count(reversed)) return reversed;
    const std::string loftr = NormalizeLoftrPairName(reversed);
    return !loftr.empty() && pair_names.count(loftr) ? reversed : "";
  }
  const size_t slash = name.rfind('/');
  const std::string scene = slash == std::string::npos ? "" : name.substr(0, slash + 1);
  const std::string base = name.substr(scene.size());
  for (size_t cut = base.find('_'); cut != std::string::npos; cut = base.find('_', cut + 1)) {
    const std::string reversed = scene + base.substr(cut + 1) + "_" + base.substr(0, cut);
    if (split_keys.count(reversed)) return reversed;
  }
  return "";
}

}  // namespace

PredictionSet ReadPredictions(const std::string& name, const std::string& path,
                              const std::set<std::string>& split_keys, int width, int height,
                              std::vector<std::string>* problems,
                              const std::map<std::string, std::string>& pair_names) {
  namespace fs = std::filesystem;
  PredictionSet set;
  set.name = name;
  set.path = path;
  const int64_t working[2][2] = {{width, height}, {width, height}};
  // `label`: the file (folder layout) or "<file>:<key>" (one .npz); `where`: the prefix of
  // member names in problem lines.
  // The name each sample key was given under (a sample key or a LoFTR pair name).
  std::map<std::string, std::string> given_as;
  auto keep = [&](const std::string& label, const std::string& where, const std::string& name,
                  const Members& members, const int64_t wh[2][2]) {
    std::string key = name;
    if (const auto named = pair_names.find(name);
        split_keys.count(key) == 0 && named != pair_names.end()) {
      key = named->second;  // a dataset pair name (or a LoFTR one as LoftrPairName writes it)
    } else if (split_keys.count(key) == 0) {
      const std::string loftr = NormalizeLoftrPairName(name);
      const auto it = loftr.empty() ? pair_names.end() : pair_names.find(loftr);
      if (it == pair_names.end()) {
        const std::string reversed = ReversedPairOfSplit(name, split_keys, pair_names);
        problems->push_back(label + ": pair " + name +
                            (loftr.empty() ? " is not a sample of the split"
                                           : " (a LoFTR pair name) is not a pair of the split") +
                            (reversed.empty()
                                 ? ""
                                 : " (it holds the pair in the other order, " + reversed +
                                       ": give it under that name with kpts0 and kpts1 swapped)"));
        return;
      }
      key = it->second;
    }
    if (const auto [it, inserted] = given_as.emplace(key, name); !inserted) {
      problems->push_back(label + ": pair " + key + " is given twice, as " + it->second +
                          " and as " + name);
      return;
    }
    PairPrediction pair;
    if (ReadPair(where, members, wh, width, height, &pair, problems)) {
      set.pairs.emplace(key, std::move(pair));
    }
  };
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    set.layout = "folder";
    std::vector<std::string> files;
    ListFolder(path, "", {}, &files, problems);
    std::sort(files.begin(), files.end());
    for (const std::string& rel : files) {
      const std::string file = (fs::path(path) / rel).string();
      if (rel.size() <= 4 || rel.compare(rel.size() - 4, 4, ".npz") != 0) {
        problems->push_back(file + ": not a .npz (a predictions folder holds <key>.npz only)");
        continue;
      }
      std::map<std::string, io::NpyArray> arrays;
      try {
        arrays = io::ReadNpz(file);
      } catch (const InputError& e) {
        problems->push_back(e.what());
        continue;
      }
      Members members;
      for (const auto& [member, array] : arrays) members[member] = &array;
      keep(file, file + ":", rel.substr(0, rel.size() - 4), members, working);
    }
    if (files.empty()) problems->push_back(path + ": no .npz file in the folder");
    return set;
  }
  set.layout = "npz";
  std::map<std::string, io::NpyArray> arrays;
  try {
    arrays = io::ReadNpz(path);
  } catch (const InputError& e) {
    problems->push_back(e.what());
    return set;
  }
  int64_t top[2][2] = {{width, height}, {width, height}};
  std::map<std::string, Members> by_key;
  for (const auto& [member, array] : arrays) {
    const size_t slash = member.rfind('/');
    if (slash == std::string::npos) {
      if (member == "resolution") {
        const std::string p = ParseResolution(array, top);
        if (!p.empty()) problems->push_back(path + ":resolution: " + p);
      } else {
        problems->push_back(path + ":" + member +
                            ": unknown member (expected '<key>/kpts0', '<key>/kpts1', "
                            "'<key>/confidence', '<key>/resolution' or 'resolution')");
      }
      continue;
    }
    by_key[member.substr(0, slash)][member.substr(slash + 1)] = &array;
  }
  for (const auto& [key, members] : by_key)
    keep(path + ":" + key, path + ":" + key + "/", key, members, top);
  return set;
}

void FilterByConfidence(double min_confidence, PredictionSet* set,
                        std::vector<std::string>* problems) {
  if (!(min_confidence > 0)) return;
  for (auto& [key, pair] : set->pairs) {
    if (!pair.has_confidence) {
      problems->push_back(set->path + ":" + key +
                          ": no 'confidence' member, which --min-confidence needs");
      continue;
    }
    PairPrediction kept;
    kept.has_confidence = true;
    for (int64_t i = 0; i < pair.size(); ++i) {
      if (pair.confidence[i] < min_confidence) continue;
      kept.kpts0.insert(kept.kpts0.end(), {pair.kpts0[2 * i], pair.kpts0[2 * i + 1]});
      kept.kpts1.insert(kept.kpts1.end(), {pair.kpts1[2 * i], pair.kpts1[2 * i + 1]});
      kept.confidence.push_back(pair.confidence[i]);
    }
    pair = std::move(kept);
  }
}

}  // namespace gt::eval

#include "libgt/pipeline/select.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <set>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"
#include "libgt/io/pickle.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/working_frame.h"

namespace gt::pipeline {
namespace {

using nlohmann::json;

// What drop_examples says of a frame without a colour image (scan.no_color, import.no_color):
// the readers keep no path of a colour file that is missing (occgt scan counts them).
constexpr char kNoColorExample[] =
    "no colour image (the dataset lists none, or its file is missing)";

std::vector<int64_t> IntegerValues(const io::NpyArray& a, const std::string& what) {
  std::vector<int64_t> out(static_cast<size_t>(a.NumElements()));
  auto copy = [&](auto tag) {
    using T = decltype(tag);
    const T* p = a.As<T>(what);
    for (size_t i = 0; i < out.size(); ++i) out[i] = static_cast<int64_t>(p[i]);
  };
  if (a.descr == "<u2")
    copy(uint16_t{});
  else if (a.descr == "<i4")
    copy(int32_t{});
  else if (a.descr == "<i8")
    copy(int64_t{});
  else if (a.descr == "<u4")
    copy(uint32_t{});
  else if (a.descr == "<u8")
    copy(uint64_t{});
  else
    throw InputError(what, "dtype '" + a.descr + "', expected an integer array");
  return out;
}

}  // namespace

namespace {

ImportList ReadLoftrMegaDepthList(const std::string& list_path) {
  ImportList list;
  const std::string dir = std::filesystem::path(list_path).parent_path().string();
  int files = 0;
  for (std::string name : io::ReadLines(list_path)) {
    while (!name.empty() && std::isspace(static_cast<unsigned char>(name.back()))) name.pop_back();
    if (name.empty() || name[0] == '#') continue;
    name = name.substr(0, name.find_first_of(" \t"));
    const bool has_ext = name.size() > 4 && name.compare(name.size() - 4, 4, ".npz") == 0;
    const std::string file = (dir.empty() ? "" : dir + "/") + name + (has_ext ? "" : ".npz");
    if (!io::FileExists(file)) {
      throw InputError(list_path, "names " + name + ", but " + file + " is missing");
    }
    const io::PyValue info = io::ReadPickle(io::ReadFileBytes(file), file);
    auto field = [&](const char* key) -> const io::PyValue& {
      if (info.kind == io::PyValue::Kind::kDict) {
        for (size_t k = 0; k < info.keys.size(); ++k) {
          if (info.keys[k] == key && info.items[k].kind == io::PyValue::Kind::kList) {
            return info.items[k];
          }
        }
      }
      throw InputError(file, std::string("expected a dict with a list or array \"") + key +
                                 "\" (LoFTR's MegaDepth scene_info)");
    };
    const io::PyValue& images = field("image_paths");
    const io::PyValue& infos = field("pair_infos");
    auto image = [&](const io::PyValue& index, size_t row) -> const std::string& {
      if (index.kind != io::PyValue::Kind::kInt || index.int_value < 0 ||
          index.int_value >= static_cast<int64_t>(images.items.size()) ||
          images.items[index.int_value].kind != io::PyValue::Kind::kStr) {
        throw InputError(file + ":pair_infos[" + std::to_string(row) + "]",
                         "expected image indices into image_paths (0.." +
                             std::to_string(images.items.size()) + ") naming an image");
      }
      return images.items[index.int_value].str;
    };
    for (size_t row = 0; row < infos.items.size(); ++row) {
      const io::PyValue& p = infos.items[row];
      const io::PyValue* ij = p.items.empty() ? nullptr : &p.items[0];
      if ((p.kind != io::PyValue::Kind::kTuple && p.kind != io::PyValue::Kind::kList) ||
          ij == nullptr || ij->items.size() != 2) {
        throw InputError(file + ":pair_infos[" + std::to_string(row) + "]",
                         "expected ((i, j), score, ...)");
      }
      const std::string& a = image(ij->items[0], row);
      const std::string& b = image(ij->items[1], row);
      std::string scene;
      for (const char* marker : {"Undistorted_SfM/", "MegaDepth_v1/"}) {
        const size_t at = a.find(marker);
        if (at != std::string::npos && scene.empty()) {
          const size_t begin = at + std::strlen(marker);
          scene = a.substr(begin, a.find('/', begin) - begin);
        }
      }
      if (scene.empty()) scene = name.substr(0, name.find('_'));
      ImportedPair pair;
      pair.id0 = std::filesystem::path(a).stem().string();
      pair.id1 = std::filesystem::path(b).stem().string();
      list[scene].push_back(pair);
    }
    ++files;
  }
  if (files == 0) throw InputError(list_path, "expected at least one scene_info name");
  return list;
}

}  // namespace

ImportList ReadImportList(const std::string& path, const std::string& format) {
  if (format == "loftr-megadepth") return ReadLoftrMegaDepthList(path);
  const auto members = io::ReadNpz(path);
  auto it = members.find("name");
  if (it == members.end())
    throw InputError(path, "no member 'name' (expected LoFTR's [N, 4] pair names)");
  const io::NpyArray& name = it->second;
  if (name.shape.size() != 2 || name.shape[1] != 4) {
    throw InputError(path + ":name", "expected shape [N, 4] (scene, sub-scene, frame0, frame1)");
  }
  const std::vector<int64_t> v = IntegerValues(name, path + ":name");
  ImportList list;
  for (int64_t r = 0; r < name.shape[0]; ++r) {
    char scene[64];
    std::snprintf(scene, sizeof(scene), "scene%04lld_%02lld", static_cast<long long>(v[r * 4]),
                  static_cast<long long>(v[r * 4 + 1]));
    ImportedPair pair;
    pair.number0 = v[r * 4 + 2];
    pair.number1 = v[r * 4 + 3];
    list[scene].push_back(pair);
  }
  return list;
}

std::vector<std::string> ResolveScenes(const Recipe& r, const datasets::DatasetReader& reader,
                                       const ImportList* imports) {
  std::vector<std::string> scenes;
  if (!r.dataset.scenes.empty()) {
    scenes = r.dataset.scenes;
  } else if (!r.dataset.split_file.empty()) {
    for (std::string line : io::ReadLines(r.dataset.split_file)) {
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())))
        line.pop_back();
      if (line.empty() || line[0] == '#') continue;
      scenes.push_back(line);
    }
    if (scenes.empty())
      throw InputError(r.file, "dataset.split_file: expected at least one scene name");
  } else if (imports) {
    for (const auto& [scene, pairs] : *imports) scenes.push_back(scene);
  }
  const std::vector<std::string> available = datasets::ListSceneNames(reader, r.dataset.root);
  if (scenes.empty()) scenes = available;
  std::sort(scenes.begin(), scenes.end());
  scenes.erase(std::unique(scenes.begin(), scenes.end()), scenes.end());
  const std::set<std::string> have(available.begin(), available.end());
  std::vector<std::string> missing;
  for (const auto& s : scenes) {
    if (!have.count(s)) missing.push_back(s);
  }
  if (!missing.empty()) {
    // Where the list came from, and how many are missing (a partial download, another root).
    const std::string source = !r.dataset.scenes.empty() ? "dataset.scenes"
                               : !r.dataset.split_file.empty()
                                   ? "dataset.split_file " + r.dataset.split_file
                                   : "selection.import_pairs.path " + r.selection.import_pairs.path;
    throw InputError(r.file, "dataset: scene '" + missing.front() + "' (of " + source +
                                 ") not found under " + r.dataset.root + " (" +
                                 std::to_string(missing.size()) + " of " +
                                 std::to_string(scenes.size()) +
                                 " scenes missing; list the scenes to build in dataset.scenes)");
  }
  if (scenes.empty())
    throw InputError(r.file, "dataset.root: no scenes found under " + r.dataset.root);
  std::map<std::string, std::string> files;
  for (const auto& s : scenes) {
    auto [it, inserted] = files.emplace(SceneFileName(s), s);
    if (!inserted) {
      throw InputError(r.file, "dataset: scenes '" + it->second + "' and '" + s +
                                   "' have the same file name after sanitising");
    }
  }
  return scenes;
}

namespace {

json PairJson(const SelectedPair& p, int score_stride) {
  return {{"scene", p.scene},
          {"frame0", {{"id", p.frame0}, {"number", p.number0}}},
          {"frame1", {{"id", p.frame1}, {"number", p.number1}}},
          {"score_stride", score_stride},
          {"score_metrics",
           {{"01", truth::MetricsJson(p.score01)}, {"10", truth::MetricsJson(p.score10)}}}};
}

SelectedPair PairFromJson(const json& j) {
  SelectedPair p;
  p.scene = j.at("scene").get<std::string>();
  p.frame0 = j.at("frame0").at("id").get<std::string>();
  p.frame1 = j.at("frame1").at("id").get<std::string>();
  p.number0 = j.at("frame0").at("number").get<int64_t>();
  p.number1 = j.at("frame1").at("number").get<int64_t>();
  p.score01 = truth::MetricsFromJson(j.at("score_metrics").at("01"));
  p.score10 = truth::MetricsFromJson(j.at("score_metrics").at("10"));
  return p;
}

}  // namespace

bool NeedsColor(const Recipe& r, const Scene& scene) {
  if (r.sample.image == ImageFormat::kNone) return false;
  for (const Frame& f : scene.frames) {
    if (!f.color_path.empty()) return true;
  }
  if (scene.NumUsable() > 0) {
    throw InputError(r.file + ": sample.image",
                     std::string("expected colour images (") + ImageFormatName(r.sample.image) +
                         "), but no frame of scene " + scene.name +
                         " has one; set sample.image: none to build without images");
  }
  return true;
}

pairs::ScanResult ScanRecipeFrames(const Recipe& r, const Scene& scene, const LabelOptions& labels,
                                   pairs::DepthCache* cache) {
  pairs::FrameScanOptions scan;
  scan.frame_stride = r.dataset.frame_stride;
  scan.min_valid_depth_fraction = r.dataset.min_valid_depth_fraction;
  scan.min_depth_m = labels.min_depth_m;
  scan.max_depth_m = labels.max_depth_m;
  pairs::ScanResult scanned = pairs::ScanFrames(scene, scan, cache);
  if (NeedsColor(r, scene)) {
    std::vector<size_t> with_color;
    for (const size_t i : scanned.kept) {
      if (!scene.frames[i].color_path.empty()) {
        with_color.push_back(i);
        continue;
      }
      ++scanned.drops["scan.no_color"];
      if (scanned.first_no_color.empty()) {
        scanned.first_no_color = scene.frames[i].id + ": " + kNoColorExample;
      }
    }
    scanned.kept = std::move(with_color);
    // A colour file that cannot be stored (not an image, another size) is that frame's
    // problem, found here from its header rather than when a sample is written.
    std::vector<size_t> kept;
    for (const size_t i : scanned.kept) {
      try {
        io::CheckFrameColorHeader(scene.frames[i]);
        kept.push_back(i);
      } catch (const InputError& e) {
        ++scanned.drops["scan.color_error"];
        if (scanned.first_color_error.empty()) {
          scanned.first_color_error = scene.frames[i].id + ": " + e.what();
        }
      }
    }
    scanned.kept = std::move(kept);
  }
  return scanned;
}

SceneSelection SelectScene(const Recipe& r, const Scene& scene, pairs::DepthCache* cache,
                           const ImportList* imports) {
  using namespace pairs;  // NOLINT(google-build-using-namespace): the stage's vocabulary
  const std::string& scene_name = scene.name;
  std::vector<Camera> cams;
  cams.reserve(scene.frames.size());
  for (const Frame& f : scene.frames) cams.push_back(truth::WorkingCamera(f, {r.width, r.height}));
  const LabelOptions labels = RecipePairTruthOptions(r, scene).labels;
  SceneSelection out;
  out.scene = scene_name;
  DropCounts drops;
  json drop_examples = json::object();  // reason -> "<scene>/<frame id>: <error>" (the first)
  std::vector<CandidatePair> candidates, pruned;
  int64_t frames_kept = 0;
  // A recipe that stores images needs both frames' colour: frames without it are skipped
  // and counted (scan.no_color, import.no_color); a scene with none at all is an error.
  const bool need_color = NeedsColor(r, scene);
  auto has_color = [&](size_t i) { return !scene.frames[i].color_path.empty(); };
  // io::CheckFrameColorHeader's problem with frame a's colour, else b's, as "<frame id>:
  // <error>"; "" when neither has one. Each frame is checked once.
  std::map<size_t, std::string> color_errors;
  auto ColorHeaderError = [&](size_t a, size_t b) -> std::string {
    for (const size_t i : {a, b}) {
      auto [it, added] = color_errors.try_emplace(i);
      if (added) {
        try {
          io::CheckFrameColorHeader(scene.frames[i]);
        } catch (const InputError& e) {
          it->second = scene.frames[i].id + ": " + e.what();
        }
      }
      if (!it->second.empty()) return it->second;
    }
    return "";
  };
  if (imports) {
    std::map<int64_t, size_t> by_number;
    std::map<std::string, size_t> by_id;
    for (size_t i = 0; i < scene.frames.size(); ++i) {
      by_number[scene.frames[i].number] = i;
      by_id[scene.frames[i].id] = i;
    }
    auto it = imports->find(scene_name);
    std::set<std::pair<size_t, size_t>> listed;  // a row given twice would make one key twice
    if (it != imports->end()) {
      for (const ImportedPair& p : it->second) {
        // A pair by id (LoFTR's MegaDepth) or by number (LoFTR's test.npz), as its frame index.
        auto index = [&](int64_t number, const std::string& id) -> std::optional<size_t> {
          if (!id.empty()) {
            auto f = by_id.find(id);
            return f == by_id.end() ? std::nullopt : std::optional<size_t>(f->second);
          }
          auto f = by_number.find(number);
          return f == by_number.end() ? std::nullopt : std::optional<size_t>(f->second);
        };
        const std::optional<size_t> a = index(p.number0, p.id0), b = index(p.number1, p.id1);
        if (!a || !b) {
          ++drops["import.missing_frame"];
        } else if (*a == *b) {
          ++drops["import.same_frame"];
        } else if (!listed.insert({*a, *b}).second) {
          ++drops["import.duplicate"];
        } else if (!scene.frames[*a].usable || !scene.frames[*b].usable) {
          ++drops["import.unusable_frame"];
        } else if (need_color && (!has_color(*a) || !has_color(*b))) {
          ++drops["import.no_color"];
          if (!drop_examples.contains("import.no_color")) {
            drop_examples["import.no_color"] = scene_name + "/" +
                                               scene.frames[has_color(*a) ? *b : *a].id + ": " +
                                               kNoColorExample;
          }
        } else if (const std::string e = need_color ? ColorHeaderError(*a, *b) : std::string();
                   !e.empty()) {
          ++drops["import.color_error"];
          if (!drop_examples.contains("import.color_error")) {
            drop_examples["import.color_error"] = scene_name + "/" + e;
          }
        } else {
          candidates.push_back({*a, *b});
        }
      }
    }
    pruned = candidates;
    frames_kept = static_cast<int64_t>(scene.NumUsable());
  } else {
    const ScanResult scanned = ScanRecipeFrames(r, scene, labels, cache);
    AddCounts(scanned.drops, &drops);
    if (!scanned.first_read_error.empty()) {
      drop_examples["scan.read_error"] = scene_name + "/" + scanned.first_read_error;
    }
    if (!scanned.first_color_error.empty()) {
      drop_examples["scan.color_error"] = scene_name + "/" + scanned.first_color_error;
    }
    if (!scanned.first_no_color.empty()) {
      drop_examples["scan.no_color"] = scene_name + "/" + scanned.first_no_color;
    }
    frames_kept = static_cast<int64_t>(scanned.kept.size());
    candidates = GenerateCandidates(scanned.kept, r.selection.max_frame_gap);
    pruned = PruneCandidates(scene, cams, candidates, scanned.median_depth_m, r.selection.pruning,
                             &drops);
  }
  // Imported pairs may list (i0 > i1); scoring and labels keep the file's order.
  std::string first_score_error;
  const std::vector<ScoredPair> scored = ScorePairs(
      scene, cams, pruned, labels, r.selection.score_stride, cache, &drops, &first_score_error);
  if (!first_score_error.empty()) {
    drop_examples["score.read_error"] = scene_name + "/" + first_score_error;
  }
  std::vector<size_t> chosen;
  if (imports) {
    for (size_t k = 0; k < scored.size(); ++k) chosen.push_back(k);
  } else {
    chosen = FilterAndSample(scored, r.selection, SceneSeed(r.seed, scene_name), &drops);
  }
  for (size_t k : chosen) {
    const ScoredPair& s = scored[k];
    SelectedPair p;
    p.scene = scene_name;
    p.frame0 = scene.frames[s.pair.i0].id;
    p.frame1 = scene.frames[s.pair.i1].id;
    p.number0 = scene.frames[s.pair.i0].number;
    p.number1 = scene.frames[s.pair.i1].number;
    p.score01 = s.m01;
    p.score10 = s.m10;
    out.pairs.push_back(p);
  }
  out.stats = {{"scene", scene_name},
               {"frames_total", static_cast<int64_t>(scene.frames.size())},
               {"frames_kept", frames_kept},
               {"candidates", static_cast<int64_t>(candidates.size())},
               {"after_pruning", static_cast<int64_t>(pruned.size())},
               {"scored", static_cast<int64_t>(scored.size())},
               {"selected", static_cast<int64_t>(out.pairs.size())},
               {"drops", drops},
               {"drop_examples", drop_examples},
               {"score_stride", r.selection.score_stride},
               {"options_digest", r.Digest()}};
  return out;
}

namespace {

std::string SelectionLinesPath(const std::string& out_dir, const std::string& scene) {
  return SelectionDir(out_dir) + "/" + SceneFileName(scene) + ".jsonl";
}
std::string SelectionStatsPath(const std::string& out_dir, const std::string& scene) {
  return SelectionDir(out_dir) + "/" + SceneFileName(scene) + ".json";
}

}  // namespace

std::string SelectionDir(const std::string& out_dir) { return out_dir + "/selection"; }

int64_t WriteSelection(const std::string& o, const SceneSelection& s) {
  std::string lines;
  const int score_stride = s.stats.at("score_stride").get<int>();
  for (const auto& p : s.pairs) lines += PairJson(p, score_stride).dump() + "\n";
  const std::string stats = s.stats.dump(2) + "\n";
  // Written at once; the stats, the scene's completion marker, are published second.
  io::WriteFilesAtomic(
      {{SelectionLinesPath(o, s.scene), lines}, {SelectionStatsPath(o, s.scene), stats}});
  return static_cast<int64_t>(lines.size() + stats.size());
}

// Reads a completed selection; nullopt when the scene is not complete.
std::optional<SceneSelection> ReadSelection(const std::string& o, const std::string& scene,
                                            const std::string& digest) {
  const std::string stats_path = SelectionStatsPath(o, scene);
  if (!io::FileExists(stats_path)) return std::nullopt;
  SceneSelection s;
  s.scene = scene;
  try {
    s.stats = json::parse(io::ReadFileBytes(stats_path));
  } catch (const json::exception& e) {
    throw InputError(stats_path, std::string("not valid JSON: ") + e.what());
  }
  if (s.stats.value("options_digest", "") != digest) {
    throw InputError(stats_path, "was selected with other options (digest " +
                                     s.stats.value("options_digest", "?") + ", recipe " + digest +
                                     "); use a fresh --out folder");
  }
  const std::string lines_path = SelectionLinesPath(o, scene);
  for (const std::string& line : io::ReadLines(lines_path)) {
    if (line.empty()) continue;
    try {
      s.pairs.push_back(PairFromJson(json::parse(line)));
    } catch (const json::exception& e) {
      throw InputError(lines_path, std::string("bad selection line: ") + e.what());
    }
  }
  if (static_cast<int64_t>(s.pairs.size()) != s.stats.value("selected", int64_t{-1})) {
    throw InputError(lines_path, "line count differs from " + stats_path);
  }
  return s;
}

std::string SceneFileName(const std::string& scene) {
  std::string out;
  for (unsigned char c : scene) {
    if (c == '/') {
      out += "__";
    } else if (std::isalnum(c) || c == '-' || c == '_') {
      out += static_cast<char>(c);
    } else {
      out += '_';
    }
  }
  return out.empty() ? "_" : out;
}

}  // namespace gt::pipeline

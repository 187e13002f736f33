#include "libgt/report/tuples_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/core/stats.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "libgt/report/split_report.h"
#include "libgt/shards/tar_shard.h"

namespace gt::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// schemas/tuples_line.schema.json "frame_ids": 2..32 distinct strings.
std::vector<std::string> NeedIds(const json& j, const std::string& where) {
  if (!j.contains("frame_ids") || !j["frame_ids"].is_array() || j["frame_ids"].size() < 2 ||
      j["frame_ids"].size() > 32) {
    throw InputError(where, "expected \"frame_ids\": an array of 2 to 32 frame ids" +
                                (j.contains("frame_ids") && j["frame_ids"].is_array()
                                     ? ", got " + std::to_string(j["frame_ids"].size())
                                     : std::string()));
  }
  std::vector<std::string> ids;
  std::set<std::string> seen;
  for (const json& v : j["frame_ids"]) {
    if (!v.is_string()) throw InputError(where, "expected \"frame_ids\" of strings");
    ids.push_back(v.get<std::string>());
    if (!seen.insert(ids.back()).second) {
      throw InputError(where,
                       "\"frame_ids\": '" + ids.back() + "' repeats, expected distinct frame ids");
    }
  }
  return ids;
}

std::optional<double> OptionalFraction(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) return std::nullopt;
  if (!j[key].is_number() || j[key].get<double>() < 0 || j[key].get<double>() > 1) {
    throw InputError(where, std::string("expected \"") + key + "\": a number in [0, 1]");
  }
  return j[key].get<double>();
}

// A value in [0, 1] at 3 significant digits, with more when those would read as the exact
// bound 0 or 1 that it is not (0.99958 is not "1").
std::string RangeEnd(double v) {
  std::string text = Num(v, 3);
  for (int digits = 4; digits <= 17 && (text == "1" || text == "0") && v != std::stod(text);
       ++digits) {
    text = Num(v, digits);
  }
  return text;
}

json Describe(std::vector<double> v, int bins) {
  json hist = json::array();
  std::vector<int64_t> counts(static_cast<size_t>(bins), 0);
  for (double x : v) {
    const int b = std::clamp(static_cast<int>(std::floor(x * bins)), 0, bins - 1);
    ++counts[static_cast<size_t>(b)];
  }
  for (int64_t c : counts) hist.push_back(c);
  json out = {{"count", static_cast<int64_t>(v.size())}, {"histogram", hist}};
  if (v.empty()) {
    for (const char* k : {"min", "median", "mean", "max"}) out[k] = nullptr;
    return out;
  }
  double sum = 0;
  for (double x : v) sum += x;  // in input order
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  out["min"] = v.front();
  out["median"] = SortedMedian(v);
  out["mean"] = sum / static_cast<double>(n);
  out["max"] = v.back();
  return out;
}

std::vector<double> OffDiagonal(const TupleSet& set) {
  std::vector<double> out;
  for (const SplitTuple& t : set.tuples) {
    const size_t n = t.frame_ids.size();
    for (size_t a = 0; a < n; ++a)
      for (size_t b = 0; b < n; ++b)
        if (a != b) out.push_back(t.covisibility[a * n + b]);
  }
  return out;
}

// The occlusion sources present, in a fixed order, with their per-tuple values.
std::vector<std::pair<std::string, std::vector<double>>> OcclusionSources(const TupleSet& set) {
  std::vector<std::pair<std::string, std::vector<double>>> out;
  std::vector<double> truth, estimate;
  for (const SplitTuple& t : set.tuples) {
    if (t.ground_truth) truth.push_back(*t.ground_truth);
    if (t.graph_estimate) estimate.push_back(*t.graph_estimate);
  }
  if (!truth.empty()) out.emplace_back("ground_truth", std::move(truth));
  if (!estimate.empty()) out.emplace_back("graph_estimate", std::move(estimate));
  return out;
}

std::string NpyMember(const std::map<std::string, std::string>& fields, const std::string& name,
                      const std::string& where) {
  if (auto it = fields.find(name); it != fields.end()) return it->second;
  if (auto it = fields.find(name + ".gz"); it != fields.end()) {
    return io::GunzipNpy(it->second, where + ":" + name + ".gz");
  }
  throw InputError(where, "expected a member " + name);
}

cv::Mat DepthPicture(const io::NpyArray& depth, size_t view, const std::string& where) {
  const int h = static_cast<int>(depth.shape.at(0)), w = static_cast<int>(depth.shape.at(1));
  const float* d = depth.As<float>(where);
  (void)view;
  float hi = 0;
  for (int64_t k = 0; k < depth.NumElements(); ++k) hi = std::max(hi, d[k]);
  cv::Mat out(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float z = d[y * w + x];
      const uint8_t g = z > 0 && hi > 0 ? static_cast<uint8_t>(40 + 215 * (1 - z / hi)) : 0;
      out.at<cv::Vec3b>(y, x) = cv::Vec3b(g, g, g);
    }
  return out;
}

}  // namespace

std::optional<TupleSet> LoadTupleSet(const std::string& dir) {
  const std::string path = (fs::path(dir) / "tuples.jsonl").string();
  if (!io::FileExists(path)) return std::nullopt;
  TupleSet set;
  set.dir = dir;
  for (const auto& [where, j] : ReadJsonLines(path)) {
    SplitTuple t;
    for (const auto& [key, value] : j.items()) {  // schemas/tuples_line.schema.json
      if (key != "scene" && key != "frame_ids" && key != "covisibility" && key != "occlusion") {
        throw InputError(where, "unexpected key \"" + key +
                                    "\" (a tuple line has scene, frame_ids, covisibility and "
                                    "occlusion)");
      }
    }
    if (!j.contains("scene") || !j["scene"].is_string() || j["scene"].get<std::string>().empty()) {
      throw InputError(where, "expected a non-empty string \"scene\"");
    }
    t.scene = j["scene"].get<std::string>();
    t.frame_ids = NeedIds(j, where);
    const size_t size = t.frame_ids.size();
    const json& c = j.value("covisibility", json());
    bool ok = c.is_array() && c.size() == size;
    for (size_t a = 0; ok && a < size; ++a) {
      ok = c[a].is_array() && c[a].size() == size;
      for (size_t b = 0; ok && b < size; ++b) {
        ok = c[a][b].is_number();
        if (ok) t.covisibility.push_back(c[a][b].get<double>());
      }
    }
    if (!ok) {
      throw InputError(where, "expected \"covisibility\": " + std::to_string(size) + "x" +
                                  std::to_string(size) + " numbers (one row per frame id)");
    }
    for (size_t k = 0; k < t.covisibility.size(); ++k) {
      const double v = t.covisibility[k];
      if (!(v >= 0 && v <= 1)) {
        throw InputError(where, "\"covisibility\"[" + std::to_string(k / size) + "][" +
                                    std::to_string(k % size) + "] is " + json(v).dump() +
                                    ", expected a number in [0, 1]");
      }
    }
    t.graph_estimate = OptionalFraction(j, "occlusion", where);
    set.tuples.push_back(std::move(t));
  }
  const std::string views = (fs::path(dir) / "views" / "pairs.jsonl").string();
  if (io::FileExists(views)) {
    set.has_shards = true;
    for (const auto& [where, r] : ReadJsonLines(views)) {
      if (!r.contains("tuple_index") || !r["tuple_index"].is_number_integer()) {
        throw InputError(where, "expected an integer \"tuple_index\"");
      }
      const int64_t k = r["tuple_index"].get<int64_t>();
      if (k < 0 || k >= static_cast<int64_t>(set.tuples.size())) {
        throw InputError(where, "tuple_index " + std::to_string(k) + " is not a line of " + path);
      }
      SplitTuple& t = set.tuples[static_cast<size_t>(k)];
      if (NeedIds(r, where) != t.frame_ids || r.value("scene", "") != t.scene) {
        throw InputError(where, "names other frames than line " + std::to_string(k + 1) + " of " +
                                    path +
                                    " (shards of other tuples: re-run occgt tuples --shards)");
      }
      // "occluded_fraction": the same number in N-view shards written before occgt 0.2.
      const char* key = r.contains("occlusion_ratio_visible") || !r.contains("occluded_fraction")
                            ? "occlusion_ratio_visible"
                            : "occluded_fraction";
      t.ground_truth = OptionalFraction(r, key, where);
      if (!t.ground_truth) {
        throw InputError(where, std::string("expected a number \"") + key + "\"");
      }
      t.shard = r.value("shard", "");
      t.key = r.value("key", "");
    }
  }
  return set;
}

json SummarizeTuples(const TupleSet& set, int bins) {
  std::map<size_t, int64_t> sizes;
  std::set<std::string> scenes;
  for (const SplitTuple& t : set.tuples) {
    ++sizes[t.frame_ids.size()];
    scenes.insert(t.scene);
  }
  json size_json = json::object();
  for (const auto& [n, count] : sizes) size_json[std::to_string(n)] = count;
  json occlusion = json::object();
  for (const auto& [source, values] : OcclusionSources(set))
    occlusion[source] = Describe(values, bins);
  return {{"count", static_cast<int64_t>(set.tuples.size())},
          {"scenes", static_cast<int64_t>(scenes.size())},
          {"sizes", size_json},
          {"bins", bins},
          {"covisibility", Describe(OffDiagonal(set), bins)},
          {"occlusion", occlusion}};
}

std::vector<size_t> PickGalleryTuples(const TupleSet& set, int count, uint64_t seed) {
  std::vector<std::pair<uint64_t, size_t>> keyed;
  const uint64_t seed_hash = Mix64(seed);
  for (size_t k = 0; k < set.tuples.size(); ++k) {
    std::string id = set.tuples[k].scene + ":";
    for (size_t v = 0; v < set.tuples[k].frame_ids.size(); ++v) {
      id += (v ? "," : "") + set.tuples[k].frame_ids[v];
    }
    keyed.emplace_back(Mix64(seed_hash ^ Fnv1a64(id)), k);
  }
  const size_t take = std::min(keyed.size(), static_cast<size_t>(std::max(count, 0)));
  std::partial_sort(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(take), keyed.end());
  std::vector<size_t> out;
  for (size_t k = 0; k < take; ++k) out.push_back(keyed[k].second);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<NamedImage> MakeTuplePlots(const TupleSet& set, int bins, const std::string& gnuplot,
                                       int width_px, int height_px,
                                       const std::string& scratch_dir) {
  fs::create_directories(scratch_dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream f(fs::path(scratch_dir) / name);
    f << text;
  };
  const json s = SummarizeTuples(set, bins);
  std::ostringstream sizes;
  int64_t most = 0;
  for (auto it = s["sizes"].begin(); it != s["sizes"].end(); ++it) {
    sizes << it.key() << " " << it.value().get<int64_t>() << "\n";
    most = std::max(most, it.value().get<int64_t>());
  }
  if (s["sizes"].empty()) sizes << "2 0\n";
  write("tuple_sizes.dat", sizes.str());
  auto hist_file = [&](const std::string& name, const json& described) {
    std::ostringstream d;
    for (int b = 0; b < bins; ++b) {
      d << Num((b + 0.5) / bins, 8) << " " << described["histogram"][b].get<int64_t>() << "\n";
    }
    write(name, d.str());
  };
  hist_file("tuple_covisibility.dat", s["covisibility"]);
  // The occlusion over the range of its data, as the pairs' histograms (HistogramRange):
  // tuples' ratios of a few percent are one bar over [0, 1].
  std::vector<std::string> sources;
  std::vector<double> all_occlusion;
  for (const auto& [source, values] : OcclusionSources(set)) {
    all_occlusion.insert(all_occlusion.end(), values.begin(), values.end());
  }
  const std::pair<double, double> occ_range = HistogramRange(all_occlusion);
  const std::vector<double> occ_edges = HistogramEdges(occ_range, bins);
  const double occ_width = (occ_range.second - occ_range.first) / bins;
  for (const auto& [source, values] : OcclusionSources(set)) {
    std::vector<int64_t> counts(static_cast<size_t>(bins), 0);
    for (double v : values) ++counts[static_cast<size_t>(HistogramBin(v, occ_edges))];
    std::ostringstream d;
    for (int b = 0; b < bins; ++b) {
      d << Num(0.5 * (occ_edges[b] + occ_edges[b + 1]), 8) << " " << counts[b] << "\n";
    }
    write("tuple_occlusion_" + source + ".dat", d.str());
    sources.push_back(source);
  }
  const std::string count = std::to_string(set.tuples.size()) + " tuples";
  std::ostringstream gp;
  gp << "set terminal pngcairo size " << width_px << "," << height_px
     << " font \"DejaVu Sans,11\" noenhanced\n"
     << "set encoding utf8\nset grid ytics lc rgb '#dddddd'\nset border 3\n"
     << "set xtics nomirror\nset ytics nomirror\nset style fill solid 0.85 border -1\n";
  gp << "set output 'tuple_sizes.png'\nset title "
     << GnuplotString("Tuple sizes (views per tuple), " + count)
     << "\nset xlabel 'views N'\nset ylabel 'tuples'\nset boxwidth 0.8\nset xtics 1\n"
     << "set xrange [*:*]\nset yrange [0:" << std::max<int64_t>(most, 1) << "*1.1]\n"
     << "plot 'tuple_sizes.dat' using 1:2 with boxes lc rgb '#5a9e4b' notitle\n";
  gp << "set output 'tuple_covisibility_hist.png'\nset title "
     << GnuplotString("Covisibility inside the tuples (every ordered pair of views a != b), " +
                      std::to_string(s["covisibility"]["count"].get<int64_t>()) + " values, " +
                      std::to_string(bins) + " bins")
     << "\nset xlabel 'visible overlap of view a in view b'\nset ylabel 'ordered pairs'\n"
     << "set xtics auto\nset xrange [0:1]\nset yrange [0:*]\nset boxwidth " << Num(0.9 / bins, 8)
     << "\n"
     << "plot 'tuple_covisibility.dat' using 1:2 with boxes lc rgb '#3b7dd8' notitle\n";
  std::vector<std::string> outputs = {"tuple_sizes.png", "tuple_covisibility_hist.png"};
  if (!sources.empty()) {
    gp << "set output 'tuple_occlusion_hist.png'\nset title "
       << GnuplotString("Occlusion of the tuples, " + count + ", " + std::to_string(bins) +
                        " bins over [" + Num(occ_range.first, 2) + ", " + Num(occ_range.second, 2) +
                        "]")
       << "\nset xlabel 'occlusion_ratio_visible'\nset ylabel 'tuples'\nset key top right\n"
       << "set xrange [" << Num(occ_range.first, 2) << ":" << Num(occ_range.second, 2) << "]\n"
       << "set boxwidth " << Num(0.9 * occ_width / static_cast<double>(sources.size()), 8) << "\n"
       << "plot ";
    const char* colours[] = {"#d8503b", "#8a5fbf"};
    for (size_t k = 0; k < sources.size(); ++k) {
      const double shift = (k - 0.5 * (sources.size() - 1)) * 0.9 * occ_width / sources.size();
      gp << (k ? ", " : "") << "'tuple_occlusion_" << sources[k] << ".dat' using ($1+("
         << Num(shift, 8) << ")):2 with boxes lc rgb '" << colours[k % 2] << "' title "
         << GnuplotString(sources[k] == "ground_truth" ? "N-view ground truth (views/pairs.jsonl)"
                                                       : "graph estimate (tuples.jsonl)");
    }
    gp << "\n";
    outputs.push_back("tuple_occlusion_hist.png");
  }
  write("tuples.gp", gp.str());
  return RunGnuplot(gnuplot, scratch_dir, "tuples.gp", outputs);
}

std::vector<TupleGalleryItem> MakeTupleGallery(const TupleSet& set,
                                               const std::vector<size_t>& indices,
                                               int thumb_width_px) {
  std::vector<TupleGalleryItem> out;
  for (size_t index : indices) {
    const SplitTuple& t = set.tuples.at(index);
    const size_t n = t.frame_ids.size();
    TupleGalleryItem item;
    item.index = index;
    std::ostringstream caption;
    caption << "tuple " << index << ": " << t.scene << ", " << n << " views";
    double lo = 1, hi = 0;
    for (size_t a = 0; a < n; ++a)
      for (size_t b = 0; b < n; ++b)
        if (a != b) {
          lo = std::min(lo, t.covisibility[a * n + b]);
          hi = std::max(hi, t.covisibility[a * n + b]);
        }
    caption << " (covisibility " << RangeEnd(lo) << ".." << RangeEnd(hi);
    if (t.ground_truth) caption << ", occluded " << Num(*t.ground_truth, 3);
    if (t.graph_estimate) caption << ", graph estimate " << Num(*t.graph_estimate, 3);
    caption << ")";
    item.caption = caption.str();
    if (t.shard.empty() || t.key.empty()) {
      item.note = "no N-view shards: `occgt tuples --shards` writes the views shown here";
      out.push_back(std::move(item));
      continue;
    }
    const std::string tar = (fs::path(set.dir) / "views" / t.shard).string();
    const std::string where = tar + ":" + t.key;
    try {
      const shards::Sample sample = shards::ReadShardSample(tar, t.key);
      std::map<std::string, std::string> fields;
      for (const auto& f : sample.fields) fields[f.name] = f.bytes;
      const io::NpyArray occluded =
          io::ParseNpy(NpyMember(fields, "occluded_in.npy", where), where + ":occluded_in.npy");
      if (occluded.shape.size() != 3 || occluded.shape[0] != static_cast<int64_t>(n)) {
        throw InputError(where, "expected occluded_in.npy of shape [N, H, W]");
      }
      const int h = static_cast<int>(occluded.shape[1]), w = static_cast<int>(occluded.shape[2]);
      const uint32_t* occ = occluded.As<uint32_t>(where + ":occluded_in.npy");
      for (size_t v = 0; v < n; ++v) {
        cv::Mat picture;
        for (const char* ext : {".png", ".jpg"}) {
          auto it = fields.find("image" + std::to_string(v) + ext);
          if (it != fields.end()) {
            picture = io::DecodeImageBytes(it->second, io::ChannelOrder::kBgr, where);
          }
        }
        if (!picture.empty() && picture.channels() == 1) {
          cv::cvtColor(picture, picture, cv::COLOR_GRAY2BGR);
        }
        if (picture.empty()) {
          const std::string name = "depth" + std::to_string(v) + ".npy";
          picture = DepthPicture(io::ParseNpy(NpyMember(fields, name, where), where + ":" + name),
                                 v, where + ":" + name);
        }
        if (picture.rows != h || picture.cols != w) {
          throw InputError(where, "view " + std::to_string(v) + " is not " + std::to_string(w) +
                                      "x" + std::to_string(h));
        }
        // Pixels OCCLUDED in at least one other view: half-way to red.
        const uint32_t others = ~(uint32_t{1} << v);
        for (int y = 0; y < h; ++y)
          for (int x = 0; x < w; ++x) {
            if (occ[(v * h + y) * static_cast<size_t>(w) + x] & others) {
              cv::Vec3b& p = picture.at<cv::Vec3b>(y, x);
              p = cv::Vec3b(static_cast<uint8_t>(p[0] / 2), static_cast<uint8_t>(p[1] / 2),
                            static_cast<uint8_t>(p[2] / 2 + 118));
            }
          }
        cv::Mat small = picture;
        if (picture.cols > thumb_width_px) {
          const double scale = static_cast<double>(thumb_width_px) / picture.cols;
          cv::resize(picture, small, cv::Size(), scale, scale, cv::INTER_AREA);
        }
        const std::string name = "view " + std::to_string(v) + ": " + t.frame_ids[v];
        item.views.push_back(
            {name, "image/jpeg", io::EncodeJpegBytes(small, io::ChannelOrder::kBgr, 85, name)});
      }
    } catch (const InputError& e) {
      item.views.clear();
      item.note = "could not be read: " + std::string(e.what());
      item.unreadable = true;
    }
    out.push_back(std::move(item));
  }
  return out;
}

std::string RenderTuplesSection(const TupleSet& set, const json& s,
                                const std::vector<NamedImage>& plots,
                                const std::vector<TupleGalleryItem>& gallery, uint64_t seed) {
  std::ostringstream h;
  auto cell = [](const json& v) { return v.is_number() ? Num(v.get<double>()) : std::string("-"); };
  const int64_t tuple_count = s["count"].get<int64_t>(), scenes = s["scenes"].get<int64_t>();
  h << "<h2>Tuples</h2>\n<p class=\"muted\">" << tuple_count
    << (tuple_count == 1 ? " N-view tuple of " : " N-view tuples of ") << scenes
    << (scenes == 1 ? " scene" : " scenes") << " (tuples.jsonl of occgt tuples)"
    << (set.has_shards ? "; their N-view shards in views/" : "; no N-view shards (views/)")
    << ". Covisibility: every entry [a][b], a &ne; b, of the tuples' matrices (visible overlap of "
       "view a in view b). Occlusion per tuple: ground truth = OCCLUDED / (VISIBLE + OCCLUDED) "
       "over the ordered pairs of views (views/pairs.jsonl occlusion_ratio_visible); graph "
       "estimate = "
       "tuples.jsonl occlusion (selection.tuples.balance_occlusion).</p>\n";
  h << "<div class=\"tables\">\n<table><tr><th>views N</th><th>tuples</th></tr>\n";
  std::map<int, int64_t> sizes;  // in increasing N (the JSON keys sort as text)
  for (auto it = s["sizes"].begin(); it != s["sizes"].end(); ++it) {
    sizes[std::stoi(it.key())] = it.value().get<int64_t>();
  }
  for (const auto& [n, count] : sizes) {
    h << "<tr><td>" << n << "</td><td class=\"n\">" << count << "</td></tr>\n";
  }
  h << "</table>\n<table><tr><th>tuples</th><th>values</th><th>min</th><th>median</th>"
       "<th>mean</th><th>max</th></tr>\n";
  auto row = [&](const std::string& label, const json& d) {
    h << "<tr><td>" << label << "</td><td class=\"n\">" << d["count"].get<int64_t>()
      << "</td><td class=\"n\">" << cell(d["min"]) << "</td><td class=\"n\">" << cell(d["median"])
      << "</td><td class=\"n\">" << cell(d["mean"]) << "</td><td class=\"n\">" << cell(d["max"])
      << "</td></tr>\n";
  };
  row("covisibility (ordered pairs of views)", s["covisibility"]);
  if (s["occlusion"].contains("ground_truth")) {
    row("occlusion (N-view ground truth)", s["occlusion"]["ground_truth"]);
  }
  if (s["occlusion"].contains("graph_estimate")) {
    row("occlusion (graph estimate)", s["occlusion"]["graph_estimate"]);
  }
  h << "</table>\n</div>\n";
  if (s["occlusion"].empty()) {
    h << "<p class=\"muted\">No occlusion of the tuples: `occgt tuples --shards` (ground truth) "
         "or selection.tuples.balance_occlusion (graph estimate) records it.</p>\n";
  }
  h << "<div class=\"plots\">\n";
  for (const auto& p : plots) {
    h << "<figure>" << ImgTag(p, PlotAlt(p.name)) << "<figcaption>" << HtmlEscape(p.name)
      << "</figcaption></figure>\n";
  }
  h << "</div>\n<h3>Tuple gallery</h3>\n<p class=\"muted\">" << gallery.size()
    << " tuples picked with seed " << seed
    << "; pixels occluded in at least one other view of the tuple tinted red.</p>\n";
  for (const auto& g : gallery) {
    h << "<div class=\"pair tuple\"><h4>" << HtmlEscape(g.caption) << "</h4>\n";
    if (!g.note.empty()) h << "<p class=\"muted\">" << HtmlEscape(g.note) << "</p>\n";
    h << "<div class=\"views\">";
    for (const auto& im : g.views) {
      h << "<figure>" << ImgTag(im, g.caption + ": " + im.name) << "<figcaption>"
        << HtmlEscape(im.name) << "</figcaption></figure>";
    }
    h << "</div></div>\n";
  }
  return h.str();
}

}  // namespace gt::report

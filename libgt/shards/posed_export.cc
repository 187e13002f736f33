#include "libgt/shards/posed_export.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/image.h"
#include "libgt/io/npy.h"
#include "libgt/shards/frame_files.h"
#include "libgt/shards/sample.h"

namespace gt::shards {
namespace {

namespace fs = std::filesystem;

// glue-factory reads depth PNGs as value / 256 (metres); DUSt3R's ScanNet++ loader as
// value / 1000.
constexpr double kGlueFactoryDepthUnits = 256.0;
constexpr double kDust3rDepthUnits = 1000.0;

struct SceneViews {
  std::string name;
  std::string folder;
  const Scene* scene = nullptr;
  std::vector<const Frame*> frames;     // the views, sorted by number
  std::map<int64_t, int64_t> index;     // Frame::number -> view index in the scene
  std::vector<const PosedPair*> pairs;  // in the given order
};

const Frame& UsableFrame(const Scene& scene, int64_t number, const std::string& what) {
  for (const Frame& f : scene.frames) {
    if (f.number == number && f.usable) return f;
  }
  throw InputError(what,
                   "scene " + scene.name + " has no usable frame number " + std::to_string(number));
}

// The scenes of the pairs (sorted by name) with the frames they use.
std::vector<SceneViews> CollectViews(const std::string& what,
                                     const std::map<std::string, const Scene*>& scenes,
                                     const std::vector<PosedPair>& pairs) {
  std::map<std::string, SceneViews> by_name;
  for (const PosedPair& p : pairs) {
    SceneViews& s = by_name[p.scene];
    if (s.scene == nullptr) {
      const auto it = scenes.find(p.scene);
      if (it == scenes.end() || it->second == nullptr) {
        throw InputError(what, "no scene data for scene " + p.scene);
      }
      s.name = p.scene;
      s.scene = it->second;
    }
    if (p.frame0 == p.frame1) {
      throw InputError(
          what, "pair of frame " + std::to_string(p.frame0) + " with itself in scene " + p.scene);
    }
    s.pairs.push_back(&p);
    s.index[p.frame0] = 0;
    s.index[p.frame1] = 0;
  }
  std::set<std::string> names;
  for (const auto& [name, s] : by_name) names.insert(name);
  const auto folders = PosedSceneFolders(names);
  std::vector<SceneViews> out;
  for (auto& [name, s] : by_name) {
    s.folder = folders.at(name);
    int64_t i = 0;
    for (auto& [number, index] : s.index) {
      s.frames.push_back(&UsableFrame(*s.scene, number, what));
      index = i++;
    }
    out.push_back(std::move(s));
  }
  return out;
}

// Already ScanNet's depth form at width x height: 16-bit PNG in millimetres, no marker but 0.
bool DepthIsMillimetrePng(const Frame& f, int width, int height) {
  std::string ext = fs::path(f.depth.path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return f.depth.format == DepthFormat::kPng16 && f.depth.scale_m_per_unit == 0.001 &&
         !f.depth_lens && f.mask_path.empty() &&
         (f.depth.invalid_value < 0 || f.depth.invalid_value == 0) && ext == ".png" &&
         f.depth_camera.width == width && f.depth_camera.height == height;
}

struct ViewOutput {
  std::vector<io::FileToWrite> files;
  std::vector<std::pair<std::string, std::string>> links;  // (source, destination)
  size_t linked = 0, converted = 0, zeroed = 0;
};

ViewOutput ExportView(const std::string& what, const Scene& scene, const Frame& f,
                      const std::string& image_dst, const std::string& depth_dst,
                      double units_per_m, const PosedExportOptions& options) {
  ViewOutput out;
  if (f.color_path.empty()) {
    throw InputError(f.depth.path, what + ": frame " + f.id + " has no colour image");
  }
  // Colour at W x H: a JPEG file of that size is linked, anything else decoded, resized
  // (bilinear, as the shards' images) and written as JPEG.
  bool link_color = false;
  if (f.color_range.size == 0 && !f.color_lens && IsJpegPath(f.color_path)) {
    int w = f.color_camera.width, h = f.color_camera.height;
    if (w <= 0) {
      const io::ImageSize size = io::ReadImageSize(f.color_path);
      w = size.width;
      h = size.height;
    }
    link_color = w == options.width && h == options.height;
  }
  if (link_color) {
    out.links.emplace_back(f.color_path, image_dst);
    ++out.linked;
  } else {
    const io::ColorImage rgb = io::ReadFrameColorResized(f, options.width, options.height);
    const cv::Mat m(rgb.height, rgb.width, CV_8UC3, const_cast<uint8_t*>(rgb.rgb.data()));
    out.files.push_back({image_dst, io::EncodeJpegBytes(m, io::ChannelOrder::kRgb,
                                                        options.jpeg_quality, f.color_path)});
    ++out.converted;
  }
  if (options.load_depth) {
    out.files.push_back(
        {depth_dst, DepthPngBytes(options.load_depth(scene, f, options.width, options.height),
                                  depth_dst, units_per_m, options.png_level, &out.zeroed)});
    ++out.converted;
  } else if (units_per_m == 1000.0 && DepthIsMillimetrePng(f, options.width, options.height)) {
    out.links.emplace_back(f.depth.path, depth_dst);
    ++out.linked;
  } else {
    out.files.push_back({depth_dst, DepthPngBytes(f, options.width, options.height, units_per_m,
                                                  options.png_level, &out.zeroed)});
    ++out.converted;
  }
  return out;
}

// The name of a view's files without extension: its frame number, or (by_id) its frame id.
std::string ViewName(const Frame& f, bool by_id) {
  return by_id ? f.id : std::to_string(f.number);
}

// Writes <scene_dir>/<image_sub>/<n>.jpg and <scene_dir>/<depth_sub>/<n>.png of every view
// (n = ViewName) and removes the files of views no longer used.
void WriteViewFiles(const std::string& what, const SceneViews& s, const std::string& scene_dir,
                    const std::string& image_sub, const std::string& depth_sub, double units_per_m,
                    const PosedExportOptions& options, PosedExportStats* stats,
                    bool by_id = false) {
  constexpr size_t kChunk = 32;
  for (size_t begin = 0; begin < s.frames.size(); begin += kChunk) {
    const size_t end = std::min(s.frames.size(), begin + kChunk);
    std::vector<ViewOutput> outputs(end - begin);
    tbb::parallel_for(begin, end, [&](size_t i) {
      const std::string n = ViewName(*s.frames[i], by_id);
      outputs[i - begin] =
          ExportView(what, *s.scene, *s.frames[i], scene_dir + "/" + image_sub + "/" + n + ".jpg",
                     scene_dir + "/" + depth_sub + "/" + n + ".png", units_per_m, options);
    });
    std::vector<io::FileToWrite> files;
    for (ViewOutput& o : outputs) {
      for (auto& [src, dst] : o.links) LinkAtomic(src, dst);
      for (io::FileToWrite& f : o.files) files.push_back(std::move(f));
      stats->linked += o.linked;
      stats->converted += o.converted;
      stats->depth_zeroed_px += o.zeroed;
    }
    io::WriteFilesAtomic(files);
  }
  std::set<std::string> jpg, png;
  for (const Frame* f : s.frames) {
    jpg.insert(ViewName(*f, by_id) + ".jpg");
    png.insert(ViewName(*f, by_id) + ".png");
  }
  RemoveOthers(scene_dir + "/" + image_sub, jpg);
  RemoveOthers(scene_dir + "/" + depth_sub, png);
  stats->views += s.frames.size();
  stats->pairs += s.pairs.size();
  ++stats->scenes;
}

std::string Number(double v) {
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

std::string Score(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

void WriteExportJson(const std::string& path, const char* format, double units_per_m,
                     const std::vector<SceneViews>& views, const PosedExportOptions& options,
                     const PosedExportStats& stats) {
  nlohmann::json scenes = nlohmann::json::object();
  for (const SceneViews& s : views) scenes[s.folder] = s.name;
  const nlohmann::json doc = {{"format", format},
                              {"width", options.width},
                              {"height", options.height},
                              {"depth_units_per_m", static_cast<int>(units_per_m)},
                              {"scenes", scenes},
                              {"views", stats.views},
                              {"pairs", stats.pairs},
                              {"linked", stats.linked},
                              {"converted", stats.converted},
                              {"depth_zeroed_px", stats.depth_zeroed_px}};
  io::WriteFileAtomic(path, doc.dump(2) + "\n");
}

void AppendMatrix(const Eigen::MatrixXd& m, std::vector<double>* out) {
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < m.cols(); ++c) out->push_back(m(r, c));
  }
}

}  // namespace

bool PosedExportOptions::Check(std::string* error) const {
  if (width < 2 || height < 2) return *error = "width, height: expected >= 2", false;
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    return *error = "jpeg_quality: expected 1..100", false;
  }
  if (png_level < 0 || png_level > 9) return *error = "png_level: expected 0..9", false;
  return true;
}

std::map<std::string, std::string> PosedSceneFolders(const std::set<std::string>& scenes) {
  std::map<std::string, std::string> folders, scene_of_folder;
  for (const std::string& s : scenes) {
    std::string folder = SanitizeScenePath(s);
    std::replace(folder.begin(), folder.end(), '/', '_');
    const auto [it, fresh] = scene_of_folder.emplace(folder, s);
    if (!fresh) {
      throw InputError("posed export",
                       "scenes " + it->second + " and " + s + " both map to folder " + folder);
    }
    folders[s] = folder;
  }
  return folders;
}

PosedExportStats ExportGlueFactory(const std::string& out_dir,
                                   const std::map<std::string, const Scene*>& scenes,
                                   const std::vector<PosedPair>& pairs,
                                   const PosedExportOptions& options) {
  const std::string what = "gluefactory export";
  if (std::string e; !options.Check(&e)) throw InputError(what + " options", e);
  const std::vector<SceneViews> views = CollectViews(what, scenes, pairs);
  const std::string data = out_dir + "/data";
  PosedExportStats stats;
  std::set<std::string> folders;
  for (const SceneViews& s : views) {
    const std::string dir = data + "/" + s.folder;
    WriteViewFiles(what, s, dir, "images", "depths", kGlueFactoryDepthUnits, options, &stats);
    std::string views_txt, pairs_txt, scores_txt;
    for (const Frame* f : s.frames) {
      // K at W x H in COLMAP's convention (centre of the top-left pixel at (0.5, 0.5)).
      const Camera k = f->depth_camera.Resized(options.width, options.height);
      const Rigid3d cam_from_world = f->world_from_cam.inverse(Eigen::Isometry);
      std::string line = std::to_string(f->number) + ".jpg";
      const Eigen::Matrix3d r = cam_from_world.linear();
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) line += " " + Number(r(i, j));
      }
      for (int i = 0; i < 3; ++i) line += " " + Number(cam_from_world.translation()(i));
      line += " PINHOLE " + std::to_string(options.width) + " " + std::to_string(options.height) +
              " " + Number(k.fx) + " " + Number(k.fy) + " " + Number(k.cx + 0.5) + " " +
              Number(k.cy + 0.5);
      views_txt += line + "\n";
    }
    for (const PosedPair* p : s.pairs) {
      const std::string names =
          std::to_string(p->frame0) + ".jpg " + std::to_string(p->frame1) + ".jpg";
      pairs_txt += names + "\n";
      scores_txt += names + " " + Score(p->score) + " " + Score(p->overlap01) + " " +
                    Score(p->overlap10) + "\n";
    }
    io::WriteFilesAtomic({{dir + "/views.txt", views_txt},
                          {dir + "/pairs.txt", pairs_txt},
                          {dir + "/pair_scores.txt", scores_txt}});
    RemoveOthers(dir, {"images", "depths", "views.txt", "pairs.txt", "pair_scores.txt"});
    folders.insert(s.folder);
  }
  RemoveOthers(data, folders);
  WriteExportJson(out_dir + "/export.json", "gluefactory", kGlueFactoryDepthUnits, views, options,
                  stats);
  return stats;
}

PosedExportStats ExportDust3r(const std::string& out_dir,
                              const std::map<std::string, const Scene*>& scenes,
                              const std::vector<PosedPair>& pairs,
                              const PosedExportOptions& options) {
  const std::string what = "dust3r export";
  if (std::string e; !options.Check(&e)) throw InputError(what + " options", e);
  const std::vector<SceneViews> views = CollectViews(what, scenes, pairs);
  PosedExportStats stats;
  std::set<std::string> keep = {"all_metadata.npz", "export.json", "scene_list.json"};
  nlohmann::json scene_list = nlohmann::json::array();
  std::vector<std::string> scene_names, images;
  std::vector<int64_t> counts, sceneids;
  std::vector<double> intrinsics, trajectories, all_pairs;
  int64_t offset = 0;
  for (size_t si = 0; si < views.size(); ++si) {
    const SceneViews& s = views[si];
    const std::string dir = out_dir + "/" + s.folder;
    // ScanNet++: DUSt3R's preprocessed layout names a view by its image stem (DSC01234; the
    // iPhone's frame_000010), the name selected_pairs.npz's `selection` lists; other datasets
    // by frame number.
    const bool by_id = s.scene->format == DatasetFormat::kScanNetPP;
    WriteViewFiles(what, s, dir, "images", "depth", kDust3rDepthUnits, options, &stats, by_id);
    std::vector<std::string> scene_images, stems;
    std::vector<double> scene_k, scene_t, scene_pairs, selected_pairs, selected_overlaps;
    for (const Frame* f : s.frames) {
      scene_images.push_back(ViewName(*f, by_id));
      stems.push_back(fs::path(f->color_path).stem().string());
      AppendMatrix(f->depth_camera.Resized(options.width, options.height).K(), &scene_k);
      AppendMatrix(f->world_from_cam.matrix(), &scene_t);
    }
    for (const PosedPair* p : s.pairs) {
      const double i = static_cast<double>(s.index.at(p->frame0));
      const double j = static_cast<double>(s.index.at(p->frame1));
      scene_pairs.insert(scene_pairs.end(), {i, j, p->score, p->overlap01, p->overlap10});
      selected_pairs.insert(selected_pairs.end(), {i, j, p->score});
      selected_overlaps.insert(selected_overlaps.end(), {p->overlap01, p->overlap10});
      all_pairs.insert(all_pairs.end(),
                       {i + static_cast<double>(offset), j + static_cast<double>(offset), p->score,
                        p->overlap01, p->overlap10});
    }
    const auto v = static_cast<int64_t>(s.frames.size());
    const auto np = static_cast<int64_t>(s.pairs.size());
    io::WriteNpz(dir + "/scene_metadata.npz",
                 {{"images", io::EncodeStringsNpy(scene_images, "dust3r export")},
                  {"intrinsics", io::EncodeNpy<double>({v, 3, 3}, scene_k)},
                  {"pairs", io::EncodeNpy<double>({np, 5}, scene_pairs)},
                  {"trajectories", io::EncodeNpy<double>({v, 4, 4}, scene_t)}});
    // DUSt3R's precomputed pairs (its preprocessing reads <pairs dir>/<scene>/
    // selected_pairs.npz: `selection` the image stems, `pairs` rows (i, j, score)).
    io::WriteNpz(dir + "/selected_pairs.npz",
                 {{"overlaps", io::EncodeNpy<double>({np, 2}, selected_overlaps)},
                  {"pairs", io::EncodeNpy<double>({np, 3}, selected_pairs)},
                  {"selection", io::EncodeStringsNpy(stems, "dust3r export")}});
    RemoveOthers(dir, {"images", "depth", "scene_metadata.npz", "selected_pairs.npz"});
    scene_list.push_back(s.folder);
    scene_names.push_back(s.folder);
    counts.push_back(offset);
    for (int64_t k = 0; k < v; ++k) sceneids.push_back(static_cast<int64_t>(si));
    images.insert(images.end(), scene_images.begin(), scene_images.end());
    intrinsics.insert(intrinsics.end(), scene_k.begin(), scene_k.end());
    trajectories.insert(trajectories.end(), scene_t.begin(), scene_t.end());
    offset += v;
    keep.insert(s.folder);
  }
  const auto nv = static_cast<int64_t>(images.size());
  const auto ns = static_cast<int64_t>(scene_names.size());
  const auto np = static_cast<int64_t>(all_pairs.size() / 5);
  io::WriteNpz(out_dir + "/all_metadata.npz",
               {{"counts", io::EncodeNpy<int64_t>({ns}, counts)},
                {"images", io::EncodeStringsNpy(images, "dust3r export")},
                {"intrinsics", io::EncodeNpy<double>({nv, 3, 3}, intrinsics)},
                {"pairs", io::EncodeNpy<double>({np, 5}, all_pairs)},
                {"sceneids", io::EncodeNpy<int64_t>({nv}, sceneids)},
                {"scenes", io::EncodeStringsNpy(scene_names, "dust3r export")},
                {"trajectories", io::EncodeNpy<double>({nv, 4, 4}, trajectories)}});
  io::WriteFileAtomic(out_dir + "/scene_list.json", scene_list.dump() + "\n");
  RemoveOthers(out_dir, keep);
  WriteExportJson(out_dir + "/export.json", "dust3r", kDust3rDepthUnits, views, options, stats);
  return stats;
}

}  // namespace gt::shards

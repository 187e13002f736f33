// Synthetic dataset writer (dataset.h).
#include "libgt/synth/dataset.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/file_read.h"
#include "libgt/io/npy.h"
#include "libgt/synth/random.h"
#include "libgt/synth/render.h"

namespace gt::synth {
namespace {

using ojson = nlohmann::ordered_json;

std::string FrameId(int i) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%06d", i);
  return buf;
}

ojson MatrixRows(const Eigen::MatrixXd& m) {
  ojson rows = ojson::array();
  for (int r = 0; r < m.rows(); ++r) {
    ojson row = ojson::array();
    for (int c = 0; c < m.cols(); ++c) row.push_back(m(r, c) == 0.0 ? 0.0 : m(r, c));
    rows.push_back(row);
  }
  return rows;
}

// The manifest with one frame per line: readable and diff-friendly, still plain JSON.
std::string DumpOneFramePerLine(const ojson& manifest) {
  std::string out = "{\n";
  for (auto it = manifest.begin(); it != manifest.end(); ++it) {
    out += "  " + ojson(it.key()).dump() + ": ";
    if (it.key() == "frames") {
      out += "[\n";
      for (size_t i = 0; i < it.value().size(); ++i) {
        out += "    " + it.value()[i].dump() + (i + 1 < it.value().size() ? ",\n" : "\n");
      }
      out += "  ]";
    } else {
      out += it.value().dump();
    }
    out += std::next(it) != manifest.end() ? ",\n" : "\n";
  }
  return out + "}\n";
}

std::string EncodePngRgb(const io::ColorImage& image, const std::string& path_for_errors) {
  const cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.rgb.data()));
  return io::EncodePngBytes(rgb, io::ChannelOrder::kRgb, 3, path_for_errors);
}

}  // namespace

bool SynthOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error != nullptr) *error = m;
    return false;
  };
  if (scenes < 1 || scenes > 1000) return fail("scenes: expected 1..1000");
  if (frames_per_scene < 1 || frames_per_scene > 100000)
    return fail("frames per scene: expected 1..100000");
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    return fail("resolution: expected 16..8192 pixels per side");
  if (holes && (max_holes_per_frame < 1 || max_holes_per_frame > 100))
    return fail("max_holes_per_frame: expected 1..100");
  if (!(focal_px > 1.0 && focal_px < 1e5)) return fail("focal_px: expected (1, 1e5)");
  std::string sub;
  if (!room.Check(&sub)) return fail("room: " + sub);
  TrajectoryOptions t = trajectory;
  t.frames = frames_per_scene;
  if (!t.Check(&sub)) return fail("trajectory: " + sub);
  return true;
}

Camera SynthCamera(const SynthOptions& o) {
  Camera c;
  c.width = o.width;
  c.height = o.height;
  c.fx = c.fy = o.focal_px * o.width / 640.0;
  c.cx = (o.width - 1) / 2.0;
  c.cy = (o.height - 1) / 2.0;
  return c;
}

std::string SynthSceneName(int scene_index) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "synth_%03d", scene_index);
  return buf;
}

uint64_t SynthSceneSeed(uint64_t dataset_seed, int scene_index) {
  return ChildSeed(dataset_seed, static_cast<uint64_t>(scene_index));
}

std::vector<HoleRect> MakeHoles(uint64_t scene_seed, int frame_index, int width, int height,
                                int max_holes) {
  SplitMix64 rng(ChildSeed(scene_seed ^ 0x686f6c6573ull, static_cast<uint64_t>(frame_index)));
  const int max_side = std::max(8, width / 12);
  const int count = rng.Int(1, max_holes);
  std::vector<HoleRect> holes;
  for (int i = 0; i < count; ++i) {
    const int w = std::min(width, rng.Int(4, max_side));
    const int h = std::min(height, rng.Int(4, max_side));
    HoleRect r;
    r.x0 = rng.Int(0, width - w);
    r.y0 = rng.Int(0, height - h);
    r.x1 = r.x0 + w;
    r.y1 = r.y0 + h;
    holes.push_back(r);
  }
  return holes;
}

void ApplyHoles(const std::vector<HoleRect>& holes, DepthImage* depth) {
  for (const auto& r : holes) {
    for (int v = std::max(0, r.y0); v < std::min(depth->height, r.y1); ++v) {
      for (int u = std::max(0, r.x0); u < std::min(depth->width, r.x1); ++u) depth->at(u, v) = 0;
    }
  }
}

void ClaimSynthFolder(const std::string& out_dir, const std::string& claim,
                      const std::string& legacy_options) {
  namespace fs = std::filesystem;
  const std::string claim_path = (fs::path(out_dir) / ".occgt-synth.json").string();
  const std::string dataset_path = (fs::path(out_dir) / "dataset.json").string();
  const std::string remedy =
      ": write into an empty folder, or delete this one, so that the two "
      "do not mix";
  if (io::FileExists(claim_path)) {
    const ojson have = ojson::parse(io::ReadFileBytes(claim_path), nullptr, false);
    if (have.is_discarded() || have != ojson::parse(claim)) {
      throw InputError(claim_path, "holds a synthetic dataset of other options " +
                                       (have.is_discarded() ? "(unreadable)" : have.dump()) +
                                       remedy);
    }
    return;
  }
  if (io::FileExists(dataset_path)) {  // written by a run before the claim existed
    const ojson have = ojson::parse(io::ReadFileBytes(dataset_path), nullptr, false);
    if (have.is_discarded() || !have.is_object() || !have.contains("options")) {
      throw InputError(dataset_path, "is not the dataset.json of occgt synth" + remedy);
    }
    if (legacy_options.empty() || have["options"] != ojson::parse(legacy_options)) {
      throw InputError(dataset_path, "holds a synthetic dataset of other options " +
                                         have["options"].dump() + remedy);
    }
  } else {
    std::error_code ec;
    if (fs::exists(out_dir, ec) && !fs::is_empty(out_dir, ec)) {
      throw InputError(out_dir, "holds files and no occgt synth dataset" + remedy);
    }
  }
  io::WriteFileAtomic(claim_path, claim + "\n");
}

SynthSummary WriteSyntheticDataset(const std::string& out_dir, const SynthOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("synth options", error);
  const Camera camera = SynthCamera(options);
  TrajectoryOptions traj = options.trajectory;
  traj.frames = options.frames_per_scene;

  namespace fs = std::filesystem;
  SynthSummary summary;
  ojson dataset;
  dataset["format"] = "occgt-synth-dataset";
  dataset["version"] = 1;
  dataset["generator"] = "occgt synth";
  dataset["options"] = {{"scenes", options.scenes},
                        {"frames_per_scene", options.frames_per_scene},
                        {"width", options.width},
                        {"height", options.height},
                        {"seed", options.seed},
                        {"holes", options.holes},
                        {"max_holes_per_frame", options.max_holes_per_frame},
                        {"focal_px", options.focal_px}};
  // A folder holding a synthetic dataset of other options (or anything else) is refused: the
  // frames and scenes this run does not write would stay beside the new ones.
  ClaimSynthFolder(out_dir, ojson{{"layout", "generic"}, {"options", dataset["options"]}}.dump(),
                   dataset["options"].dump());
  summary.files += 1;
  dataset["scenes"] = ojson::array();

  for (int s = 0; s < options.scenes; ++s) {
    const uint64_t scene_seed = SynthSceneSeed(options.seed, s);
    SynthScene scene = MakeRoomScene(scene_seed, options.room);
    scene.name = SynthSceneName(s);
    const std::vector<Rigid3d> poses = Trajectory(scene, traj);
    const fs::path scene_dir = fs::path(out_dir) / scene.name;

    ojson manifest;
    manifest["format"] = "occgt-scene-manifest";
    manifest["version"] = 1;
    manifest["scene"] = scene.name;
    manifest["depth_range_m"] = {0.05, 50.0};
    manifest["frames"] = ojson::array();
    ojson holes_json = ojson::object();
    for (int f = 0; f < options.frames_per_scene; ++f) {
      const std::string id = FrameId(f);
      RenderedView view = RenderView(scene, camera, poses[f]);
      if (options.holes) {
        const auto holes =
            MakeHoles(scene_seed, f, camera.width, camera.height, options.max_holes_per_frame);
        ApplyHoles(holes, &view.depth);
        ojson list = ojson::array();
        for (const auto& r : holes) list.push_back({r.x0, r.y0, r.x1, r.y1});
        holes_json[id] = list;
      }
      const std::string depth_rel = "depth/" + id + ".npy";
      const std::string color_rel = "color/" + id + ".png";
      io::WriteNpy<float>((scene_dir / depth_rel).string(), {camera.height, camera.width},
                          view.depth.values_m);
      const std::string color_path = (scene_dir / color_rel).string();
      io::WriteFileAtomic(color_path, EncodePngRgb(view.color, color_path));
      summary.files += 2;

      ojson frame;
      frame["id"] = id;
      frame["depth"] = {{"path", depth_rel}, {"format", "npy"}};
      frame["K"] = MatrixRows(camera.K());
      frame["width"] = camera.width;
      frame["height"] = camera.height;
      frame["world_from_cam"] = MatrixRows(poses[f].matrix());
      frame["color"] = {{"path", color_rel}};
      manifest["frames"].push_back(frame);
    }
    io::WriteFileAtomic((scene_dir / "scene.json").string(), DumpOneFramePerLine(manifest));
    summary.files += 1;
    summary.frames += options.frames_per_scene;
    summary.scene_names.push_back(scene.name);

    ojson entry;
    entry["name"] = scene.name;
    entry["manifest"] = scene.name + "/scene.json";
    entry["frames"] = options.frames_per_scene;
    entry["objects"] = static_cast<int>(scene.objects.size());
    entry["room_size_m"] = {scene.room_size_m.x(), scene.room_size_m.y(), scene.room_size_m.z()};
    entry["holes"] = holes_json;
    dataset["scenes"].push_back(entry);
  }
  io::WriteFileAtomic((fs::path(out_dir) / "dataset.json").string(), dataset.dump(2) + "\n");
  summary.files += 1;
  return summary;
}

}  // namespace gt::synth

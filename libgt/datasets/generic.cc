// occgt generic manifest reader: schemas/manifest.schema.json, validated here in C++ with
// errors that give the manifest path and the JSON field path
// ("scenes/a/scene.json: frames[3].K: expected a 3x3 array of numbers").
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "libgt/core/camera.h"
#include "libgt/core/error.h"
#include "libgt/datasets/json_input.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"

namespace gt::datasets {
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

constexpr const char* kManifestName = "scene.json";

// "" when `path` is a regular file or nothing is there; else "<path>: <what is there>", in
// the folder readers' words (text_parsing.h NotAFileProblem).
std::string NotAFileDetail(const std::string& path) {
  const std::string problem = NotAFileProblem(path);
  return problem.empty() ? "" : path + ": " + problem;
}

// Validation context: the manifest path and helpers that throw with the field path.
class Validator {
 public:
  explicit Validator(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& expected) const {
    throw InputError(path_, field + ": " + expected);
  }

  void RequireObject(const json& j, const std::string& field, const std::set<std::string>& allowed,
                     const std::set<std::string>& required) const {
    if (!j.is_object()) Fail(field.empty() ? "(top level)" : field, "expected an object");
    for (const auto& [key, value] : j.items()) {
      if (!allowed.count(key)) Fail(Join(field, key), "unknown field");
    }
    for (const auto& key : required) {
      if (!j.contains(key)) Fail(Join(field, key), "required field is missing");
    }
  }

  std::string String(const json& j, const std::string& field, bool non_empty = true) const {
    if (!j.is_string() || (non_empty && j.get<std::string>().empty())) {
      Fail(field, non_empty ? "expected a non-empty string" : "expected a string");
    }
    return j.get<std::string>();
  }

  double Number(const json& j, const std::string& field) const {
    if (!j.is_number()) Fail(field, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) Fail(field, "expected a finite number");
    return v;
  }

  int64_t Integer(const json& j, const std::string& field, int64_t min, int64_t max) const {
    bool ok = j.is_number_integer();
    if (!ok && j.is_number_float()) {
      const double v = j.get<double>();
      ok = std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e15;
    }
    if (!ok) Fail(field, "expected an integer");
    const int64_t v =
        j.is_number_float() ? static_cast<int64_t>(j.get<double>()) : j.get<int64_t>();
    if (v < min || v > max) {
      Fail(field, "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) +
                      "], got " + std::to_string(v));
    }
    return v;
  }

  Eigen::MatrixXd Matrix(const json& j, const std::string& field, int rows, int cols) const {
    const std::string expected =
        "expected a " + std::to_string(rows) + "x" + std::to_string(cols) + " array of numbers";
    if (!j.is_array() || static_cast<int>(j.size()) != rows) Fail(field, expected);
    Eigen::MatrixXd m(rows, cols);
    for (int r = 0; r < rows; ++r) {
      const json& row = j[static_cast<size_t>(r)];
      if (!row.is_array() || static_cast<int>(row.size()) != cols) Fail(field, expected);
      for (int c = 0; c < cols; ++c) {
        const json& x = row[static_cast<size_t>(c)];
        if (!x.is_number()) Fail(field, expected);
        m(r, c) = x.get<double>();
      }
    }
    return m;
  }

  Camera CameraOf(const json& K, const std::string& k_field, int width, int height) const {
    const Eigen::Matrix3d k = Matrix(K, k_field, 3, 3);
    if (!Camera::IsPinholeMatrix(k)) {
      Fail(k_field, "expected K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]");
    }
    const Camera cam = Camera::FromK(k, width, height);
    std::string error;
    if (!cam.Check(&error)) Fail(k_field, error);
    return cam;
  }

  static std::string Join(const std::string& parent, const std::string& key) {
    return parent.empty() ? key : parent + "." + key;
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

json ParseManifest(const std::string& path) {
  return ParseJsonInput(io::ReadFileBytes(path), path);
}

std::string ResolvePath(const fs::path& base, const std::string& p) {
  const fs::path q(p);
  return (q.is_absolute() ? q : base / q).lexically_normal().string();
}

bool IsJsonFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec) && fs::path(path).extension() == ".json";
}

// The manifest of a single-scene root, or "" when root holds several scenes.
std::string SingleManifest(const std::string& root) {
  if (IsJsonFile(root)) return root;
  const std::string p = (fs::path(root) / kManifestName).string();
  return io::FileExists(p) ? p : "";
}

std::string ManifestSceneName(const std::string& path) {
  const json j = ParseManifest(path);
  if (!j.is_object() || !j.contains("scene") || !j["scene"].is_string()) {
    throw InputError(path, "scene: expected a string");
  }
  return j["scene"].get<std::string>();
}

}  // namespace

std::vector<std::string> GenericReader::ListScenes(const std::string& root) const {
  RequireRoot(root);
  RequireFinishedSynth(root);
  const std::string single = SingleManifest(root);
  if (!single.empty()) return {ManifestSceneName(single)};
  std::vector<std::string> out;
  for (const auto& name : ListSubfolders(root)) {
    if (io::FileExists((fs::path(root) / name / kManifestName).string())) out.push_back(name);
  }
  if (out.empty()) {
    throw InputError(root,
                     "no generic scene found (expected a .json manifest, scene.json, or "
                     "subfolders with scene.json)");
  }
  return out;
}

Scene GenericReader::ReadScene(const std::string& root, const std::string& scene_name) const {
  RequireRoot(root);
  RequireFinishedSynth(root);
  if (std::string e = CheckSceneName(scene_name); !e.empty()) {
    throw InputError("scene '" + scene_name + "'", e);
  }
  std::string manifest = SingleManifest(root);
  if (manifest.empty() ||
      (!scene_name.empty() &&
       io::FileExists((fs::path(root) / scene_name / kManifestName).string()))) {
    if (scene_name.empty()) throw InputError(root, "no scene.json here and no scene name given");
    manifest = (fs::path(root) / scene_name / kManifestName).string();
    if (!io::FileExists(manifest)) throw InputError(manifest, "scene manifest not found");
  }
  return ParseGenericManifest(io::ReadFileBytes(manifest), manifest, scene_name, options_);
}

Scene ParseGenericManifest(std::string_view text, const std::string& manifest,
                           const std::string& scene_name, const ReaderOptions& options) {
  const Validator val(manifest);
  const json j = ParseJsonInput(text, manifest);
  val.RequireObject(j, "", {"$schema", "format", "version", "scene", "depth_range_m", "frames"},
                    {"format", "version", "scene", "frames"});
  if (!j["format"].is_string() || j["format"].get<std::string>() != "occgt-scene-manifest") {
    val.Fail("format", "expected \"occgt-scene-manifest\"");
  }
  if (!j["version"].is_number_integer() || j["version"].get<int64_t>() != 1) {
    val.Fail("version", "expected 1");
  }
  const std::string manifest_scene = val.String(j["scene"], "scene");
  static const std::regex kScenePattern("^[A-Za-z0-9_][A-Za-z0-9_.-]*$");
  static const std::regex kIdPattern("^[A-Za-z0-9_-]+$");
  if (manifest_scene.size() > 64 || !std::regex_match(manifest_scene, kScenePattern)) {
    val.Fail("scene", "expected a name of letters, digits, '_', '.', '-' (at most 64)");
  }

  Scene scene;
  scene.name = scene_name.empty() ? manifest_scene : scene_name;
  scene.format = DatasetFormat::kGeneric;
  scene.path = manifest;
  // scene.min/max_depth_m: the defaults (core/depth.h) unless depth_range_m is given.
  if (j.contains("depth_range_m")) {
    const json& r = j["depth_range_m"];
    if (!r.is_array() || r.size() != 2) val.Fail("depth_range_m", "expected [min, max] in metres");
    scene.min_depth_m = val.Number(r[0], "depth_range_m[0]");
    scene.max_depth_m = val.Number(r[1], "depth_range_m[1]");
    if (scene.min_depth_m < 0) val.Fail("depth_range_m[0]", "expected a number >= 0");
    if (!(scene.max_depth_m > scene.min_depth_m)) {
      val.Fail("depth_range_m[1]", "expected a number > depth_range_m[0]");
    }
  }

  const json& frames = j["frames"];
  if (!frames.is_array() || frames.empty())
    val.Fail("frames", "expected a non-empty array (empty scene)");
  const fs::path base = fs::path(manifest).parent_path();
  std::set<std::string> ids;
  for (size_t i = 0; i < frames.size(); ++i) {
    const std::string fp = "frames[" + std::to_string(i) + "]";
    const json& fj = frames[i];
    val.RequireObject(fj, fp, {"id", "depth", "K", "width", "height", "world_from_cam", "color"},
                      {"id", "depth", "K", "width", "height", "world_from_cam"});
    Frame f;
    f.id = val.String(fj["id"], fp + ".id");
    if (f.id.size() > 32 || !std::regex_match(f.id, kIdPattern)) {
      val.Fail(fp + ".id", "expected letters, digits, '_' or '-' (at most 32), got '" + f.id + "'");
    }
    if (!ids.insert(f.id).second) val.Fail(fp + ".id", "duplicate frame id '" + f.id + "'");
    f.number = static_cast<int64_t>(i);

    const int width = static_cast<int>(val.Integer(fj["width"], fp + ".width", 1, 1 << 16));
    const int height = static_cast<int>(val.Integer(fj["height"], fp + ".height", 1, 1 << 16));
    f.depth_camera = val.CameraOf(fj["K"], fp + ".K", width, height);

    const std::string dp = fp + ".depth";
    const json& dj = fj["depth"];
    val.RequireObject(dj, dp, {"path", "format", "scale_m", "invalid_value", "channel"},
                      {"path", "format"});
    f.depth.path = ResolvePath(base, val.String(dj["path"], dp + ".path"));
    const std::string format = dj["format"].is_string() ? dj["format"].get<std::string>() : "";
    if (format == "npy") {
      f.depth.format = DepthFormat::kNpyFloat32;
    } else if (format == "png16") {
      f.depth.format = DepthFormat::kPng16;
      if (!dj.contains("scale_m")) val.Fail(dp + ".scale_m", "required for png16 depth");
    } else if (format == "exr") {
      f.depth.format = DepthFormat::kExr;
    } else {
      val.Fail(dp + ".format", "expected one of \"npy\", \"png16\", \"exr\"");
    }
    if (dj.contains("scale_m")) {
      if (format != "png16") val.Fail(dp + ".scale_m", "allowed for png16 depth only");
      f.depth.scale_m_per_unit = val.Number(dj["scale_m"], dp + ".scale_m");
      if (!(f.depth.scale_m_per_unit > 0)) val.Fail(dp + ".scale_m", "expected a number > 0");
    }
    if (dj.contains("invalid_value")) {
      if (format != "png16") val.Fail(dp + ".invalid_value", "allowed for png16 depth only");
      f.depth.invalid_value =
          static_cast<int>(val.Integer(dj["invalid_value"], dp + ".invalid_value", 0, 65535));
    }
    if (dj.contains("channel")) {
      if (format != "exr") val.Fail(dp + ".channel", "allowed for exr depth only");
      f.depth.exr_channel = val.String(dj["channel"], dp + ".channel");
    } else if (format == "exr") {
      f.depth.exr_channel = options.exr_channel;
    }

    const std::string pose_field = fp + ".world_from_cam";
    SetMatrixPose(val.Matrix(fj["world_from_cam"], pose_field, 4, 4),
                  PoseLocator::JsonField(manifest, pose_field), &f);

    if (fj.contains("color")) {
      const std::string cp = fp + ".color";
      const json& cj = fj["color"];
      val.RequireObject(cj, cp, {"path", "K", "width", "height"}, {"path"});
      f.color_path = ResolvePath(base, val.String(cj["path"], cp + ".path"));
      if (cj.contains("width") != cj.contains("height")) {
        val.Fail(cp + (cj.contains("width") ? ".height" : ".width"),
                 "width and height go together");
      }
      int cw = 0, ch = 0;
      // A colour file whose header cannot be read, or a path that is no file: the problem.
      std::string unreadable = NotAFileDetail(f.color_path);
      if (cj.contains("width")) {
        cw = static_cast<int>(val.Integer(cj["width"], cp + ".width", 1, 1 << 16));
        ch = static_cast<int>(val.Integer(cj["height"], cp + ".height", 1, 1 << 16));
      } else if (io::FileExists(f.color_path)) {
        try {
          const io::ImageSize s = io::ReadImageSize(f.color_path);
          cw = s.width;
          ch = s.height;
        } catch (const InputError& e) {
          unreadable = e.what();
        }
      }
      if (!unreadable.empty()) {
        // One damaged image is this frame's problem, not the scene's: unusable, counted.
        MarkUnusable(&f, kReasonColorUnreadable, unreadable);
        f.color_path.clear();
      } else if (cj.contains("K")) {
        if (cw == 0) val.Fail(cp + ".width", "required with color.K when the image is missing");
        f.color_camera = val.CameraOf(cj["K"], cp + ".K", cw, ch);
      } else if (cw > 0) {
        f.color_camera = f.depth_camera.Resized(cw, ch);
      }
      // A colour file that does not exist: the frame has no colour, as in the folder readers
      // (ScanNet, 7-Scenes, TartanAir); `occgt scan` counts the usable frames without colour.
      if (!io::FileExists(f.color_path)) {
        f.color_path.clear();
        f.color_camera = Camera();
      }
    }

    if (options.check_depth_files && !io::FileExists(f.depth.path)) {
      // Any path (not named by the id); a folder or a dangling link there says so.
      const std::string problem = NotAFileDetail(f.depth.path);
      MarkUnusable(&f, kReasonDepthMissing, problem.empty() ? f.depth.path : problem);
    }
    scene.frames.push_back(std::move(f));
  }
  return scene;
}

}  // namespace gt::datasets

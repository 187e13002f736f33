#include "libgt/pipeline/split_depth.h"

#include <tbb/parallel_for.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "libgt/core/error.h"
#include "libgt/io/file_read.h"
#include "libgt/pipeline/recipe.h"

namespace gt::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string StringField(const json& obj, const char* key, const std::string& where) {
  if (!obj.contains(key) || !obj[key].is_string()) {
    throw InputError(where + "." + key, "expected a string");
  }
  return obj[key].get<std::string>();
}

double NumberField(const json& obj, const char* key, const std::string& where) {
  if (!obj.contains(key) || !obj[key].is_number()) {
    throw InputError(where + "." + key, "expected a number");
  }
  return obj[key].get<double>();
}

}  // namespace

BuildDataset ReadBuildDataset(const std::string& dir, const std::string& root_override) {
  const std::string file = (fs::path(dir) / "recipe.json").string();
  if (!io::FileExists(file)) {
    throw InputError(file, "missing (not the output folder of occgt build?)");
  }
  json j;
  try {
    j = json::parse(io::ReadFileBytes(file));
  } catch (const json::exception&) {
    throw InputError(file, "expected JSON (the resolved recipe of occgt build)");
  }
  if (!j.is_object() || !j.contains("dataset") || !j["dataset"].is_object()) {
    throw InputError(file + ": dataset", "expected an object");
  }
  const json& d = j["dataset"];
  const std::string where = file + ": dataset";
  BuildDataset b;
  const std::string format = StringField(d, "format", where);
  if (format == "synthetic") {
    b.format = DatasetFormat::kGeneric;
    b.root = (fs::path(dir) / "data").string();
  } else {
    b.format = ParseDatasetFormat(format, where + ".format");
    b.root = StringField(d, "root", where);
  }
  if (!root_override.empty()) b.root = root_override;
  if (b.format == DatasetFormat::kScanNetPP) {
    if (!d.contains("device")) {
      throw InputError(where + ".device",
                       "missing: a ScanNet++ build records the device (dslr or iphone) it read; "
                       "rebuild with a recipe that names dataset.device");
    }
    b.reader.scannetpp_device =
        datasets::ParseScanNetPPDevice(StringField(d, "device", where), where + ".device");
  }
  if (d.contains("tum_max_dt_s")) b.reader.tum_max_dt_s = NumberField(d, "tum_max_dt_s", where);
  if (d.contains("mesh_path")) b.mesh_path = StringField(d, "mesh_path", where);
  if (d.contains("depth_source")) {
    b.depth.source = render::ParseDepthSourceMode(StringField(d, "depth_source", where),
                                                  where + ".depth_source");
  }
  if (d.contains("fused_depth")) {
    b.depth.fused.abs_tol_m = NumberField(d["fused_depth"], "abs_tol_m", where + ".fused_depth");
    b.depth.fused.rel_tol = NumberField(d["fused_depth"], "rel_tol", where + ".fused_depth");
  }
  std::string error;
  if (!b.depth.Check(&error)) throw InputError(where + ".fused_depth", error);
  if (!j.contains("resolution") || !j["resolution"].is_array() || j["resolution"].size() != 2 ||
      !j["resolution"][0].is_number_integer() || !j["resolution"][1].is_number_integer()) {
    throw InputError(file + ": resolution", "expected [W, H]");
  }
  b.resolution = {j["resolution"][0].get<int>(), j["resolution"][1].get<int>()};
  if (!b.resolution.Check(&error)) throw InputError(file + ": resolution", error);
  return b;
}

std::optional<report::SplitDepthShares> ComputeSplitDepthShares(const std::string& dir,
                                                                const std::string& root_override) {
  // recipe.json is optional for a report (a split assembled by hand): no build, no source.
  if (!io::FileExists((fs::path(dir) / "recipe.json").string())) return std::nullopt;
  const BuildDataset b = ReadBuildDataset(dir, root_override);
  if (b.depth.source == render::DepthSourceMode::kSensor) return std::nullopt;
  const report::SplitData split = report::LoadSplit(dir, report::SplitReportOptions());
  // The distinct frames of the pairs, by scene (sorted by name, then frame id).
  std::map<std::string, std::map<std::string, int>> frames_by_scene;
  for (const auto& p : split.pairs) {
    frames_by_scene[p.scene][p.frame0] = 0;
    frames_by_scene[p.scene][p.frame1] = 0;
  }
  if (b.format == DatasetFormat::kScanNetPP) {
    for (const auto& [name, ids] : frames_by_scene) {
      for (const auto& [id, unused] : ids) {
        datasets::CheckScanNetPPFrameId(b.reader.scannetpp_device, id, dir + "/pairs.jsonl",
                                        dir + "/recipe.json: dataset.device");
      }
    }
  }
  const auto reader = datasets::MakeReader(b.format, b.reader);
  std::vector<Scene> scenes;
  std::vector<std::pair<size_t, size_t>> work;  // (scene, frame index in it)
  for (const auto& [name, ids] : frames_by_scene) {
    Scene scene = reader->ReadScene(b.root, name);
    ApplyMeshPath(b.mesh_path, &scene);
    for (const auto& [id, unused] : ids) {
      work.emplace_back(scenes.size(), truth::FindFrame(scene, id, dir + "/pairs.jsonl"));
    }
    scenes.push_back(std::move(scene));
  }
  std::vector<render::DepthAgreement> counts(work.size());
  tbb::parallel_for(size_t{0}, work.size(), [&](size_t k) {
    const Scene& scene = scenes[work[k].first];
    counts[k] = truth::CompareWorkingDepthWithMesh(scene, scene.frames[work[k].second],
                                                   b.resolution, b.depth);
  });
  report::SplitDepthShares out;
  out.source = b.depth.source;
  out.tolerance = b.depth.fused;
  out.width = b.resolution.width;
  out.height = b.resolution.height;
  for (size_t k = 0; k < work.size(); ++k) {
    if (out.scenes.empty() || out.scenes.back().name != scenes[work[k].first].name) {
      out.scenes.push_back({scenes[work[k].first].name, 0, {}});
    }
    out.scenes.back().frames += 1;
    out.scenes.back().counts += counts[k];
    out.total += counts[k];
    out.frames += 1;
  }
  return out;
}

}  // namespace gt::pipeline

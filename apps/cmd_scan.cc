// occgt scan ROOT --format F [--scene NAME] [--json] [--check-depth]: lists the scenes of
// a dataset root with frame counts, unusable frames by reason (with the first few frames of
// each and where their problem is), depth size and K (docs/CLI.md; JSON output follows
// schemas/scan.schema.json).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/job_flags.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/datasets/reader.h"
#include "libgt/datasets/scan.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/render/frame_depth.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/working_frame.h"

namespace occgt {
namespace {

struct ScanArgs {
  std::string root;
  std::string format;
  std::string scene;
  DeviceFlag device;
  // Flags of one format or of a mesh given on the command line: refused where they would be
  // ignored (the first such flag).
  std::string exr_channel_flag, tum_flag, mesh_flag;
  bool json = false;
  gt::datasets::ReaderOptions reader;
  gt::datasets::ScanOptions scan;
  std::string mesh;     // --mesh: every scene's mesh ({scene} = its name); "" = the reader's
  int mesh_stride = 1;  // --mesh-stride: compare every n-th usable frame with the mesh
  gt::render::FusedDepthOptions tolerance;
};

// The sensor-vs-mesh comparison of a scene that has a mesh (docs/GROUND_TRUTH.md "Depth
// sources"): per compared frame and in total.
struct MeshAgreement {
  std::string mesh;
  std::vector<std::pair<std::string, gt::render::DepthAgreement>> frames;
  gt::render::DepthAgreement total;
  // Frames whose sensor depth, mask or mesh could not be read: (id, error), skipped.
  std::vector<std::pair<std::string, std::string>> unreadable;
};

// Every --mesh-stride-th frame the summary counts usable (its mask and, with --check-depth,
// its depth checked): a frame that fails to read is skipped and listed, never fatal.
MeshAgreement CompareWithMesh(const gt::Scene& scene, const gt::datasets::SceneSummary& summary,
                              const ScanArgs& args) {
  MeshAgreement out;
  out.mesh = scene.mesh_path;
  gt::render::FrameDepthOptions options;
  options.fused = args.tolerance;
  int k = 0;
  for (const gt::Frame& f : scene.frames) {
    if (summary.usable_ids.count(f.id) == 0 || k++ % args.mesh_stride != 0) continue;
    try {
      const gt::render::DepthAgreement a = gt::truth::CompareWorkingDepthWithMesh(
          scene, f, {f.depth_camera.width, f.depth_camera.height}, options);
      out.total += a;
      out.frames.emplace_back(f.id, a);
    } catch (const gt::InputError& e) {
      out.unreadable.emplace_back(f.id, e.what());
    }
  }
  return out;
}

nlohmann::ordered_json MeshAgreementJson(const MeshAgreement& m, const ScanArgs& args) {
  nlohmann::ordered_json j;
  j["mesh"] = m.mesh;
  j["tolerance"] = {{"abs_tol_m", args.tolerance.abs_tol_m}, {"rel_tol", args.tolerance.rel_tol}};
  j["frames"] = nlohmann::ordered_json::array();
  for (const auto& [id, a] : m.frames) {
    nlohmann::ordered_json f = gt::truth::DepthAgreementJson(a);
    f["id"] = id;
    j["frames"].push_back(f);
  }
  j["total"] = gt::truth::DepthAgreementJson(m.total);
  j["unreadable"] = nlohmann::ordered_json::array();
  for (const auto& [id, error] : m.unreadable)
    j["unreadable"].push_back({{"id", id}, {"error", error}});
  return j;
}

nlohmann::ordered_json ReasonsJson(const std::map<std::string, size_t>& reasons) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [reason, count] : reasons) j[reason] = count;
  return j;
}

nlohmann::ordered_json ExamplesJson(
    const std::map<std::string, std::vector<gt::datasets::UnusableExample>>& examples) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [reason, list] : examples) {
    j[reason] = nlohmann::ordered_json::array();
    for (const auto& e : list) j[reason].push_back({{"frame", e.frame}, {"detail", e.detail}});
  }
  return j;
}

nlohmann::ordered_json SceneJson(const gt::datasets::SceneSummary& s) {
  nlohmann::ordered_json j;
  j["name"] = s.name;
  j["path"] = s.path;
  j["frames"] = s.frames;
  j["usable"] = s.usable;
  j["unusable"] = s.unusable();
  j["unusable_reasons"] = ReasonsJson(s.unusable_reasons);
  j["unusable_examples"] = ExamplesJson(s.unusable_examples);
  // No frame with a depth camera (a MegaDepth scene without its model): null, as colour's.
  if (s.depth_camera.width > 0 && s.depth_camera.height > 0) {
    j["depth_size"] = {s.depth_camera.width, s.depth_camera.height};
    j["K"] = gt::truth::MatrixJson(s.depth_camera.K());
  } else {
    j["depth_size"] = nullptr;
    j["K"] = nullptr;
  }
  j["uniform_depth_camera"] = s.uniform_depth_camera;
  j["depth_range_m"] = {s.min_depth_m, s.max_depth_m};
  if (s.usable_with_color > 0) {
    j["color"] = {{"usable_with_color", s.usable_with_color},
                  {"size", {s.color_camera.width, s.color_camera.height}},
                  {"K", gt::truth::MatrixJson(s.color_camera.K())},
                  {"uniform_color_camera", s.uniform_color_camera}};
  } else {
    j["color"] = {{"usable_with_color", 0},
                  {"size", nullptr},
                  {"K", nullptr},
                  {"uniform_color_camera", true}};
  }
  j["warnings"] = s.warnings;
  if (s.depth_checked) {
    j["depth_check"] = {{"files_read", s.depth_files_read},
                        {"files_bad", s.depth_files_bad},
                        {"mean_valid_fraction", s.mean_valid_fraction},
                        {"errors", s.depth_errors}};
  } else {
    j["depth_check"] = nullptr;
  }
  return j;
}

void PrintSceneText(const gt::datasets::SceneSummary& s) {
  std::ostringstream out;
  const gt::Camera& c = s.depth_camera;
  out << "scene " << gt::OneLine(s.name) << "  (" << gt::OneLine(s.path) << ")\n"
      << "  frames " << s.frames << ", usable " << s.usable << ", unusable " << s.unusable() << "\n"
      << "  depth ";
  if (c.width > 0 && c.height > 0) {
    out << c.width << "x" << c.height << ", K fx=" << c.fx << " fy=" << c.fy << " cx=" << c.cx
        << " cy=" << c.cy << (s.uniform_depth_camera ? "" : " (first frame; varies)");
  } else {
    out << "camera unknown (no frame has one)";
  }
  out << ", valid range [" << s.min_depth_m << ", " << s.max_depth_m << "] m\n";
  for (const auto& [reason, count] : s.unusable_reasons) {
    out << "  unusable " << count << ": " << reason << "\n";
    const auto it = s.unusable_examples.find(reason);
    const size_t listed = it == s.unusable_examples.end() ? 0 : it->second.size();
    for (size_t i = 0; i < listed; ++i) {
      const gt::datasets::UnusableExample& e = it->second[i];
      // One line each, whatever a path holds (a newline in a folder name as \x0a).
      out << "    frame " << gt::OneLine(e.frame)
          << (e.detail.empty() ? "" : ": " + gt::OneLine(e.detail)) << "\n";
    }
    if (listed > 0 && listed < count) out << "    ... and " << count - listed << " more\n";
  }
  const gt::Camera& cc = s.color_camera;
  out << "  colour " << s.usable_with_color << " of " << s.usable << " usable frames";
  if (s.usable_with_color > 0) {
    out << ", " << cc.width << "x" << cc.height << ", K fx=" << cc.fx << " fy=" << cc.fy
        << " cx=" << cc.cx << " cy=" << cc.cy
        << (s.uniform_color_camera ? "" : " (first frame; varies)");
  }
  out << "\n";
  for (const auto& w : s.warnings) out << "  warning: " << gt::OneLine(w) << "\n";
  if (s.depth_checked) {
    out << "  depth check: " << s.depth_files_read << " read, " << s.depth_files_bad
        << " bad, mean valid fraction " << s.mean_valid_fraction << "\n";
    for (const auto& e : s.depth_errors) out << "    " << gt::OneLine(e) << "\n";
  }
  std::cout << out.str();
}

void RunScan(const ScanArgs& args) {
  if (!std::isfinite(args.reader.tum_max_dt_s) || args.reader.tum_max_dt_s < 0) {
    std::ostringstream given;  // as written: -1, inf, nan (not to_string's -1.000000)
    given << args.reader.tum_max_dt_s;
    throw gt::InputError("--tum-max-dt",
                         "expected a finite number of seconds >= 0, got '" + given.str() + "'");
  }
  const gt::DatasetFormat format = gt::ParseDatasetFormat(args.format, "--format");
  gt::datasets::ReaderOptions reader_options = args.reader;
  reader_options.scannetpp_device = args.device.Resolve(format);
  if (!args.exr_channel_flag.empty() && format != gt::DatasetFormat::kGeneric) {
    throw gt::InputError(args.exr_channel_flag, "only for the generic format");
  }
  if (!args.tum_flag.empty() && format != gt::DatasetFormat::kTum) {
    throw gt::InputError(args.tum_flag, "only for the tum format");
  }
  // Only ScanNet's and ScanNet++'s readers know a scene's mesh; others need --mesh.
  if (!args.mesh_flag.empty() && args.mesh.empty() && format != gt::DatasetFormat::kScanNet &&
      format != gt::DatasetFormat::kScanNetPP) {
    throw gt::InputError(args.mesh_flag, "only with a mesh: --mesh PATH (the " + args.format +
                                             " reader has none of its own)");
  }
  const auto reader = gt::datasets::MakeReader(format, reader_options);
  std::vector<std::string> names;
  if (!args.scene.empty()) {
    names.push_back(args.scene);
  } else {
    names = gt::datasets::ListSceneNames(*reader, args.root);
  }
  if (args.mesh_stride < 1) throw gt::InputError("--mesh-stride", "expected an integer >= 1");
  std::string error;
  if (!args.tolerance.Check(&error)) {
    ThrowOptionsError(error, "scan options",
                      {{"abs_tol_m", "--abs-tol-m", true}, {"rel_tol", "--rel-tol", true}});
  }
  std::vector<gt::datasets::SceneSummary> summaries;
  std::vector<std::optional<MeshAgreement>> agreements;
  for (const auto& name : names) {
    gt::Scene scene = reader->ReadScene(args.root, name);
    gt::pipeline::ApplyMeshPath(args.mesh, &scene);
    summaries.push_back(gt::datasets::SummarizeScene(scene, args.scan));
    agreements.emplace_back();
    if (!scene.mesh_path.empty()) {
      agreements.back() = CompareWithMesh(scene, summaries.back(), args);
    }
  }
  size_t frames = 0, usable = 0, with_color = 0;
  std::map<std::string, size_t> reasons;
  for (const auto& s : summaries) {
    frames += s.frames;
    usable += s.usable;
    with_color += s.usable_with_color;
    for (const auto& [reason, count] : s.unusable_reasons) reasons[reason] += count;
  }
  if (args.json) {
    nlohmann::ordered_json j;
    j["tool"] = "occgt scan";
    j["version"] = 2;  // 2: K as a 3x3 matrix, mesh_depth records with counts (occgt 0.2)
    j["format"] = args.format;
    j["root"] = args.root;
    j["check_depth"] = args.scan.check_depth;
    if (format == gt::DatasetFormat::kScanNetPP) j["device"] = args.device.name;
    j["scenes"] = nlohmann::ordered_json::array();
    for (size_t i = 0; i < summaries.size(); ++i) {
      j["scenes"].push_back(SceneJson(summaries[i]));
      if (agreements[i]) j["scenes"].back()["mesh_depth"] = MeshAgreementJson(*agreements[i], args);
    }
    j["totals"] = {{"scenes", summaries.size()},
                   {"frames", frames},
                   {"usable", usable},
                   {"unusable", frames - usable},
                   {"usable_with_color", with_color},
                   {"unusable_reasons", ReasonsJson(reasons)}};
    std::cout << j.dump(2) << "\n";
    return;
  }
  for (size_t i = 0; i < summaries.size(); ++i) {
    PrintSceneText(summaries[i]);
    if (const auto& m = agreements[i]) {
      const double n = static_cast<double>(std::max<int64_t>(1, m->total.Total()));
      std::printf(
          "  mesh %s, %zu frames vs sensor (within %.3g m + %.3g of depth): agree %.3f, "
          "disagree %.3f, mesh only %.3f, sensor only %.3f\n",
          m->mesh.c_str(), m->frames.size(), args.tolerance.abs_tol_m, args.tolerance.rel_tol,
          m->total.agree / n, m->total.disagree / n, m->total.mesh_only / n,
          m->total.sensor_only / n);
      if (!m->unreadable.empty()) {
        std::printf("  mesh comparison skipped %zu unreadable frame(s), first %s: %s\n",
                    m->unreadable.size(), m->unreadable[0].first.c_str(),
                    m->unreadable[0].second.c_str());
      }
    }
  }
  std::cout << "total: " << summaries.size() << " scene(s), " << frames << " frames, " << usable
            << " usable (" << with_color << " with colour), " << frames - usable << " unusable\n";
}

}  // namespace

void AddScanCommand(CLI::App& app) {
  auto args = std::make_shared<ScanArgs>();
  auto* cmd = app.add_subcommand("scan", "List the scenes and frames of a dataset root");
  cmd->add_option("root", args->root, "Dataset root, scene folder or manifest")->required();
  cmd->add_option("--format", args->format,
                  "Dataset layout: scannet, tartanair, sevenscenes, tum, megadepth, generic, "
                  "scannetpp")
      ->required();
  cmd->add_option("--scene", args->scene, "Only this scene (a name listed by scan)");
  cmd->add_flag("--json", args->json, "Print one JSON document (schemas/scan.schema.json)");
  cmd->add_flag("--check-depth", args->scan.check_depth,
                "Read every depth file (size check and valid fraction) and every colour "
                "file's header");
  cmd->add_option("--tum-max-dt", args->reader.tum_max_dt_s,
                  "TUM: max time difference for pose/colour association (s)")
      ->capture_default_str();
  AddDeviceFlag(cmd, &args->device);
  cmd->add_option("--exr-channel", args->reader.exr_channel,
                  "Generic: default EXR depth channel (name or suffix)");
  cmd->add_option("--mesh", args->mesh,
                  "A mesh for the scenes ({scene} = the scene's name; default: the dataset's own, "
                  "e.g. ScanNet's <scene>_vh_clean_2.ply): sensor vs rendered depth per frame");
  cmd->add_option("--mesh-stride", args->mesh_stride,
                  "With a mesh: compare every n-th usable frame (default 1)");
  cmd->add_option("--abs-tol-m", args->tolerance.abs_tol_m,
                  "With a mesh: sensor and mesh agree within abs-tol-m + rel-tol * depth (0.2)");
  cmd->add_option("--rel-tol", args->tolerance.rel_tol, "With a mesh: see --abs-tol-m (0.01)");
  cmd->callback([args, cmd] {
    const auto first_given = [cmd](std::initializer_list<const char*> flags) {
      for (const char* f : flags) {
        if (cmd->get_option(f)->count() > 0) return std::string(f);
      }
      return std::string();
    };
    args->exr_channel_flag = first_given({"--exr-channel"});
    args->tum_flag = first_given({"--tum-max-dt"});
    args->mesh_flag = first_given({"--mesh-stride", "--abs-tol-m", "--rel-tol"});
    RunScan(*args);
  });
}

}  // namespace occgt

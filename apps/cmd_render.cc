// occgt render --root R --format F --scene S [--mesh M] [--frames ID,ID,...] [--stride N]
//   [--resolution WxH] [--near-m A] [--far-m B] [--abs-tol-m T] [--rel-tol R] --out DIR
// Depth rendered from the scene's mesh (libgt/render) at the frames' poses, in their depth
// camera: per frame <id>_depth.npy (float32 metres), <id>_depth.png (uint16 mm), and
// <id>_triangles.npy (int32, -1 = none), <id>_picture.png (sensor | rendered | agreement when
// the frame has sensor depth), and render.json (schemas/render.schema.json) with the
// sensor-vs-mesh counts of every frame and in total. docs/CLI.md "render".
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/job_flags.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/folder_lock.h"
#include "libgt/io/npy.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/render/depth_picture.h"
#include "libgt/render/frame_depth.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/working_frame.h"

namespace occgt {
namespace {

struct RenderArgs {
  std::string root, format, scene, mesh, frames, out;
  DeviceFlag device;
  int stride = 1;
  std::optional<std::string> resolution;
  gt::render::FrameDepthOptions depth;
};

// The temporary names of render's own files in DIR: "<id>_depth.npy.part" (and the other
// three per frame) until every frame is done, "<name>.part.tmp" and "render.json.tmp" while
// one is written (io::WriteFileAtomic). Removed on Ctrl-C or SIGTERM, and as stale by the
// next run into DIR (one that was killed left them); no other file is.
TemporaryNames RenderTemporaries(const std::string& out_dir) {
  TemporaryNames names;
  names.dir = out_dir;
  for (const char* file : {"_depth.npy", "_depth.png", "_triangles.npy", "_picture.png"}) {
    names.suffixes.push_back(std::string(file) + ".part");
    names.suffixes.push_back(std::string(file) + ".part.tmp");
  }
  names.names = {"render.json.tmp"};
  return names;
}

void RunRender(const RenderArgs& args) {
  ExitOnInterrupt("the files of this run are removed, earlier ones kept; re-run the same command");
  std::string error;
  if (!args.depth.Check(&error)) {
    ThrowOptionsError(error, "render options",
                      {{"near_m", "--near-m", true},
                       {"far_m", "--far-m", true},
                       {"abs_tol_m", "--abs-tol-m", true},
                       {"rel_tol", "--rel-tol", true}});
  }
  if (args.stride < 1) throw gt::InputError("--stride", "expected an integer >= 1");
  const gt::DatasetFormat format = gt::ParseDatasetFormat(args.format, "--format");
  std::optional<gt::truth::Resolution> resolution;
  if (args.resolution) resolution = gt::truth::ParseResolution(*args.resolution, "--resolution");
  gt::datasets::ReaderOptions reader_options;
  reader_options.scannetpp_device = args.device.Resolve(format);
  gt::Scene scene =
      gt::datasets::MakeReader(format, reader_options)->ReadScene(args.root, args.scene);
  gt::pipeline::ApplyMeshPath(args.mesh, &scene);
  if (scene.mesh_path.empty()) {
    throw gt::InputError("--mesh", "scene " + scene.name + " has no mesh of its own" +
                                       scene.MissingMeshNote() + ": give one");
  }
  std::vector<size_t> frames;
  if (!args.frames.empty()) {
    for (const std::string& id : SplitList(args.frames, "--frames", "frame ids")) {
      frames.push_back(gt::truth::FindFrame(scene, id));
    }
  } else {
    int k = 0;
    for (size_t i = 0; i < scene.frames.size(); ++i) {
      if (scene.frames[i].usable && k++ % args.stride == 0) frames.push_back(i);
    }
    if (frames.empty()) {  // nothing to render: say why (an empty render.json said nothing)
      const gt::Frame* first = nullptr;
      for (const gt::Frame& f : scene.frames) {
        if (!f.usable) {
          first = &f;
          break;
        }
      }
      throw gt::InputError(
          scene.name, scene.frames.empty()
                          ? std::string("no frames to render")
                          : "no usable frame to render (" + std::to_string(scene.frames.size()) +
                                " unusable; the first, " + first->id + ": " +
                                first->UnusableMessage() + "; occgt scan lists them all)");
    }
  }
  const auto renderer = gt::render::SharedMeshRenderer(scene.mesh_path);
  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec) throw gt::InputError(args.out, "cannot create the folder: " + ec.message());
  // One render per folder at a time (a second one would remove the first one's temporaries
  // as stale): byte 0 of DIR/.render.lock, released when the process ends.
  const std::unique_ptr<gt::io::FileLock> lock =
      gt::io::FileLock::TryAcquire(args.out + "/.render.lock", 0);
  if (!lock) {
    throw gt::InputError(args.out,
                         "another occgt render is writing this folder now; wait for "
                         "it to end or use another --out");
  }
  const TemporaryNames temporaries = RenderTemporaries(args.out);
  RemoveTemporaries(temporaries);  // of an earlier run that was killed (SIGKILL, a crash)
  RemoveOnInterrupt(temporaries);
  gt::render::RenderOptions options;
  options.near_m = args.depth.near_m;
  options.far_m = args.depth.far_m;
  options.triangle_ids = true;

  nlohmann::ordered_json report;
  report["scene"] = scene.name;
  report["format"] = gt::DatasetFormatName(format);
  report["mesh"] = scene.mesh_path;
  report["triangles"] = renderer->NumTriangles();
  report["near_m"] = options.near_m;
  report["far_m"] = options.far_m;
  report["tolerance"] = {{"abs_tol_m", args.depth.fused.abs_tol_m},
                         {"rel_tol", args.depth.fused.rel_tol}};
  report["frames"] = nlohmann::ordered_json::array();
  gt::render::DepthAgreement total;
  bool any_sensor = false, any_hit = false;
  // Every file is written under "<name>.part" first and renamed once every frame is done,
  // so that a frame failing halfway leaves no file of this run (and replaces none of an
  // earlier one); render.json comes last.
  std::vector<std::string> staged;
  const auto stage = [&](const std::string& path, const std::string& bytes) {
    gt::io::WriteFileAtomic(path + ".part", bytes);
    staged.push_back(path);
  };
  const auto unstage = [&] {
    std::error_code ec;
    for (const std::string& path : staged) std::filesystem::remove(path + ".part", ec);
  };
  try {
    for (size_t i : frames) {
      const gt::Frame& frame = scene.frames[i];
      const gt::Camera camera =
          resolution ? gt::truth::WorkingCamera(frame, *resolution) : frame.depth_camera;
      const gt::render::RenderedDepth r = renderer->Render(camera, frame.world_from_cam, options);
      gt::DepthImage mesh(camera.width, camera.height);
      mesh.values_m.assign(r.depth_m.begin(), r.depth_m.end());
      // A pixel without image (anonymised, outside a distorted camera's image) has no depth
      // and no triangle, as the frame's depth everywhere else (Scene.load, pair, exports).
      gt::io::ApplyFrameMask(frame, &mesh);
      std::vector<int32_t> ids(r.triangle_id.begin(), r.triangle_id.end());
      for (size_t k = 0; k < ids.size(); ++k) {
        if (mesh.values_m[k] == 0.0f) ids[k] = -1;
      }
      std::vector<uint16_t> mm(mesh.values_m.size());
      for (size_t k = 0; k < mm.size(); ++k) {
        const double v = std::round(mesh.values_m[k] * 1000.0);
        mm[k] = v >= 1 && v <= 65535 ? static_cast<uint16_t>(v) : 0;  // beyond 65.535 m: none
      }
      std::optional<gt::DepthImage> sensor;
      std::string sensor_error;  // a sensor depth file that cannot be read: the frame still renders
      if (!frame.depth.path.empty() && gt::io::FileExists(frame.depth.path)) {
        try {
          sensor = gt::truth::LoadWorkingDepth(frame, {camera.width, camera.height});
        } catch (const gt::InputError& e) {
          sensor_error = e.what();
        }
      }
      nlohmann::ordered_json fj;
      fj["id"] = frame.id;
      fj["size"] = {camera.width, camera.height};
      int64_t hits = 0;
      for (float d : mesh.values_m) hits += d > 0;
      any_hit = any_hit || hits > 0;
      fj["rendered_fraction"] =
          static_cast<double>(hits) / std::max<size_t>(1, mesh.values_m.size());
      if (sensor) {
        const gt::render::DepthAgreement a = gt::render::CompareSensorAndMesh(
            *sensor, mesh, scene.min_depth_m, scene.max_depth_m, args.depth.fused);
        total += a;
        any_sensor = true;
        fj["sensor"] = gt::truth::DepthAgreementJson(a);
      } else {
        fj["sensor"] = nullptr;
        if (!sensor_error.empty()) fj["sensor_error"] = sensor_error;
      }
      const std::vector<int64_t> shape = {camera.height, camera.width};
      const cv::Mat png16(camera.height, camera.width, CV_16UC1, mm.data());
      const cv::Mat picture =
          gt::render::DepthComparisonPicture(sensor ? &*sensor : nullptr, mesh, scene.min_depth_m,
                                             scene.max_depth_m, args.depth.fused);
      const std::string base = args.out + "/" + frame.id;
      stage(base + "_depth.npy", gt::io::EncodeNpy<float>(shape, mesh.values_m));
      stage(base + "_depth.png",
            gt::io::EncodePngBytes(png16, gt::io::ChannelOrder::kRgb, 6, base + "_depth.png"));
      stage(base + "_triangles.npy", gt::io::EncodeNpy<int32_t>(shape, ids));
      stage(base + "_picture.png",
            gt::io::EncodePngBytes(picture, gt::io::ChannelOrder::kRgb, 6, base + "_picture.png"));
      report["frames"].push_back(fj);
    }
    // Published as a whole: an interrupt now waits for the renames and render.json.
    const HoldInterrupts hold;
    for (const std::string& path : staged) {
      std::error_code ec;
      std::filesystem::rename(path + ".part", path, ec);
      if (ec) throw gt::InputError(path, "cannot rename " + path + ".part: " + ec.message());
    }
    report["total"] =
        any_sensor ? gt::truth::DepthAgreementJson(total) : nlohmann::ordered_json(nullptr);
    gt::io::WriteFileAtomic(args.out + "/render.json", report.dump(2) + "\n");
  } catch (...) {
    unstage();
    throw;
  }
  std::printf("render %s: %zu frames of %s (%zu triangles)", scene.name.c_str(), frames.size(),
              scene.mesh_path.c_str(), renderer->NumTriangles());
  if (any_sensor) {
    const double n = static_cast<double>(std::max<int64_t>(1, total.Total()));
    std::printf(
        "; vs sensor (tolerance %.3g m + %.3g of depth): agree %.3f, disagree %.3f, mesh only "
        "%.3f, "
        "sensor only %.3f",
        args.depth.fused.abs_tol_m, args.depth.fused.rel_tol, total.agree / n, total.disagree / n,
        total.mesh_only / n, total.sensor_only / n);
  }
  std::printf(" -> %s\n", args.out.c_str());
  int unreadable = 0;
  for (const auto& fj : report["frames"]) {
    if (!fj.contains("sensor_error")) continue;
    if (unreadable++ == 0) {
      std::printf("  sensor depth unreadable for frame %s: %s\n",
                  fj["id"].get<std::string>().c_str(),
                  fj["sensor_error"].get<std::string>().c_str());
    }
  }
  if (unreadable > 1)
    std::printf("  ... and %d more frame(s) (render.json: sensor_error)\n", unreadable - 1);
  // A mesh in other units (millimetres) or another world frame renders nothing, silently.
  if (!frames.empty() && !any_hit) {
    std::printf(
        "  warning: the mesh covers no pixel of any frame: is it in metres and in the "
        "frames' world frame (the poses')?\n");
  }
}

}  // namespace

void AddRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand(
      "render", "Render depth and triangle ids of frames from the scene's mesh (docs/CLI.md)");
  cmd->add_option("--root", args->root, "dataset root")->required();
  cmd->add_option("--format", args->format, "dataset format (scannet, sevenscenes, ...)")
      ->required();
  AddDeviceFlag(cmd, &args->device);
  cmd->add_option("--scene", args->scene, "scene name (see occgt scan)")->required();
  cmd->add_option("--mesh", args->mesh,
                  "the scene's mesh (PLY, in the poses' world frame; default: the dataset's own)");
  auto* frames = cmd->add_option("--frames", args->frames,
                                 "frame ids ID,ID,... (default: every usable frame)");
  cmd->add_option("--stride", args->stride, "without --frames: every n-th usable frame")
      ->capture_default_str()
      ->excludes(frames);
  cmd->add_option("--resolution", args->resolution, "WxH (default: the depth camera's size)");
  cmd->add_option("--near-m", args->depth.near_m, "nearest depth rendered (m)")
      ->capture_default_str();
  cmd->add_option("--far-m", args->depth.far_m, "farthest depth rendered (m)")
      ->capture_default_str();
  cmd->add_option("--abs-tol-m", args->depth.fused.abs_tol_m,
                  "sensor and mesh agree within abs-tol-m + rel-tol * depth")
      ->capture_default_str();
  cmd->add_option("--rel-tol", args->depth.fused.rel_tol, "see --abs-tol-m")->capture_default_str();
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->callback([args] { RunRender(*args); });
}

}  // namespace occgt

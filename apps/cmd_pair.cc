// occgt pair --root R --format F --scene S --frames ID0,ID1 [--preset P] [overrides] --out DIR
// Labels one pair of frames (GROUND_TRUTH.md §2–4) at the working resolution and writes
// label01.npy, label10.npy (uint8 HxW), matches.npy (int32 Mx2), match_type.npy (uint8 M),
// match_xy.npy (float32 Mx2), cells0.npy, cells1.npy (uint8 (H/s)x(W/s)) and meta.json
// (schemas/pair_meta.schema.json). Layouts: docs/GROUND_TRUTH.md.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "gt/core/version.h"
#include "libgt/core/error.h"
#include "libgt/geometry/pair.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/files.h"
#include "libgt/io/npy.h"
#include "libgt/io/reader.h"

namespace occgt {
namespace {

struct PairArgs {
  std::string root, format, scene, frames, out;
  std::string preset = "default";
  std::string resolution = "640x480";
  std::optional<double> abs_tol_m, rel_tol, min_depth_m, max_depth_m;
  std::string relative_to, bounds, target_lookup, missing_target, anchor = "center";
  int stride = 8;
  bool no_mutual = false;
  int score_stride = 1;
};

std::pair<int, int> ParseResolution(const std::string& s) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  std::istringstream in(s);
  // Same bounds as a recipe's resolution: a typo such as 60000x60000 must not become a
  // multi-gigabyte allocation (std::bad_alloc).
  if (!(in >> w >> x >> h) || x != 'x' || (in >> extra) || w <= 0 || h <= 0 || w > 8192 ||
      h > 8192) {
    throw gt::InputError("--resolution",
                         "expected WxH with integers in 1..8192, got '" + s + "'");
  }
  return {w, h};
}

const gt::Frame& FindFrame(const gt::Scene& scene, const std::string& id) {
  for (const auto& f : scene.frames) {
    if (f.id != id) continue;
    if (!f.usable)
      throw gt::InputError("--frames", "frame " + id + " is unusable: " + f.unusable_reason);
    return f;
  }
  throw gt::InputError("--frames", "no frame with id '" + id + "' in scene " + scene.name);
}

nlohmann::ordered_json PoseJson(const gt::Rigid3d& pose) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

nlohmann::ordered_json KJson(const gt::Camera& c) {
  return {{c.fx, 0.0, c.cx}, {0.0, c.fy, c.cy}, {0.0, 0.0, 1.0}};
}

nlohmann::ordered_json MetricsJson(const gt::DirectionMetrics& m) {
  nlohmann::ordered_json counts;
  for (int k = 0; k < gt::kNumPixelLabels; ++k) {
    counts[gt::PixelLabelName(static_cast<gt::PixelLabel>(k))] = m.counts[k];
  }
  return {{"sampled", m.sampled},
          {"valid", m.valid},
          {"counts", counts},
          {"overlap", m.overlap},
          {"consistent_overlap", m.consistent_overlap},
          {"occlusion_ratio", m.occlusion_ratio},
          {"occlusion_ratio_visible", m.occlusion_ratio_visible}};
}

void RunPair(const PairArgs& args) {
  // Options first: bad flags fail before any file is read.
  gt::LabelOptions lo = gt::LabelPreset(args.preset);
  if (args.abs_tol_m) lo.abs_tol_m = *args.abs_tol_m;
  if (args.rel_tol) lo.rel_tol = *args.rel_tol;
  if (!args.relative_to.empty()) lo.relative_to = gt::ParseRelativeTo(args.relative_to);
  if (!args.bounds.empty()) lo.bounds = gt::ParseBounds(args.bounds);
  if (!args.target_lookup.empty()) lo.target_lookup = gt::ParseTargetLookup(args.target_lookup);
  if (!args.missing_target.empty()) {
    lo.missing_target = gt::ParseMissingTarget(args.missing_target);
  }
  gt::PatchOptions po;
  po.stride = args.stride;
  po.anchor = gt::ParseAnchor(args.anchor);
  po.mutual = !args.no_mutual;
  std::string error;
  if (!po.Check(&error)) throw gt::InputError("--stride", error);
  if (args.score_stride < 1) throw gt::InputError("--score-stride", "expected >= 1");
  const auto [width, height] = ParseResolution(args.resolution);
  const size_t comma = args.frames.find(',');
  if (comma == std::string::npos || comma == 0 || comma + 1 == args.frames.size() ||
      args.frames.find(',', comma + 1) != std::string::npos) {
    throw gt::InputError("--frames", "expected two frame ids ID0,ID1, got '" + args.frames + "'");
  }
  const std::string id0 = args.frames.substr(0, comma), id1 = args.frames.substr(comma + 1);

  const auto reader = gt::io::MakeReader(args.format);
  const gt::Scene scene = reader->ReadScene(args.root, args.scene);
  // Dataset validity range unless overridden.
  lo.min_depth_m = args.min_depth_m.value_or(scene.min_depth_m);
  lo.max_depth_m = args.max_depth_m.value_or(scene.max_depth_m);
  if (!lo.Check(&error)) throw gt::InputError("label options", error);
  const gt::Frame& f0 = FindFrame(scene, id0);
  const gt::Frame& f1 = FindFrame(scene, id1);
  const gt::DepthImage raw0 =
      gt::io::ReadDepth(f0.depth, f0.depth_camera.width, f0.depth_camera.height);
  const gt::DepthImage raw1 =
      gt::io::ReadDepth(f1.depth, f1.depth_camera.width, f1.depth_camera.height);
  const gt::DepthImage d0 = gt::ResizeDepthNearest(raw0, width, height);
  const gt::DepthImage d1 = gt::ResizeDepthNearest(raw1, width, height);
  const gt::Camera c0 = f0.depth_camera.Resized(width, height);
  const gt::Camera c1 = f1.depth_camera.Resized(width, height);
  const gt::PairLabels p =
      gt::LabelPair(d0, c0, f0.world_from_cam, d1, c1, f1.world_from_cam, lo, po);
  gt::DirectionMetrics m01 = p.m01, m10 = p.m10;
  if (args.score_stride != 1) {
    m01 = gt::MetricsFromLabels(p.l01, args.score_stride);
    m10 = gt::MetricsFromLabels(p.l10, args.score_stride);
  }

  const std::string& out = args.out;
  const int64_t m = static_cast<int64_t>(p.patches.size());
  const auto& pm = p.patches;
  gt::io::WriteNpy<uint8_t>(out + "/label01.npy", {height, width}, p.l01.labels);
  gt::io::WriteNpy<uint8_t>(out + "/label10.npy", {height, width}, p.l10.labels);
  gt::io::WriteNpy<int32_t>(out + "/matches.npy", {m, 2}, pm.matches);
  gt::io::WriteNpy<uint8_t>(out + "/match_type.npy", {m}, pm.match_type);
  gt::io::WriteNpy<float>(out + "/match_xy.npy", {m, 2}, pm.match_xy);
  gt::io::WriteNpy<uint8_t>(out + "/cells0.npy", {pm.cells_h0, pm.cells_w0}, pm.cells0);
  gt::io::WriteNpy<uint8_t>(out + "/cells1.npy", {pm.cells_h1, pm.cells_w1}, pm.cells1);

  nlohmann::ordered_json j;
  j["tool"] = "occgt pair";
  j["occgt_version"] = gt::kVersion;
  j["format"] = args.format;
  j["scene"] = scene.name;
  j["frames"] = {id0, id1};
  j["resolution"] = {width, height};
  j["K0"] = KJson(c0);
  j["K1"] = KJson(c1);
  j["world_from_cam0"] = PoseJson(f0.world_from_cam);
  j["world_from_cam1"] = PoseJson(f1.world_from_cam);
  j["cam1_from_cam0"] = PoseJson(p.cam1_from_cam0);
  j["preset"] = args.preset;
  j["label_options"] = {{"min_depth_m", lo.min_depth_m},
                        {"max_depth_m", lo.max_depth_m},
                        {"abs_tol_m", lo.abs_tol_m},
                        {"rel_tol", lo.rel_tol},
                        {"relative_to", gt::RelativeToName(lo.relative_to)},
                        {"bounds", gt::BoundsName(lo.bounds)},
                        {"target_lookup", gt::TargetLookupName(lo.target_lookup)},
                        {"missing_target", gt::MissingTargetName(lo.missing_target)},
                        {"cheirality", lo.cheirality},
                        {"projection_eps_m", lo.projection_eps_m}};
  j["patch_options"] = {
      {"stride", po.stride}, {"anchor", gt::AnchorName(po.anchor)}, {"mutual", po.mutual}};
  j["score_stride"] = args.score_stride;
  j["label_codes"] = nlohmann::ordered_json::object();
  for (int k = 0; k < gt::kNumPixelLabels; ++k) {
    j["label_codes"][gt::PixelLabelName(static_cast<gt::PixelLabel>(k))] = k;
  }
  j["metrics01"] = MetricsJson(m01);
  j["metrics10"] = MetricsJson(m10);
  int64_t by_type[3] = {0, 0, 0};
  for (uint8_t t : pm.match_type) ++by_type[t];
  j["matches"] = {{"total", m}, {"vv", by_type[0]}, {"vo", by_type[1]}, {"ov", by_type[2]}};
  gt::io::WriteFileAtomic(out + "/meta.json", j.dump(2) + "\n");

  std::printf(
      "pair %s %s,%s: overlap %.3f / %.3f, occlusion %.3f / %.3f, matches %lld "
      "(vv %lld, vo %lld, ov %lld) -> %s\n",
      scene.name.c_str(), id0.c_str(), id1.c_str(), m01.overlap, m10.overlap, m01.occlusion_ratio,
      m10.occlusion_ratio, static_cast<long long>(m), static_cast<long long>(by_type[0]),
      static_cast<long long>(by_type[1]), static_cast<long long>(by_type[2]), out.c_str());
}

}  // namespace

void AddPairCommand(CLI::App& app) {
  auto args = std::make_shared<PairArgs>();
  auto* cmd = app.add_subcommand("pair", "label one pair of frames and write its ground truth");
  cmd->add_option("--root", args->root, "dataset root")->required();
  cmd->add_option("--format", args->format, "dataset format (scannet, tartanair, ...)")->required();
  cmd->add_option("--scene", args->scene, "scene name (see occgt scan)")->required();
  cmd->add_option("--frames", args->frames, "two frame ids: ID0,ID1")->required();
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->add_option("--preset", args->preset,
                  "label preset: default, occ2net, occ2net-compat, loftr, superglue");
  cmd->add_option("--resolution", args->resolution, "working resolution WxH (default 640x480)");
  cmd->add_option("--abs-tol-m", args->abs_tol_m, "absolute depth tolerance (m)");
  cmd->add_option("--rel-tol", args->rel_tol, "relative depth tolerance (fraction)");
  cmd->add_option("--relative-to", args->relative_to, "projected|observed");
  cmd->add_option("--bounds", args->bounds, "pixel-area|strict");
  cmd->add_option("--target-lookup", args->target_lookup, "nearest|truncate");
  cmd->add_option("--missing-target", args->missing_target, "unknown|as-zero-depth");
  cmd->add_option("--min-depth-m", args->min_depth_m, "minimum valid depth (dataset default)");
  cmd->add_option("--max-depth-m", args->max_depth_m, "maximum valid depth (dataset default)");
  cmd->add_option("--stride", args->stride, "patch cell size in pixels (default 8)");
  cmd->add_option("--anchor", args->anchor, "center|corner (default center)");
  cmd->add_flag("--no-mutual", args->no_mutual, "keep vv matches without the loop-back check");
  cmd->add_option("--score-stride", args->score_stride,
                  "metrics on every N-th pixel in x and y (default 1)");
  cmd->callback([args] { RunPair(*args); });
}

}  // namespace occgt

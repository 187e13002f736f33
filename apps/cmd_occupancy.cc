// occgt occupancy --root R --format F --scene S --frames ID0,ID1 [--resolution WxH] --out DIR
//   [--voxel-m 0.05] [--max-range-m 10] [--near-m 0.1] [--far-m 10] [--bins 64]
//   [--spacing linear|log|inverse] [--traversal exact|center] [--scope pair|window:N|scene:S]
//   [--mode octomap|two_point] [--dense] [--save-octree map.bt]
// Occupancy target of one pair (GROUND_TRUTH.md §5, docs/OCCUPANCY.md): writes occ0.npy,
// known0.npy, occ1.npy, known1.npy (uint64 [H/2, W/2]), with --dense occupancy0.npy and
// occupancy1.npy (uint8 [bins, H/2, W/2]), and occupancy.json
// (schemas/occupancy.schema.json).
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "gt/core/version.h"
#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/files.h"
#include "libgt/io/npy.h"
#include "libgt/io/reader.h"
#include "libgt/occupancy/pair_occupancy.h"

namespace occgt {
namespace {

namespace occ = gt::occupancy;

struct OccupancyArgs {
  std::string root, format, scene, frames, out;
  std::string resolution = "640x480";
  std::optional<double> min_depth_m, max_depth_m;
  double voxel_m = 0.05, max_range_m = 10.0, near_m = 0.1, far_m = 10.0;
  int bins = 64;
  std::string spacing = "linear", traversal = "exact", scope = "pair", mode = "octomap";
  bool dense = false, downsample = false, no_downsample = false, remove_outliers = false;
  std::string save_octree;
};

std::pair<int, int> ParseResolution(const std::string& s) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  std::istringstream in(s);
  if (!(in >> w >> x >> h) || x != 'x' || (in >> extra) || w <= 1 || h <= 1 || w > 8192 ||
      h > 8192) {
    throw gt::InputError("--resolution", "expected WxH with integers in 2..8192, got '" + s + "'");
  }
  return {w, h};
}

size_t FindFrame(const gt::Scene& scene, const std::string& id) {
  for (size_t i = 0; i < scene.frames.size(); ++i) {
    const auto& f = scene.frames[i];
    if (f.id != id) continue;
    if (!f.usable)
      throw gt::InputError("--frames", "frame " + id + " is unusable: " + f.unusable_reason);
    return i;
  }
  throw gt::InputError("--frames", "no frame with id '" + id + "' in scene " + scene.name);
}

nlohmann::ordered_json CountsJson(const occ::FrustumVolume& v) {
  const occ::VolumeCounts c = occ::CountBins(v);
  const double total = static_cast<double>(c.occupied + c.free + c.unknown);
  return {{"occupied", c.occupied},
          {"free", c.free},
          {"unknown", c.unknown},
          {"occupied_fraction", total > 0 ? c.occupied / total : 0.0},
          {"free_fraction", total > 0 ? c.free / total : 0.0},
          {"unknown_fraction", total > 0 ? c.unknown / total : 0.0}};
}

void RunOccupancy(const OccupancyArgs& args) {
  // Options first: bad flags fail before any file is read.
  occ::FusionOptions fo;
  fo.voxel_size_m = args.voxel_m;
  fo.max_range_m = args.max_range_m;
  if (args.downsample && args.no_downsample)
    throw gt::InputError("--downsample", "conflicts with --no-downsample");
  fo.downsample = args.downsample;  // off by default, as in the library and `build`
  fo.remove_outliers = args.remove_outliers;
  occ::ParseFusionScope(args.scope, &fo);
  std::string error;
  if (!fo.Check(&error)) throw gt::InputError("fusion options", error);
  occ::BinOptions bo;
  bo.num_bins = args.bins;
  bo.near_m = args.near_m;
  bo.far_m = args.far_m;
  bo.spacing = occ::ParseBinSpacing(args.spacing);
  bo.traversal = occ::ParseTraversal(args.traversal);
  if (!bo.Check(&error)) throw gt::InputError("bin options", error);
  const occ::OccupancyMode mode = occ::ParseOccupancyMode(args.mode);
  if (mode == occ::OccupancyMode::kTwoPoint && !args.save_octree.empty())
    throw gt::InputError("--save-octree", "needs --mode octomap");
  const auto [width, height] = ParseResolution(args.resolution);
  const size_t comma = args.frames.find(',');
  if (comma == std::string::npos || comma == 0 || comma + 1 == args.frames.size() ||
      args.frames.find(',', comma + 1) != std::string::npos) {
    throw gt::InputError("--frames", "expected two frame ids ID0,ID1, got '" + args.frames + "'");
  }
  const std::string id0 = args.frames.substr(0, comma), id1 = args.frames.substr(comma + 1);

  const auto reader = gt::io::MakeReader(args.format);
  const gt::Scene scene = reader->ReadScene(args.root, args.scene);
  const double min_depth_m = args.min_depth_m.value_or(scene.min_depth_m);
  const double max_depth_m = args.max_depth_m.value_or(scene.max_depth_m);
  const size_t i0 = FindFrame(scene, id0), i1 = FindFrame(scene, id1);

  // Depth of a frame at the working resolution; the pair's frames must read, others of a
  // window/scene scope are skipped (and reported) when they do not.
  auto load = [&](size_t i, gt::DepthImage* depth, gt::Camera* cam) {
    const gt::Frame& f = scene.frames[i];
    const gt::DepthImage raw =
        gt::io::ReadDepth(f.depth, f.depth_camera.width, f.depth_camera.height);
    *depth = gt::ResizeDepthNearest(raw, width, height);
    *cam = f.depth_camera.Resized(width, height);
  };
  gt::DepthImage d0, d1;
  gt::Camera c0, c1;
  load(i0, &d0, &c0);
  load(i1, &d1, &c1);
  const occ::FusionInput in0{&d0, c0, scene.frames[i0].world_from_cam, min_depth_m, max_depth_m};
  const occ::FusionInput in1{&d1, c1, scene.frames[i1].world_from_cam, min_depth_m, max_depth_m};

  std::vector<std::string> fused_ids;
  nlohmann::ordered_json skipped = nlohmann::ordered_json::array();
  std::optional<occ::OccupancyMap> map;
  occ::PairOccupancy pair;
  if (mode == occ::OccupancyMode::kOctomap) {
    const std::vector<size_t> idx = fo.scope == occ::FusionScope::kPair
                                        ? std::vector<size_t>{i0, i1}
                                        : occ::ScopeFrameIndices(scene, i0, i1, fo);
    std::vector<gt::DepthImage> depths(idx.size());
    std::vector<occ::FusionInput> inputs;
    for (size_t j = 0; j < idx.size(); ++j) {
      gt::Camera cam;
      try {
        load(idx[j], &depths[j], &cam);
      } catch (const gt::InputError& e) {
        if (idx[j] == i0 || idx[j] == i1) throw;
        skipped.push_back({{"frame", scene.frames[idx[j]].id}, {"reason", e.what()}});
        continue;
      }
      inputs.push_back(
          {&depths[j], cam, scene.frames[idx[j]].world_from_cam, min_depth_m, max_depth_m});
      fused_ids.push_back(scene.frames[idx[j]].id);
    }
    map = occ::FuseOccupancy(inputs, fo);
    pair = occ::ComputePairOccupancy(in0, in1, fo, bo, mode, &*map);
  } else {
    pair = occ::ComputePairOccupancy(in0, in1, fo, bo, mode);
  }

  const std::string& out = args.out;
  const int64_t gw = pair.cam0.width, gh = pair.cam0.height;
  gt::io::WriteNpy<uint64_t>(out + "/occ0.npy", {gh, gw}, pair.cam0.occ);
  gt::io::WriteNpy<uint64_t>(out + "/known0.npy", {gh, gw}, pair.cam0.known);
  gt::io::WriteNpy<uint64_t>(out + "/occ1.npy", {gh, gw}, pair.cam1.occ);
  gt::io::WriteNpy<uint64_t>(out + "/known1.npy", {gh, gw}, pair.cam1.known);
  nlohmann::ordered_json files = {"occ0.npy", "known0.npy", "occ1.npy", "known1.npy"};
  if (args.dense) {
    const int64_t d = bo.num_bins;
    gt::io::WriteNpy<uint8_t>(out + "/occupancy0.npy", {d, gh, gw}, occ::DenseVolume(pair.cam0));
    gt::io::WriteNpy<uint8_t>(out + "/occupancy1.npy", {d, gh, gw}, occ::DenseVolume(pair.cam1));
    files.push_back("occupancy0.npy");
    files.push_back("occupancy1.npy");
  }
  if (map && !args.save_octree.empty()) map->SaveBinary(args.save_octree);

  nlohmann::ordered_json j;
  j["tool"] = "occgt occupancy";
  j["occgt_version"] = gt::kVersion;
  j["format"] = args.format;
  j["scene"] = scene.name;
  j["frames"] = {id0, id1};
  j["resolution"] = {width, height};
  j["grid"] = {gw, gh};
  j["mode"] = occ::OccupancyModeName(mode);
  j["encoding"] = {{"occ", "uint64 [H/2, W/2], bit k set: bin k occupied"},
                   {"known", "uint64 [H/2, W/2], bit k set: bin k occupied or free"},
                   {"dense", "uint8 [bins, H/2, W/2]: 0 free, 1 occupied, 255 unknown"}};
  j["bins"] = {{"num_bins", bo.num_bins},
               {"near_m", bo.near_m},
               {"far_m", bo.far_m},
               {"spacing", occ::BinSpacingName(bo.spacing)},
               {"traversal", occ::TraversalName(bo.traversal)},
               {"edges_m", pair.cam0.edges_m}};
  j["fusion"] = {{"scope", occ::FusionScopeName(fo)},
                 {"voxel_size_m", fo.voxel_size_m},
                 {"max_range_m", fo.max_range_m},
                 {"downsample", fo.downsample},
                 {"remove_outliers", fo.remove_outliers},
                 {"outlier_k", fo.outlier_k},
                 {"outlier_stddev", fo.outlier_stddev},
                 {"min_depth_m", min_depth_m},
                 {"max_depth_m", max_depth_m},
                 {"fused_frames", fused_ids},
                 {"skipped_frames", skipped}};
  if (map) {
    const occ::FusionStats& s = map->stats();
    j["fusion"]["stats"] = {{"frames", s.frames},
                            {"pixels", s.pixels},
                            {"invalid_pixels", s.invalid_pixels},
                            {"out_of_key_range", s.out_of_key_range},
                            {"after_downsample", s.after_downsample},
                            {"downsample_fallbacks", s.downsample_fallbacks},
                            {"outliers_removed", s.outliers_removed},
                            {"inserted_points", s.inserted_points},
                            {"leaf_nodes", map->NumLeafNodes()}};
  }
  j["counts0"] = CountsJson(pair.cam0);
  j["counts1"] = CountsJson(pair.cam1);
  j["files"] = files;
  gt::io::WriteFileAtomic(out + "/occupancy.json", j.dump(2) + "\n");

  const auto c = occ::CountBins(pair.cam0);
  const double total = static_cast<double>(c.occupied + c.free + c.unknown);
  std::printf("occupancy %s %s,%s (%s, %s): cam0 occupied %.3f free %.3f unknown %.3f -> %s\n",
              scene.name.c_str(), id0.c_str(), id1.c_str(), occ::OccupancyModeName(mode).c_str(),
              occ::FusionScopeName(fo).c_str(), c.occupied / total, c.free / total,
              c.unknown / total, out.c_str());
  if (!skipped.empty())
    std::printf("skipped %zu frame(s) of the scope (see occupancy.json)\n", skipped.size());
}

}  // namespace

void AddOccupancyCommand(CLI::App& app) {
  auto args = std::make_shared<OccupancyArgs>();
  auto* cmd = app.add_subcommand("occupancy", "64-bin occupancy target of one pair of frames");
  cmd->add_option("--root", args->root, "dataset root")->required();
  cmd->add_option("--format", args->format, "dataset format (scannet, tartanair, ...)")->required();
  cmd->add_option("--scene", args->scene, "scene name (see occgt scan)")->required();
  cmd->add_option("--frames", args->frames, "two frame ids: ID0,ID1")->required();
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->add_option("--resolution", args->resolution, "working resolution WxH (default 640x480)");
  cmd->add_option("--min-depth-m", args->min_depth_m, "minimum valid depth (dataset default)");
  cmd->add_option("--max-depth-m", args->max_depth_m, "maximum valid depth (dataset default)");
  cmd->add_option("--voxel-m", args->voxel_m, "OctoMap resolution in metres (default 0.05)");
  cmd->add_option("--max-range-m", args->max_range_m,
                  "ray truncation in metres, <= 0 unlimited (default 10)");
  cmd->add_option("--near-m", args->near_m, "first bin edge, planar depth (default 0.1)");
  cmd->add_option("--far-m", args->far_m, "last bin edge, planar depth (default 10)");
  cmd->add_option("--bins", args->bins, "number of depth bins, 1..64 (default 64)");
  cmd->add_option("--spacing", args->spacing, "linear|log|inverse (default linear)");
  cmd->add_option("--traversal", args->traversal, "exact|center (default exact)");
  cmd->add_option("--scope", args->scope, "pair|window:N|scene:S (default pair)");
  cmd->add_option("--mode", args->mode, "octomap|two_point (default octomap)");
  cmd->add_flag("--dense", args->dense, "also write occupancy0/1.npy, uint8 [bins, H/2, W/2]");
  cmd->add_flag("--downsample", args->downsample,
                "one centroid per voxel before insertion (default off)");
  cmd->add_flag("--no-downsample", args->no_downsample,
                "insert every point (the default; kept for old command lines)");
  cmd->add_flag("--remove-outliers", args->remove_outliers, "statistical outlier removal");
  cmd->add_option("--save-octree", args->save_octree, "also write the fused map (.bt)");
  cmd->callback([args] { RunOccupancy(*args); });
}

}  // namespace occgt

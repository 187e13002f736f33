// occgt occupancy [--recipe R.yaml] --root R --format F --scene S --frames ID0,ID1
//   [--resolution WxH] --out DIR
//   [--voxel-m 0.05] [--max-range-m FAR] [--near-m 0.1] [--far-m 10] [--bins 64]
//   [--spacing linear|log|inverse] [--traversal exact|center] [--scope pair|window:N|scene:S]
//   [--mode octomap|two_point] [--dense] [--save-octree map.bt]
// Occupancy target of one pair (GROUND_TRUTH.md §5, docs/OCCUPANCY.md): writes the folder of
// libgt/truth/pair_files.h (occ/known words, with --dense the uint8 volumes, occupancy.json).
// The work is truth::FuseScope + truth::ComputePairTruth; this file parses flags and prints.
#include <cstdio>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "apps/pair_recipe.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/pair_truth.h"

namespace occgt {
namespace {

namespace occ = gt::occupancy;

struct OccupancyArgs {
  PairDatasetArgs data;
  // Unset: the recipe's value (--recipe), else the defaults of a recipe without the key.
  std::optional<double> voxel_m, max_range_m, near_m, far_m;
  std::optional<int> bins, outlier_k;
  std::optional<double> outlier_stddev;
  std::optional<std::string> spacing, traversal, scope, mode;
  bool dense = false, downsample = false, no_downsample = false, remove_outliers = false;
  std::string save_octree;
};

void RunOccupancy(const OccupancyArgs& args) {
  // Settings first: bad flags fail before any file is read.
  PairSetup setup = StartPairSetup(args.data);
  gt::truth::OccupancySettings& os = setup.settings.occupancy;
  os.enabled = true;
  if (args.voxel_m) os.voxel_m = *args.voxel_m;
  if (args.max_range_m) os.max_range_m = *args.max_range_m;
  if (args.bins) os.bins = *args.bins;
  if (args.near_m) os.near_m = *args.near_m;
  if (args.far_m) os.far_m = *args.far_m;
  if (args.spacing) os.spacing = occ::ParseBinSpacing(*args.spacing);
  if (args.traversal) os.traversal = occ::ParseTraversal(*args.traversal);
  if (args.mode) os.mode = occ::ParseOccupancyMode(*args.mode);
  if (args.downsample && args.no_downsample)
    throw gt::InputError("--downsample", "conflicts with --no-downsample");
  // Given flags win over a --recipe's keys; the filters are off by default, as in the
  // library and `build`.
  if (args.downsample) os.downsample = true;
  if (args.no_downsample) os.downsample = false;
  if (args.remove_outliers) os.remove_outliers = true;
  if (args.outlier_k) os.outlier_k = *args.outlier_k;
  if (args.outlier_stddev) os.outlier_stddev = *args.outlier_stddev;
  if (!gt::truth::OccupancySettingsProblem(os).empty()) {  // a recipe's keys were checked
    throw gt::InputError(args.outlier_k ? "--outlier-k" : "--outlier-stddev",
                         "used with --remove-outliers (or a --recipe's "
                         "occupancy.remove_outliers: true) only");
  }
  if (args.scope) {
    occ::FusionOptions scope;
    occ::ParseFusionScope(*args.scope, &scope);
    os.scope = scope.scope;
    os.window = scope.window;
    os.scene_stride = scope.scene_stride;
  }
  // The fusion's flags do nothing in two_point (they were recorded in occupancy.json and
  // not applied).
  if (os.mode == occ::OccupancyMode::kTwoPoint) {
    for (const auto& [flag, given] :
         std::vector<std::pair<const char*, bool>>{{"--voxel-m", args.voxel_m.has_value()},
                                                   {"--max-range-m", args.max_range_m.has_value()},
                                                   {"--scope", args.scope.has_value()},
                                                   {"--traversal", args.traversal.has_value()},
                                                   {"--downsample", args.downsample},
                                                   {"--remove-outliers", args.remove_outliers}}) {
      if (given)
        throw gt::InputError(flag, "used by --mode octomap only (two_point fuses nothing)");
    }
  }
  const std::vector<FieldFlag> occupancy_flags = {
      {"voxel_m", "--voxel-m", args.voxel_m.has_value()},
      {"max_range_m", "--max-range-m", args.max_range_m.has_value()},
      // --far-m is also the ray range when --max-range-m is not given (--far-m inf).
      {"max_range_m", "--far-m", args.far_m.has_value() && !args.max_range_m.has_value()},
      {"window", "--scope", args.scope.has_value()},
      {"scene", "--scope", args.scope.has_value()},
      {"num_bins", "--bins", args.bins.has_value()},
      {"near_m", "--near-m", args.near_m.has_value()},
      {"outlier_k", "--outlier-k", args.outlier_k.has_value()},
      {"outlier_stddev", "--outlier-stddev", args.outlier_stddev.has_value()},
      {"far_m", "--far-m", args.far_m.has_value() || args.near_m.has_value()}};
  gt::truth::PairTruthOptions o = ResolveSettings(setup, args.data, PairOutputs::kOccupancyOnly,
                                                  "occupancy options", occupancy_flags);
  if (o.mode == occ::OccupancyMode::kTwoPoint && !args.save_octree.empty())
    throw gt::InputError("--save-octree", "needs --mode octomap");
  // OctoMap's binary format is .bt (octovis goes by the suffix); the suffix also keeps a
  // mistyped path from replacing a dataset file (a depth .npy was overwritten).
  if (const std::string& p = args.save_octree;
      !p.empty() && (p.size() < 4 || p.compare(p.size() - 3, 3, ".bt") != 0)) {
    throw gt::InputError("--save-octree", "expected a path ending in .bt, got '" + p + "'");
  }
  const PairDatasetArgs& d = args.data;
  gt::truth::PairSource source{setup.format, d.scene,           "", "", 0, 0, "", setup.resolution,
                               "",           setup.depth.source};
  if (setup.format == gt::DatasetFormat::kScanNetPP) {
    source.device = gt::datasets::ScanNetPPDeviceName(setup.reader.scannetpp_device);
  }
  if (setup.format == gt::DatasetFormat::kTum) source.tum_max_dt_s = setup.reader.tum_max_dt_s;
  std::tie(source.id0, source.id1) = gt::truth::ParseFramePair(d.frames);

  const gt::Scene scene = ReadSetupScene(setup, d.scene);
  source.scene = scene.name;
  // The scene's depth range: the validity range of the fusion.
  o = ResolveForScene(setup, d, scene, PairOutputs::kOccupancyOnly, "occupancy options",
                      occupancy_flags);
  const occ::FusionOptions& fo = o.fusion;
  const size_t i0 = gt::truth::FindFrame(scene, source.id0);
  const size_t i1 = gt::truth::FindFrame(scene, source.id1);
  source.number0 = scene.frames[i0].number;
  source.number1 = scene.frames[i1].number;
  const gt::truth::WorkingFrame w0 = LoadSetupFrame(setup, scene, scene.frames[i0]);
  const gt::truth::WorkingFrame w1 = LoadSetupFrame(setup, scene, scene.frames[i1]);
  auto load = [&](size_t i) {  // the pair's frames are read once
    return i == i0 ? w0 : i == i1 ? w1 : LoadSetupFrame(setup, scene, scene.frames[i]);
  };
  std::optional<gt::truth::ScopeMap> scope;
  gt::truth::PairTruth truth;
  try {  // a voxel size whose key range cannot hold the frames is refused before fusing them
    if (o.mode == occ::OccupancyMode::kOctomap)
      scope = gt::truth::FuseScope(scene, i0, i1, o, load);
    truth = gt::truth::ComputePairTruth(w0, w1, o, scope ? &scope->map : nullptr);
  } catch (const gt::InputError& e) {
    RethrowNamingFlag(e, {{"voxel_m", "--voxel-m", args.voxel_m.has_value()}});
  }
  // The map first: a --save-octree that cannot be written fails before the folder is
  // published.
  if (scope && !args.save_octree.empty()) scope->map.SaveBinary(args.save_octree);
  gt::truth::WriteOccupancyFolder(d.out, source, o, *truth.occupancy, scope ? &*scope : nullptr,
                                  args.dense);

  const auto c = occ::CountBins(truth.occupancy->cam0);
  const double total = static_cast<double>(c.occupied + c.free + c.unknown);
  std::printf("occupancy %s %s,%s (%s, %s): cam0 occupied %.3f free %.3f unknown %.3f -> %s\n",
              scene.name.c_str(), source.id0.c_str(), source.id1.c_str(),
              occ::OccupancyModeName(o.mode).c_str(), occ::FusionScopeName(fo).c_str(),
              c.occupied / total, c.free / total, c.unknown / total, d.out.c_str());
  if (scope && !scope->skipped.empty())
    std::printf("skipped %zu frame(s) of the scope (see occupancy.json)\n", scope->skipped.size());
  if (const std::optional<occ::FusionStats>& st = truth.occupancy->fusion_stats) {
    // Every dropped point is counted: a voxel size or range that drops many shows here.
    std::printf("fusion: %lld pixels, %lld invalid, %lld outside the key range",
                static_cast<long long>(st->pixels), static_cast<long long>(st->invalid_pixels),
                static_cast<long long>(st->out_of_key_range));
    if (fo.downsample)
      std::printf(", %lld after downsampling", static_cast<long long>(st->after_downsample));
    if (fo.remove_outliers)
      std::printf(", %lld outliers removed", static_cast<long long>(st->outliers_removed));
    std::printf(", %lld inserted (fusion.stats of occupancy.json)\n",
                static_cast<long long>(st->inserted_points));
  }
}

}  // namespace

void AddOccupancyCommand(CLI::App& app) {
  auto args = std::make_shared<OccupancyArgs>();
  // The defaults of the help text are the resolution's (the Options structs' values).
  const gt::truth::PairTruthOptions def = gt::truth::ResolvePairTruthOptions({});
  auto* cmd = app.add_subcommand("occupancy", "64-bin occupancy target of one pair of frames");
  PairDatasetArgs& d = args->data;
  AddPairDatasetFlags(cmd, &d, "its resolution, depth range and occupancy options");
  cmd->add_option("--voxel-m", args->voxel_m,
                  "OctoMap resolution in metres (default " + Num(def.fusion.voxel_m) + ")");
  cmd->add_option("--max-range-m", args->max_range_m,
                  "ray truncation in metres, <= 0 unlimited (default: the last bin edge)");
  cmd->add_option("--near-m", args->near_m,
                  "first bin edge, planar depth (default " + Num(def.bins.near_m) + ")");
  cmd->add_option(
      "--far-m", args->far_m,
      "last bin edge, planar depth, and the ray range (default " + Num(def.bins.far_m) + ")");
  cmd->add_option("--bins", args->bins,
                  "number of depth bins, 1..64 (default " + Num(def.bins.num_bins) + ")");
  cmd->add_option("--spacing", args->spacing,
                  "linear|log|inverse (default " + occ::BinSpacingName(def.bins.spacing) + ")");
  cmd->add_option("--traversal", args->traversal,
                  "exact|center (default " + occ::TraversalName(def.bins.traversal) + ")");
  cmd->add_option("--scope", args->scope,
                  "pair|window:N|scene:S (default " + occ::FusionScopeName(def.fusion) + ")");
  cmd->add_option("--mode", args->mode,
                  "octomap|two_point (default " + occ::OccupancyModeName(def.mode) + ")");
  cmd->add_flag("--dense", args->dense, "also write occ0/1_dense.npy, uint8 [bins, H/2, W/2]");
  cmd->add_flag("--downsample", args->downsample,
                std::string("one centroid per voxel before insertion (default ") +
                    (def.fusion.downsample ? "on" : "off") + ")");
  cmd->add_flag("--no-downsample", args->no_downsample,
                "insert every point (the default; kept for old command lines)");
  cmd->add_flag("--remove-outliers", args->remove_outliers,
                std::string("statistical outlier removal after the downsampling (default ") +
                    (def.fusion.remove_outliers ? "on" : "off") + ")");
  cmd->add_option("--outlier-k", args->outlier_k,
                  "neighbours of the outlier removal (default " + Num(def.fusion.outlier_k) + ")");
  cmd->add_option("--outlier-stddev", args->outlier_stddev,
                  "outlier removal: drop points whose mean neighbour distance exceeds the mean "
                  "by this many standard deviations (default " +
                      Num(def.fusion.outlier_stddev) + ")");
  cmd->add_option("--save-octree", args->save_octree, "also write the fused map (.bt)");
  cmd->callback([args] { RunOccupancy(*args); });
}

}  // namespace occgt

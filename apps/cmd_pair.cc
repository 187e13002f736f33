// occgt pair [--recipe R.yaml] --root R --format F --scene S --frames ID0,ID1 [--preset P]
//   [overrides] --out DIR
// Labels one pair of frames (GROUND_TRUTH.md §2–4) at the working resolution and writes
// the folder of libgt/truth/pair_files.h (label maps, matches, cells, meta.json). The work is
// truth::ComputePairTruth; this file parses flags and prints one line.
#include <cstdio>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/pair_recipe.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/truth/pair_files.h"
#include "libgt/truth/pair_settings.h"
#include "libgt/truth/pair_truth.h"

namespace occgt {
namespace {

struct PairArgs {
  PairDatasetArgs data;
  // Unset: the recipe's value (--recipe), else the defaults of a recipe without the key.
  std::optional<std::string> preset;
  std::optional<double> abs_tol_m, rel_tol;
  std::string relative_to, bounds, target_lookup, missing_target;
  std::optional<int> stride;
  std::optional<std::string> anchor;
  bool mutual = false, no_mutual = false;  // neither: the recipe's patches.mutual
  std::optional<int> score_stride;         // unset: the recipe's selection.score_stride, else 1
};

void RunPair(const PairArgs& args) {
  ExitOnInterrupt(
      "--out may hold some files of this run beside an earlier run's: re-run the same command");
  // Settings first: bad flags fail before any file is read.
  const PairDatasetArgs& d = args.data;
  PairSetup setup = StartPairSetup(d);
  gt::truth::PairSettings& st = setup.settings;
  st.occupancy.enabled = false;
  gt::truth::LabelSettings& ls = st.labels;
  if (args.preset) {
    gt::LabelPreset(*args.preset);  // a bad name fails now
    ls.preset = *args.preset;
  }
  if (args.abs_tol_m) ls.abs_tol_m = *args.abs_tol_m;
  if (args.rel_tol) ls.rel_tol = *args.rel_tol;
  if (!args.relative_to.empty()) ls.relative_to = gt::ParseRelativeTo(args.relative_to);
  if (!args.bounds.empty()) ls.bounds = gt::ParseBounds(args.bounds);
  if (!args.target_lookup.empty()) ls.target_lookup = gt::ParseTargetLookup(args.target_lookup);
  if (!args.missing_target.empty()) ls.missing_target = gt::ParseMissingTarget(args.missing_target);
  if (args.stride) st.patches.stride = *args.stride;
  if (args.anchor) st.patches.anchor = gt::ParseAnchor(*args.anchor);
  if (args.mutual) st.patches.mutual = true;
  if (args.no_mutual) st.patches.mutual = false;
  const std::vector<FieldFlag> pair_flags = {
      {"stride", "--stride", args.stride.has_value()},
      {"abs_tol_m", "--abs-tol-m", args.abs_tol_m.has_value()},
      {"rel_tol", "--rel-tol", args.rel_tol.has_value()}};
  ResolveSettings(setup, d, PairOutputs::kAll, "pair options", pair_flags);
  const int score_stride =
      args.score_stride.value_or(setup.recipe ? setup.recipe->selection.score_stride : 1);
  if (score_stride < 1) throw gt::InputError("--score-stride", "expected >= 1");
  gt::truth::PairSource source{
      setup.format, d.scene, "", "", 0, 0, ls.preset, setup.resolution, "", setup.depth.source};
  if (setup.format == gt::DatasetFormat::kScanNetPP) {
    source.device = gt::datasets::ScanNetPPDeviceName(setup.reader.scannetpp_device);
  }
  if (setup.format == gt::DatasetFormat::kTum) source.tum_max_dt_s = setup.reader.tum_max_dt_s;
  std::tie(source.id0, source.id1) = gt::truth::ParseFramePair(d.frames);

  const gt::Scene scene = ReadSetupScene(setup, d.scene);
  source.scene = scene.name;
  const gt::truth::PairTruthOptions o =
      ResolveForScene(setup, d, scene, PairOutputs::kAll, "pair options", pair_flags);
  const gt::Frame& f0 = scene.frames[gt::truth::FindFrame(scene, source.id0)];
  const gt::Frame& f1 = scene.frames[gt::truth::FindFrame(scene, source.id1)];
  source.number0 = f0.number;
  source.number1 = f1.number;
  const gt::truth::WorkingFrame w0 = LoadSetupFrame(setup, scene, f0);
  const gt::truth::WorkingFrame w1 = LoadSetupFrame(setup, scene, f1);
  const gt::truth::PairTruth truth = gt::truth::ComputePairTruth(w0, w1, o);
  gt::truth::WritePairFolder(d.out, source, w0, w1, o, truth, score_stride);

  const gt::PairLabels& p = truth.labels;
  const gt::DirectionMetrics m01 =
      score_stride == 1 ? p.m01 : gt::MetricsFromLabels(p.l01, score_stride);
  const gt::DirectionMetrics m10 =
      score_stride == 1 ? p.m10 : gt::MetricsFromLabels(p.l10, score_stride);
  const gt::MatchTypeCounts c = gt::CountMatchTypes(p.patches);
  const std::string grid =
      score_stride == 1 ? "" : " (score grid, every " + std::to_string(score_stride) + ")";
  std::printf(
      "pair %s %s,%s: overlap %.3f / %.3f, occlusion %.3f / %.3f%s, matches %zu "
      "(vv %lld, vo %lld, ov %lld) -> %s\n",
      scene.name.c_str(), source.id0.c_str(), source.id1.c_str(), m01.overlap, m10.overlap,
      m01.occlusion_ratio, m10.occlusion_ratio, grid.c_str(), p.patches.size(),
      static_cast<long long>(c.vv), static_cast<long long>(c.vo), static_cast<long long>(c.ov),
      d.out.c_str());
}

}  // namespace

void AddPairCommand(CLI::App& app) {
  auto args = std::make_shared<PairArgs>();
  auto* cmd = app.add_subcommand("pair", "Label one pair of frames and write its ground truth");
  PairDatasetArgs& d = args->data;
  AddPairDatasetFlags(cmd, &d, "its resolution, depth range, labels and patches");
  std::string presets;
  for (const std::string& name : gt::PresetNames()) presets += (presets.empty() ? "" : ", ") + name;
  cmd->add_option("--preset", args->preset, "label preset: " + presets);
  const gt::PatchOptions patches;  // the defaults of the help text
  cmd->add_option("--abs-tol-m", args->abs_tol_m, "absolute depth tolerance (m)");
  cmd->add_option("--rel-tol", args->rel_tol, "relative depth tolerance (fraction)");
  cmd->add_option("--relative-to", args->relative_to, "projected|observed");
  cmd->add_option("--bounds", args->bounds, "pixel-area|strict");
  cmd->add_option("--target-lookup", args->target_lookup, "nearest|truncate");
  cmd->add_option("--missing-target", args->missing_target, "unknown|as-zero-depth");
  cmd->add_option("--stride", args->stride,
                  "patch cell size in pixels (default " + Num(patches.stride) + ")");
  cmd->add_option("--anchor", args->anchor,
                  std::string("center|corner (default ") + gt::AnchorName(patches.anchor) + ")");
  auto* mutual = cmd->add_flag("--mutual", args->mutual,
                               "vv matches need the loop-back check (the default); overrides "
                               "the recipe's patches.mutual");
  cmd->add_flag("--no-mutual", args->no_mutual,
                "keep vv matches without the loop-back check; overrides the recipe's "
                "patches.mutual")
      ->excludes(mutual);
  cmd->add_option("--score-stride", args->score_stride,
                  "metrics on every N-th pixel in x and y (default: the recipe's "
                  "selection.score_stride, else 1)");
  cmd->callback([args] { RunPair(*args); });
}

}  // namespace occgt

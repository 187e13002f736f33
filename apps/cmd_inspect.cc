// occgt inspect pair | split: pictures of one pair and a report of a split (libgt/report).
//   occgt inspect pair (--shard X.tar --key K | --pair-dir D | [--recipe R.yaml] --root R
//                      --format F --scene S --frames A,B [pair flags]) --out DIR
//   (--pair-dir: a folder of `occgt pair`, of `occgt occupancy`, or of both; a computed pair
//   takes its settings as `occgt pair` does, apps/pair_recipe.h)
//   occgt inspect split DIR [--out OUT] [--eval eval.json ...]
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/pair_recipe.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/io/folder_lock.h"
#include "libgt/pipeline/split_depth.h"
#include "libgt/report/pair_source.h"
#include "libgt/report/split_report.h"
#include "libgt/truth/working_frame.h"

namespace occgt {
namespace {

struct InspectPairArgs {
  std::string shard, key, pair_dir;
  // The pair computed from a scene, as `occgt pair` reads it (--recipe, --root, --format,
  // --scene, --frames, the depth flags); also --out, and --root for --pair-dir's colour.
  PairDatasetArgs data;
  std::string image0, image1;
  std::optional<std::string> preset;  // default: the recipe's, else truth::LabelSettings's
  bool no_occupancy = false;
  int max_lines = 200;
  uint64_t seed = 0;
  double alpha = 0.55;
  int slice_row = -1;
  // The flags given that only a computed pair uses (a shard sample or a pair folder holds
  // its own resolution, labels and occupancy): refused with --shard or --pair-dir.
  std::vector<std::string> computed_only_given;
  bool images_given = false;  // --image0/--image1: --pair-dir only
};

struct InspectSplitArgs {
  std::string dir, out, aggregate = "mean", occlusion_metric = "image", gallery_order = "random";
  int gallery = 6;
  uint64_t seed = 0;
  int bins = 20;
  std::vector<std::string> eval;
  int eval_gallery = 4;
  int gallery_tuples = gt::report::SplitReportOptions().gallery_tuples;
  std::string root;  // the dataset root when recipe.json's no longer holds (depth sources)
};

void RunInspectPair(const InspectPairArgs& a) {
  const PairDatasetArgs& d = a.data;
  // --root alone with --pair-dir only says where the colour images are.
  const bool scene_source = !d.scene.empty() || !d.frames.empty() || !d.recipe.empty() ||
                            (!d.root.empty() && a.pair_dir.empty());
  const int sources = (!a.shard.empty() || !a.key.empty()) + !a.pair_dir.empty() + scene_source;
  if (sources != 1) {
    throw gt::InputError("--shard/--pair-dir/--root",
                         "expected exactly one source: --shard/--key, --pair-dir, or "
                         "--root/--format/--scene/--frames");
  }
  const bool read_source = !a.shard.empty() || !a.key.empty() || !a.pair_dir.empty();
  if (read_source && !a.computed_only_given.empty()) {
    throw gt::InputError(a.computed_only_given.front(),
                         "only for a pair computed here (--root/--scene/--frames): the pair of "
                         "--shard or --pair-dir has its own (it would be ignored)");
  }
  if (a.pair_dir.empty() && a.images_given) {
    throw gt::InputError(a.image0.empty() ? "--image1" : "--image0",
                         "only with --pair-dir (it would be ignored)");
  }
  if (a.image0.empty() != a.image1.empty()) {  // one colour image alone would be ignored
    throw gt::InputError(a.image0.empty() ? "--image0" : "--image1",
                         "expected both --image0 and --image1 (the colour of both frames)");
  }
  // The picture flags are checked before any pair is read or computed (the defaults pass:
  // a failure comes from a flag).
  gt::report::PairPictureOptions po;
  po.matches.max_lines = a.max_lines;
  po.matches.seed = a.seed;
  po.labels.alpha = a.alpha;
  po.occupancy.slice_row = a.slice_row;
  if (std::string error; !po.Check(&error)) {
    ThrowOptionsError(error, "inspect options",
                      {{"max_lines", "--max-lines", true},
                       {"alpha", "--alpha", true},
                       {"slice_row", "--slice-row", true}});
  }
  gt::report::PairData pair;
  if (!a.shard.empty() || !a.key.empty()) {
    if (a.shard.empty() || a.key.empty()) {
      throw gt::InputError("--shard/--key", "expected both a shard and a sample key");
    }
    pair = gt::report::LoadPairFromShard(a.shard, a.key);
  } else if (!a.pair_dir.empty()) {
    pair = gt::report::LoadPairFromDir(a.pair_dir, a.image0, a.image1, d.root);
  } else {
    if (d.scene.empty() || d.frames.empty()) {
      throw gt::InputError("--scene/--frames", "expected both with --root or --recipe");
    }
    // The settings as `occgt pair` takes them (the recipe's, or the defaults, then the
    // flags), with the occupancy on unless the recipe or --no-occupancy turns it off.
    PairSetup setup = StartPairSetup(d);
    gt::truth::PairSettings& st = setup.settings;
    if (a.preset) {
      gt::LabelPreset(*a.preset);  // a bad name fails before any file is read
      st.labels.preset = *a.preset;
    }
    if (a.no_occupancy) st.occupancy.enabled = false;
    ResolveSettings(setup, d, PairOutputs::kAll, "pair options");
    const gt::Scene scene = ReadSetupScene(setup, d.scene);
    const gt::truth::PairTruthOptions o =
        ResolveForScene(setup, d, scene, PairOutputs::kAll, "pair options");
    const auto [id0, id1] = gt::truth::ParseFramePair(d.frames);
    pair = gt::report::ComputePairFromScene(scene, id0, id1, o, setup.resolution, setup.depth);
  }
  const auto written = gt::report::WritePairPictures(gt::report::RenderPair(pair, po), d.out);
  if (pair.has_labels) {
    std::printf("inspect pair %s: %d x %d, %zu matches%s%s\n", pair.name.c_str(), pair.width,
                pair.height, pair.matches.size(), pair.has_images ? "" : " (no colour images)",
                pair.has_occupancy ? ", occupancy" : "");
  } else {
    std::printf("inspect pair %s: %d x %d, occupancy only (no labels or matches)\n",
                pair.name.c_str(), pair.width, pair.height);
  }
  if (!pair.depth_source.empty()) {
    std::printf("  labels from depth source %s%s\n", pair.depth_source.c_str(),
                pair.depth_sources.empty()
                    ? ""
                    : " (depth.png: sensor | rendered | fused | sensor vs mesh)");
  }
  for (const auto& p : written) std::printf("  wrote %s\n", p.c_str());
}

// The lock file of a report folder (RunInspectSplit).
constexpr const char* kInspectLock = ".inspect.lock";

void RunInspectSplit(const InspectSplitArgs& a) {
  ExitOnInterrupt(
      "the report folder may hold some files of this run beside an earlier run's: re-run the "
      "same command");
  gt::report::SplitReportOptions o;
  o.aggregate = gt::ParseAggregate(a.aggregate, "--aggregate");
  o.occlusion_metric = gt::ParseOcclusionMetric(a.occlusion_metric, "--occlusion-metric");
  o.gallery_pairs = a.gallery;
  o.seed = a.seed;
  o.gallery_order = gt::report::ParseGalleryOrder(a.gallery_order, "--gallery-order");
  o.histogram_bins = a.bins;
  o.eval_paths = a.eval;
  o.eval_gallery_pairs = a.eval_gallery;
  o.gallery_tuples = a.gallery_tuples;
  std::string error;
  if (!o.Check(&error)) {  // the defaults pass: a failure comes from a flag
    ThrowOptionsError(error, "occgt inspect split",
                      {{"histogram_bins", "--bins", true},
                       {"gallery_pairs", "--gallery", true},
                       {"eval_gallery_pairs", "--eval-gallery", true},
                       {"gallery_tuples", "--gallery-tuples", true}});
  }
  const std::string out = a.out.empty() ? a.dir + "/inspect" : a.out;
  // An interrupt removes the report's temporaries: "<name>.tmp" of its own files, the
  // gnuplot scratch folder, and the report folder when this run created it and published
  // nothing into it (every file is published whole, by a rename).
  TemporaryNames temporaries;
  temporaries.dir = out;
  for (const std::string& name : gt::report::SplitReportFileNames()) {
    temporaries.names.push_back(name + ".tmp");
  }
  temporaries.folders = {gt::report::kSplitReportScratch};
  std::error_code ec;
  const bool created = !std::filesystem::exists(out, ec);
  temporaries.remove_dir_if_empty = created;
  // One report per folder at a time (a second run would take the first one's files for an
  // earlier run's, and an interrupt of either would remove the other's temporaries): byte 0
  // of OUT/.inspect.lock, released when the process ends. A folder this run created is left
  // as it was found (absent) when the run fails or is interrupted before writing into it.
  std::filesystem::create_directories(out, ec);
  if (ec) throw gt::InputError(out, "cannot create the report folder: " + ec.message());
  const std::string lock_path = out + "/" + kInspectLock;
  std::unique_ptr<gt::io::FileLock> lock = gt::io::FileLock::TryAcquire(lock_path, 0);
  const auto leave_as_found = [&] {
    if (!created) return;
    lock.reset();
    std::filesystem::remove(lock_path, ec);
    std::filesystem::remove(out, ec);  // only when empty
  };
  if (!lock) {
    throw gt::InputError(out,
                         "another occgt inspect split is writing this report folder now "
                         "(it holds " +
                             lock_path +
                             "); wait for it to end or use "
                             "another --out");
  }
  if (created) temporaries.names.push_back(kInspectLock);
  RemoveOnInterrupt(temporaries);
  std::optional<gt::report::SplitDepthShares> shares;
  gt::report::SplitReportFiles files;
  try {
    // A build with rendered depth (mesh or fused): the sensor-vs-mesh shares of its frames.
    shares = gt::pipeline::ComputeSplitDepthShares(a.dir, a.root);
    files = gt::report::WriteSplitReport(a.dir, out, o, shares ? &*shares : nullptr);
  } catch (...) {
    leave_as_found();
    throw;
  }
  std::printf("inspect split %s\n", a.dir.c_str());
  if (shares) {
    const double n = static_cast<double>(std::max<int64_t>(1, shares->total.Total()));
    std::printf(
        "  depth source %s, %lld frames vs mesh (within %g m + %g of depth): sensor only "
        "%.4f, mesh only %.4f, agree %.4f, disagree %.4f, neither %.4f\n",
        gt::render::DepthSourceModeName(shares->source), static_cast<long long>(shares->frames),
        shares->tolerance.abs_tol_m, shares->tolerance.rel_tol, shares->total.sensor_only / n,
        shares->total.mesh_only / n, shares->total.agree / n, shares->total.disagree / n,
        shares->total.neither / n);
  }
  for (const auto& p : files.written) std::printf("  wrote %s\n", p.c_str());
  for (const auto& p : files.removed) std::printf("  removed %s (an earlier run's)\n", p.c_str());
  // Shown on the page too; said here so that a script sees it (the report is still written).
  if (!files.unreadable.empty()) {
    std::fprintf(stderr, "occgt: warning: %zu gallery entries could not be read (first: %s)\n",
                 files.unreadable.size(), files.unreadable.front().c_str());
  }
  for (const auto& w : files.warnings) std::fprintf(stderr, "occgt: warning: %s\n", w.c_str());
}

}  // namespace

void AddInspectCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("inspect", "Pictures of a pair and a report of a split");
  cmd->require_subcommand(1);

  auto pa = std::make_shared<InspectPairArgs>();
  auto* pair = cmd->add_subcommand(
      "pair",
      "matches.png, labels.png, occupancy.png of one pair (from a shard sample, an "
      "`occgt pair` folder, or a scene and two frames)");
  pair->add_option("--shard", pa->shard, "WebDataset shard (.tar) holding the sample");
  pair->add_option("--key", pa->key, "sample key in the shard, e.g. scene/000010_000020");
  pair->add_option("--pair-dir", pa->pair_dir,
                   "output folder of `occgt pair` and/or `occgt occupancy`");
  pair->add_option("--image0", pa->image0, "colour image of frame 0 (with --pair-dir)");
  pair->add_option("--image1", pa->image1, "colour image of frame 1 (with --pair-dir)");
  AddPairDatasetFlags(pair, &pa->data,
                      "the pair's resolution, depth range, labels and occupancy (when the pair "
                      "is computed here)",
                      PairFlags::kOneOfSources);
  pair->get_option("--root")->description(
      "dataset root: compute the pair here (with --scene, --frames), or, with --pair-dir, "
      "where its colour images are (default: the recipe's)");
  pair->get_option("--out")->description("folder for the PNG files");
  pair->add_option("--preset", pa->preset,
                   "label preset (computed pair; default: the recipe's, else default)");
  pair->add_flag("--no-occupancy", pa->no_occupancy, "skip the occupancy fusion (computed pair)");
  pair->add_option("--max-lines", pa->max_lines, "match lines drawn at most")
      ->capture_default_str();
  NonNegative(pair->add_option("--seed", pa->seed, "seed of the drawn subset of matches"))
      ->capture_default_str();
  pair->add_option("--alpha", pa->alpha, "weight of label colours over the images")
      ->capture_default_str();
  pair->add_option("--slice-row", pa->slice_row,
                   "half-grid row of the occupancy slice (-1: middle)")
      ->capture_default_str();
  pair->callback([pa, pair] {
    for (const char* flag :
         {"--recipe", "--format", "--resolution", "--min-depth-m", "--max-depth-m",
          "--depth-source", "--device", "--tum-max-dt", "--mesh", "--preset", "--no-occupancy"}) {
      if (pair->count(flag) > 0) pa->computed_only_given.push_back(flag);
    }
    pa->images_given = pair->count("--image0") + pair->count("--image1") > 0;
    RunInspectPair(*pa);
  });

  auto sa = std::make_shared<InspectSplitArgs>();
  auto* split = cmd->add_subcommand(
      "split",
      "plots (gnuplot), a self-contained report.html and report.json of an `occgt build` "
      "folder (and of the tuples of `occgt tuples` in it)");
  split
      ->add_option("dir", sa->dir,
                   "output folder of `occgt build` (pairs.jsonl, summary.json) and/or of "
                   "`occgt tuples` (tuples.jsonl, views/)")
      ->required();
  split->add_option("--out", sa->out, "report folder (default DIR/inspect)");
  split->add_option("--aggregate", sa->aggregate, "combine both directions: min, mean, max")
      ->capture_default_str();
  split
      ->add_option("--occlusion-metric", sa->occlusion_metric,
                   "image (OCCLUDED / W*H) or visible (OCCLUDED / (VISIBLE+OCCLUDED))")
      ->capture_default_str();
  split->add_option("--gallery", sa->gallery, "pairs shown with their pictures")
      ->capture_default_str();
  NonNegative(split->add_option("--seed", sa->seed, "seed of the gallery choice"))
      ->capture_default_str();
  split
      ->add_option("--gallery-order", sa->gallery_order,
                   "random (seeded) or most-occluded (largest occlusion ratio first)")
      ->capture_default_str();
  split
      ->add_option("--bins", sa->bins,
                   "histogram bins over the data's range (widened to multiples of 0.05)")
      ->capture_default_str();
  split->add_option("--eval", sa->eval,
                    "eval.json of `occgt eval` on this split: adds the evaluation section "
                    "(repeat to compare several files' prediction sets)");
  split->add_option("--eval-gallery", sa->eval_gallery, "worst pairs shown per prediction set")
      ->capture_default_str();
  split
      ->add_option("--gallery-tuples", sa->gallery_tuples,
                   "N-view tuples shown with their views (when DIR has the tuples.jsonl of "
                   "occgt tuples)")
      ->capture_default_str();
  split->add_option("--root", sa->root,
                    "dataset root of a build with depth_source mesh or fused, when recipe.json's "
                    "dataset.root does not hold from here (the depth-source shares re-read it)");
  split->callback([sa] { RunInspectSplit(*sa); });
}

}  // namespace occgt

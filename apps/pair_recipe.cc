#include "apps/pair_recipe.h"

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"

namespace occgt {

PairSetup StartPairSetup(const PairDatasetArgs& args) {
  PairSetup s;
  // A recipe without keys is the defaults: one mapping for both cases keeps them equal.
  gt::pipeline::Recipe defaults;
  if (!args.recipe.empty()) {
    gt::pipeline::RecipeOverrides overrides;
    overrides.root = args.root;
    s.recipe = gt::pipeline::LoadRecipe(args.recipe, overrides);
  }
  const gt::pipeline::Recipe& r = s.recipe ? *s.recipe : defaults;
  s.settings = gt::pipeline::RecipePairSettings(r);
  s.resolution = {r.width, r.height};
  if (args.resolution) s.resolution = gt::truth::ParseResolution(*args.resolution, "--resolution");
  if (args.min_depth_m) s.settings.labels.min_depth_m = *args.min_depth_m;
  if (args.max_depth_m) s.settings.labels.max_depth_m = *args.max_depth_m;

  s.root = args.root;
  if (s.recipe && s.root.empty()) {
    s.root = r.dataset.root;
    if (s.root.empty()) {  // synthetic: generated into the build's folder
      throw gt::InputError("--root", "required with a synthetic recipe (the build's DIR/data)");
    }
  }
  if (s.root.empty()) throw gt::InputError("--root", "required (or --recipe)");
  s.depth = gt::pipeline::RecipeFrameDepthOptions(r);
  if (args.depth_source)
    s.depth.source = gt::render::ParseDepthSourceMode(*args.depth_source, "--depth-source");
  s.mesh_path = args.mesh.empty() ? r.dataset.mesh_path : args.mesh;
  if (!args.format.empty()) {
    s.format = gt::ParseDatasetFormat(args.format, "--format");
  } else if (s.recipe) {
    s.format = r.dataset.format;  // generic for a synthetic recipe
  } else {
    throw gt::InputError("--format", "required (or --recipe)");
  }
  if (args.device && s.format != gt::DatasetFormat::kScanNetPP) {
    throw gt::InputError("--device", "only for the scannetpp format");
  }
  s.reader = gt::pipeline::RecipeReaderOptions(r);
  if (args.tum_max_dt_s) {
    if (s.format != gt::DatasetFormat::kTum) {
      throw gt::InputError("--tum-max-dt", "only for the tum format");
    }
    if (!std::isfinite(*args.tum_max_dt_s) || *args.tum_max_dt_s < 0) {
      throw gt::InputError("--tum-max-dt", "expected a finite number of seconds >= 0");
    }
    s.reader.tum_max_dt_s = *args.tum_max_dt_s;
  }
  if (s.format == gt::DatasetFormat::kScanNetPP) {
    const auto [id0, id1] = gt::truth::ParseFramePair(args.frames);
    std::string device_source;
    if (args.device) {
      s.reader.scannetpp_device = gt::datasets::ParseScanNetPPDevice(*args.device, "--device");
      device_source = "--device";
      if (s.recipe && s.recipe->dataset.format == gt::DatasetFormat::kScanNetPP &&
          s.recipe->dataset.device != s.reader.scannetpp_device) {
        throw gt::InputError("--device",
                             std::string(*args.device) + " differs from " + args.recipe +
                                 "'s dataset.device " +
                                 gt::datasets::ScanNetPPDeviceName(s.recipe->dataset.device));
      }
    } else if (s.recipe && s.recipe->dataset.format == gt::DatasetFormat::kScanNetPP) {
      device_source = args.recipe + ": dataset.device";  // RecipeReaderOptions gave it
    } else {
      s.reader.scannetpp_device = gt::datasets::ScanNetPPDeviceOfFrameId(id0);
      device_source = "the frame id '" + id0 + "'";
    }
    for (const std::string& id : {id0, id1}) {
      gt::datasets::CheckScanNetPPFrameId(s.reader.scannetpp_device, id, "--frames", device_source);
    }
  }
  return s;
}

void AddPairDatasetFlags(CLI::App* cmd, PairDatasetArgs* d, const std::string& recipe_gives,
                         PairFlags use) {
  const gt::truth::Resolution res;  // the default of the help text
  const bool only = use == PairFlags::kOnlySource;
  cmd->add_option("--recipe", d->recipe,
                  "build recipe: " + recipe_gives +
                      " (flags override); also its dataset root and format unless given");
  cmd->add_option("--root", d->root, "dataset root (default: the recipe's)");
  cmd->add_option("--format", d->format, "dataset format (scannet, tartanair, ...)");
  cmd->add_option("--scene", d->scene, "scene name (see occgt scan)")->required(only);
  cmd->add_option("--frames", d->frames, "two frame ids: ID0,ID1")->required(only);
  cmd->add_option("--out", d->out, "output folder")->required();
  cmd->add_option("--resolution", d->resolution,
                  "working resolution WxH (default " + std::to_string(res.width) + "x" +
                      std::to_string(res.height) + ")");
  cmd->add_option("--min-depth-m", d->min_depth_m, "minimum valid depth (dataset default)");
  cmd->add_option("--max-depth-m", d->max_depth_m, "maximum valid depth (dataset default)");
  cmd->add_option("--depth-source", d->depth_source,
                  "sensor|mesh|fused: depth files, rendered from the scene's mesh, or both "
                  "(default: the recipe's, else sensor)");
  cmd->add_option("--device", d->device,
                  "scannetpp: dslr or iphone (default: the recipe's dataset.device, else from "
                  "the frame ids: frame_NNNNNN = iphone)");
  cmd->add_option("--tum-max-dt", d->tum_max_dt_s,
                  "tum: max time difference for pose/colour association, seconds (default: the "
                  "recipe's dataset.tum_max_dt_s, else 0.02)");
  cmd->add_option("--mesh", d->mesh,
                  "the scene's mesh (PLY, in the poses' world frame; default: the recipe's "
                  "dataset.mesh_path, else the dataset's own)");
}

gt::Scene ReadSetupScene(const PairSetup& setup, const std::string& scene_name) {
  gt::Scene scene =
      gt::datasets::MakeReader(setup.format, setup.reader)->ReadScene(setup.root, scene_name);
  gt::pipeline::ApplyMeshPath(setup.mesh_path, &scene);
  return scene;
}

gt::truth::WorkingFrame LoadSetupFrame(const PairSetup& setup, const gt::Scene& scene,
                                       const gt::Frame& frame) {
  return gt::truth::LoadWorkingFrame(scene, frame, setup.resolution, setup.depth);
}

gt::truth::DatasetDepthRange DepthRangeFor(const PairSetup& setup, const gt::Scene& scene) {
  return setup.recipe ? gt::pipeline::RecipeDepthRange(*setup.recipe, scene)
                      : gt::truth::DepthRangeOf(scene);
}

namespace {

gt::truth::PairTruthOptions Checked(gt::truth::PairTruthOptions o, const PairSetup& setup,
                                    const PairDatasetArgs& args, PairOutputs outputs,
                                    const std::string& what, std::vector<FieldFlag> flags) {
  o.labels_and_matches = outputs == PairOutputs::kAll;
  std::string error;
  if (!o.Check(&error)) {
    flags.push_back({"min_depth_m", "--min-depth-m", args.min_depth_m.has_value()});
    flags.push_back({"max_depth_m", "--max-depth-m", args.max_depth_m.has_value()});
    ThrowOptionsError(error, what, flags);
  }
  // One patch cell must fit the working resolution (else the labels fail after the frames
  // are read): named by --stride when given, else by --resolution.
  const int stride = o.patches.stride;
  const gt::truth::Resolution& r = setup.resolution;
  if (o.labels_and_matches && (r.width < stride || r.height < stride)) {
    flags.push_back({"stride", "--resolution", args.resolution.has_value()});
    ThrowOptionsError("stride " + std::to_string(stride) + " is larger than the " +
                          std::to_string(r.width) + "x" + std::to_string(r.height) +
                          " working resolution (one patch cell must fit)",
                      what, flags);
  }
  return o;
}

}  // namespace

gt::truth::PairTruthOptions ResolveSettings(const PairSetup& setup, const PairDatasetArgs& args,
                                            PairOutputs outputs, const std::string& what,
                                            const std::vector<FieldFlag>& flags) {
  return Checked(gt::truth::ResolvePairTruthOptions(setup.settings), setup, args, outputs, what,
                 flags);
}

gt::truth::PairTruthOptions ResolveForScene(const PairSetup& setup, const PairDatasetArgs& args,
                                            const gt::Scene& scene, PairOutputs outputs,
                                            const std::string& what,
                                            const std::vector<FieldFlag>& flags) {
  return Checked(gt::truth::ResolvePairTruthOptions(setup.settings, DepthRangeFor(setup, scene)),
                 setup, args, outputs, what, flags);
}

}  // namespace occgt

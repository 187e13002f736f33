// occgt synth --out DIR [--scenes N] [--frames N] [--resolution WxH] [--seed S] [--no-holes]:
// writes the synthetic dataset of libgt/synth/dataset.h (docs/SYNTH.md).
#include <chrono>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/usage.h"
#include "libgt/core/error.h"
#include "libgt/core/human.h"
#include "libgt/synth/dataset.h"
#include "libgt/synth/scannetpp_layout.h"

namespace occgt {
namespace {

struct SynthArgs {
  std::string out;
  std::string resolution = "640x480";
  std::string layout = "generic";
  bool no_holes = false;
  gt::synth::SynthOptions options;
};

// The fields of SynthOptions::Check and ScanNetPPSynthOptions::Check that a flag sets: a
// value out of their range is a usage error naming the flag (exit 2). Nothing but the flags
// and the valid defaults sets them, so each counts as given.
const std::vector<FieldFlag> kSynthFlags = {{"scenes", "--scenes", true},
                                            {"frames", "--frames", true},
                                            {"resolution", "--resolution", true},
                                            {"DSLR size", "--resolution", true}};

// --layout scannetpp: the fixture of libgt/synth/scannetpp_layout.h (DSLR at --resolution).
void RunScanNetPPSynth(const SynthArgs& args) {
  if (args.no_holes) {  // that layout punches no holes: the flag would be ignored
    throw gt::InputError("--no-holes", "only for --layout generic");
  }
  gt::synth::ScanNetPPSynthOptions o;
  o.scenes = args.options.scenes;
  o.frames = args.options.frames_per_scene;
  o.dslr_width = args.options.width;
  o.dslr_height = args.options.height;
  o.seed = args.options.seed;
  std::string error;
  if (!o.Check(&error)) ThrowOptionsError(error, "occgt synth --layout scannetpp", kSynthFlags);
  const auto start = std::chrono::steady_clock::now();
  const gt::synth::ScanNetPPSynthSummary summary = gt::synth::WriteScanNetPPSynth(args.out, o);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "synth: " << gt::Counted(static_cast<long long>(summary.scene_names.size()), "scene")
            << " in ScanNet++'s layout, " << o.frames << " DSLR and " << o.frames
            << " iPhone frames each (DSLR " << o.dslr_width << "x" << o.dslr_height << ", seed "
            << o.seed << ") written to " << args.out << " in " << std::fixed << std::setprecision(2)
            << seconds << " s\n"
            << "  read it with --format scannetpp " << args.out << "\n";
}

void RunSynth(SynthArgs& args) {
  ExitOnInterrupt("the dataset in --out is incomplete: re-run the same command");
  static const std::regex kResolution("([0-9]{1,5})x([0-9]{1,5})");
  std::smatch m;
  if (!std::regex_match(args.resolution, m, kResolution)) {
    throw gt::InputError("--resolution",
                         "expected WxH, e.g. 640x480, got '" + args.resolution + "'");
  }
  args.options.width = std::stoi(m[1]);
  args.options.height = std::stoi(m[2]);
  args.options.holes = !args.no_holes;
  if (args.layout != "generic" && args.layout != "scannetpp") {
    throw gt::InputError("--layout", "expected generic or scannetpp, got '" + args.layout + "'");
  }
  if (args.layout == "scannetpp") {
    RunScanNetPPSynth(args);
    return;
  }
  std::string error;
  if (!args.options.Check(&error)) ThrowOptionsError(error, "occgt synth", kSynthFlags);

  const auto start = std::chrono::steady_clock::now();
  const gt::synth::SynthSummary summary = gt::synth::WriteSyntheticDataset(args.out, args.options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "synth: " << gt::Counted(static_cast<long long>(summary.scene_names.size()), "scene")
            << ", " << gt::Counted(summary.frames, "frame") << " (" << args.options.width << "x"
            << args.options.height << ", seed " << args.options.seed << ") written to " << args.out
            << " in " << std::fixed << std::setprecision(2) << seconds << " s\n"
            << "  read it with --format generic " << ShellWord(args.out) << "\n";
}

}  // namespace

void AddSynthCommand(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  auto* cmd = app.add_subcommand(
      "synth", "Write a synthetic dataset (rooms with boxes, poles and panels; exact depth)");
  cmd->add_option("--out", args->out, "Output folder (created when missing)")->required();
  cmd->add_option("--scenes", args->options.scenes, "Number of rooms")->capture_default_str();
  cmd->add_option("--frames", args->options.frames_per_scene, "Frames per room")
      ->capture_default_str();
  cmd->add_option("--resolution", args->resolution, "Image size WxH")->capture_default_str();
  NonNegative(cmd->add_option("--seed", args->options.seed, "Random seed"))->capture_default_str();
  cmd->add_flag("--no-holes", args->no_holes, "Do not punch invalid-depth holes");
  cmd->add_option("--layout", args->layout,
                  "generic (occgt's manifest) or scannetpp (ScanNet++'s folders, distorted "
                  "cameras, a mesh)")
      ->capture_default_str();
  cmd->callback([args] { RunSynth(*args); });
}

}  // namespace occgt

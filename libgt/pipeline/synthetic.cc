#include "libgt/pipeline/synthetic.h"

#include <nlohmann/json.hpp>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/synth/dataset.h"

namespace gt::pipeline {

void EnsureSyntheticDataset(const std::string& root, const SyntheticDatasetOptions& options) {
  const nlohmann::json wanted = {{"generator", "occgt synth"}, {"scenes", options.scenes},
                                 {"frames", options.frames},   {"width", options.width},
                                 {"height", options.height},   {"seed", options.seed}};
  const std::string marker = root + "/.complete";
  if (io::FileExists(marker)) {
    nlohmann::json have;
    try {
      have = nlohmann::json::parse(io::ReadFileBytes(marker));
    } catch (const nlohmann::json::exception&) {
      throw InputError(marker, "not valid JSON (delete the folder to regenerate it)");
    }
    if (have != wanted) {
      throw InputError(marker, "holds a synthetic dataset of other options " + have.dump() +
                                   " than dataset.synthetic " + wanted.dump() +
                                   "; use a fresh --out folder");
    }
    return;
  }
  synth::SynthOptions o;
  o.scenes = options.scenes;
  o.frames_per_scene = options.frames;
  o.width = options.width;
  o.height = options.height;
  o.seed = options.seed;
  std::string error;
  if (!o.Check(&error)) throw InputError("dataset.synthetic", error);
  synth::WriteSyntheticDataset(root, o);
  io::WriteFileAtomic(marker, wanted.dump(2) + "\n");
}

}  // namespace gt::pipeline

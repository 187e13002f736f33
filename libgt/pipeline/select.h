// The select stage of `occgt build` (docs/USER_GUIDE.md, SCALE.md): per scene, frame scan →
// candidates (or imported pairs) → pruning → scoring → filters → seeded sampling
// (libgt/pairs/selection.h), recorded under the output folder DIR:
//   DIR/selection/<scene>.jsonl   selected pairs in selection order, one JSON object each
//                                 {scene, frame0, frame1 ({id, number}), score_stride,
//                                 score_metrics}
//   DIR/selection/<scene>.json    per-scene counts and drops; written last, it is the
//                                 scene's completion marker (a re-run skips the scene)
// (<scene> is SceneFileName(scene name); two scenes with the same file name are an error.)
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libgt/datasets/reader.h"
#include "libgt/pairs/selection.h"
#include "libgt/pipeline/recipe.h"
#include "libgt/pipeline/sample.h"

namespace gt::pipeline {

// Imported pairs, scene → pairs in file order: by frame number (format "loftr-npz", LoFTR's
// test.npz `name` [N, 4]) or by frame id (format "loftr-megadepth": LoFTR's MegaDepth
// scene_info files named by a list file, below).
struct ImportedPair {
  int64_t number0 = 0, number1 = 0;  // Frame::number, when the ids are empty
  std::string id0, id1;              // Frame::id
};
using ImportList = std::map<std::string, std::vector<ImportedPair>>;
// "loftr-megadepth": `path` is a list file (LoFTR's megadepth_test_1500.txt), one name a
// line, each naming <name>.npz beside it, a pickled dict (io/pickle.h ReadPickle) with
// "image_paths" and "pair_infos" [((i, j), score, ...)]; a pair is (stem of image_paths[i],
// stem of image_paths[j]) in the scene named by the folder after "Undistorted_SfM/" (or
// "MegaDepth_v1/") in the image path, else the name before its first '_'. Throws InputError
// naming the file and field.
ImportList ReadImportList(const std::string& path, const std::string& format = "loftr-npz");

// The recipe's scenes (dataset.scenes, the split file, the imported scenes or every scene
// under the root), sorted, each checked to exist; throws InputError naming the recipe.
std::vector<std::string> ResolveScenes(const Recipe& recipe, const datasets::DatasetReader& reader,
                                       const ImportList* imports);

// Scene file name under DIR/selection: every byte outside [A-Za-z0-9_-] replaced by '_'
// and '/' by "__".
std::string SceneFileName(const std::string& scene);

struct SceneSelection {
  std::string scene;
  std::vector<SelectedPair> pairs;
  nlohmann::json stats;  // counts, drops, options_digest
};

// Whether the recipe stores images (sample.image other than none), which needs each frame's
// colour; then InputError("<recipe>: sample.image", ...) when the scene has usable frames but
// none with colour.
bool NeedsColor(const Recipe& recipe, const Scene& scene);
// The frames the recipe keeps, as the build and `occgt covis` scan them: pairs::ScanFrames
// with the recipe's frame stride, minimum valid depth fraction and the labels' depth range,
// then, when NeedsColor, without the frames that have no colour ("scan.no_color").
pairs::ScanResult ScanRecipeFrames(const Recipe& recipe, const Scene& scene,
                                   const LabelOptions& labels, pairs::DepthCache* cache);

// Selects the pairs of one scene (decoding depth through `cache`).
SceneSelection SelectScene(const Recipe& recipe, const Scene& scene, pairs::DepthCache* cache,
                           const ImportList* imports);

std::string SelectionDir(const std::string& out_dir);
// Publishes the scene's lines and then its stats (the completion marker); returns the bytes
// written.
int64_t WriteSelection(const std::string& out_dir, const SceneSelection& selection);
// A completed selection; nullopt when the scene is not complete. A selection made with
// another options digest is an InputError (use a fresh --out).
std::optional<SceneSelection> ReadSelection(const std::string& out_dir, const std::string& scene,
                                            const std::string& digest);

}  // namespace gt::pipeline

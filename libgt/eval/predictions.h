// A matcher's predictions on a split, read from NumPy files (docs/EVAL.md "Predictions").
//
// Two layouts, both keyed by occgt's sample key "<scene>/<frame0>_<frame1>" (or by LoFTR's
// pair name: below):
//  - one .npz for the whole split, members "<key>/kpts0", "<key>/kpts1", optional
//    "<key>/confidence" and "<key>/resolution", and an optional top-level "resolution"
//    (np.savez(path, **{key + "/kpts0": ..., ...}));
//  - a folder of one .npz per pair, DIR/<key>.npz (DIR/<scene>/<frame0>_<frame1>.npz),
//    members "kpts0", "kpts1", optional "confidence" and "resolution"; a file's path under
//    DIR without ".npz" is its key or LoFTR pair name (each '/' a subfolder). Subfolders and
//    symlinks to folders are followed; a symlink back to a folder above it (a loop) is a
//    problem, and every other file must be such a .npz: nothing is skipped.
// kpts0, kpts1: float32 (float64 accepted) [N, 2] pixels (x, y), pixel centres at integer
// coordinates, at `resolution` = [W, H] (integer dtype; [2, 2] gives image 0's and image
// 1's rows) or, without one, at the split's working resolution. Every point must lie in
// the pixel area [-0.5, W - 0.5) x [-0.5, H - 0.5) of its stated resolution. Points are
// rescaled to the working resolution with x' = s (x + 0.5) - 0.5 (GROUND_TRUTH.md §1).
// confidence: float32/float64 [N], finite; kept, and used only for --min-confidence.
// Every problem (unreadable file, unknown member, wrong dtype or shape, NaN/inf, point out
// of the image, key not in the split) is one line "<file>[:<member>]: <problem>"; a pair
// with a problem is left out of the set, and the caller stops when any line was written.
// Pairs of the split without a prediction are not a problem here: the evaluation counts
// them as failures (pose error +inf, no matches).
// LoFTR pair names: the identifier LoFTR's test loop forms, '#'.join(pair_names), e.g.
// "scene0707_00/color/15.jpg#scene0707_00/color/585.jpg" (each side <folder>/color/<n>.jpg,
// <folder> the LoFTR scene folder of the split's scene, <n> Frame::number; any leading
// path components, such as a data root, are ignored). A key that is not a sample key is
// looked up in `pair_names` (LoftrPairName of every pair of the split); the same pair
// under two names is a problem.
// Dataset pair names: what a LoFTR-style loop forms from the `pair_names` of occgt's torch
// datasets (ShardDataset, PairIndexDataset): "<scene>/<id0>#<scene>/<id1>" (DatasetPairName),
// looked up in `pair_names` as it is.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace gt::eval {

struct PairPrediction {
  std::vector<float> kpts0;       // [N, 2] pixels at the working resolution
  std::vector<float> kpts1;       // [N, 2]
  std::vector<float> confidence;  // [N], empty when the file has none
  bool has_confidence = false;
  int64_t size() const { return static_cast<int64_t>(kpts0.size() / 2); }
};

struct PredictionSet {
  std::string name;    // label in outputs (unique among the sets of one evaluation)
  std::string path;    // the .npz or folder it was read from
  std::string layout;  // "npz" (one file) or "folder" (one .npz per pair)
  std::map<std::string, PairPrediction> pairs;  // by sample key
};

// Reads `path` (a .npz file or a folder of per-pair .npz). `split_keys`: the split's
// sample keys; `width`, `height`: its working resolution. Appends one line per problem
// to `problems` (in a deterministic order: members sorted by name).
PredictionSet ReadPredictions(const std::string& name, const std::string& path,
                              const std::set<std::string>& split_keys, int width, int height,
                              std::vector<std::string>* problems,
                              const std::map<std::string, std::string>& pair_names = {});

// LoFTR's identifier of a pair: "<folder>/color/<n0>.jpg#<folder>/color/<n1>.jpg".
std::string LoftrPairName(const std::string& folder, int64_t number0, int64_t number1);

// The pair name of occgt's torch datasets: "<scene>/<id0>#<scene>/<id1>".
std::string DatasetPairName(const std::string& scene, const std::string& id0,
                            const std::string& id1);

// A LoFTR pair name as LoftrPairName writes it: each '#'-side cut to its last three path
// components ("<folder>/color/<n>.<ext>" with any image extension becomes ".jpg"); "" when
// `name` is not of that form.
std::string NormalizeLoftrPairName(const std::string& name);

// Keeps the matches with confidence >= min_confidence (a pair without confidence is a
// problem line when min_confidence > 0).
void FilterByConfidence(double min_confidence, PredictionSet* set,
                        std::vector<std::string>* problems);

}  // namespace gt::eval

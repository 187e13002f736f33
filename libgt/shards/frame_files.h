// Frame files shared by the trainer exports (docs/EXPORTS.md): the LoFTR tree
// (loftr_tree.h) and the posed-image exports for glue-factory and DUSt3R (posed_export.h).
// One place converts a frame's depth to a 16-bit PNG, links files that already have the
// right form, writes pose matrices as text and removes what an earlier export left.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <set>
#include <string>

#include "libgt/core/depth.h"
#include "libgt/core/frame.h"

namespace gt::shards {

// ".jpg" / ".jpeg" in any case.
bool IsJpegPath(const std::string& path);

// The frame's depth (read at the size its reader announced, resized nearest-neighbour with
// the pixel-centre rule when width x height differs, as the working depth is) as a uint16
// grey PNG of round(d * units_per_m): 0 where the depth is invalid (0, NaN, the dataset's
// marker such as 7-Scenes' 65535), and 0 for finite depth whose value does not fit 16 bits
// (counted in *zeroed). InputError naming the file when it cannot be read.
std::string DepthPngBytes(const Frame& f, int width, int height, double units_per_m, int png_level,
                          size_t* zeroed);

// The depth an export writes for a frame of a scene at width x height (planar metres, 0 or
// NaN = invalid), when it is not the sensor's depth file: the pipeline passes the build's
// depth source (dataset.depth_source: mesh or fused, render/frame_depth.h) down as this, so
// that the exports write the depth the shards used. An empty loader means the depth file.
using FrameDepthLoader =
    std::function<DepthImage(const Scene& scene, const Frame& frame, int width, int height)>;

// `depth` (already at its output size) as the PNG above; `name` names it in errors.
std::string DepthPngBytes(const DepthImage& depth, const std::string& name, double units_per_m,
                          int png_level, size_t* zeroed);

// 4 lines of 4 numbers, one space apart, LF after each line, %.17g.
std::string Matrix4Text(const Eigen::Matrix4d& m);

// Publishes `dst` as a link to `src` (hard link, else an absolute symlink) through a
// temporary and a rename; nothing to do when dst already is that file. InputError naming
// dst on failure.
void LinkAtomic(const std::string& src, const std::string& dst);

// Removes the entries of `dir` whose names are not in `keep` (left-overs of an earlier
// export); nothing when dir does not exist.
void RemoveOthers(const std::string& dir, const std::set<std::string>& keep);

}  // namespace gt::shards

// HDF5 depth maps (MegaDepth v1 `depths/*.h5`, docs/DATASETS.md "MegaDepth"), read through
// Debian's libhdf5 C API, whose headers only libgt/io/hdf5_depth.cc includes. A depth map is
// the 2-D dataset kHdf5DepthDataset of shape (H, W), any floating-point type (converted to
// float32 by HDF5), metres up to the scene's scale; values are returned as stored (the
// caller turns invalid markers into 0). The size is checked from the dataspace before the
// pixel buffer is allocated: at most 65536 a side and 2^27 pixels, and expected_width x
// expected_height when those are > 0. Every failure is one InputError naming the file (no
// HDF5 error stack is printed on stderr).
#pragma once

#include <string>
#include <string_view>

#include "libgt/core/depth.h"

namespace gt::io {

inline constexpr const char* kHdf5DepthDataset = "depth";

DepthImage ReadHdf5Depth(const std::string& path, int expected_width = 0, int expected_height = 0);
// The same from the file's bytes in memory (an HDF5 file image; `path` names it).
DepthImage DecodeHdf5Depth(std::string_view bytes, const std::string& path, int expected_width = 0,
                           int expected_height = 0);
// An HDF5 file holding `depth` as the float32 dataset kHdf5DepthDataset (H, W), written
// atomically (io/atomic_file.h): MegaDepth's layout, for test fixtures and small exports.
void WriteHdf5Depth(const std::string& path, const DepthImage& depth);

}  // namespace gt::io

#include "libgt/shards/frame_files.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"

namespace gt::shards {

namespace fs = std::filesystem;

bool IsJpegPath(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".jpg" || ext == ".jpeg";
}

std::string DepthPngBytes(const Frame& f, int width, int height, double units_per_m, int png_level,
                          size_t* zeroed) {
  DepthImage depth = io::ReadFrameDepth(f);
  if (depth.width != width || depth.height != height) {
    depth = ResizeDepthNearest(depth, width, height);
  }
  return DepthPngBytes(depth, f.depth.path, units_per_m, png_level, zeroed);
}

std::string DepthPngBytes(const DepthImage& depth, const std::string& name, double units_per_m,
                          int png_level, size_t* zeroed) {
  cv::Mat units(depth.height, depth.width, CV_16UC1);
  size_t n_zeroed = 0;
  for (int v = 0; v < depth.height; ++v) {
    auto* row = units.ptr<uint16_t>(v);
    for (int u = 0; u < depth.width; ++u) {
      const float d = depth.at(u, v);
      if (!std::isfinite(d) || d <= 0.0f) {
        row[u] = 0;
        continue;
      }
      const double value = std::round(static_cast<double>(d) * units_per_m);
      if (value > 65535.0) {
        row[u] = 0;
        ++n_zeroed;
      } else {
        row[u] = static_cast<uint16_t>(value);
      }
    }
  }
  *zeroed = n_zeroed;
  return io::EncodePngBytes(units, io::ChannelOrder::kRgb, png_level, name);
}

std::string Matrix4Text(const Eigen::Matrix4d& m) {
  std::string text;
  char buf[32];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof(buf), "%.17g", m(r, c));
      if (c) text += ' ';
      text += buf;
    }
    text += '\n';
  }
  return text;
}

void LinkAtomic(const std::string& src, const std::string& dst) {
  std::error_code ec;
  if (fs::exists(dst, ec) && fs::equivalent(src, dst, ec)) return;
  fs::create_directories(fs::path(dst).parent_path(), ec);
  const std::string tmp = dst + ".tmp";
  fs::remove(tmp, ec);
  ec.clear();
  fs::create_hard_link(src, tmp, ec);
  if (ec) {
    ec.clear();
    fs::create_symlink(fs::absolute(src), tmp, ec);
  }
  if (ec) throw InputError(dst, "cannot link to " + src + ": " + ec.message());
  fs::rename(tmp, dst, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError(dst, "cannot rename the link into place: " + ec.message());
  }
}

void RemoveOthers(const std::string& dir, const std::set<std::string>& keep) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  std::vector<fs::path> stale;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!keep.count(e.path().filename().string())) stale.push_back(e.path());
  }
  for (const fs::path& p : stale) fs::remove_all(p, ec);
}

}  // namespace gt::shards

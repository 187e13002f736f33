#include "libgt/shards/loftr_tree.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/core/mat.hpp>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/image.h"
#include "libgt/shards/frame_files.h"
#include "libgt/shards/loftr_export.h"

namespace gt::shards {
namespace {

namespace fs = std::filesystem;

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Already ScanNet's depth: 16-bit PNG in millimetres, no marker but 0, at 640x480.
bool DepthIsScanNetForm(const Frame& f) {
  return f.depth.format == DepthFormat::kPng16 && f.depth.scale_m_per_unit == 0.001 &&
         !f.depth_lens && f.mask_path.empty() &&
         (f.depth.invalid_value < 0 || f.depth.invalid_value == 0) &&
         Lower(fs::path(f.depth.path).extension().string()) == ".png" &&
         f.depth_camera.width == kLoftrWidth && f.depth_camera.height == kLoftrHeight;
}

std::string IntrinsicText(const Camera& camera) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = camera.K();
  return Matrix4Text(m);
}

// One frame's outputs: files to write (converted) and links to make.
struct FrameOutput {
  std::vector<io::FileToWrite> files;
  std::vector<std::pair<std::string, std::string>> links;  // (source, destination)
  Camera color_camera;                                     // K of the colour file as written
  size_t linked = 0, converted = 0, zeroed = 0;
};

FrameOutput ExportFrame(const Scene& scene, const Frame& f, const std::string& folder,
                        const LoftrTreeOptions& options) {
  FrameOutput out;
  const std::string n = std::to_string(f.number);
  if (f.color_path.empty()) {
    throw InputError(f.depth.path, "loftr tree: frame " + f.id +
                                       " has no colour image (LoFTR reads color/" + n + ".jpg)");
  }
  // Colour.
  const std::string color_dst = folder + "/color/" + n + ".jpg";
  // A JPEG file is linked; a payload inside a container (.sens) or another format is
  // decoded and written as JPEG.
  if (f.color_range.size == 0 && !f.color_lens && IsJpegPath(f.color_path)) {
    out.links.emplace_back(f.color_path, color_dst);
    ++out.linked;
    if (f.color_camera.width > 0) {
      out.color_camera = f.color_camera;
    } else {
      const io::ImageSize size = io::ReadImageSize(f.color_path);
      out.color_camera = f.depth_camera.Resized(size.width, size.height);
    }
  } else {
    const io::ColorImage rgb = io::ReadFrameColor(f);
    const cv::Mat m(rgb.height, rgb.width, CV_8UC3, const_cast<uint8_t*>(rgb.rgb.data()));
    out.files.push_back({color_dst, io::EncodeJpegBytes(m, io::ChannelOrder::kRgb,
                                                        options.jpeg_quality, f.color_path)});
    ++out.converted;
    out.color_camera = f.color_camera.width == rgb.width && f.color_camera.height == rgb.height
                           ? f.color_camera
                           : f.depth_camera.Resized(rgb.width, rgb.height);
  }
  // Depth.
  const std::string depth_dst = folder + "/depth/" + n + ".png";
  if (options.load_depth) {
    out.files.push_back(
        {depth_dst, DepthPngBytes(options.load_depth(scene, f, kLoftrWidth, kLoftrHeight),
                                  depth_dst, 1000.0, options.png_level, &out.zeroed)});
    ++out.converted;
  } else if (DepthIsScanNetForm(f)) {
    out.links.emplace_back(f.depth.path, depth_dst);
    ++out.linked;
  } else {
    out.files.push_back({depth_dst, DepthPngBytes(f, kLoftrWidth, kLoftrHeight, 1000.0,
                                                  options.png_level, &out.zeroed)});
    ++out.converted;
  }
  // Pose.
  out.files.push_back({folder + "/pose/" + n + ".txt", Matrix4Text(f.world_from_cam.matrix())});
  return out;
}

const Frame& FrameByNumber(const Scene& scene, int64_t number) {
  for (const Frame& f : scene.frames) {
    if (f.number == number && f.usable) return f;
  }
  throw InputError("loftr tree",
                   "scene " + scene.name + " has no usable frame number " + std::to_string(number));
}

}  // namespace

std::map<std::string, std::string> LoftrSceneFolders(const std::set<std::string>& scenes) {
  std::map<std::string, std::string> folders;
  std::map<std::string, std::string> scene_of_folder;
  int64_t other = 0;
  for (const std::string& s : scenes) {
    std::string folder = s;
    if (!ParseScanNetSceneName(s)) {
      // Its name is a line of scenes.txt (loftr_export.h), which a line break would split.
      if (s.find_first_of("\r\n") != std::string::npos) {
        throw InputError("loftr export", "scene " + s +
                                             " has a line break in its name, which scenes.txt "
                                             "(one scene name a line) cannot hold; rename it");
      }
      char buf[32];
      std::snprintf(buf, sizeof(buf), "scene%04lld_00", static_cast<long long>(other++));
      folder = buf;
    }
    const auto [it, fresh] = scene_of_folder.emplace(folder, s);
    if (!fresh) {
      throw InputError("loftr export", "scenes " + it->second + " and " + s +
                                           " both map to LoFTR's folder " + folder);
    }
    folders[s] = folder;
  }
  return folders;
}

bool LoftrTreeOptions::Check(std::string* error) const {
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    return *error = "jpeg_quality: expected 1..100", false;
  }
  if (png_level < 0 || png_level > 9) return *error = "png_level: expected 0..9", false;
  return true;
}

LoftrTreeStats ExportLoftrTree(const std::string& tree_dir,
                               const std::vector<LoftrTreeScene>& scenes,
                               const LoftrTreeOptions& options) {
  if (std::string e; !options.Check(&e)) throw InputError("loftr tree options", e);
  LoftrTreeStats stats;
  std::set<std::string> folders;
  for (const LoftrTreeScene& s : scenes) {
    if (s.scene == nullptr || s.folder.empty()) throw InputError("loftr tree", "empty scene");
    if (!folders.insert(s.folder).second) {
      throw InputError("loftr tree", "folder " + s.folder + " given twice");
    }
    std::vector<int64_t> numbers = s.numbers;
    std::sort(numbers.begin(), numbers.end());
    numbers.erase(std::unique(numbers.begin(), numbers.end()), numbers.end());
    std::vector<const Frame*> frames;
    for (int64_t n : numbers) frames.push_back(&FrameByNumber(*s.scene, n));
    const std::string folder = (fs::path(tree_dir) / s.folder).string();

    // Chunks of frames: decode and encode in parallel, then publish the chunk's files.
    constexpr size_t kChunk = 32;
    Camera color_camera;
    for (size_t begin = 0; begin < frames.size(); begin += kChunk) {
      const size_t end = std::min(frames.size(), begin + kChunk);
      std::vector<FrameOutput> outputs(end - begin);
      tbb::parallel_for(begin, end, [&](size_t i) {
        outputs[i - begin] = ExportFrame(*s.scene, *frames[i], folder, options);
      });
      std::vector<io::FileToWrite> files;
      for (FrameOutput& o : outputs) {
        for (auto& [src, dst] : o.links) LinkAtomic(src, dst);
        for (io::FileToWrite& f : o.files) files.push_back(std::move(f));
        stats.linked += o.linked;
        stats.converted += o.converted;
        stats.depth_zeroed_px += o.zeroed;
      }
      if (begin == 0 && !outputs.empty()) color_camera = outputs.front().color_camera;
      io::WriteFilesAtomic(files);
    }
    stats.frames += frames.size();
    if (!frames.empty()) {
      const Camera depth_camera = frames.front()->depth_camera.Resized(kLoftrWidth, kLoftrHeight);
      io::WriteFilesAtomic(
          {{folder + "/intrinsic/intrinsic_depth.txt", IntrinsicText(depth_camera)},
           {folder + "/intrinsic/intrinsic_color.txt", IntrinsicText(color_camera)}});
    }
    std::set<std::string> jpg, png, txt;
    for (const Frame* f : frames) {
      const std::string n = std::to_string(f->number);
      jpg.insert(n + ".jpg");
      png.insert(n + ".png");
      txt.insert(n + ".txt");
    }
    RemoveOthers(folder + "/color", jpg);
    RemoveOthers(folder + "/depth", png);
    RemoveOthers(folder + "/pose", txt);
    RemoveOthers(folder + "/intrinsic", {"intrinsic_depth.txt", "intrinsic_color.txt"});
    RemoveOthers(folder, {"color", "depth", "pose", "intrinsic"});
  }
  RemoveOthers(tree_dir, folders);
  return stats;
}

}  // namespace gt::shards

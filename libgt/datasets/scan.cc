#include "libgt/datasets/scan.h"

#include <cmath>
#include <sstream>

#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/datasets/readers.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"

namespace gt::datasets {

bool ScanOptions::Check(std::string* error) const {
  if (max_errors_listed < 0) {
    if (error) *error = "max_errors_listed must be >= 0";
    return false;
  }
  if (max_examples_listed < 0) {
    if (error) *error = "max_examples_listed must be >= 0";
    return false;
  }
  return true;
}

namespace {
bool SameCamera(const Camera& a, const Camera& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
         a.cx == b.cx && a.cy == b.cy;
}
}  // namespace

std::vector<std::string> DatasetCaveats(DatasetFormat format) {
  if (format == DatasetFormat::kSevenScenes) {
    return {
        "7-Scenes depth and colour come from different, unregistered cameras (no "
        "extrinsics are published): labels follow the depth camera, and colour pixels are "
        "only approximately aligned with them"};
  }
  if (format == DatasetFormat::kScanNetPP) {
    return {
        "ScanNet++ frames are undistorted at load into ScanNet++'s pinhole camera (fisheye: "
        "balance 0, principal point (w/2, h/2); OPENCV: the optimal new K); DSLR images have "
        "no sensor depth: it is rendered from scans/mesh_aligned_0.05.ply, and anonymised "
        "pixels have none"};
  }
  if (format == DatasetFormat::kMegaDepth) {
    return {
        "MegaDepth depth is multi-view stereo with holes and errors, and its scale is "
        "arbitrary per scene: expect a share of INCONSISTENT and UNKNOWN labels (see the "
        "report), use relative tolerances (preset megadepth), and images of other aspect "
        "ratios are stretched to the working resolution"};
  }
  return {};
}

namespace {
// The pixel area is [-0.5, w - 0.5] x [-0.5, h - 0.5] (core/camera.h: pixel centres at integers).
bool PrincipalPointInImage(const Camera& c) {
  return c.cx >= -0.5 && c.cx <= c.width - 0.5 && c.cy >= -0.5 && c.cy <= c.height - 0.5;
}

// A colour K whose principal point lies outside its image: intrinsics of another image size
// (ScanNet's intrinsic_color.txt of the 1296x968 original beside colour resized to 640x480).
// One line naming the K's file when the reader knows it, the sizes and the frames; "" when
// every frame with colour is consistent.
std::string ColorPrincipalPointWarning(const Scene& scene) {
  size_t with_color = 0, outside = 0;
  const Frame* first = nullptr;
  for (const Frame& f : scene.frames) {
    if (f.color_path.empty() || f.color_camera.width <= 0 || f.color_camera.height <= 0) continue;
    ++with_color;
    if (PrincipalPointInImage(f.color_camera)) continue;
    if (first == nullptr) first = &f;
    ++outside;
  }
  if (first == nullptr) return "";
  const std::string source =
      scene.format == DatasetFormat::kScanNet ? ScanNetColorIntrinsicsSource(scene) : "";
  const Camera& c = first->color_camera;
  std::ostringstream s;
  s << (source.empty() ? "colour K" : source) << ": principal point (" << c.cx << ", " << c.cy
    << ") lies outside the " << c.width << "x" << c.height << " colour image (" << outside << " of "
    << with_color << " frames with colour; first: frame " << first->id << "): expected a K for "
    << c.width << "x" << c.height
    << " images (intrinsics of the original size beside resized images?); colour pixels will "
       "not line up with depth";
  return s.str();
}

// The principal point lies within the central half of the image (a quarter of the size
// from the centre at most). A K of twice the size has it at the far edge, still inside.
bool PrincipalPointCentral(const Camera& c) {
  return std::abs(c.cx - 0.5 * (c.width - 1)) <= 0.25 * c.width &&
         std::abs(c.cy - 0.5 * (c.height - 1)) <= 0.25 * c.height;
}

// The same for the depth K at the depth size the reader found (a wrong depth K misplaces
// every label, not only the colour), by the stricter rule above: a depth map at half the
// size of its K (a 7-Scenes depth PNG at 320x240 beside the 640x480 K) is caught too.
std::string DepthPrincipalPointWarning(const Scene& scene) {
  size_t outside = 0;
  const Frame* first = nullptr;
  for (const Frame& f : scene.frames) {
    if (f.depth_camera.width <= 0 || f.depth_camera.height <= 0) continue;
    if (PrincipalPointCentral(f.depth_camera)) continue;
    if (first == nullptr) first = &f;
    ++outside;
  }
  if (first == nullptr) return "";
  const Camera& c = first->depth_camera;
  std::ostringstream s;
  s << "depth K: principal point (" << c.cx << ", " << c.cy
    << ") lies outside the central half of the " << c.width << "x" << c.height << " depth map ("
    << outside << " of " << scene.frames.size() << " frames; first: frame " << first->id
    << "): expected a K for " << c.width << "x" << c.height
    << " depth maps (intrinsics of another size?); every label of these frames would be "
       "misplaced";
  return s.str();
}

// "" when the mask has a valid (255) pixel, kReasonMaskCoversImage when none, else the error.
std::string MaskProblem(const std::string& path) {
  try {
    const cv::Mat m = io::DecodeImageBytes(io::ReadFileBytes(path), io::ChannelOrder::kRgb, path);
    if (m.type() != CV_8UC1) return path + ": mask: expected an 8-bit grey image";
    for (int v = 0; v < m.rows; ++v) {
      const uint8_t* row = m.ptr<uint8_t>(v);
      for (int u = 0; u < m.cols; ++u) {
        if (row[u] == 255) return "";
      }
    }
    return kReasonMaskCoversImage;
  } catch (const InputError& e) {
    return e.what();
  }
}
}  // namespace

SceneSummary SummarizeScene(const Scene& scene, const ScanOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("scan options", error);
  SceneSummary s;
  s.name = scene.name;
  s.path = scene.path;
  s.frames = scene.frames.size();
  s.min_depth_m = scene.min_depth_m;
  s.max_depth_m = scene.max_depth_m;
  if (!scene.frames.empty()) s.depth_camera = scene.frames.front().depth_camera;
  s.warnings = DatasetCaveats(scene.format);
  s.warnings.insert(s.warnings.end(), scene.reader_warnings.begin(), scene.reader_warnings.end());
  if (scene.format == DatasetFormat::kTum) {
    for (std::string& w : TumSceneWarnings(scene)) s.warnings.push_back(std::move(w));
  }
  for (std::string w : {DepthPrincipalPointWarning(scene), ColorPrincipalPointWarning(scene)}) {
    if (!w.empty()) s.warnings.push_back(std::move(w));
  }
  // ScanNet++ renders the DSLR's depth from the scene's mesh: without it those frames have
  // none (a build drops every one as scan.read_error).
  if (scene.format == DatasetFormat::kScanNetPP && scene.mesh_path.empty()) {
    s.warnings.push_back(
        "no mesh (scans/mesh_aligned_0.05.ply is missing): the DSLR frames have no depth "
        "without it, and depth_source mesh or fused cannot run on this scene");
  }
  const Frame* first_without_color = nullptr;
  bool have_color_camera = false;
  s.depth_checked = options.check_depth;
  double fraction_sum = 0.0;
  size_t bad_colors = 0;  // with check_depth: colour headers unreadable or of another size
  std::string first_bad_color;
  const auto count_unusable = [&](const Frame& f, const std::string& reason,
                                  const std::string& detail) {
    if (static_cast<int>(s.unusable_reasons[reason]++) < options.max_examples_listed) {
      s.unusable_examples[reason].push_back({f.id, detail});
    }
  };
  for (const Frame& f : scene.frames) {
    if (!SameCamera(f.depth_camera, s.depth_camera)) s.uniform_depth_camera = false;
    if (!f.usable) {
      count_unusable(f, f.unusable_reason, f.unusable_detail);
      continue;
    }
    if (options.check_masks && !f.mask_path.empty()) {
      const std::string problem = MaskProblem(f.mask_path);
      if (!problem.empty()) {
        count_unusable(
            f, problem == kReasonMaskCoversImage ? kReasonMaskCoversImage : kReasonMaskUnreadable,
            problem == kReasonMaskCoversImage ? f.mask_path + ": no pixel is 255" : problem);
        continue;
      }
    }
    if (options.check_depth) {
      try {
        const DepthImage d = io::ReadFrameDepth(f);
        ++s.depth_files_read;
        fraction_sum += ValidDepthFraction(d, scene.min_depth_m, scene.max_depth_m);
      } catch (const InputError& e) {
        ++s.depth_files_bad;
        count_unusable(f, kReasonDepthUnreadable, e.what());
        if (static_cast<int>(s.depth_errors.size()) < options.max_errors_listed) {
          s.depth_errors.emplace_back(e.what());
        }
        continue;
      }
    }
    ++s.usable;
    s.usable_ids.insert(f.id);
    if (f.color_path.empty() && first_without_color == nullptr) first_without_color = &f;
    // With check_depth, the colour file's header too (what a build storing images reads at
    // its scan: a frame failing it is skipped there, scan.color_error).
    bool color_ok = !f.color_path.empty();
    if (color_ok && options.check_depth) {
      try {
        io::CheckFrameColorHeader(f);
      } catch (const InputError& e) {
        color_ok = false;
        if (bad_colors++ == 0) first_bad_color = "frame " + f.id + ": " + e.what();
      }
    }
    if (color_ok) {
      ++s.usable_with_color;
      if (!have_color_camera) {
        s.color_camera = f.color_camera;
        have_color_camera = true;
      } else if (!SameCamera(f.color_camera, s.color_camera)) {
        s.uniform_color_camera = false;
      }
    }
  }
  if (s.depth_files_read > 0) s.mean_valid_fraction = fraction_sum / s.depth_files_read;
  if (bad_colors > 0) {
    s.warnings.push_back(std::to_string(bad_colors) +
                         " usable frame(s) have a colour file whose header cannot be read or "
                         "gives another size than its K's (first: " +
                         first_bad_color +
                         "): a build that stores images skips them (drop scan.color_error)");
  }
  if (s.usable > 0 && s.usable_with_color == 0) {
    s.warnings.emplace_back(
        "no usable frame has a colour image: a build that stores images "
        "stops (set sample.image: none)");
  } else if (first_without_color != nullptr) {
    s.warnings.emplace_back(
        std::to_string(s.usable - s.usable_with_color - bad_colors) + " of " +
        std::to_string(s.usable) + " usable frames have no colour image (first: frame " +
        first_without_color->id + "): a build that stores images skips them (drop scan.no_color)");
  }
  return s;
}

}  // namespace gt::datasets

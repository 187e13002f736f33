#include "libgt/io/scan.h"

#include "libgt/core/depth.h"
#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"

namespace gt::io {

bool ScanOptions::Check(std::string* error) const {
  if (max_errors_listed < 0) {
    if (error) *error = "max_errors_listed must be >= 0";
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
  s.depth_checked = options.check_depth;
  double fraction_sum = 0.0;
  for (const Frame& f : scene.frames) {
    if (!SameCamera(f.depth_camera, s.depth_camera)) s.uniform_depth_camera = false;
    if (!f.usable) {
      ++s.unusable_reasons[f.unusable_reason];
      continue;
    }
    if (options.check_depth) {
      try {
        const DepthImage d = ReadDepth(f.depth, f.depth_camera.width, f.depth_camera.height);
        ++s.depth_files_read;
        fraction_sum += ValidDepthFraction(d, scene.min_depth_m, scene.max_depth_m);
      } catch (const InputError& e) {
        ++s.depth_files_bad;
        ++s.unusable_reasons[kReasonDepthUnreadable];
        if (static_cast<int>(s.depth_errors.size()) < options.max_errors_listed) {
          s.depth_errors.emplace_back(e.what());
        }
        continue;
      }
    }
    ++s.usable;
  }
  if (s.depth_files_read > 0) s.mean_valid_fraction = fraction_sum / s.depth_files_read;
  return s;
}

}  // namespace gt::io

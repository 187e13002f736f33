#include "libgt/truth/working_frame.h"

#include <cstdlib>
#include <sstream>
#include <utility>

#include "libgt/core/error.h"
#include "libgt/io/depth_io.h"

namespace gt::truth {

bool Resolution::Check(std::string* error) const {
  if (width < kMinResolution || height < kMinResolution || width > kMaxResolution ||
      height > kMaxResolution) {
    *error = "expected width and height in " + std::to_string(kMinResolution) + ".." +
             std::to_string(kMaxResolution) + ", got " + std::to_string(width) + "x" +
             std::to_string(height);
    return false;
  }
  return true;
}

Resolution ParseResolution(const std::string& text, const std::string& field) {
  Resolution r;
  char x = 0, extra = 0;
  std::istringstream in(text);
  std::string error;
  if (!(in >> r.width >> x >> r.height) || x != 'x' || (in >> extra) || !r.Check(&error)) {
    throw InputError(field, "expected WxH with integers in " + std::to_string(kMinResolution) +
                                ".." + std::to_string(kMaxResolution) + ", got '" + text + "'");
  }
  return r;
}

Camera WorkingCamera(const Frame& frame, const Resolution& resolution) {
  return frame.depth_camera.Resized(resolution.width, resolution.height);
}

DepthImage LoadWorkingDepth(const Frame& frame, const Resolution& resolution) {
  DepthImage full = io::ReadFrameDepth(frame);
  if (full.width == resolution.width && full.height == resolution.height) return full;
  return ResizeDepthNearest(full, resolution.width, resolution.height);
}

WorkingFrame LoadWorkingFrame(const Frame& frame, const Resolution& resolution) {
  WorkingFrame f;
  f.depth = std::make_shared<const DepthImage>(LoadWorkingDepth(frame, resolution));
  f.camera = WorkingCamera(frame, resolution);
  f.world_from_cam = frame.world_from_cam;
  return f;
}

DepthImage LoadWorkingDepth(const Scene& scene, const Frame& frame, const Resolution& resolution,
                            const render::FrameDepthOptions& depth,
                            render::DepthAgreement* agreement) {
  if (depth.source == render::DepthSourceMode::kSensor && agreement == nullptr) {
    return LoadWorkingDepth(frame, resolution);
  }
  if (depth.source == render::DepthSourceMode::kMesh && agreement == nullptr) {
    return render::LoadFrameDepth(scene, frame, WorkingCamera(frame, resolution),
                                  depth);  // no sensor read
  }
  // A frame without a depth file (ScanNet++ DSLR) has no sensor depth anywhere.
  const DepthImage sensor = frame.depth.path.empty()
                                ? DepthImage(resolution.width, resolution.height)
                                : LoadWorkingDepth(frame, resolution);
  return render::LoadFrameDepth(scene, frame, WorkingCamera(frame, resolution), depth, agreement,
                                &sensor);
}

render::DepthAgreement CompareWorkingDepthWithMesh(const Scene& scene, const Frame& frame,
                                                   const Resolution& resolution,
                                                   const render::FrameDepthOptions& depth) {
  render::FrameDepthOptions mesh = depth;
  mesh.source = render::DepthSourceMode::kMesh;
  render::DepthAgreement agreement;
  LoadWorkingDepth(scene, frame, resolution, mesh, &agreement);
  return agreement;
}

WorkingFrame LoadWorkingFrame(const Scene& scene, const Frame& frame, const Resolution& resolution,
                              const render::FrameDepthOptions& depth) {
  WorkingFrame f;
  f.depth = std::make_shared<const DepthImage>(LoadWorkingDepth(scene, frame, resolution, depth));
  f.camera = WorkingCamera(frame, resolution);
  f.world_from_cam = frame.world_from_cam;
  return f;
}

size_t FindFrame(const Scene& scene, const std::string& id, const std::string& field) {
  for (size_t i = 0; i < scene.frames.size(); ++i) {
    const Frame& f = scene.frames[i];
    if (f.id != id) continue;
    if (!f.usable) throw InputError(field, "frame " + id + " is unusable: " + f.UnusableMessage());
    return i;
  }
  // A frame number given for an id ("40" for TartanAir's "000040"): name the id.
  std::string example;
  char* end = nullptr;
  const long long number = std::strtoll(id.c_str(), &end, 10);
  for (const Frame& f : scene.frames) {
    if (!id.empty() && *end == '\0' && f.number == number) {
      example = " (did you mean '" + f.id + "'?)";
      break;
    }
  }
  if (example.empty() && !scene.frames.empty()) {
    example = " (ids look like '" + scene.frames.front().id + "')";
  }
  throw InputError(field, "no frame with id '" + id + "' in scene " + scene.name + example);
}

std::pair<std::string, std::string> ParseFramePair(const std::string& text,
                                                   const std::string& field) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos || comma == 0 || comma + 1 == text.size() ||
      text.find(',', comma + 1) != std::string::npos) {
    throw InputError(field, "expected two frame ids ID0,ID1, got '" + text + "'");
  }
  // A frame with itself is every pixel VISIBLE: a typo, not a pair (as render's --frames).
  if (text.compare(0, comma, text, comma + 1) == 0) {
    throw InputError(field, "'" + text.substr(0, comma) + "' given twice in '" + text +
                                "': expected two different frames");
  }
  return {text.substr(0, comma), text.substr(comma + 1)};
}

}  // namespace gt::truth

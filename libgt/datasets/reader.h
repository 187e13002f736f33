// One interface for every dataset layout (docs/DATASETS.md). A reader lists the scenes
// under a root and reads one scene's frames: ids, K at the depth resolution,
// world_from_cam in OpenCV axes, the depth source and the colour path with its K.
// It never guesses silently: a missing file, a short pose file, a bad token or a size
// mismatch throws InputError naming the file; a frame that is unusable (lost tracking,
// non-rigid pose, missing depth) is kept with usable = false and the reason.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/frame.h"

namespace gt::datasets {

// ScanNet++: which camera's images a scene's frames are (dataset option `device`).
enum class ScanNetPPDevice { kDslr, kIphone };
const char* ScanNetPPDeviceName(ScanNetPPDevice device);  // "dslr", "iphone"
// InputError(field, "unknown device '<name>', expected dslr or iphone").
ScanNetPPDevice ParseScanNetPPDevice(std::string_view name, const std::string& field);

// The device whose frame ids look like `frame_id`: iPhone frames are frame_%06d, DSLR images
// DSC%05d. The rule for commands given frame ids without a device, and for `occgt pair`
// folders written before meta.json recorded the device; a build records it (recipe.json's
// dataset.device) and commands re-reading a build use that.
ScanNetPPDevice ScanNetPPDeviceOfFrameId(std::string_view frame_id);
// Refuses a frame id of the other device's shape: InputError(field, "'frame_000010' is an
// iPhone frame id, but <device_source> says dslr"). device_source names where the device
// came from (a flag, "<dir>/recipe.json: dataset.device", ...).
void CheckScanNetPPFrameId(ScanNetPPDevice device, std::string_view frame_id,
                           const std::string& field, const std::string& device_source);

struct ReaderOptions {
  double tum_max_dt_s = 0.02;     // TUM: max |t_depth - t_pose| and |t_depth - t_rgb| (seconds)
  std::string exr_channel;        // generic manifest: default EXR channel when a frame has none
  bool check_depth_files = true;  // stat every depth file while reading a scene
  ScanNetPPDevice scannetpp_device = ScanNetPPDevice::kDslr;  // scannetpp: dslr/ or iphone/

  bool Check(std::string* error) const;
};

class DatasetReader {
 public:
  virtual ~DatasetReader() = default;
  virtual DatasetFormat Format() const = 0;
  // Scene names under root, sorted. A root that is itself one scene yields one name.
  virtual std::vector<std::string> ListScenes(const std::string& root) const = 0;
  virtual Scene ReadScene(const std::string& root, const std::string& scene_name) const = 0;
};

// reader.ListScenes(root), each name checked to be UTF-8 text: occgt's JSON outputs
// (pairs.jsonl, summaries, `scan --json`) and Python's str name every scene by it, so a
// folder name that is not is an InputError naming the folder (before any work), not a
// failure at the first JSON line.
std::vector<std::string> ListSceneNames(const DatasetReader& reader, const std::string& root);

// The names of every format (DatasetFormatName of kAllDatasetFormats, in that order).
std::vector<std::string> KnownFormats();
// The reader of a format (core/frame.h ParseDatasetFormat turns a name into one); throws
// InputError("reader options", ...) for options that fail Check.
std::unique_ptr<DatasetReader> MakeReader(DatasetFormat format, const ReaderOptions& options = {});

}  // namespace gt::datasets

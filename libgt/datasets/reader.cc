#include "libgt/datasets/reader.h"

#include <cmath>

#include "libgt/core/error.h"
#include "libgt/core/utf8.h"
#include "libgt/datasets/readers.h"
#include "libgt/datasets/text_parsing.h"

namespace gt::datasets {

bool ReaderOptions::Check(std::string* error) const {
  if (!std::isfinite(tum_max_dt_s) || tum_max_dt_s < 0) {
    if (error)
      *error = "tum_max_dt_s must be a finite number >= 0, got " + std::to_string(tum_max_dt_s);
    return false;
  }
  return true;
}

const char* ScanNetPPDeviceName(ScanNetPPDevice device) {
  return device == ScanNetPPDevice::kDslr ? "dslr" : "iphone";
}

ScanNetPPDevice ParseScanNetPPDevice(std::string_view name, const std::string& field) {
  if (name == "dslr") return ScanNetPPDevice::kDslr;
  if (name == "iphone") return ScanNetPPDevice::kIphone;
  throw InputError(field, "unknown device '" + std::string(name) + "', expected dslr or iphone");
}

ScanNetPPDevice ScanNetPPDeviceOfFrameId(std::string_view frame_id) {
  return frame_id.rfind("frame_", 0) == 0 ? ScanNetPPDevice::kIphone : ScanNetPPDevice::kDslr;
}

void CheckScanNetPPFrameId(ScanNetPPDevice device, std::string_view frame_id,
                           const std::string& field, const std::string& device_source) {
  const ScanNetPPDevice shape = ScanNetPPDeviceOfFrameId(frame_id);
  if (shape == device) return;
  throw InputError(field, "'" + std::string(frame_id) + "' is " +
                              (shape == ScanNetPPDevice::kIphone ? "an iPhone" : "a DSLR") +
                              " frame id, but " + device_source + " says " +
                              ScanNetPPDeviceName(device));
}

std::vector<std::string> KnownFormats() {
  std::vector<std::string> names;
  for (const DatasetFormat f : kAllDatasetFormats) names.emplace_back(DatasetFormatName(f));
  return names;
}

std::vector<std::string> ListSceneNames(const DatasetReader& reader, const std::string& root) {
  std::vector<std::string> names = reader.ListScenes(root);
  for (const std::string& name : names) {
    if (!IsUtf8(name)) {
      const std::string folder = FolderName(root) == name ? root : root + "/" + name;
      throw InputError(folder,
                       "the scene's folder name is not UTF-8 text (occgt names each "
                       "scene by it in JSON and Python): rename the folder");
    }
  }
  return names;
}

std::unique_ptr<DatasetReader> MakeReader(DatasetFormat format, const ReaderOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("reader options", error);
  switch (format) {
    case DatasetFormat::kScanNet:
      return std::make_unique<ScanNetReader>(options);
    case DatasetFormat::kTartanAir:
      return std::make_unique<TartanAirReader>(options);
    case DatasetFormat::kSevenScenes:
      return std::make_unique<SevenScenesReader>(options);
    case DatasetFormat::kTum:
      return std::make_unique<TumReader>(options);
    case DatasetFormat::kMegaDepth:
      return std::make_unique<MegaDepthReader>(options);
    case DatasetFormat::kGeneric:
      return std::make_unique<GenericReader>(options);
    case DatasetFormat::kScanNetPP:
      return std::make_unique<ScanNetPPReader>(options);
  }
  GT_ASSERT(false && "unknown DatasetFormat");
  return nullptr;
}

}  // namespace gt::datasets

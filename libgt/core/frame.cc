#include "libgt/core/frame.h"

#include "libgt/core/error.h"

namespace gt {

const char* DatasetFormatName(DatasetFormat format) {
  switch (format) {
    case DatasetFormat::kScanNet:
      return "scannet";
    case DatasetFormat::kTartanAir:
      return "tartanair";
    case DatasetFormat::kSevenScenes:
      return "sevenscenes";
    case DatasetFormat::kTum:
      return "tum";
    case DatasetFormat::kMegaDepth:
      return "megadepth";
    case DatasetFormat::kGeneric:
      return "generic";
    case DatasetFormat::kScanNetPP:
      return "scannetpp";
  }
  GT_ASSERT(false && "unknown DatasetFormat");
  return "";
}

DatasetFormat ParseDatasetFormat(std::string_view name, const std::string& field) {
  std::string known;
  for (const DatasetFormat f : kAllDatasetFormats) {
    if (name == DatasetFormatName(f)) return f;
    known += (known.empty() ? "" : ", ") + std::string(DatasetFormatName(f));
  }
  throw InputError(field, "unknown format '" + std::string(name) + "', expected one of: " + known);
}

}  // namespace gt

#include "libgt/io/reader.h"

#include <cmath>

#include "libgt/core/error.h"
#include "libgt/io/readers.h"

namespace gt::io {

bool ReaderOptions::Check(std::string* error) const {
  if (!std::isfinite(tum_max_dt_s) || tum_max_dt_s < 0) {
    if (error)
      *error = "tum_max_dt_s must be a finite number >= 0, got " + std::to_string(tum_max_dt_s);
    return false;
  }
  return true;
}

std::vector<std::string> KnownFormats() {
  return {"scannet", "tartanair", "sevenscenes", "tum", "megadepth", "generic"};
}

std::unique_ptr<DatasetReader> MakeReader(const std::string& format, const ReaderOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("reader options", error);
  if (format == "scannet") return std::make_unique<ScanNetReader>(options);
  if (format == "tartanair") return std::make_unique<TartanAirReader>(options);
  if (format == "sevenscenes") return std::make_unique<SevenScenesReader>(options);
  if (format == "tum") return std::make_unique<TumReader>(options);
  if (format == "megadepth") return std::make_unique<MegaDepthReader>(options);
  if (format == "generic") return std::make_unique<GenericReader>(options);
  std::string known;
  for (const auto& f : KnownFormats()) known += (known.empty() ? "" : ", ") + f;
  throw InputError("--format", "unknown format '" + format + "', expected one of: " + known);
}

}  // namespace gt::io

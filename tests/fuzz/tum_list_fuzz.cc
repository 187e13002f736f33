// TUM "timestamp filename" lists (rgb.txt / depth.txt, the association input):
// gt::datasets::ParseTimedPathList, then the whole TUM reader on a per-process scratch sequence
// whose depth.txt, rgb.txt and groundtruth.txt are the input split at the first two NUL
// bytes (association by nearest timestamp, pose checks, duplicate ids).
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>

#include "libgt/datasets/reader.h"
#include "libgt/datasets/text_parsing.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

void WriteFile(const std::string& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text = gt::fuzz::Bytes(data, size);
  const std::string name = "depth.txt";
  gt::fuzz::ExpectValueOrInputError(name, [&] {
    const auto list = gt::datasets::ParseTimedPathList(text, name);
    for (size_t i = 1; i < list.size(); ++i) {
      if (list[i].t < list[i - 1].t) std::abort();
    }
  });

  static const std::string dir = [] {
    const auto d = std::filesystem::temp_directory_path() /
                   ("occgt-fuzz-tum-" + std::to_string(::getpid())) / "rgbd_dataset_freiburg1_x";
    std::filesystem::create_directories(d);
    return d.string();
  }();
  const size_t a = text.find('\0');
  const size_t b = a == std::string_view::npos ? a : text.find('\0', a + 1);
  WriteFile(dir + "/depth.txt", text.substr(0, a));
  WriteFile(dir + "/rgb.txt", a == std::string_view::npos ? "" : text.substr(a + 1, b - a - 1));
  WriteFile(dir + "/groundtruth.txt", b == std::string_view::npos ? "" : text.substr(b + 1));
  gt::datasets::ReaderOptions options;
  options.check_depth_files = false;
  gt::fuzz::ExpectValueOrInputError(dir, [&] {
    const gt::Scene scene = gt::datasets::MakeReader(gt::DatasetFormat::kTum, options)->ReadScene(dir, "");
    for (const gt::Frame& f : scene.frames) {
      if (f.usable && !f.world_from_cam.matrix().allFinite()) std::abort();
    }
  });
  return 0;
}

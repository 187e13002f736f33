#include "libgt/io/hdf5_depth.h"

#include <hdf5.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"

namespace gt::io {
namespace {

constexpr hsize_t kMaxSide = kMaxImageSidePx;
constexpr hsize_t kMaxPixels = hsize_t{1} << 27;

// A thread-safe libhdf5 (Debian's is: H5_HAVE_THREADSAFE) serialises its calls itself;
// another build is serialised here.
#ifdef H5_HAVE_THREADSAFE
struct NoLock {};
NoLock Lock() { return {}; }
#else
std::mutex hdf5_mutex;
std::unique_lock<std::mutex> Lock() { return std::unique_lock<std::mutex>(hdf5_mutex); }
#endif

// Closes an HDF5 identifier with its close function when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// HDF5 prints its error stack on stderr by default, per thread in a thread-safe build.
void Quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// A name for an in-memory (core driver) file. The driver first tries to open the name on
// disk and refuses a file image when that succeeds, so it must never exist (/dev/null is
// not a folder); and HDF5 takes two open core files of one name for the same file, so
// every call gets its own.
std::string InMemoryName() {
  static std::atomic<uint64_t> counter{0};
  return "/dev/null/occgt-hdf5-image-" + std::to_string(counter.fetch_add(1));
}

DepthImage ReadOpenFile(hid_t file, const std::string& path, int expected_width,
                        int expected_height) {
  const std::string field = std::string("dataset '") + kHdf5DepthDataset + "'";
  if (H5Lexists(file, kHdf5DepthDataset, H5P_DEFAULT) <= 0) {
    throw InputError(path, "no " + field + " (a MegaDepth depth file holds /depth)");
  }
  Handle dataset(H5Dopen2(file, kHdf5DepthDataset, H5P_DEFAULT), H5Dclose);
  if (!dataset.ok()) throw InputError(path, field + ": cannot open (not a dataset?)");
  Handle type(H5Dget_type(dataset.get()), H5Tclose);
  if (!type.ok() || H5Tget_class(type.get()) != H5T_FLOAT) {
    throw InputError(path, field + ": expected floating-point values (float32 depth)");
  }
  Handle space(H5Dget_space(dataset.get()), H5Sclose);
  if (!space.ok() || H5Sget_simple_extent_ndims(space.get()) != 2) {
    throw InputError(path, field + ": expected a 2-D array (H, W)");
  }
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  if (dims[0] == 0 || dims[1] == 0 || dims[0] > kMaxSide || dims[1] > kMaxSide ||
      dims[0] * dims[1] > kMaxPixels) {
    throw InputError(path, field + ": implausible shape (" + std::to_string(dims[0]) + ", " +
                               std::to_string(dims[1]) + ")");
  }
  const int h = static_cast<int>(dims[0]), w = static_cast<int>(dims[1]);
  if (expected_width > 0 && expected_height > 0 && (w != expected_width || h != expected_height)) {
    throw InputError(path, "depth is " + std::to_string(w) + "x" + std::to_string(h) +
                               ", expected " + std::to_string(expected_width) + "x" +
                               std::to_string(expected_height));
  }
  DepthImage d(w, h);
  if (H5Dread(dataset.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.values_m.data()) <
      0) {
    throw InputError(path, field + ": cannot read the values (damaged or cut file?)");
  }
  return d;
}

}  // namespace

DepthImage ReadHdf5Depth(const std::string& path, int expected_width, int expected_height) {
  [[maybe_unused]] const auto lock = Lock();
  Quiet();
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    throw InputError(path, "not an HDF5 file (missing, unreadable or damaged)");
  }
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) throw InputError(path, "cannot open as HDF5 (damaged or cut file?)");
  return ReadOpenFile(file.get(), path, expected_width, expected_height);
}

DepthImage DecodeHdf5Depth(std::string_view bytes, const std::string& path, int expected_width,
                           int expected_height) {
  [[maybe_unused]] const auto lock = Lock();
  Quiet();
  static const char kSignature[] = "\x89HDF\r\n\x1a\n";
  if (bytes.size() < 8 || bytes.compare(0, 8, std::string_view(kSignature, 8)) != 0) {
    throw InputError(path, "not an HDF5 file (no HDF5 signature at byte 0)");
  }
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  // The core driver on a copy of the bytes, without a backing file.
  if (!fapl.ok() || H5Pset_fapl_core(fapl.get(), 1 << 16, 0) < 0 ||
      H5Pset_file_image(fapl.get(), const_cast<char*>(bytes.data()), bytes.size()) < 0) {
    throw InputError(path, "HDF5: cannot set up an in-memory file");
  }
  Handle file(H5Fopen(InMemoryName().c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (!file.ok()) throw InputError(path, "cannot open as HDF5 (damaged or cut file?)");
  return ReadOpenFile(file.get(), path, expected_width, expected_height);
}

void WriteHdf5Depth(const std::string& path, const DepthImage& depth) {
  if (depth.width <= 0 || depth.height <= 0 ||
      depth.values_m.size() != static_cast<size_t>(depth.width) * depth.height) {
    throw InputError(path, "depth to write has an empty or inconsistent size");
  }
  std::string image;
  {
    [[maybe_unused]] const auto lock = Lock();
    Quiet();
    Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    if (!fapl.ok() || H5Pset_fapl_core(fapl.get(), 1 << 16, 0) < 0) {
      throw InputError(path, "HDF5: cannot set up an in-memory file");
    }
    Handle file(H5Fcreate(InMemoryName().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                H5Fclose);
    const hsize_t dims[2] = {static_cast<hsize_t>(depth.height), static_cast<hsize_t>(depth.width)};
    Handle space(H5Screate_simple(2, dims, nullptr), H5Sclose);
    if (!file.ok() || !space.ok()) throw InputError(path, "HDF5: cannot create the file");
    Handle dataset(H5Dcreate2(file.get(), kHdf5DepthDataset, H5T_IEEE_F32LE, space.get(),
                              H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                   H5Dclose);
    if (!dataset.ok() || H5Dwrite(dataset.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                  depth.values_m.data()) < 0) {
      throw InputError(path, "HDF5: cannot write the depth dataset");
    }
    if (H5Fflush(file.get(), H5F_SCOPE_GLOBAL) < 0) throw InputError(path, "HDF5: cannot flush");
    const ssize_t n = H5Fget_file_image(file.get(), nullptr, 0);
    if (n <= 0) throw InputError(path, "HDF5: cannot get the file image");
    image.resize(static_cast<size_t>(n));
    if (H5Fget_file_image(file.get(), image.data(), image.size()) != n) {
      throw InputError(path, "HDF5: cannot get the file image");
    }
  }
  WriteFileAtomic(path, image);
}

}  // namespace gt::io

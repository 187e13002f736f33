#include "libgt/datasets/colmap.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>

#include "libgt/core/camera.h"
#include "libgt/core/error.h"
#include "libgt/datasets/text_parsing.h"
#include "libgt/io/file_read.h"

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the COLMAP reader assumes a little-endian host (the files' byte order)"
#endif

namespace gt::datasets {
namespace fs = std::filesystem;
namespace {

constexpr size_t kMaxNameBytes = 4096;
constexpr uint64_t kCameraHeaderBytes = 4 + 4 + 8 + 8;
constexpr uint64_t kImageHeaderBytes = 4 + 7 * 8 + 4;
constexpr uint64_t kPoint2DBytes = 24;

struct Model {
  int id;
  const char* name;
  int num_params;
};
// COLMAP's camera models (src/colmap/sensor/models.h), id, name and parameter count.
constexpr Model kModels[] = {
    {0, "SIMPLE_PINHOLE", 3},
    {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},
    {3, "RADIAL", 5},
    {4, "OPENCV", 8},
    {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},
    {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4},
    {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16},
};

const Model* ModelById(int id) {
  for (const Model& m : kModels) {
    if (m.id == id) return &m;
  }
  return nullptr;
}
const Model* ModelByName(const std::string& name) {
  for (const Model& m : kModels) {
    if (name == m.name) return &m;
  }
  return nullptr;
}

// Sequential little-endian reads from bytes in memory, each checked against what is left.
class Cursor {
 public:
  Cursor(std::string_view bytes, const std::string& path) : bytes_(bytes), path_(path) {}
  void Need(uint64_t n, const std::string& field) const {
    if (n > Remaining()) {
      throw InputError(path_, field + ": file ends at byte " + std::to_string(bytes_.size()) +
                                  ", expected " + std::to_string(n) + " bytes at byte " +
                                  std::to_string(offset_) + " (truncated file?)");
    }
  }
  template <typename T>
  T Get(const std::string& field) {
    Need(sizeof(T), field);
    T v;
    std::memcpy(&v, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return v;
  }
  // Bytes up to a NUL (consumed, not returned).
  std::string CString(const std::string& field) {
    const size_t end = bytes_.find('\0', offset_);
    if (end == std::string_view::npos) {
      throw InputError(path_, field + ": no terminating NUL before the end of the file at byte " +
                                  std::to_string(bytes_.size()) + " (truncated file?)");
    }
    if (end - offset_ > kMaxNameBytes) {
      throw InputError(path_, field + ": longer than " + std::to_string(kMaxNameBytes) + " bytes");
    }
    std::string s(bytes_.substr(offset_, end - offset_));
    offset_ = end + 1;
    return s;
  }
  void Skip(uint64_t n, const std::string& field) {
    Need(n, field);
    offset_ += n;
  }
  uint64_t Remaining() const { return bytes_.size() - offset_; }
  // A count read from the file, refused when count records of at least min_bytes each
  // cannot fit in what is left.
  uint64_t Count(const std::string& field, uint64_t min_bytes) {
    const auto n = Get<uint64_t>(field);
    if (n > Remaining() / min_bytes) {
      throw InputError(path_, field + ": " + std::to_string(n) + ", but the file holds at most " +
                                  std::to_string(Remaining() / min_bytes) + " records of " +
                                  std::to_string(min_bytes) + " bytes after it (truncated file?)");
    }
    return n;
  }
  bool AtEnd() const { return offset_ == bytes_.size(); }

 private:
  std::string_view bytes_;
  const std::string& path_;
  uint64_t offset_ = 0;
};

int CheckedSide(int64_t v, const std::string& where, const char* field) {
  if (v < 1 || v > kMaxImageSidePx) {
    throw InputError(where, std::string(field) + ": " + std::to_string(v) +
                                ", expected an image size in 1.." +
                                std::to_string(kMaxImageSidePx));
  }
  return static_cast<int>(v);
}

void AddCamera(ColmapCamera c, const std::string& where, std::map<int64_t, ColmapCamera>* out) {
  for (double p : c.params) {
    if (!std::isfinite(p)) throw InputError(where, "camera parameters must be finite");
  }
  const int64_t id = c.id;
  if (!out->emplace(id, std::move(c)).second) {
    throw InputError(where, "camera id " + std::to_string(id) + " appears twice");
  }
}

// Tokens of a text line (split on spaces and tabs).
std::vector<std::string> Tokens(std::string_view line) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.emplace_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

int64_t ParseInteger(const std::string& token, const std::string& where, const char* field) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(token.c_str(), &end, 10);
  if (token.empty() || *end != '\0' || errno == ERANGE) {
    throw InputError(where, std::string(field) + ": expected an integer, found '" + token + "'");
  }
  return v;
}

// The numbers of tokens t[begin, end), one number each (ParseNumbers alone would also split
// a token at a comma: "0.5,0.5" would shift every later field).
std::vector<double> ParseFieldNumbers(const std::vector<std::string>& t, size_t begin, size_t end,
                                      const std::string& path, int line_no,
                                      const std::string& where) {
  std::vector<double> out;
  for (size_t k = begin; k < end; ++k) {
    const std::vector<double> v = ParseNumbers(t[k], path, line_no);
    if (v.size() != 1) {
      throw InputError(
          where, "field " + std::to_string(k + 1) + ": expected one number, found '" + t[k] + "'");
    }
    out.push_back(v[0]);
  }
  return out;
}

// A uint64 size from a file as int64 (sizes above kMaxImageSidePx become kMaxImageSidePx + 1).
int64_t Clamped(uint64_t v) {
  return static_cast<int64_t>(std::min<uint64_t>(v, kMaxImageSidePx + 1));
}

bool IsCommentOrBlank(std::string_view line) {
  const size_t i = line.find_first_not_of(" \t\r");
  return i == std::string_view::npos || line[i] == '#';
}

}  // namespace

std::map<int64_t, ColmapCamera> ParseColmapCamerasBinary(std::string_view bytes,
                                                         const std::string& path) {
  Cursor in(bytes, path);
  const uint64_t n = in.Count("camera count", kCameraHeaderBytes);
  std::map<int64_t, ColmapCamera> out;
  for (uint64_t i = 0; i < n; ++i) {
    const std::string rec = "camera " + std::to_string(i);
    ColmapCamera c;
    c.id = in.Get<int32_t>(rec + " camera_id");
    const auto model_id = in.Get<int32_t>(rec + " model_id");
    const Model* m = ModelById(model_id);
    if (m == nullptr) {
      throw InputError(path, rec + " (id " + std::to_string(c.id) + "): unknown model_id " +
                                 std::to_string(model_id) + " (COLMAP's models are 0..11)");
    }
    c.model = m->name;
    c.width =
        CheckedSide(Clamped(in.Get<uint64_t>(rec + " width")), path, (rec + " width").c_str());
    c.height =
        CheckedSide(Clamped(in.Get<uint64_t>(rec + " height")), path, (rec + " height").c_str());
    in.Need(uint64_t(m->num_params) * 8, rec + " params");
    for (int p = 0; p < m->num_params; ++p) c.params.push_back(in.Get<double>(rec + " params"));
    AddCamera(std::move(c), path + " " + rec, &out);
  }
  if (!in.AtEnd()) {
    throw InputError(
        path, std::to_string(in.Remaining()) + " bytes after the last camera (not a cameras.bin?)");
  }
  return out;
}

std::vector<ColmapImage> ParseColmapImagesBinary(std::string_view bytes, const std::string& path) {
  Cursor in(bytes, path);
  // The smallest record: header, a one-byte name (its NUL) and the 2D point count.
  const uint64_t n = in.Count("image count", kImageHeaderBytes + 1 + 8);
  std::vector<ColmapImage> out;
  out.reserve(static_cast<size_t>(n));
  for (uint64_t i = 0; i < n; ++i) {
    const std::string rec = "image " + std::to_string(i);
    ColmapImage im;
    im.id = in.Get<int32_t>(rec + " image_id");
    for (int k = 0; k < 4; ++k) im.qvec_wxyz[k] = in.Get<double>(rec + " qvec");
    for (int k = 0; k < 3; ++k) im.tvec[k] = in.Get<double>(rec + " tvec");
    im.camera_id = in.Get<int32_t>(rec + " camera_id");
    im.name = in.CString(rec + " name");
    if (im.name.empty()) throw InputError(path, rec + " name: empty");
    const auto points = in.Get<uint64_t>(rec + " num_points2D");
    if (points > in.Remaining() / kPoint2DBytes) {
      throw InputError(path, rec + " (" + im.name + ") num_points2D: " + std::to_string(points) +
                                 ", but only " + std::to_string(in.Remaining()) +
                                 " bytes are left (truncated file?)");
    }
    in.Skip(points * kPoint2DBytes, rec + " points2D");
    out.push_back(std::move(im));
  }
  if (!in.AtEnd()) {
    throw InputError(
        path, std::to_string(in.Remaining()) + " bytes after the last image (not an images.bin?)");
  }
  return out;
}

std::map<int64_t, ColmapCamera> ParseColmapCamerasText(std::string_view text,
                                                       const std::string& path) {
  std::map<int64_t, ColmapCamera> out;
  const std::vector<std::string> lines = io::SplitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (IsCommentOrBlank(lines[i])) continue;
    const std::string where = path + ":" + std::to_string(i + 1);
    const std::vector<std::string> t = Tokens(lines[i]);
    if (t.size() < 4) {
      throw InputError(where, "expected 'CAMERA_ID MODEL WIDTH HEIGHT PARAMS...', found " +
                                  std::to_string(t.size()) + " fields");
    }
    ColmapCamera c;
    c.id = ParseInteger(t[0], where, "CAMERA_ID");
    const Model* m = ModelByName(t[1]);
    if (m == nullptr) throw InputError(where, "MODEL: unknown COLMAP camera model '" + t[1] + "'");
    c.model = m->name;
    c.width = CheckedSide(ParseInteger(t[2], where, "WIDTH"), where, "WIDTH");
    c.height = CheckedSide(ParseInteger(t[3], where, "HEIGHT"), where, "HEIGHT");
    if (static_cast<int>(t.size()) - 4 != m->num_params) {
      throw InputError(where, "model " + c.model + " has " + std::to_string(m->num_params) +
                                  " parameters, found " + std::to_string(t.size() - 4));
    }
    c.params = ParseFieldNumbers(t, 4, t.size(), path, static_cast<int>(i) + 1, where);
    AddCamera(std::move(c), where, &out);
  }
  return out;
}

std::string ColmapImageWhere(const std::string& images_path, const ColmapImage& image) {
  return image.line_no > 0 ? images_path + ":" + std::to_string(image.line_no) : images_path;
}

std::vector<ColmapImage> ParseColmapImagesText(std::string_view text, const std::string& path) {
  std::vector<ColmapImage> out;
  const std::vector<std::string> lines = io::SplitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (IsCommentOrBlank(lines[i])) continue;
    const std::string where = path + ":" + std::to_string(i + 1);
    const std::vector<std::string> t = Tokens(lines[i]);
    if (t.size() != 10) {
      throw InputError(where,
                       "expected 'IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' (10 fields, a "
                       "name without spaces), found " +
                           std::to_string(t.size()) + " fields");
    }
    ColmapImage im;
    im.id = ParseInteger(t[0], where, "IMAGE_ID");
    const std::vector<double> v = ParseFieldNumbers(t, 1, 8, path, static_cast<int>(i) + 1, where);
    im.qvec_wxyz = Eigen::Vector4d(v[0], v[1], v[2], v[3]);
    im.tvec = Eigen::Vector3d(v[4], v[5], v[6]);
    im.camera_id = ParseInteger(t[8], where, "CAMERA_ID");
    im.name = t[9];
    im.line_no = static_cast<int>(i) + 1;
    out.push_back(std::move(im));
    // The POINTS2D line that follows (X Y POINT3D_ID triples, possibly empty) is not read.
    // A model written without those lines has the next image's line there: 10 fields, never
    // a multiple of 3, so it is read as an image (skipping it lost every second image).
    if (i + 1 < lines.size() && Tokens(lines[i + 1]).size() % 3 == 0) ++i;
  }
  return out;
}

namespace {

bool Exists(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

}  // namespace

bool HasColmapModel(const std::string& folder) {
  const fs::path d(folder);
  return (Exists(d / "cameras.bin") && Exists(d / "images.bin")) ||
         (Exists(d / "cameras.txt") && Exists(d / "images.txt"));
}

ColmapModel ReadColmapModel(const std::string& folder) {
  const fs::path d(folder);
  ColmapModel model;
  if (Exists(d / "cameras.bin") && Exists(d / "images.bin")) {
    model.cameras_path = (d / "cameras.bin").string();
    model.images_path = (d / "images.bin").string();
    model.cameras =
        ParseColmapCamerasBinary(io::ReadFileBytes(model.cameras_path), model.cameras_path);
    model.images = ParseColmapImagesBinary(io::ReadFileBytes(model.images_path), model.images_path);
  } else if (Exists(d / "cameras.txt") && Exists(d / "images.txt")) {
    model.cameras_path = (d / "cameras.txt").string();
    model.images_path = (d / "images.txt").string();
    model.cameras =
        ParseColmapCamerasText(io::ReadFileBytes(model.cameras_path), model.cameras_path);
    model.images = ParseColmapImagesText(io::ReadFileBytes(model.images_path), model.images_path);
  } else {
    throw InputError(folder,
                     "no COLMAP model (expected cameras.bin + images.bin or cameras.txt + "
                     "images.txt)");
  }
  std::map<int64_t, const ColmapImage*> by_id;
  for (const ColmapImage& im : model.images) {
    const auto [it, fresh] = by_id.emplace(im.id, &im);
    if (!fresh) {
      throw InputError(
          ColmapImageWhere(model.images_path, im),
          "image id " + std::to_string(im.id) +
              (it->second->line_no > 0 ? " repeats line " + std::to_string(it->second->line_no)
                                       : std::string(" appears twice")));
    }
    if (model.cameras.count(im.camera_id) == 0) {
      throw InputError(model.images_path, "image " + std::to_string(im.id) + " (" + im.name +
                                              "): camera_id " + std::to_string(im.camera_id) +
                                              " is not in " + model.cameras_path);
    }
  }
  return model;
}

Camera ColmapPinholeCamera(const ColmapCamera& c, const std::string& cameras_path) {
  Camera cam;
  cam.width = c.width;
  cam.height = c.height;
  if (c.model == "PINHOLE" && c.params.size() == 4) {
    cam.fx = c.params[0];
    cam.fy = c.params[1];
    cam.cx = c.params[2] - 0.5;
    cam.cy = c.params[3] - 0.5;
  } else if (c.model == "SIMPLE_PINHOLE" && c.params.size() == 3) {
    cam.fx = cam.fy = c.params[0];
    cam.cx = c.params[1] - 0.5;
    cam.cy = c.params[2] - 0.5;
  } else {
    throw InputError(cameras_path, "camera " + std::to_string(c.id) + ": model " + c.model +
                                       " is not supported (expected PINHOLE or SIMPLE_PINHOLE, "
                                       "an undistorted model: see colmap image_undistorter)");
  }
  if (!(cam.fx > 0) || !(cam.fy > 0)) {
    throw InputError(cameras_path,
                     "camera " + std::to_string(c.id) + ": focal length must be positive");
  }
  return cam;
}

LensCamera ColmapLensCamera(const ColmapCamera& c, const std::string& cameras_path) {
  const std::string where = "camera " + std::to_string(c.id);
  LensCamera lens;
  lens.pinhole.width = c.width;
  lens.pinhole.height = c.height;
  const std::vector<double>& p = c.params;
  auto expect = [&](size_t n) {
    if (p.size() != n) {
      throw InputError(cameras_path, where + ": model " + c.model + " has " + std::to_string(n) +
                                         " parameters, got " + std::to_string(p.size()));
    }
  };
  auto set_k = [&](double fx, double fy, double cx, double cy) {
    lens.pinhole.fx = fx;
    lens.pinhole.fy = fy;
    lens.pinhole.cx = cx - 0.5;  // COLMAP's first pixel centre is (0.5, 0.5)
    lens.pinhole.cy = cy - 0.5;
  };
  if (c.model == "PINHOLE") {
    expect(4);
    set_k(p[0], p[1], p[2], p[3]);
  } else if (c.model == "SIMPLE_PINHOLE") {
    expect(3);
    set_k(p[0], p[0], p[1], p[2]);
  } else if (c.model == "SIMPLE_RADIAL" || c.model == "RADIAL") {
    expect(c.model == "RADIAL" ? 5 : 4);
    set_k(p[0], p[0], p[1], p[2]);
    lens.model = LensModel::kOpenCv;
    lens.coeffs = {p[3], c.model == "RADIAL" ? p[4] : 0.0, 0.0, 0.0, 0.0};
  } else if (c.model == "OPENCV" || c.model == "OPENCV_FISHEYE") {
    expect(8);
    set_k(p[0], p[1], p[2], p[3]);
    lens.model = c.model == "OPENCV" ? LensModel::kOpenCv : LensModel::kOpenCvFisheye;
    lens.coeffs = {p[4], p[5], p[6], p[7], 0.0};
  } else {
    throw InputError(cameras_path,
                     where + ": model " + c.model +
                         " is not supported (expected PINHOLE, SIMPLE_PINHOLE, SIMPLE_RADIAL, "
                         "RADIAL, OPENCV or OPENCV_FISHEYE)");
  }
  std::string error;
  if (!lens.Check(&error)) throw InputError(cameras_path, where + " (" + c.model + "): " + error);
  return lens;
}

namespace {
Eigen::Vector4d Xyzw(const Eigen::Vector4d& wxyz) {
  return Eigen::Vector4d(wxyz[1], wxyz[2], wxyz[3], wxyz[0]);
}
}  // namespace

std::optional<PoseDefect> ColmapPoseDefect(const ColmapImage& image) {
  return FindPoseDefectTQ(image.tvec, Xyzw(image.qvec_wxyz));
}

Rigid3d ColmapWorldFromCam(const ColmapImage& image) {
  return RigidFromTQ(image.tvec, Xyzw(image.qvec_wxyz)).inverse(Eigen::Isometry);
}

}  // namespace gt::datasets

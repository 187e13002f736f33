#include "libgt/datasets/text_parsing.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>

#include "libgt/core/camera.h"
#include "libgt/core/error.h"
#include "libgt/io/file_read.h"

namespace gt::datasets {
namespace fs = std::filesystem;

std::string LineWhere(const std::string& path, int line_no) {
  return path + ":" + std::to_string(line_no);
}

std::string PoseReason(const PoseDefect& defect) {
  std::ostringstream s;
  s << "pose: ";
  switch (defect.kind) {
    case PoseDefectKind::kNonFinite:
      // The words of PoseProblem / PoseProblemTQ, unchanged: they hold no measured value.
    case PoseDefectKind::kLastRow:
    case PoseDefectKind::kReflection:
      s << defect.text;
      break;
    case PoseDefectKind::kNotOrthonormal:
      s << "rotation is not orthonormal (|R^T R - I| > " << kRigidTolerance << ")";
      break;
    case PoseDefectKind::kQuaternionNorm:
      s << "quaternion norm is not within " << kQuaternionNormTolerance << " of 1";
      break;
  }
  return s.str();
}

PoseLocator PoseLocator::Whole(std::string where) {
  PoseLocator l;
  l.kind_ = Kind::kWhole;
  l.name_ = std::move(where);
  return l;
}

PoseLocator PoseLocator::TextLines(std::string path, const std::array<int, 16>& line_of) {
  PoseLocator l;
  l.kind_ = Kind::kText;
  l.name_ = std::move(path);
  l.line_of_ = line_of;
  return l;
}

PoseLocator PoseLocator::JsonField(std::string manifest, std::string field) {
  PoseLocator l;
  l.kind_ = Kind::kJson;
  l.name_ = std::move(manifest);
  l.field_ = std::move(field);
  return l;
}

std::string PoseLocator::Entry(int row, int col) const {
  switch (kind_) {
    case Kind::kWhole:
      break;
    case Kind::kText:
      return LineWhere(name_, line_of_[static_cast<size_t>(4 * row + col)]);
    case Kind::kJson:
      return name_ + ": " + field_ + "[" + std::to_string(row) + "][" + std::to_string(col) + "]";
  }
  return name_;
}

std::string PoseLocator::Rows(int first_row, int last_row) const {
  switch (kind_) {
    case Kind::kWhole:
      break;
    case Kind::kText: {
      const auto begin = line_of_.begin() + 4 * first_row;
      const auto end = line_of_.begin() + 4 * (last_row + 1);
      const int first = *std::min_element(begin, end);
      const int last = *std::max_element(begin, end);
      return LineWhere(name_, first) + (last == first ? "" : "-" + std::to_string(last));
    }
    case Kind::kJson:
      return name_ + ": " + field_ +
             (first_row == last_row ? "[" + std::to_string(first_row) + "]" : "");
  }
  return name_;
}

Unusable PoseUnusable(const PoseDefect& defect, const PoseLocator& where) {
  Unusable u;
  u.reason = PoseReason(defect);
  std::string place;
  if (defect.kind == PoseDefectKind::kReflection) {
    place = where.Rows(0, 2);
  } else if (defect.row < 0) {
    place = where.All();  // a translation + quaternion record
  } else if (defect.col >= 0) {
    place = where.Entry(defect.row, defect.col);
  } else {
    place = where.Rows(defect.row, defect.row);
  }
  u.detail =
      place + ": " + (defect.kind == PoseDefectKind::kNonFinite ? "non-finite value" : defect.text);
  return u;
}

bool SetMatrixPose(const Eigen::Matrix4d& world_from_cam, const PoseLocator& where, Frame* frame) {
  if (const auto defect = FindPoseDefect(world_from_cam)) {
    MarkUnusable(frame, PoseUnusable(*defect, where));
    return false;
  }
  frame->world_from_cam = RigidFromMatrix(world_from_cam);
  return true;
}

bool SetTQPose(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw, const PoseLocator& where,
               Frame* frame) {
  if (const auto defect = FindPoseDefectTQ(t, q_xyzw)) {
    MarkUnusable(frame, PoseUnusable(*defect, where));
    return false;
  }
  frame->world_from_cam = RigidFromTQ(t, q_xyzw);
  return true;
}

namespace {

// All numbers of `text`, row-major, exactly rows * cols of them, and the 1-based line of
// each (line_of may be null).
Eigen::MatrixXd ParseMatrixEntries(std::string_view text, const std::string& name, int rows,
                                   int cols, std::vector<int>* line_of) {
  const std::vector<std::string> lines = io::SplitLines(text);
  std::vector<double> values;
  std::vector<int> value_lines;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line_no = static_cast<int>(i) + 1;
    const std::vector<double> row = ParseNumbers(lines[i], name, line_no);
    values.insert(values.end(), row.begin(), row.end());
    value_lines.insert(value_lines.end(), row.size(), line_no);
  }
  const size_t expected = static_cast<size_t>(rows) * cols;
  if (values.size() != expected) {
    std::ostringstream msg;
    msg << "expected " << expected << " numbers (" << rows << "x" << cols << " matrix), found "
        << values.size();
    throw InputError(name, msg.str());
  }
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m(r, c) = values[static_cast<size_t>(r) * cols + c];
  }
  if (line_of != nullptr) *line_of = std::move(value_lines);
  return m;
}

}  // namespace

PoseText ReadPoseText(const std::string& path) {
  return ParsePoseText(io::ReadFileBytes(path), path);
}

PoseText ParsePoseText(std::string_view text, const std::string& name) {
  std::vector<int> line_of;
  PoseText out;
  out.world_from_cam = ParseMatrixEntries(text, name, 4, 4, &line_of);
  std::array<int, 16> lines{};
  std::copy(line_of.begin(), line_of.end(), lines.begin());
  out.where = PoseLocator::TextLines(name, lines);
  return out;
}

std::string PreferredFile::Pick(std::initializer_list<std::string> candidates) {
  std::string kept;
  for (const std::string& path : candidates) {
    if (path.empty() || !io::FileExists(path)) continue;
    if (kept.empty()) {
      kept = path;
    } else {
      if (frames_++ == 0) kept_ = kept, other_ = path;
      break;
    }
  }
  return kept;
}

void PreferredFile::Note(Scene* scene) const {
  if (frames_ == 0) return;
  scene->reader_warnings.push_back(std::to_string(frames_) + " frame(s) have two " + role_ +
                                   " files, and each reads the first (the first frame: " + kept_ +
                                   ", not " + other_ + ")");
}

bool SetPoseFromText(const std::string& path, Frame* frame) {
  std::string text;
  try {
    text = io::ReadFileBytes(path);
  } catch (const InputError& e) {
    MarkUnusable(frame, kReasonPoseUnreadable, e.what());
    return false;
  }
  PoseText pose;
  try {
    pose = ParsePoseText(text, path);
  } catch (const InputError& e) {
    MarkUnusable(frame, kReasonPoseMalformed, e.what());
    return false;
  }
  return SetMatrixPose(pose.world_from_cam, pose.where, frame);
}

Eigen::MatrixXd ReadMatrixText(const std::string& path, int rows, int cols) {
  return ParseMatrixText(io::ReadFileBytes(path), path, rows, cols);
}

Eigen::MatrixXd ParseMatrixText(std::string_view text, const std::string& name, int rows,
                                int cols) {
  return ParseMatrixEntries(text, name, rows, cols, nullptr);
}

Eigen::Matrix3d ReadIntrinsicsText(const std::string& path) {
  return ParseIntrinsicsText(io::ReadFileBytes(path), path);
}

Eigen::Matrix3d ParseIntrinsicsText(std::string_view text, const std::string& name) {
  const std::vector<std::string> lines = io::SplitLines(text);
  size_t count = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    count += ParseNumbers(lines[i], name, static_cast<int>(i) + 1).size();
  }
  if (count != 9 && count != 16) {
    throw InputError(name, "expected a 3x3 or 4x4 intrinsics matrix (9 or 16 numbers), found " +
                               std::to_string(count) + " numbers");
  }
  const int n = count == 9 ? 3 : 4;
  return CheckedIntrinsics(ParseMatrixText(text, name, n, n).topLeftCorner<3, 3>(), name);
}

Eigen::Matrix3d CheckedIntrinsics(const Eigen::Matrix3d& K, const std::string& where) {
  // A skew (K(0,1)) or K(1,0) has no place in occgt's pinhole camera: refused, not dropped.
  if (!Camera::IsPinholeMatrix(K) || !(K(0, 0) > 0) || !(K(1, 1) > 0)) {
    throw InputError(where, "expected K = [[fx 0 cx] [0 fy cy] [0 0 1]] with finite fx, fy > 0");
  }
  return K;
}

std::vector<TextRecord> ReadRecords(const std::string& path) {
  return ParseRecords(io::ReadFileBytes(path));
}

std::vector<TextRecord> ParseRecords(std::string_view text) {
  const std::vector<std::string> lines = io::SplitLines(text);
  std::vector<TextRecord> out;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    TextRecord rec;
    rec.line_no = static_cast<int>(i) + 1;
    std::istringstream ss(line);
    std::string tok;
    while (ss >> tok) rec.tokens.push_back(tok);
    out.push_back(std::move(rec));
  }
  return out;
}

std::vector<TimedPath> ParseTimedPathList(std::string_view text, const std::string& name) {
  std::vector<TimedPath> out;
  for (const auto& rec : ParseRecords(text)) {
    if (rec.tokens.size() != 2) {
      throw InputError(
          LineWhere(name, rec.line_no),
          "expected 'timestamp filename', found " + std::to_string(rec.tokens.size()) + " fields");
    }
    const std::vector<double> v = ParseNumbers(rec.tokens[0], name, rec.line_no);
    if (v.size() != 1 || !std::isfinite(v[0])) {
      throw InputError(LineWhere(name, rec.line_no), "expected a finite timestamp");
    }
    out.push_back({v[0], rec.tokens[1], rec.line_no});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const TimedPath& a, const TimedPath& b) { return a.t < b.t; });
  // One timestamp, two files: which frame is meant cannot be told. The same entry twice is
  // one frame.
  std::vector<TimedPath> kept;
  for (TimedPath& e : out) {
    if (!kept.empty() && kept.back().t == e.t) {
      if (kept.back().file == e.file) continue;
      const int first = std::min(kept.back().line_no, e.line_no);
      const int second = std::max(kept.back().line_no, e.line_no);
      const std::string& later = e.line_no == second ? e.file : kept.back().file;
      throw InputError(LineWhere(name, second), "timestamp repeats line " + std::to_string(first) +
                                                    " with another file (" + later +
                                                    "; expected one file per timestamp)");
    }
    kept.push_back(std::move(e));
  }
  return kept;
}

std::vector<TimedPose> ParseTimedPoses(std::string_view text, const std::string& name) {
  std::vector<TimedPose> out;
  for (const auto& rec : ParseRecords(text)) {
    std::string line;
    for (const auto& tok : rec.tokens) line += tok + " ";
    const std::vector<double> v = ParseNumbers(line, name, rec.line_no);
    if (v.size() != 8) {
      throw InputError(
          LineWhere(name, rec.line_no),
          "expected 8 numbers (timestamp tx ty tz qx qy qz qw), found " + std::to_string(v.size()));
    }
    if (!std::isfinite(v[0])) {
      throw InputError(LineWhere(name, rec.line_no), "expected a finite timestamp");
    }
    out.push_back({rec.line_no, v[0], rec.tokens[0], Eigen::Vector3d(v[1], v[2], v[3]),
                   Eigen::Vector4d(v[4], v[5], v[6], v[7])});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
  // One timestamp, two poses: which one is meant cannot be told (the first was taken).
  for (size_t i = 1; i < out.size(); ++i) {
    const TimedPose& a = out[i - 1];
    const TimedPose& b = out[i];
    if (a.t == b.t && (a.translation != b.translation || a.q_xyzw != b.q_xyzw)) {
      const int first = std::min(a.line_no, b.line_no), second = std::max(a.line_no, b.line_no);
      throw InputError(LineWhere(name, second),
                       "timestamp " + (b.line_no == second ? b.t_text : a.t_text) +
                           " repeats line " + std::to_string(first) +
                           " with another pose (expected one pose per timestamp)");
    }
  }
  return out;
}

std::vector<TQLine> ParseTQLines(std::string_view text, const std::string& name) {
  const std::vector<std::string> lines = io::SplitLines(text);
  std::vector<TQLine> out;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line_no = static_cast<int>(i) + 1;
    const std::vector<double> v = ParseNumbers(lines[i], name, line_no);
    if (v.empty()) continue;
    if (v.size() != 7) {
      throw InputError(
          LineWhere(name, line_no),
          "expected 7 numbers (tx ty tz qx qy qz qw), found " + std::to_string(v.size()));
    }
    out.push_back(
        {line_no, Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector4d(v[3], v[4], v[5], v[6])});
  }
  return out;
}

std::vector<NumberedFile> ListNumberedFiles(const std::string& folder, const std::string& prefix,
                                            const std::string& suffix) {
  std::vector<NumberedFile> out;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return out;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("._", 0) == 0) continue;  // AppleDouble
    if (name.size() <= prefix.size() + suffix.size()) continue;
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    if (name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
    const std::string digits =
        name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (digits.empty() || digits.size() > 15 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      continue;
    }
    // A frame file that cannot be read (a folder, a dangling or looping link, a socket) is
    // an error, never a silently missing frame.
    if (const std::string problem = NotAFileProblem(entry.path().string()); !problem.empty()) {
      throw InputError(entry.path().string(), problem);
    }
    NumberedFile f;
    f.number = std::stoll(digits);
    f.stem = digits;
    f.path = entry.path().string();
    out.push_back(std::move(f));
  }
  std::sort(out.begin(), out.end(), [](const NumberedFile& a, const NumberedFile& b) {
    return a.number != b.number ? a.number < b.number : a.stem < b.stem;
  });
  // "1.txt" and "01.txt" would be two frames with the same number: refuse to guess.
  for (size_t i = 1; i < out.size(); ++i) {
    if (out[i].number == out[i - 1].number) {
      throw InputError(folder, "files " + fs::path(out[i - 1].path).filename().string() + " and " +
                                   fs::path(out[i].path).filename().string() +
                                   " both give frame number " + std::to_string(out[i].number));
    }
  }
  return out;
}

std::vector<NumberedFile> MergeNumberedFiles(const std::vector<std::vector<NumberedFile>>& lists) {
  std::map<int64_t, NumberedFile> by_number;
  for (const auto& list : lists) {
    for (const NumberedFile& f : list) by_number.emplace(f.number, f);  // the first list wins
  }
  std::vector<NumberedFile> out;
  out.reserve(by_number.size());
  for (auto& [number, f] : by_number) out.push_back(std::move(f));
  return out;
}

std::vector<std::string> ListSubfolders(const std::string& folder) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return out;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] == '.') continue;
    if (entry.is_directory(ec)) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string NotAFileProblem(const std::string& path) {
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(path, ec);
  if (ec || !fs::exists(link) || fs::is_regular_file(fs::status(path, ec))) return "";
  if (fs::is_symlink(link) && !fs::exists(path, ec)) {
    return "dangling symbolic link (expected a readable file)";
  }
  return "expected a regular file, found a folder or special file";
}

void RequireRoot(const std::string& root) {
  std::error_code ec;
  if (root.empty() || !fs::exists(root, ec)) throw InputError(root, "dataset root not found");
}

void RequireFinishedSynth(const std::string& root) {
  fs::path dir = fs::absolute(root).lexically_normal();
  if (!dir.has_filename()) dir = dir.parent_path();  // a trailing '/'
  for (int up = 0; up < 3 && !dir.empty(); ++up, dir = dir.parent_path()) {
    if (!io::FileExists((dir / ".occgt-synth.json").string())) continue;
    const std::string dataset = (dir / "dataset.json").string();
    if (!io::FileExists(dataset)) {
      throw InputError(dataset,
                       "missing: the folder is an `occgt synth` dataset whose run did not "
                       "finish (.occgt-synth.json is written first, dataset.json last): re-run "
                       "the same occgt synth command to complete it");
    }
    return;
  }
}

std::string FolderName(const std::string& path) {
  fs::path p(path);
  if (!p.has_filename()) p = p.parent_path();  // trailing '/'
  std::string name = p.filename().string();
  if (name == "." || name.empty()) name = fs::absolute(p).lexically_normal().filename().string();
  if (name.empty()) name = fs::absolute(p).lexically_normal().parent_path().filename().string();
  return name;
}

Scene NewFolderScene(const std::string& folder, const std::string& scene_name, DatasetFormat format,
                     double min_depth_m, double max_depth_m) {
  Scene scene;
  scene.name = scene_name.empty() ? FolderName(folder) : scene_name;
  scene.format = format;
  scene.path = folder;
  scene.min_depth_m = min_depth_m;
  scene.max_depth_m = max_depth_m;
  return scene;
}

std::string CheckSceneName(const std::string& name) {
  if (name.empty()) return "";
  if (name.front() == '/')
    return "expected a scene name relative to the dataset root, got an absolute path";
  size_t start = 0;
  while (start <= name.size()) {
    size_t slash = name.find('/', start);
    if (slash == std::string::npos) slash = name.size();
    if (name.compare(start, slash - start, "..") == 0 && slash - start == 2) {
      return "expected a scene name inside the dataset root (no '..' components)";
    }
    start = slash + 1;
  }
  return "";
}

std::string ResolveSceneFolder(const std::string& root, const std::string& name,
                               bool root_is_scene) {
  RequireRoot(root);
  if (root_is_scene && (name.empty() || name == FolderName(root))) return root;
  if (name.empty()) throw InputError(root, "not a scene folder and no scene name given");
  if (std::string e = CheckSceneName(name); !e.empty()) throw InputError("scene '" + name + "'", e);
  const std::string folder = (fs::path(root) / name).string();
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw InputError(folder, "scene folder not found");
  return folder;
}

void MarkUnusable(Frame* frame, const std::string& reason, const std::string& detail) {
  if (!frame->usable) return;
  frame->usable = false;
  frame->unusable_reason = reason;
  frame->unusable_detail = detail;
}

void MarkUnusable(Frame* frame, const Unusable& why) {
  MarkUnusable(frame, why.reason, why.detail);
}

namespace {

bool EqualsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

// One token as a double: decimal/scientific notation, or inf/-inf/+inf/infinity/nan.
bool ParseToken(std::string_view tok, double* value) {
  std::string_view body = tok;
  double sign = 1.0;
  if (!body.empty() && (body[0] == '-' || body[0] == '+')) {
    sign = body[0] == '-' ? -1.0 : 1.0;
    body.remove_prefix(1);
  }
  if (EqualsNoCase(body, "inf") || EqualsNoCase(body, "infinity")) {
    *value = sign * std::numeric_limits<double>::infinity();
    return true;
  }
  if (EqualsNoCase(body, "nan")) {
    *value = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  // strtod also accepts hex floats and "nan(...)": only allow plain decimal characters.
  for (char c : body) {
    if (!((c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '-' || c == '+')) {
      return false;
    }
  }
  if (body.empty()) return false;
  const std::string s(tok);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size()) return false;
  *value = v;  // overflow gives +-HUGE_VAL (inf), which callers treat as non-finite
  return true;
}

}  // namespace

std::vector<double> ParseNumbers(std::string_view line, const std::string& path, int line_no) {
  std::vector<double> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r' ||
                               line[i] == '\n' || line[i] == ',')) {
      ++i;
    }
    if (i >= line.size()) break;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r' &&
           line[j] != '\n' && line[j] != ',') {
      ++j;
    }
    const std::string_view tok = line.substr(i, j - i);
    double v = 0;
    if (!ParseToken(tok, &v)) {
      if (line_no == 1 && i == 0 && tok.substr(0, 3) == "\xEF\xBB\xBF") {  // invisible in print
        throw InputError(LineWhere(path, line_no),
                         "the file starts with a UTF-8 byte-order mark (bytes EF BB BF); "
                         "expected a number: save it without the mark");
      }
      throw InputError(LineWhere(path, line_no),
                       "expected a number, found '" + std::string(tok) + "'");
    }
    out.push_back(v);
    i = j;
  }
  return out;
}

}  // namespace gt::datasets

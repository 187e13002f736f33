// Parsing helpers shared by the dataset readers (libgt/datasets/*.cc), so that every reader
// reports the same errors in the same words: numeric matrices in text files (poses,
// intrinsics), timestamped lists (TUM), folder listings sorted by frame number, scene
// folder resolution and the unusable-frame reasons that `occgt scan` counts.
//
// Matrices are read row-major from all numbers of the file (blank lines ignored); the
// count must match exactly, otherwise InputError("<path>", "expected 16 numbers (4x4),
// found 12"). A token that is not a number is InputError("<path>:<line>", ...).
//
// A pose that parses but cannot be used (non-finite, not rigid) makes its frame unusable,
// not the scene: the frame gets a stable reason (the category `occgt scan` counts) and a
// detail naming where the pose was read, "<file>:<line>: non-finite value" (PoseLocator).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "libgt/core/frame.h"
#include "libgt/core/pose.h"

namespace gt::datasets {

// Whitespace-separated doubles of one text line; accepts "inf", "-inf", "nan" (any case),
// which ScanNet writes for lost tracking. Throws InputError("<path>:<line>", ...) on a
// token that is not a number.
std::vector<double> ParseNumbers(std::string_view line, const std::string& path, int line_no);

// "<path>:<line>": where a message about one line of a text file points.
std::string LineWhere(const std::string& path, int line_no);

// Why a frame is unusable (Frame::unusable_reason / unusable_detail): `reason` is one
// stable category per kind of problem, the string `occgt scan` counts frames by; `detail`
// is "<where>: <what was found>", "" when the reason says it all.
struct Unusable {
  std::string reason;
  std::string detail;
};

// Stable reasons for unusable frames (counted by `occgt scan`).
inline constexpr const char* kReasonDepthMissing = "depth: missing file";
// generic: a colour file that exists but whose image header cannot be read (the detail is
// the read error, naming the file).
inline constexpr const char* kReasonColorUnreadable = "colour: unreadable image";
// A frame whose depth or colour file exists but whose pose file does not (ScanNet's exports,
// 7-Scenes: one pose file per frame); the detail is the pose file's path.
inline constexpr const char* kReasonPoseMissing = "pose: missing file";
inline constexpr const char* kReasonPoseUnreadable = "pose: unreadable file";
inline constexpr const char* kReasonPoseMalformed = "pose: malformed file";
// The pose reasons: "pose: " + the category of a PoseDefect (core/pose.h), without the
// measured value (that goes to the detail), e.g. "pose: non-finite pose entries (lost
// tracking)" (a 4x4 matrix), "pose: non-finite pose entries" (translation + quaternion),
// "pose: rotation is not orthonormal (|R^T R - I| > 0.001)".
std::string PoseReason(const PoseDefect& defect);

// Names where the entries of a pose were read, for the detail of an unusable frame.
class PoseLocator {
 public:
  // Every entry is `where`: one record ("<file>:<line>" of a "tx ty tz qx qy qz qw" line,
  // "<file>: frame 10" of a .sens, "<file>: image 5" of a COLMAP model).
  static PoseLocator Whole(std::string where);
  // A 4x4 matrix from a text file, entry (r, c) on line line_of[4 * r + c] (1-based):
  // "<path>:<line>", or "<path>:<first>-<last>" for rows spread over several lines.
  static PoseLocator TextLines(std::string path, const std::array<int, 16>& line_of);
  // A 4x4 matrix as a JSON array of rows at `field` of `manifest`:
  // "<manifest>: <field>[r][c]", a row "<field>[r]", several rows "<field>".
  static PoseLocator JsonField(std::string manifest, std::string field);

  std::string Entry(int row, int col) const;
  std::string Rows(int first_row, int last_row) const;
  std::string All() const { return Rows(0, 3); }

 private:
  enum class Kind { kWhole, kText, kJson };
  Kind kind_ = Kind::kWhole;
  std::string name_;   // where (kWhole), the file (kText, kJson)
  std::string field_;  // kJson
  std::array<int, 16> line_of_{};
};

// The Unusable of a pose defect read at `where`: PoseReason, and the detail
// "<where of the entry, row or rows>: <what>", what being "non-finite value" or the
// defect's words with the measured value ("quaternion norm is 2, expected 1").
Unusable PoseUnusable(const PoseDefect& defect, const PoseLocator& where);

// Sets frame->world_from_cam from a 4x4 camera-to-world matrix (RigidFromMatrix), or, when
// FindPoseDefect finds a defect, marks the frame unusable with PoseUnusable. Returns
// whether the pose was set.
bool SetMatrixPose(const Eigen::Matrix4d& world_from_cam, const PoseLocator& where, Frame* frame);
// The same for a translation + quaternion (x, y, z, w) pose (RigidFromTQ).
bool SetTQPose(const Eigen::Vector3d& t, const Eigen::Vector4d& q_xyzw, const PoseLocator& where,
               Frame* frame);

// A 4x4 pose text file (ScanNet pose/<n>.txt, frame-XXXXXX.pose.txt, 7-Scenes): the matrix
// (as ReadMatrixText(path, 4, 4), with its errors) and the line of each entry.
struct PoseText {
  Eigen::Matrix4d world_from_cam = Eigen::Matrix4d::Identity();
  PoseLocator where;
};
PoseText ReadPoseText(const std::string& path);
PoseText ParsePoseText(std::string_view text, const std::string& name);
// ReadPoseText + SetMatrixPose for a per-frame pose file: a file that cannot be read
// (kReasonPoseUnreadable), malformed text (kReasonPoseMalformed: not 16 numbers, a token
// that is not a number; detail the parse error naming the file) and a bad pose all mark
// the frame unusable (one bad frame among thousands is skipped and counted, not fatal).
bool SetPoseFromText(const std::string& path, Frame* frame);

// All numbers of a text file, row-major, with exactly rows * cols entries.
Eigen::MatrixXd ReadMatrixText(const std::string& path, int rows, int cols);
// K from a 3x3 or 4x4 (top-left 3x3 used) text file; a malformed K (non-finite, fx/fy <= 0,
// bottom row not [0 0 1]) is InputError naming the file.
Eigen::Matrix3d ReadIntrinsicsText(const std::string& path);
// The same from text already in memory; `name` (a path) is used in error messages. The
// Read* functions above are ReadFileBytes + these; the fuzz targets (tests/fuzz) call them.
Eigen::MatrixXd ParseMatrixText(std::string_view text, const std::string& name, int rows, int cols);
Eigen::Matrix3d ParseIntrinsicsText(std::string_view text, const std::string& name);
// The K check of ReadIntrinsicsText for a K parsed elsewhere: throws InputError(where, ...)
// unless K is finite with fx, fy > 0 and bottom row [0 0 1]; returns K.
Eigen::Matrix3d CheckedIntrinsics(const Eigen::Matrix3d& K, const std::string& where);

// A text line split off a list file: its 1-based line number and numbers/tokens.
struct TextRecord {
  int line_no = 0;
  std::vector<std::string> tokens;
};
// Non-empty lines that do not start with '#', split on whitespace.
std::vector<TextRecord> ReadRecords(const std::string& path);
std::vector<TextRecord> ParseRecords(std::string_view text);

// TUM "timestamp filename" lists (rgb.txt, depth.txt), sorted by time (stable). `file` is
// the name as written in the list (relative to the sequence folder). A line without
// exactly two fields or with a non-finite timestamp is InputError("<name>:<line>", ...), and
// so is a timestamp given twice with two files (the same line twice is kept once).
struct TimedPath {
  double t = 0;
  std::string file;
  int line_no = 0;
};
std::vector<TimedPath> ParseTimedPathList(std::string_view text, const std::string& name);

// "timestamp tx ty tz qx qy qz qw" lines (TUM groundtruth.txt), sorted by time (stable);
// '#' comments and blank lines skipped. Exactly 8 numbers a line and a finite timestamp,
// else InputError("<name>:<line>", ...). Pose values are not checked here (SetTQPose).
struct TimedPose {
  int line_no = 0;
  double t = 0;
  std::string t_text;  // the timestamp as written
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector4d q_xyzw = Eigen::Vector4d(0, 0, 0, 1);
};
std::vector<TimedPose> ParseTimedPoses(std::string_view text, const std::string& name);

// "tx ty tz qx qy qz qw" lines (TartanAir pose_left.txt): blank lines skipped, every other
// line exactly 7 numbers, else InputError("<name>:<line>", ...). In file order.
struct TQLine {
  int line_no = 0;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector4d q_xyzw = Eigen::Vector4d(0, 0, 0, 1);
};
std::vector<TQLine> ParseTQLines(std::string_view text, const std::string& name);

// A file in a folder whose name is <prefix><digits><suffix>.
struct NumberedFile {
  int64_t number = 0;
  std::string stem;  // the digits as written ("0048", "000150")
  std::string path;  // full path
};
// Files of `folder` named prefix + digits + suffix, sorted by number (then by stem), with
// AppleDouble "._*" files ignored. Missing folder: empty result.
std::vector<NumberedFile> ListNumberedFiles(const std::string& folder, const std::string& prefix,
                                            const std::string& suffix);

// The frames of several listings of one scene (pose, depth, colour files): one entry per
// frame number, sorted by number; a number in several lists takes the entry of the first
// list holding it (its stem is the frame id).
std::vector<NumberedFile> MergeNumberedFiles(const std::vector<std::vector<NumberedFile>>& lists);

// Immediate subfolders of `folder`, sorted by name, hidden and "._*" entries ignored.
std::vector<std::string> ListSubfolders(const std::string& folder);
// "" when `path` is a regular file (through links) or nothing is there; else what is there
// instead: "dangling symbolic link (expected a readable file)" (a dangling or looping link),
// "expected a regular file, found a folder or special file".
std::string NotAFileProblem(const std::string& path);

// Throws InputError(root, "dataset root not found") when root does not exist.
void RequireRoot(const std::string& root);
// Throws InputError naming DIR/dataset.json when root, its parent or its grandparent is the
// folder DIR of an `occgt synth` run that did not finish: its claim .occgt-synth.json (written
// first) without dataset.json (written last). A killed run's folder read as a smaller
// dataset, without a word (docs/SYNTH.md).
void RequireFinishedSynth(const std::string& root);
// "" when `name` is a usable scene name: relative, no ".." component (scene names select
// folders under the root; they never leave it). Output names are sanitised separately.
std::string CheckSceneName(const std::string& name);
// The folder of scene `name` under root (InputError when CheckSceneName fails): root itself when
// `root_is_scene` and name is empty or equals the root's folder name, else root/name; InputError
// naming the folder when it does not exist.
std::string ResolveSceneFolder(const std::string& root, const std::string& name,
                               bool root_is_scene);
// Last path component of a folder (without trailing '/').
std::string FolderName(const std::string& path);
// An empty Scene read from `folder`: named scene_name, or the folder's name when that is
// empty, with the reader's format and valid depth range [min_depth_m, max_depth_m].
Scene NewFolderScene(const std::string& folder, const std::string& scene_name, DatasetFormat format,
                     double min_depth_m, double max_depth_m);

// Marks a frame unusable with `reason` (and `detail`) unless it already is (the first
// reason wins).
void MarkUnusable(Frame* frame, const std::string& reason, const std::string& detail = "");

// The file of one role of a frame (its colour, its depth) among candidate paths in order of
// preference: Pick gives the first that exists ("" for none; empty candidates are skipped)
// and counts the frames where a later one exists too; Note adds one scene warning for all
// of them, naming the first ("2 frame(s) have two colour files, and each reads the first
// (the first frame: .../0054.jpg, not .../0054.png)"), so that no choice is silent.
class PreferredFile {
 public:
  explicit PreferredFile(std::string role) : role_(std::move(role)) {}
  std::string Pick(std::initializer_list<std::string> candidates);
  void Note(Scene* scene) const;

 private:
  std::string role_;
  size_t frames_ = 0;         // frames with more than one candidate on disk
  std::string kept_, other_;  // those of the first such frame
};
void MarkUnusable(Frame* frame, const Unusable& why);

}  // namespace gt::datasets

// Parsing helpers shared by the dataset readers (libgt/datasets/*.cc), so that every reader
// reports the same errors in the same words: numeric matrices in text files (poses,
// intrinsics), timestamped lists (TUM), folder listings sorted by frame number, scene
// folder resolution and the unusable-frame reasons that `occgt scan` counts.
//
// Matrices are read row-major from all numbers of the file (blank lines ignored); the
// count must match exactly, otherwise InputError("<path>", "expected 16 numbers (4x4),
// found 12"). A token that is not a number is InputError("<path>:<line>", ...).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/frame.h"

namespace gt::datasets {

// Whitespace-separated doubles of one text line; accepts "inf", "-inf", "nan" (any case),
// which ScanNet writes for lost tracking. Throws InputError("<path>:<line>", ...) on a
// token that is not a number.
std::vector<double> ParseNumbers(std::string_view line, const std::string& path, int line_no);

// Stable reasons for unusable frames (counted by `occgt scan`).
inline constexpr const char* kReasonDepthMissing = "depth: missing file";
// "pose: " + PoseProblem(...) text, e.g. "pose: non-finite pose entries (lost tracking)".
std::string PoseReason(const std::string& problem);

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
// exactly two fields or with a non-finite timestamp is InputError("<name>:<line>", ...).
struct TimedPath {
  double t = 0;
  std::string file;
};
std::vector<TimedPath> ParseTimedPathList(std::string_view text, const std::string& name);

// "timestamp tx ty tz qx qy qz qw" lines (TUM groundtruth.txt), sorted by time (stable);
// '#' comments and blank lines skipped. Exactly 8 numbers a line and a finite timestamp,
// else InputError("<name>:<line>", ...). Pose values are not checked here (PoseProblemTQ).
struct TimedPose {
  double t = 0;
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

// Immediate subfolders of `folder`, sorted by name, hidden and "._*" entries ignored.
std::vector<std::string> ListSubfolders(const std::string& folder);

// Throws InputError(root, "dataset root not found") when root does not exist.
void RequireRoot(const std::string& root);
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

// Marks a frame unusable with `reason` unless it already is (the first reason wins).
void MarkUnusable(Frame* frame, const std::string& reason);

}  // namespace gt::datasets

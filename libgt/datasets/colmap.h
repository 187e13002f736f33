// COLMAP sparse models (cameras and images), binary or text, as COLMAP documents them
// ("Output format" of its documentation; docs/DATASETS.md "MegaDepth"). points3D and the
// images' 2D points are not needed and are skipped.
//
// cameras.bin: uint64 count, then per camera int32 camera_id, int32 model_id, uint64 width,
//   uint64 height, and the model's parameter count of float64 (SIMPLE_PINHOLE 0: f, cx, cy;
//   PINHOLE 1: fx, fy, cx, cy; ids 2..10 are distorted models, counts 4 5 8 8 12 5 4 5 12).
// images.bin: uint64 count, then per image int32 image_id, float64 qw qx qy qz, float64
//   tx ty tz, int32 camera_id, the name as bytes up to a NUL, uint64 num_points2D and that
//   many (float64 x, float64 y, int64 point3D_id) records (24 bytes each).
// cameras.txt: "CAMERA_ID MODEL WIDTH HEIGHT PARAMS..." lines; images.txt: per image a line
//   "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME" followed by one line of 2D points (which
//   may be empty). '#' lines are comments. All little-endian.
// (qvec, tvec) is cam_from_world: p_in_cam = R(q) p_in_world + t.
//
// Every count and size is checked against the bytes left before anything is allocated: a
// cut or damaged file is one InputError naming the file, the record and the field.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libgt/core/camera.h"
#include "libgt/core/lens.h"
#include "libgt/core/pose.h"

namespace gt::datasets {

struct ColmapCamera {
  int64_t id = 0;
  std::string model;  // "PINHOLE", "SIMPLE_PINHOLE", "SIMPLE_RADIAL", ...
  int width = 0;
  int height = 0;
  std::vector<double> params;
};

struct ColmapImage {
  int64_t id = 0;
  Eigen::Vector4d qvec_wxyz = Eigen::Vector4d(1, 0, 0, 0);  // cam_from_world rotation
  Eigen::Vector3d tvec = Eigen::Vector3d::Zero();           // cam_from_world translation
  int64_t camera_id = 0;
  std::string name;  // relative to the image folder, as COLMAP wrote it
  int line_no = 0;   // its line in images.txt (1-based); 0 when read from images.bin
};
// "<images path>:<line>" of an image read from images.txt, else the images path.
std::string ColmapImageWhere(const std::string& images_path, const ColmapImage& image);

struct ColmapModel {
  std::string cameras_path;  // the files read (named in messages)
  std::string images_path;
  std::map<int64_t, ColmapCamera> cameras;  // by camera id
  std::vector<ColmapImage> images;          // in file order
};

// Parsers of one file's bytes; `path` names it in messages. Duplicate ids, unknown model
// names or ids and wrong parameter counts are errors.
std::map<int64_t, ColmapCamera> ParseColmapCamerasBinary(std::string_view bytes,
                                                         const std::string& path);
std::vector<ColmapImage> ParseColmapImagesBinary(std::string_view bytes, const std::string& path);
std::map<int64_t, ColmapCamera> ParseColmapCamerasText(std::string_view text,
                                                       const std::string& path);
std::vector<ColmapImage> ParseColmapImagesText(std::string_view text, const std::string& path);

// True when `folder` holds cameras.bin + images.bin or cameras.txt + images.txt.
bool HasColmapModel(const std::string& folder);
// The model of `folder`: the binary pair when both .bin files exist, else the text pair
// (InputError naming the folder when neither is complete). Every image's camera_id must
// name a camera of cameras.* (else InputError naming images.* and the image).
ColmapModel ReadColmapModel(const std::string& folder);

// K at the camera's width x height for an undistorted model: PINHOLE (fx, fy, cx, cy) or
// SIMPLE_PINHOLE (f, cx, cy). Another model is InputError(cameras_path, "camera N: model
// X is not supported ..."). COLMAP's principal point is in pixel units with the centre of
// the top-left pixel at (0.5, 0.5); occgt's pixel centres are integers (camera.h), so
// cx_occgt = cx_colmap - 0.5 (and likewise cy).
Camera ColmapPinholeCamera(const ColmapCamera& camera, const std::string& cameras_path);
// The camera with its lens (core/lens.h), principal point converted as above: PINHOLE,
// SIMPLE_PINHOLE (kPinhole), SIMPLE_RADIAL (f cx cy k), RADIAL (f cx cy k1 k2), OPENCV
// (fx fy cx cy k1 k2 p1 p2) (kOpenCv) and OPENCV_FISHEYE (fx fy cx cy k1 k2 k3 k4)
// (kOpenCvFisheye). Another model, or a camera that fails LensCamera::Check, is
// InputError(cameras_path, "camera N: ...").
LensCamera ColmapLensCamera(const ColmapCamera& camera, const std::string& cameras_path);

// world_from_cam of an image: the inverse of cam_from_world (R(qvec), tvec), the quaternion
// normalised; ColmapPoseDefect (FindPoseDefectTQ: non-finite entries, |q| not within 1e-3
// of 1) says when it cannot be used.
std::optional<PoseDefect> ColmapPoseDefect(const ColmapImage& image);
Rigid3d ColmapWorldFromCam(const ColmapImage& image);

}  // namespace gt::datasets

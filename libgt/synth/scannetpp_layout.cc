// The synthetic ScanNet++-layout fixture (scannetpp_layout.h).
#include "libgt/synth/scannetpp_layout.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <sstream>

#include "libgt/core/error.h"
#include "libgt/io/atomic_file.h"
#include "libgt/io/codec.h"
#include "libgt/io/iphone_depth.h"
#include "libgt/synth/dataset.h"
#include "libgt/synth/render.h"
#include "libgt/synth/trajectory.h"

namespace gt::synth {
namespace fs = std::filesystem;
namespace {

std::string Fmt(const char* format, int value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// The 8 corners of a box (centre, half sizes, yaw about +z), index bit k = sign of axis k.
std::array<Eigen::Vector3d, 8> Corners(const Eigen::Vector3d& center, const Eigen::Vector3d& half,
                                       double yaw) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::array<Eigen::Vector3d, 8> c;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d s((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
    c[i] = center + R * s.cwiseProduct(half);
  }
  return c;
}

// The mesh of the scene: 12 triangles per box (the room and every object), binary PLY.
std::string RoomMeshPly(const SynthScene& scene) {
  std::vector<std::array<Eigen::Vector3d, 8>> boxes;
  std::vector<Eigen::Vector3d> colors;
  boxes.push_back(Corners(scene.room_size_m / 2, scene.room_size_m / 2, 0.0));
  colors.push_back(scene.room_materials[0].albedo_rgb);
  for (const auto& b : scene.objects) {
    boxes.push_back(Corners(b.center_in_world, b.half_size_m, b.yaw_rad));
    colors.push_back(b.material.albedo_rgb);
  }
  // Faces of a box by corner index (two triangles each): -x, +x, -y, +y, -z, +z.
  static const int kQuads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                   {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment occgt synth --layout scannetpp\n"
         << "element vertex " << boxes.size() * 8 << "\nproperty float x\nproperty float y\n"
         << "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
         << "element face " << boxes.size() * 12
         << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string out = header.str();
  for (size_t b = 0; b < boxes.size(); ++b) {
    for (const Eigen::Vector3d& p : boxes[b]) {
      for (int k = 0; k < 3; ++k) {
        const float f = static_cast<float>(p[k]);
        char bytes[4];
        std::memcpy(bytes, &f, 4);
        out.append(bytes, 4);
      }
      for (int k = 0; k < 3; ++k) {
        out.push_back(static_cast<char>(std::lround(255.0 * colors[b][k])));
      }
    }
  }
  for (size_t b = 0; b < boxes.size(); ++b) {
    for (const auto& q : kQuads) {
      for (const std::array<int, 3> tri :
           {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
        out.push_back(3);
        for (int k : tri) {
          const int32_t index = static_cast<int32_t>(b * 8 + k);
          char bytes[4];
          std::memcpy(bytes, &index, 4);
          out.append(bytes, 4);
        }
      }
    }
  }
  return out;
}

struct LensView {
  cv::Mat3b rgb;    // R, G, B
  cv::Mat1f depth;  // planar z, metres; 0 where no ray or no hit
};

// Colour and depth of a distorted camera: every pixel shaded along its exact ray.
LensView RenderLensView(const SynthScene& scene, const LensCamera& lens,
                        const Rigid3d& world_from_cam, bool color) {
  LensView view;
  const int w = lens.pinhole.width, h = lens.pinhole.height;
  view.rgb = cv::Mat3b(h, w, cv::Vec3b(0, 0, 0));
  view.depth = cv::Mat1f(h, w, 0.0f);
  const Eigen::Matrix3d R = world_from_cam.linear();
  const Eigen::Vector3d o = world_from_cam.translation();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const auto ab = UndistortPixel(lens, u, v);
      if (!ab) continue;
      const Eigen::Vector3d d = R * Eigen::Vector3d(ab->x(), ab->y(), 1.0);
      const RayHit hit = CastRay(scene, o, d);
      if (!hit.hit()) continue;
      view.depth(v, u) = static_cast<float>(hit.t);
      if (color) {
        const Eigen::Vector3d c = ShadeHit(scene, o + hit.t * d, hit);
        for (int k = 0; k < 3; ++k) {
          view.rgb(v, u)[k] = static_cast<uint8_t>(std::lround(255.0 * c[k]));
        }
      }
    }
  }
  return view;
}

std::string CamerasTxt(const char* model, const LensCamera& lens, int n_coeffs) {
  std::string s =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n# Number of cameras: 1\n";
  const Camera& c = lens.pinhole;
  s += std::string("1 ") + model + " " + std::to_string(c.width) + " " + std::to_string(c.height) +
       " " + Num(c.fx) + " " + Num(c.fy) + " " + Num(c.cx + 0.5) + " " + Num(c.cy + 0.5);
  for (int k = 0; k < n_coeffs; ++k) s += " " + Num(lens.coeffs[k]);
  return s + "\n";
}

std::string ImageLine(int id, const Rigid3d& world_from_cam, const std::string& name) {
  const Rigid3d cam_from_world = world_from_cam.inverse();
  const Eigen::Quaterniond q(cam_from_world.linear());
  const Eigen::Vector3d t = cam_from_world.translation();
  return std::to_string(id) + " " + Num(q.w()) + " " + Num(q.x()) + " " + Num(q.y()) + " " +
         Num(q.z()) + " " + Num(t.x()) + " " + Num(t.y()) + " " + Num(t.z()) + " 1 " + name +
         "\n\n";
}

constexpr const char* kImagesHeader =
    "# Image list with two lines of data per image:\n"
    "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
    "#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
constexpr const char* kPointsHeader =
    "# 3D point list with one line of data per point:\n"
    "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";

std::string Jpeg(const cv::Mat3b& rgb, const std::string& path) {
  return io::EncodeJpegBytes(rgb, io::ChannelOrder::kRgb, 95, path);
}
std::string Png(const cv::Mat& m, const std::string& path) {
  return io::EncodePngBytes(m, io::ChannelOrder::kRgb, 3, path);
}

// A small rigid offset: the iPhone walks beside the DSLR.
Rigid3d Beside(const Rigid3d& pose, int i) {
  Rigid3d offset = Rigid3d::Identity();
  offset.translation() = Eigen::Vector3d(0.12, -0.05, 0.03 * (i % 3));
  offset.linear() = Eigen::AngleAxisd(0.08, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return pose * offset;
}

}  // namespace

bool ScanNetPPSynthOptions::Check(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (scenes < 1 || scenes > 100) return fail("scenes: expected 1..100");
  if (frames < 2 || frames > 1000) return fail("frames: expected 2..1000");
  if (dslr_width < 32 || dslr_height < 32 || dslr_width > 4096 || dslr_height > 4096) {
    return fail("DSLR size: expected 32..4096 pixels per side");
  }
  if (iphone_width < 32 || iphone_height < 32 || iphone_width > 4096 || iphone_height > 4096) {
    return fail("iPhone size: expected 32..4096 pixels per side");
  }
  return true;
}

std::string ScanNetPPSynthSceneName(int scene_index) { return Fmt("synthpp_%03d", scene_index); }
std::string ScanNetPPSynthDslrName(int i) { return Fmt("DSC%05d.JPG", 10 * (i + 1)); }

LensCamera ScanNetPPSynthDslrLens(const ScanNetPPSynthOptions& o) {
  // ScanNet++'s DSLR proportions: fx ~ 0.45 w, a mild fisheye distortion.
  LensCamera lens;
  lens.pinhole.width = o.dslr_width;
  lens.pinhole.height = o.dslr_height;
  lens.pinhole.fx = 0.4516 * o.dslr_width;
  lens.pinhole.fy = 0.4513 * o.dslr_width;
  lens.pinhole.cx = (o.dslr_width - 1) / 2.0 - 0.8;
  lens.pinhole.cy = (o.dslr_height - 1) / 2.0 + 0.6;
  lens.model = LensModel::kOpenCvFisheye;
  lens.coeffs = {-0.0297, -0.0049, 0.0011, -0.0004, 0.0};
  return lens;
}

LensCamera ScanNetPPSynthIphoneLens(const ScanNetPPSynthOptions& o) {
  LensCamera lens;
  lens.pinhole.width = o.iphone_width;
  lens.pinhole.height = o.iphone_height;
  lens.pinhole.fx = 0.7526 * o.iphone_width;
  lens.pinhole.fy = 0.7524 * o.iphone_width;
  lens.pinhole.cx = (o.iphone_width - 1) / 2.0 + 1.1;
  lens.pinhole.cy = (o.iphone_height - 1) / 2.0 - 0.7;
  lens.model = LensModel::kOpenCv;
  lens.coeffs = {0.071, -0.171, 0.0012, -0.0007, 0.0};
  return lens;
}

ScanNetPPSynthScene MakeScanNetPPSynthScene(const ScanNetPPSynthOptions& options, int scene_index) {
  ScanNetPPSynthScene s;
  s.scene = MakeRoomScene(SynthSceneSeed(options.seed, scene_index));
  s.scene.name = ScanNetPPSynthSceneName(scene_index);
  // A third of the room's camera loop: neighbouring frames overlap (24 degrees apart at 5
  // frames), as in a capture.
  TrajectoryOptions traj;
  traj.frames = 3 * options.frames;
  s.dslr_poses = Trajectory(s.scene, traj);
  s.dslr_poses.resize(static_cast<size_t>(options.frames));
  for (int i = 0; i <= options.frames; ++i) {  // one more: the iPhone frame without a pose
    s.iphone_poses.push_back(Beside(s.dslr_poses[i % options.frames], i));
  }
  return s;
}

ScanNetPPSynthSummary WriteScanNetPPSynth(const std::string& out_dir,
                                          const ScanNetPPSynthOptions& options) {
  std::string error;
  if (!options.Check(&error)) throw InputError("synth scannetpp options", error);
  ScanNetPPSynthSummary summary;
  const LensCamera dslr = ScanNetPPSynthDslrLens(options);
  const LensCamera phone = ScanNetPPSynthIphoneLens(options);
  LensCamera phone_depth = phone;
  phone_depth.pinhole = phone.pinhole.Resized(io::kIphoneDepthWidth, io::kIphoneDepthHeight);
  auto write = [&](const fs::path& path, const std::string& bytes) {
    io::WriteFileAtomic(path.string(), bytes);
    ++summary.files;
  };
  // Two runs' scenes and frames never mix (dataset.h ClaimSynthFolder).
  const nlohmann::ordered_json claim = {{"layout", "scannetpp"},
                                        {"options",
                                         {{"scenes", options.scenes},
                                          {"frames", options.frames},
                                          {"dslr_width", options.dslr_width},
                                          {"dslr_height", options.dslr_height},
                                          {"iphone_width", options.iphone_width},
                                          {"iphone_height", options.iphone_height},
                                          {"seed", options.seed}}}};
  ClaimSynthFolder(out_dir, claim.dump(), "");
  ++summary.files;
  for (int s = 0; s < options.scenes; ++s) {
    const ScanNetPPSynthScene truth = MakeScanNetPPSynthScene(options, s);
    const fs::path dir = fs::path(out_dir) / "data" / truth.scene.name;
    write(dir / "scans" / "mesh_aligned_0.05.ply", RoomMeshPly(truth.scene));

    // DSLR.
    const fs::path d = dir / "dslr";
    std::string images = kImagesHeader;
    std::string train = "", test = "";
    for (int i = 0; i < options.frames; ++i) {
      const std::string name = ScanNetPPSynthDslrName(i);
      const std::string stem = name.substr(0, name.size() - 4);
      images += ImageLine(i + 1, truth.dslr_poses[i], name);
      const LensView view = RenderLensView(truth.scene, dslr, truth.dslr_poses[i], true);
      write(d / "resized_images" / name, Jpeg(view.rgb, name));
      cv::Mat1b mask(dslr.pinhole.height, dslr.pinhole.width, uint8_t(255));
      if (i == options.frames - 1) {
        mask.setTo(0);  // a frame anonymised entirely
      } else if (i % 2 == 0) {
        mask(cv::Rect(mask.cols / 3, mask.rows / 3, mask.cols / 6, mask.rows / 5)).setTo(0);
      }
      write(d / "resized_anon_masks" / (stem + ".png"), Png(mask, stem));
      (i % 4 == 3 ? test : train) +=
          std::string(i % 4 == 3 ? (test.empty() ? "" : ", ") : (train.empty() ? "" : ", ")) +
          "\"" + name + "\"";
    }
    // An image without a pose (rendered from the first pose, never named in COLMAP), and a
    // test image whose file is missing.
    const LensView extra = RenderLensView(truth.scene, dslr, truth.dslr_poses[0], true);
    write(d / "resized_images" / "DSC90000.JPG", Jpeg(extra.rgb, "DSC90000.JPG"));
    write(d / "resized_anon_masks" / "DSC90000.png",
          Png(cv::Mat1b(dslr.pinhole.height, dslr.pinhole.width, uint8_t(255)), "DSC90000"));
    test += std::string(test.empty() ? "" : ", ") + "\"DSC90001.JPG\"";
    write(d / "train_test_lists.json", "{\"train\": [" + train + "], \"test\": [" + test + "]}\n");
    write(d / "colmap" / "cameras.txt", CamerasTxt("OPENCV_FISHEYE", dslr, 4));
    write(d / "colmap" / "images.txt", images);
    write(d / "colmap" / "points3D.txt", kPointsHeader);

    // iPhone: frames 0..frames-1 posed, frame `frames` without a pose.
    const fs::path p = dir / "iphone";
    std::string phone_images = kImagesHeader;
    std::vector<DepthImage> depths;
    for (int i = 0; i <= options.frames; ++i) {
      const std::string stem = Fmt("frame_%06d", i);
      if (i < options.frames)
        phone_images += ImageLine(i + 1, truth.iphone_poses[i], stem + ".jpg");
      const LensView view = RenderLensView(truth.scene, phone, truth.iphone_poses[i], true);
      write(p / "rgb" / (stem + ".jpg"), Jpeg(view.rgb, stem));
      cv::Mat1b mask(phone.pinhole.height, phone.pinhole.width, uint8_t(255));
      if (i % 3 == 1)
        mask(cv::Rect(mask.cols / 2, mask.rows / 4, mask.cols / 5, mask.rows / 4)).setTo(0);
      write(p / "rgb_masks" / (stem + ".png"), Png(mask, stem));
      const LensView dv = RenderLensView(truth.scene, phone_depth, truth.iphone_poses[i], false);
      DepthImage depth(dv.depth.cols, dv.depth.rows);
      cv::Mat1w mm(dv.depth.rows, dv.depth.cols);
      for (int v = 0; v < dv.depth.rows; ++v) {
        for (int u = 0; u < dv.depth.cols; ++u) {
          const double z = dv.depth(v, u);
          const double rounded = std::round(z * 1000.0);
          mm(v, u) = rounded > 0 && rounded < 65535 ? static_cast<uint16_t>(rounded) : 0;
          depth.at(u, v) = dv.depth(v, u);
        }
      }
      write(p / "depth" / (stem + ".png"), io::EncodePngBytes(mm, io::ChannelOrder::kRgb, 3, stem));
      depths.push_back(std::move(depth));
    }
    write(p / "depth.bin", io::EncodeIphoneDepthBinRecords(depths, /*lz4=*/true));
    write(p / "colmap" / "cameras.txt", CamerasTxt("OPENCV", phone, 4));
    write(p / "colmap" / "images.txt", phone_images);
    write(p / "colmap" / "points3D.txt", kPointsHeader);
    summary.scene_names.push_back(truth.scene.name);
  }
  // Last: the run is complete (the readers refuse a claimed folder without it).
  nlohmann::ordered_json dataset = claim;
  dataset["scenes"] = summary.scene_names;
  write(fs::path(out_dir) / "dataset.json", dataset.dump(2) + "\n");
  return summary;
}

}  // namespace gt::synth

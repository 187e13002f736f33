// ScanNet++ reader on occgt's own ScanNet++-layout fixture (synth/scannetpp_layout.h): frames,
// cameras and poses against the fixture's truth, colour undistorted against the exact pinhole
// view, iPhone depth (PNG and depth.bin) against the exact depth along each ray, masks,
// the unusable frames `scan` must explain, and bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>

#include "libgt/core/error.h"
#include "libgt/datasets/reader.h"
#include "libgt/datasets/scan.h"
#include "libgt/datasets/undistorted_camera.h"
#include "libgt/geometry/labels.h"
#include "libgt/io/codec.h"
#include "libgt/io/depth_io.h"
#include "libgt/io/file_read.h"
#include "libgt/io/image.h"
#include "libgt/io/iphone_depth.h"
#include "libgt/io/undistort.h"
#include "libgt/render/frame_depth.h"
#include "libgt/shards/posed_export.h"
#include "libgt/synth/render.h"
#include "libgt/synth/scannetpp_layout.h"
#include "libgt/truth/working_frame.h"

namespace gt {
namespace {
namespace fs = std::filesystem;

synth::ScanNetPPSynthOptions SmallOptions() {
  synth::ScanNetPPSynthOptions o;
  o.frames = 4;
  o.dslr_width = 240;
  o.dslr_height = 160;
  o.iphone_width = 192;
  o.iphone_height = 144;
  o.seed = 3;
  return o;
}

class ScanNetPP : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("occgt_scannetpp_test_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    synth::WriteScanNetPPSynth(root_->string(), SmallOptions());
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
  }
  static Scene Read(datasets::ScanNetPPDevice device, const std::string& root = "") {
    datasets::ReaderOptions options;
    options.scannetpp_device = device;
    const auto reader = datasets::MakeReader(DatasetFormat::kScanNetPP, options);
    const std::string r = root.empty() ? root_->string() : root;
    const auto scenes = reader->ListScenes(r);
    EXPECT_EQ(scenes.size(), 1u);
    return reader->ReadScene(r, scenes.at(0));
  }
  static fs::path SceneDir() { return *root_ / "data" / synth::ScanNetPPSynthSceneName(0); }
  // A copy of the fixture to damage.
  static fs::path Copy(const std::string& name) {
    const fs::path to =
        fs::temp_directory_path() / ("occgt_scannetpp_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(to);
    fs::copy(*root_, to, fs::copy_options::recursive);
    return to;
  }
  static fs::path* root_;
};
fs::path* ScanNetPP::root_ = nullptr;

const Frame* Find(const Scene& scene, const std::string& id) {
  for (const Frame& f : scene.frames) {
    if (f.id == id) return &f;
  }
  return nullptr;
}

void ExpectPoseNear(const Rigid3d& a, const Rigid3d& b) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(ScanNetPP, DslrFramesCamerasAndPoses) {
  const synth::ScanNetPPSynthOptions o = SmallOptions();
  const auto truth = synth::MakeScanNetPPSynthScene(o, 0);
  const Scene scene = Read(datasets::ScanNetPPDevice::kDslr);
  EXPECT_EQ(scene.format, DatasetFormat::kScanNetPP);
  EXPECT_EQ(scene.mesh_path, (SceneDir() / "scans" / "mesh_aligned_0.05.ply").string());
  ASSERT_EQ(scene.frames.size(), static_cast<size_t>(o.frames + 2));
  const LensCamera lens = synth::ScanNetPPSynthDslrLens(o);
  const Camera undistorted = datasets::ScanNetPPUndistortedCamera(lens, "cameras.txt", 1);
  for (int i = 0; i < o.frames; ++i) {
    const std::string name = synth::ScanNetPPSynthDslrName(i);
    const Frame* f = Find(scene, name.substr(0, name.size() - 4));
    ASSERT_NE(f, nullptr) << name;
    ASSERT_TRUE(f->color_lens.has_value());
    EXPECT_EQ(f->color_lens->model, LensModel::kOpenCvFisheye);
    // COLMAP's +0.5 principal point is converted back exactly.
    EXPECT_NEAR(f->color_lens->pinhole.cx, lens.pinhole.cx, 1e-12);
    EXPECT_NEAR(f->color_lens->pinhole.cy, lens.pinhole.cy, 1e-12);
    EXPECT_NEAR(f->color_lens->coeffs[0], lens.coeffs[0], 1e-15);
    EXPECT_NEAR(f->color_camera.fx, undistorted.fx, 1e-9);
    EXPECT_EQ(f->color_camera.cx, lens.pinhole.width / 2.0);
    EXPECT_EQ(f->depth_camera.width, lens.pinhole.width);
    EXPECT_TRUE(f->depth.path.empty());  // DSLR: no sensor depth
    ExpectPoseNear(f->world_from_cam, truth.dslr_poses[i]);
    EXPECT_EQ(f->mask_path, (SceneDir() / "dslr" / "resized_anon_masks" /
                             (name.substr(0, name.size() - 4) + ".png"))
                                .string());
    EXPECT_TRUE(f->usable) << f->UnusableMessage();
  }
  const Frame* no_pose = Find(scene, "DSC90000");
  ASSERT_NE(no_pose, nullptr);
  EXPECT_FALSE(no_pose->usable);
  EXPECT_EQ(no_pose->unusable_reason, "pose: image not in the COLMAP model");
  const Frame* no_file = Find(scene, "DSC90001");
  ASSERT_NE(no_file, nullptr);
  EXPECT_FALSE(no_file->usable);
  EXPECT_EQ(no_file->unusable_reason, "colour: missing file");
}

TEST_F(ScanNetPP, ScanExplainsEveryUnusableImage) {
  const Scene scene = Read(datasets::ScanNetPPDevice::kDslr);
  const datasets::SceneSummary s = datasets::SummarizeScene(scene, {});
  EXPECT_EQ(s.frames, scene.frames.size());
  EXPECT_EQ(s.usable, s.frames - 3);
  EXPECT_EQ(s.unusable_reasons.at("pose: image not in the COLMAP model"), 1u);
  EXPECT_EQ(s.unusable_reasons.at("colour: missing file"), 1u);
  EXPECT_EQ(s.unusable_reasons.at("mask: covers the whole image"), 1u);
  EXPECT_EQ(s.unusable_examples.at("mask: covers the whole image").at(0).frame,
            synth::ScanNetPPSynthDslrName(SmallOptions().frames - 1).substr(0, 8));
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_NE(s.warnings[0].find("ScanNet++"), std::string::npos);
}

// Mean absolute difference over the interior of two RGB images.
double MeanAbsDiff(const io::ColorImage& a, const io::ColorImage& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  double sum = 0;
  size_t n = 0;
  for (int v = 3; v < a.height - 3; ++v) {
    for (int u = 3; u < a.width - 3; ++u) {
      for (int k = 0; k < 3; ++k) sum += std::abs(int(a.pixel(u, v)[k]) - int(b.pixel(u, v)[k]));
      n += 3;
    }
  }
  return sum / n;
}

TEST_F(ScanNetPP, ColourIsUndistortedIntoThePinholeCamera) {
  const auto truth = synth::MakeScanNetPPSynthScene(SmallOptions(), 0);
  for (const auto device : {datasets::ScanNetPPDevice::kDslr, datasets::ScanNetPPDevice::kIphone}) {
    const Scene scene = Read(device);
    const Frame& f = scene.frames.at(1);
    ASSERT_TRUE(f.usable) << f.UnusableMessage();
    const io::ColorImage got = io::ReadFrameColor(f);
    const io::ColorImage exact = synth::RenderColor(truth.scene, f.color_camera, f.world_from_cam);
    Camera shifted = f.color_camera;
    shifted.cx += 1.0;
    const io::ColorImage off = synth::RenderColor(truth.scene, shifted, f.world_from_cam);
    const double err = MeanAbsDiff(got, exact), err_off = MeanAbsDiff(got, off);
    EXPECT_LT(err, 6.0) << datasets::ScanNetPPDeviceName(device);
    // The right camera explains the image clearly better than one a pixel off.
    EXPECT_LT(err, 0.75 * err_off) << datasets::ScanNetPPDeviceName(device);
    // Resized reads go through the same undistortion.
    const io::ColorImage small = io::ReadFrameColorResized(f, 96, 64);
    EXPECT_EQ(small.width, 96);
  }
}

TEST_F(ScanNetPP, IphoneDepthIsTheExactDepthAlongTheNearestDistortedRay) {
  const synth::ScanNetPPSynthOptions o = SmallOptions();
  const auto truth = synth::MakeScanNetPPSynthScene(o, 0);
  const Scene scene = Read(datasets::ScanNetPPDevice::kIphone);
  ASSERT_EQ(scene.frames.size(), static_cast<size_t>(o.frames + 1));
  EXPECT_EQ(scene.frames.back().unusable_reason, "pose: image not in the COLMAP model");
  int checked = 0, masked = 0;
  for (int i = 0; i < o.frames; ++i) {
    const Frame& f = scene.frames.at(i);
    ASSERT_TRUE(f.usable) << f.UnusableMessage();
    ExpectPoseNear(f.world_from_cam, truth.iphone_poses[i]);
    ASSERT_TRUE(f.depth_lens.has_value());
    EXPECT_EQ(f.depth_camera.width, 256);
    EXPECT_EQ(f.depth_camera.height, 192);
    const DepthImage d = io::ReadFrameDepth(f);
    const io::UndistortMaps& maps = io::GetUndistortMaps(*f.depth_lens, f.depth_camera);
    for (int v = 0; v < d.height; ++v) {
      for (int u = 0; u < d.width; ++u) {
        const int x = static_cast<int>(std::floor(double(maps.map_x(v, u)) + 0.5));
        const int y = static_cast<int>(std::floor(double(maps.map_y(v, u)) + 0.5));
        if (x < 0 || y < 0 || x >= f.depth_lens->pinhole.width ||
            y >= f.depth_lens->pinhole.height) {
          EXPECT_EQ(d.at(u, v), 0.0f);
          continue;
        }
        if (d.at(u, v) == 0.0f) {
          ++masked;
          continue;
        }
        const auto ab = UndistortPixel(*f.depth_lens, x, y);
        ASSERT_TRUE(ab.has_value());
        const Eigen::Vector3d dir =
            f.world_from_cam.linear() * Eigen::Vector3d(ab->x(), ab->y(), 1);
        const synth::RayHit hit = synth::CastRay(truth.scene, f.world_from_cam.translation(), dir);
        ASSERT_TRUE(hit.hit());
        ASSERT_NEAR(d.at(u, v), hit.t, 0.0005 + 1e-6) << u << "," << v;  // mm rounding
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, o.frames * 256 * 192 * 8 / 10);
  EXPECT_GT(masked, 0);  // frame 1 has an anonymised rectangle
}

TEST_F(ScanNetPP, DslrDepthIsRenderedInTheUndistortedCameraAndLabelsMatchTheExactOnes) {
  // depth_source mesh: rendered from scans/mesh_aligned_0.05.ply in the undistorted pinhole
  // camera at the working size, anonymised pixels 0; against the analytic scene's depth.
  const auto truth = synth::MakeScanNetPPSynthScene(SmallOptions(), 0);
  const Scene scene = Read(datasets::ScanNetPPDevice::kDslr);
  ASSERT_FALSE(scene.mesh_path.empty());
  render::FrameDepthOptions mesh;
  mesh.source = render::DepthSourceMode::kMesh;
  const truth::Resolution res{160, 104};
  std::vector<DepthImage> loaded, exact;
  std::vector<Camera> cams;
  std::vector<Rigid3d> poses;
  for (int i = 0; i < 3; ++i) {  // frames 0 and 2 have an anonymised rectangle
    const std::string name = synth::ScanNetPPSynthDslrName(i);
    const Frame* f = Find(scene, name.substr(0, name.size() - 4));
    ASSERT_NE(f, nullptr);
    ASSERT_TRUE(f->usable);
    const Camera cam = truth::WorkingCamera(*f, res);
    const DepthImage got = truth::LoadWorkingDepth(scene, *f, res, mesh, nullptr);
    const DepthImage want = synth::RenderDepth(truth.scene, cam, f->world_from_cam);
    // The mask in this camera (border 255, < 255 -> 0).
    const cv::Mat m =
        io::DecodeImageBytes(io::ReadFileBytes(f->mask_path), io::ChannelOrder::kRgb, f->mask_path);
    const cv::Mat1b valid = io::UndistortMask(m, *f->color_lens, cam);
    int masked = 0, compared = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        if (valid(v, u) != 255) {
          ASSERT_EQ(got.at(u, v), 0.0f) << name << " " << u << "," << v;
          ++masked;
          continue;
        }
        ASSERT_NEAR(got.at(u, v), want.at(u, v), 1e-4) << name << " " << u << "," << v;
        ++compared;
      }
    }
    EXPECT_EQ(masked > 0, i % 2 == 0) << name;
    EXPECT_GT(compared, cam.width * cam.height / 2);
    // The exact depth with the same anonymised pixels removed: labels then differ only by the
    // mesh's float precision.
    DepthImage want_masked = want;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        if (valid(v, u) != 255) want_masked.at(u, v) = 0.0f;
      }
    }
    loaded.push_back(got);
    exact.push_back(want_masked);
    cams.push_back(cam);
    poses.push_back(f->world_from_cam);
  }
  // Labels of frame 1 towards frames 0 and 2 (which have anonymised rectangles), from the
  // loaded depth and from the exact depth with the same pixels anonymised: equal.
  for (int b : {0, 2}) {
    const Rigid3d b_from_a = poses[b].inverse() * poses[1];
    const LabelOptions o = LabelPreset("default");
    const DirectionLabels got = LabelDirection(loaded[1], cams[1], loaded[b], cams[b], b_from_a, o);
    const DirectionLabels want = LabelDirection(exact[1], cams[1], exact[b], cams[b], b_from_a, o);
    int64_t same = 0, n = 0;
    for (size_t i = 0; i < got.labels.size(); ++i) {
      ++n;
      same += got.labels[i] == want.labels[i];
    }
    EXPECT_GT(double(same) / n, 0.999) << "frame 1 -> " << b;
  }
}

TEST_F(ScanNetPP, DslrDust3rExportWritesTheRenderedDepthInMillimetres) {
  // The DSLR has no depth file: the DUSt3R export writes the depth the build uses (rendered
  // from the mesh, passed in as the export's depth loader) as uint16 mm, anonymised pixels 0,
  // which must be the analytic scene's depth rounded to the millimetre.
  const auto truth = synth::MakeScanNetPPSynthScene(SmallOptions(), 0);
  const Scene scene = Read(datasets::ScanNetPPDevice::kDslr);
  render::FrameDepthOptions mesh;
  mesh.source = render::DepthSourceMode::kMesh;
  shards::PosedExportOptions options;
  options.width = 160;
  options.height = 104;
  std::vector<int64_t> numbers;
  for (int i = 0; i < 3; ++i) {
    const std::string name = synth::ScanNetPPSynthDslrName(i);
    const Frame* f = Find(scene, name.substr(0, name.size() - 4));
    ASSERT_NE(f, nullptr);
    numbers.push_back(f->number);
  }
  const std::vector<shards::PosedPair> pairs = {
      {scene.name, numbers[0], numbers[1], 0.5, 0.4, 0.6},
      {scene.name, numbers[1], numbers[2], 0.5, 0.6, 0.4}};
  const std::map<std::string, const Scene*> scenes = {{scene.name, &scene}};
  const fs::path out = *root_ / "export_dust3r";
  // Without the loader: the missing depth file is an error, as before.
  EXPECT_THROW(shards::ExportDust3r(out.string(), scenes, pairs, options), InputError);
  options.load_depth = [&](const Scene& s, const Frame& f, int w, int h) {
    return truth::LoadWorkingDepth(s, f, truth::Resolution{w, h}, mesh);
  };
  const shards::PosedExportStats stats = shards::ExportDust3r(out.string(), scenes, pairs, options);
  EXPECT_EQ(stats.views, 3u);
  const std::string folder = shards::PosedSceneFolders({scene.name}).at(scene.name);
  for (int i = 0; i < 3; ++i) {
    const std::string name = synth::ScanNetPPSynthDslrName(i);
    const Frame* f = Find(scene, name.substr(0, name.size() - 4));
    const Camera cam = truth::WorkingCamera(*f, {options.width, options.height});
    const DepthImage exact = synth::RenderDepth(truth.scene, cam, f->world_from_cam);
    // Named by the image stem (DUSt3R's ScanNet++ basenames, those of selected_pairs.npz).
    EXPECT_EQ(f->id, name.substr(0, name.size() - 4));
    EXPECT_TRUE(fs::is_regular_file(out / folder / "images" / (f->id + ".jpg"))) << f->id;
    EXPECT_FALSE(fs::exists(out / folder / "depth" / (std::to_string(f->number) + ".png")));
    const std::string png = (out / folder / "depth" / (f->id + ".png")).string();
    const cv::Mat got = io::DecodeImageBytes(io::ReadFileBytes(png), io::ChannelOrder::kRgb, png);
    ASSERT_EQ(got.type(), CV_16UC1) << png;
    ASSERT_EQ(got.cols, options.width);
    ASSERT_EQ(got.rows, options.height);
    const cv::Mat m =
        io::DecodeImageBytes(io::ReadFileBytes(f->mask_path), io::ChannelOrder::kRgb, f->mask_path);
    const cv::Mat1b valid = io::UndistortMask(m, *f->color_lens, cam);
    int masked = 0, compared = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const uint16_t mm = got.at<uint16_t>(v, u);
        if (valid(v, u) != 255) {
          ASSERT_EQ(mm, 0) << name << " " << u << "," << v;
          ++masked;
          continue;
        }
        const float d = exact.at(u, v);
        if (!(d > 0.0f)) continue;
        // Rounded to the millimetre: within half a millimetre plus the render's 1e-4 m.
        ASSERT_NEAR(mm / 1000.0, d, 0.0005 + 1e-4) << name << " " << u << "," << v;
        ++compared;
      }
    }
    EXPECT_EQ(masked > 0, i % 2 == 0) << name;
    EXPECT_GT(compared, cam.width * cam.height / 2) << name;
  }
  EXPECT_TRUE(fs::is_regular_file(out / folder / "selected_pairs.npz"));
  EXPECT_TRUE(fs::is_regular_file(out / "scene_list.json"));
}

TEST_F(ScanNetPP, IphoneDepthBinGivesThePngsValues) {
  const fs::path copy = Copy("depthbin");
  fs::remove_all(copy / "data" / synth::ScanNetPPSynthSceneName(0) / "iphone" / "depth");
  const Scene from_bin = Read(datasets::ScanNetPPDevice::kIphone, copy.string());
  const Scene from_png = Read(datasets::ScanNetPPDevice::kIphone);
  ASSERT_EQ(from_bin.frames.size(), from_png.frames.size());
  for (size_t i = 0; i + 1 < from_bin.frames.size(); ++i) {
    EXPECT_EQ(from_bin.frames[i].depth.format, DepthFormat::kIphoneBinRecord);
    const DepthImage a = io::ReadFrameDepth(from_bin.frames[i]);
    const DepthImage b = io::ReadFrameDepth(from_png.frames[i]);
    ASSERT_EQ(a.values_m, b.values_m) << "frame " << i;
  }
  fs::remove_all(copy);
}

TEST_F(ScanNetPP, BadInputIsOneClearError) {
  auto message = [&](const fs::path& root, datasets::ScanNetPPDevice device) {
    try {
      Read(device, root.string());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const fs::path copy = Copy("bad");
  const fs::path dslr = copy / "data" / synth::ScanNetPPSynthSceneName(0) / "dslr";
  auto write = [](const fs::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
  };
  // An unknown camera model.
  write(dslr / "colmap" / "cameras.txt", "1 FOV 240 160 100 100 120 80 0.1\n");
  std::string m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("cameras.txt"), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  // A pinhole-family camera where the DSLR must be a fisheye.
  write(dslr / "colmap" / "cameras.txt", "1 OPENCV 240 160 100 100 120 80 0.1 0 0 0\n");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("expected OPENCV_FISHEYE"), std::string::npos) << m;
  // A fisheye with a negative focal length.
  write(dslr / "colmap" / "cameras.txt", "1 OPENCV_FISHEYE 240 160 -100 100 120 80 0 0 0 0\n");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("focal"), std::string::npos) << m;
  // Restore the camera, then break images.txt.
  fs::copy_file(SceneDir() / "dslr" / "colmap" / "cameras.txt", dslr / "colmap" / "cameras.txt",
                fs::copy_options::overwrite_existing);
  write(dslr / "colmap" / "images.txt", "1 1 0 0 0 0 0 x 1 DSC00010.JPG\n\n");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("images.txt"), std::string::npos) << m;
  fs::copy_file(SceneDir() / "dslr" / "colmap" / "images.txt", dslr / "colmap" / "images.txt",
                fs::copy_options::overwrite_existing);
  // Bad train/test lists.
  write(dslr / "train_test_lists.json", "{\"train\": 3}");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("train_test_lists.json: train: expected a list"), std::string::npos) << m;
  write(dslr / "train_test_lists.json", "{\"train\": [");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("not valid JSON"), std::string::npos) << m;
  write(dslr / "train_test_lists.json", "{\"train\": [], \"test\": [], \"train\": []}");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("train_test_lists.json: train: duplicate key"), std::string::npos) << m;
  fs::remove(dslr / "train_test_lists.json");
  // No COLMAP model at all.
  fs::remove_all(dslr / "colmap");
  m = message(copy, datasets::ScanNetPPDevice::kDslr);
  EXPECT_NE(m.find("no COLMAP model of the dslr images"), std::string::npos) << m;
  // A mask of the wrong size: reading the frame's depth names the mask.
  const Scene phone = Read(datasets::ScanNetPPDevice::kIphone, copy.string());
  const Frame& f = phone.frames.at(0);
  write(f.mask_path, "");
  try {
    io::ReadFrameDepth(f);
    ADD_FAILURE() << "no error for an empty mask";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(f.mask_path), std::string::npos) << e.what();
  }
  // An unknown device.
  EXPECT_THROW(datasets::ParseScanNetPPDevice("kinect", "dataset.device"), InputError);
  // A frame id of the other device's shape is refused, naming both.
  datasets::CheckScanNetPPFrameId(datasets::ScanNetPPDevice::kDslr, "DSC00010", "--frames", "x");
  datasets::CheckScanNetPPFrameId(datasets::ScanNetPPDevice::kIphone, "frame_000010", "--frames",
                                  "x");
  try {
    datasets::CheckScanNetPPFrameId(datasets::ScanNetPPDevice::kDslr, "frame_000010", "--frames",
                                    "r.yaml: dataset.device");
    ADD_FAILURE() << "an iPhone id passed as a DSLR one";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--frames"), std::string::npos) << what;
    EXPECT_NE(what.find("'frame_000010' is an iPhone frame id, but r.yaml: dataset.device says dslr"),
              std::string::npos)
        << what;
  }
  EXPECT_THROW(datasets::CheckScanNetPPFrameId(datasets::ScanNetPPDevice::kIphone, "DSC00010",
                                               "--frames", "x"),
               InputError);
  fs::remove_all(copy);
}

TEST(IphoneDepthBin, BothEncodingsRoundTripAndDamageIsNamed) {
  std::vector<DepthImage> frames;
  for (int k = 0; k < 3; ++k) {
    DepthImage d(io::kIphoneDepthWidth, io::kIphoneDepthHeight);
    for (int v = 0; v < d.height; ++v) {
      for (int u = 0; u < d.width; ++u) {
        d.at(u, v) = (u + v) % 17 == 0 ? 0.0f : 0.5f + 0.001f * ((u * 7 + v * 3 + k * 11) % 4000);
      }
    }
    frames.push_back(d);
  }
  const fs::path dir = fs::temp_directory_path() / ("occgt_depthbin_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto write = [](const fs::path& p, const std::string& bytes) {
    std::ofstream(p, std::ios::binary) << bytes;
  };
  struct Case {
    const char* name;
    std::string bytes;
    DepthFormat format;
    double tol;
  };
  const std::vector<Case> cases = {
      {"deflate.bin", io::EncodeIphoneDepthBinDeflate(frames), DepthFormat::kIphoneBinDeflate, 0},
      {"lz4.bin", io::EncodeIphoneDepthBinRecords(frames, true), DepthFormat::kIphoneBinRecord,
       0.0005 + 1e-7},
      {"zrec.bin", io::EncodeIphoneDepthBinRecords(frames, false), DepthFormat::kIphoneBinRecord,
       0}};
  for (const Case& c : cases) {
    const fs::path p = dir / c.name;
    write(p, c.bytes);
    const io::IphoneDepthBin bin = io::ScanIphoneDepthBin(p.string());
    ASSERT_EQ(bin.format, c.format) << c.name;
    for (int k = 0; k < 3; ++k) {
      DepthSource src;
      src.path = p.string();
      src.format = bin.format;
      src.frame_index = k;
      src.width = io::kIphoneDepthWidth;
      src.height = io::kIphoneDepthHeight;
      if (bin.format == DepthFormat::kIphoneBinRecord) src.range = bin.records.at(k);
      const DepthImage d = io::ReadDepth(src, 256, 192);
      for (size_t i = 0; i < d.values_m.size(); ++i) {
        ASSERT_NEAR(d.values_m[i], frames[k].values_m[i], c.tol) << c.name << " frame " << k;
      }
    }
    // A frame past the end of the whole-file stream is named.
    if (c.format == DepthFormat::kIphoneBinDeflate) {
      DepthSource src;
      src.path = p.string();
      src.format = c.format;
      src.frame_index = 5;
      try {
        io::ReadDepth(src);
        ADD_FAILURE() << "no error";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("depth frame 5"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("holds 3 frames"), std::string::npos) << e.what();
      }
    }
  }
  // A damaged record (payload bytes flipped) is named, not decoded into garbage.
  std::string bad = io::EncodeIphoneDepthBinRecords(frames, false);
  for (size_t i = 10; i < 200; ++i) bad[i] = static_cast<char>(bad[i] ^ 0x5A);
  write(dir / "bad.bin", bad);
  const io::IphoneDepthBin bin = io::ScanIphoneDepthBin((dir / "bad.bin").string());
  ASSERT_EQ(bin.format, DepthFormat::kIphoneBinRecord);
  DepthSource src;
  src.path = (dir / "bad.bin").string();
  src.format = bin.format;
  src.frame_index = 0;
  src.range = bin.records.at(0);
  EXPECT_THROW(io::ReadDepth(src), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gt

// libgt/eval: the AUC, pose-error, epipolar-distance and per-type scoring functions on
// cases whose answers are known in closed form (GROUND_TRUTH.md §7; docs/EVAL.md). The
// whole protocol is also checked against a cv2 reference in tests/eval/cli_test.py.
#include "libgt/eval/pose.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "libgt/core/error.h"
#include "libgt/eval/evaluate.h"
#include "libgt/eval/match_quality.h"
#include "libgt/eval/protocol.h"
#include "tests/support/test_support.h"

namespace gt::eval {
namespace {

TEST(PoseAuc, TrapezoidByHand) {
  // errors 1, 3: points (0,0) (1,0.5) (3,1), then flat to the threshold.
  // At 2: area 0.25 + (2-1)*0.5 = 0.75 -> 0.375. At 4: 0.25 + 1.5 + 1 = 2.75 -> 0.6875.
  const std::vector<double> auc = PoseAuc({3, 1}, {2, 4});
  ASSERT_EQ(auc.size(), 2u);
  EXPECT_DOUBLE_EQ(auc[0], 0.375);
  EXPECT_DOUBLE_EQ(auc[1], 0.6875);
  // All zero errors -> 1; all failures -> 0; a failure halves the recall.
  EXPECT_DOUBLE_EQ(PoseAuc({0, 0, 0}, {5})[0], 1.0);
  EXPECT_DOUBLE_EQ(PoseAuc({kInfiniteError, kInfiniteError}, {5})[0], 0.0);
  EXPECT_DOUBLE_EQ(PoseAuc({0, kInfiniteError}, {5})[0], 0.5);
  EXPECT_DOUBLE_EQ(PoseAuc({}, {5})[0], 0.0);
  // An error equal to the threshold is not counted (LoFTR's searchsorted, side left).
  EXPECT_DOUBLE_EQ(PoseAuc({5}, {5})[0], 0.0);
}

Eigen::Matrix3d Rot(double deg, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

TEST(RelativePoseError, KnownAngles) {
  const Eigen::Matrix3d R_gt = Rot(20, {0, 1, 0});
  const Eigen::Vector3d t_gt(1, 0, 0);
  PoseError e = RelativePoseError(R_gt, t_gt, Rot(7, {1, 2, 3}) * R_gt, t_gt);
  EXPECT_NEAR(e.rotation_deg, 7, 1e-9);
  EXPECT_NEAR(e.translation_deg, 0, 1e-6);
  EXPECT_NEAR(e.max_deg, 7, 1e-9);
  // The sign of t is not observable: folded to 0; orthogonal: 90; 30 deg -> 30, 150 -> 30.
  EXPECT_NEAR(RelativePoseError(R_gt, t_gt, R_gt, -t_gt).translation_deg, 0, 1e-6);
  EXPECT_NEAR(RelativePoseError(R_gt, t_gt, R_gt, {0, 0, 2}).translation_deg, 90, 1e-9);
  EXPECT_NEAR(RelativePoseError(R_gt, t_gt, R_gt, Rot(30, {0, 0, 1}) * t_gt).translation_deg, 30,
              1e-9);
  EXPECT_NEAR(RelativePoseError(R_gt, t_gt, R_gt, Rot(150, {0, 0, 1}) * t_gt).translation_deg, 30,
              1e-9);
  // A pure rotation in the ground truth: only the rotation is scored.
  EXPECT_EQ(RelativePoseError(R_gt, Eigen::Vector3d::Zero(), R_gt, t_gt).translation_deg, 0);
  EXPECT_TRUE(std::isinf(NoPoseError().max_deg));
}

struct Scene {
  Eigen::Matrix3d K, R;
  Eigen::Vector3d t;
  std::vector<float> kpts0, kpts1;
};

// Random points in front of both cameras, projected exactly.
Scene MakeScene(int n, uint32_t seed) {
  Scene s;
  s.K << 500, 0, 319.5, 0, 520, 239.5, 0, 0, 1;
  s.R = Rot(10, {0.2, 1, 0.1});
  s.t = Eigen::Vector3d(-0.5, 0.05, 0.1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5), z(2, 6);
  while (static_cast<int>(s.kpts0.size() / 2) < n) {
    const Eigen::Vector3d p0(u(rng), u(rng), z(rng));
    const Eigen::Vector3d p1 = s.R * p0 + s.t;
    const Eigen::Vector3d x0 = s.K * p0 / p0.z(), x1 = s.K * p1 / p1.z();
    if (p1.z() <= 0.5 || x0.x() < 0 || x0.x() > 639 || x0.y() < 0 || x0.y() > 479 || x1.x() < 0 ||
        x1.x() > 639 || x1.y() < 0 || x1.y() > 479) {
      continue;
    }
    s.kpts0.insert(s.kpts0.end(), {static_cast<float>(x0.x()), static_cast<float>(x0.y())});
    s.kpts1.insert(s.kpts1.end(), {static_cast<float>(x1.x()), static_cast<float>(x1.y())});
  }
  return s;
}

TEST(EstimateRelativePose, ExactMatchesGiveTheTruePose) {
  const Scene s = MakeScene(300, 1);
  const auto pose = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, PoseEstimatorOptions{});
  ASSERT_TRUE(pose.has_value());
  const PoseError e = RelativePoseError(s.R, s.t, pose->cam1_from_cam0_R, pose->cam1_from_cam0_t);
  EXPECT_LT(e.max_deg, 0.05);
  EXPECT_GT(pose->inliers, 290);
  // Same input, same answer (OpenCV seeds its RANSAC per call).
  const auto again = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, PoseEstimatorOptions{});
  EXPECT_EQ(again->cam1_from_cam0_R, pose->cam1_from_cam0_R);
  // Fewer than 5 matches: no pose.
  const std::vector<float> four0(s.kpts0.begin(), s.kpts0.begin() + 8);
  const std::vector<float> four1(s.kpts1.begin(), s.kpts1.begin() + 8);
  EXPECT_FALSE(EstimateRelativePose(four0, four1, s.K, s.K, PoseEstimatorOptions{}).has_value());
  std::string error;
  PoseEstimatorOptions bad;
  bad.min_matches = 4;
  EXPECT_FALSE(bad.Check(&error));
  bad = PoseEstimatorOptions{};
  bad.confidence = 1;
  EXPECT_FALSE(bad.Check(&error));
}

// LoFTR's loop runs `cv2.recoverPose(_E, kpts0, kpts1, np.eye(3), 1e9, mask=mask)` in
// Python. OpenCV's binding gives that call the overload without distanceThresh (the 1e9
// lands in its R output), so the default distance of 50 applies: a point triangulated
// farther than 50 baselines is no inlier. EstimateRelativePose follows the call as it runs.
// Points up to 120 baselines away tell the two apart; LoFTR's Python loop (cv2, the same
// OpenCV) is the reference, and C++'s cv::recoverPose shows that 1e9 would count more.
TEST(EstimateRelativePose, SameAsLoftrsPythonCallOnFarPoints) {
  Scene s;
  s.K << 500, 0, 319.5, 0, 520, 239.5, 0, 0, 1;
  s.R = Rot(2, {0.1, 1, 0});
  s.t = Eigen::Vector3d(0.05, 0.01, 0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1), z(1, 6);
  while (s.kpts0.size() < 2 * 200) {
    const Eigen::Vector3d p0(u(rng), 0.7 * u(rng), z(rng));
    const Eigen::Vector3d p1 = s.R * p0 + s.t;
    const Eigen::Vector3d x0 = s.K * p0 / p0.z(), x1 = s.K * p1 / p1.z();
    if (x0.x() < 0 || x0.x() > 639 || x0.y() < 0 || x0.y() > 479 || x1.x() < 0 || x1.x() > 639 ||
        x1.y() < 0 || x1.y() > 479) {
      continue;
    }
    s.kpts0.insert(s.kpts0.end(), {static_cast<float>(x0.x()), static_cast<float>(x0.y())});
    s.kpts1.insert(s.kpts1.end(), {static_cast<float>(x1.x()), static_cast<float>(x1.y())});
  }
  const auto pose = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, PoseEstimatorOptions{});
  ASSERT_TRUE(pose.has_value());

  const std::string dir = test::ScratchDir("pose_loftr_call");
  {
    std::ofstream f(dir + "/kpts.txt");
    f.precision(9);  // float32 round trip
    for (size_t k = 0; k < s.kpts0.size(); k += 2) {
      f << s.kpts0[k] << " " << s.kpts0[k + 1] << " " << s.kpts1[k] << " " << s.kpts1[k + 1]
        << "\n";
    }
  }
  // LoFTR's estimate_pose (src/utils/metrics.py) at its defaults: thresh 0.5 px, conf
  // 0.99999, K0 = K1 = K; prints the winning block's count, R and t.
  const auto r = test::RunShell(
      "/usr/bin/python3 -c \"\n"
      "import sys, numpy as np, cv2\n"
      "a = np.loadtxt(sys.argv[1], dtype=np.float32).astype(np.float64)\n"
      "K = np.array([[500, 0, 319.5], [0, 520, 239.5], [0, 0, 1]], np.float64)\n"
      "k0 = (a[:, 0:2] - K[[0, 1], [2, 2]]) / K[[0, 1], [0, 1]]\n"
      "k1 = (a[:, 2:4] - K[[0, 1], [2, 2]]) / K[[0, 1], [0, 1]]\n"
      "thr = 0.5 / np.mean([K[0, 0], K[1, 1], K[0, 0], K[1, 1]])\n"
      "E, mask = cv2.findEssentialMat(k0, k1, np.eye(3), threshold=thr, prob=0.99999, "
      "method=cv2.RANSAC)\n"
      "best = None\n"
      "for _E in np.split(E, len(E) / 3):\n"
      "    n, R, t, _ = cv2.recoverPose(_E, k0, k1, np.eye(3), 1e9, mask=mask)\n"
      "    if best is None or n > best[0]: best = (n, R, t)\n"
      "print(best[0], *map(repr, best[1].ravel()), *map(repr, best[2].ravel()))\n"
      "\" '" +
      dir + "/kpts.txt'");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  std::istringstream in(r.stdout_text);
  int inliers = 0;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  in >> inliers;
  for (int k = 0; k < 9; ++k) in >> R(k / 3, k % 3);
  for (int k = 0; k < 3; ++k) in >> t(k);
  ASSERT_TRUE(in) << r.stdout_text;
  EXPECT_EQ(pose->inliers, inliers);
  EXPECT_EQ(pose->cam1_from_cam0_R, R);
  EXPECT_EQ(pose->cam1_from_cam0_t, t);

  // The same E and mask with distanceThresh 1e9 (what the Python line seems to ask for):
  // more inliers, so this scene tells the two apart.
  const int n = static_cast<int>(s.kpts0.size() / 2);
  cv::Mat p0(n, 2, CV_64F), p1(n, 2, CV_64F);
  for (int i = 0; i < n; ++i) {
    p0.at<double>(i, 0) = (static_cast<double>(s.kpts0[2 * i]) - 319.5) / 500;
    p0.at<double>(i, 1) = (static_cast<double>(s.kpts0[2 * i + 1]) - 239.5) / 520;
    p1.at<double>(i, 0) = (static_cast<double>(s.kpts1[2 * i]) - 319.5) / 500;
    p1.at<double>(i, 1) = (static_cast<double>(s.kpts1[2 * i + 1]) - 239.5) / 520;
  }
  cv::Mat mask;
  const double thr = 0.5 / ((500.0 + 520.0 + 500.0 + 520.0) / 4);
  const cv::Mat E = cv::findEssentialMat(p0, p1, cv::Mat::eye(3, 3, CV_64F), cv::RANSAC, 0.99999,
                                         thr, 1000, mask);
  int most_far = 0;
  for (int k = 0; k < E.rows / 3; ++k) {
    cv::Mat m = mask.clone(), Rk, tk;
    most_far = std::max(most_far, cv::recoverPose(E.rowRange(3 * k, 3 * k + 3).clone(), p0, p1,
                                                  cv::Mat::eye(3, 3, CV_64F), Rk, tk, 1e9, m));
  }
  EXPECT_GT(most_far, inliers + 20);
}

const PoseMethod kAllMethods[] = {PoseMethod::kRansac,      PoseMethod::kLmeds,
                                  PoseMethod::kUsacDefault, PoseMethod::kUsacAccurate,
                                  PoseMethod::kUsacMagsac,  PoseMethod::kUsacProsac};

// Confidences for PROSAC: any order works on exact matches.
std::vector<float> Confidences(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> c(n);
  for (float& x : c) x = u(rng);
  return c;
}

TEST(EstimateRelativePose, EveryMethodRecoversTheExactPose) {
  const Scene s = MakeScene(300, 5);
  const std::vector<float> conf = Confidences(s.kpts0.size() / 2, 9);
  for (const PoseMethod m : kAllMethods) {
    for (const FocalMean f : {FocalMean::kLoftr, FocalMean::kAll}) {
      SCOPED_TRACE(std::string(PoseMethodName(m)) + " focal " + FocalMeanName(f));
      PoseEstimatorOptions o;
      o.method = m;
      o.focal_mean = f;
      const auto pose = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, o, &conf, 7);
      ASSERT_TRUE(pose.has_value());
      const PoseError e =
          RelativePoseError(s.R, s.t, pose->cam1_from_cam0_R, pose->cam1_from_cam0_t);
      EXPECT_LT(e.max_deg, 0.05);
      EXPECT_GT(pose->inliers, 290);
    }
  }
}

// Matches of a random scene in pixels (K of MakeScene): Gaussian noise `noise_px` in
// image 1, the first `outliers` share replaced by uniform points; confidences lower for
// outliers (uniform 0..0.6) than for inliers (0.3..1), as a matcher's would be.
struct NoisyScene {
  Scene scene;
  std::vector<float> confidence;
};
NoisyScene MakeNoisyScene(std::mt19937* rng, int n, double noise_px, double outliers) {
  std::uniform_real_distribution<double> angle(5, 20), axis(-1, 1);
  NoisyScene out;
  Scene fresh;
  fresh.K << 500, 0, 319.5, 0, 520, 239.5, 0, 0, 1;
  fresh.R = Rot(angle(*rng), {axis(*rng), axis(*rng), axis(*rng)});
  fresh.t = Eigen::Vector3d(axis(*rng), axis(*rng), axis(*rng)).normalized() * 0.8;
  std::uniform_real_distribution<double> u(-2, 2), z(3, 8), x(0, 639), y(0, 479);
  std::normal_distribution<double> g(0, noise_px);
  std::uniform_real_distribution<float> c_out(0, 0.6f), c_in(0.3f, 1);
  const int n_out = static_cast<int>(outliers * n);
  while (static_cast<int>(fresh.kpts0.size() / 2) < n) {
    const Eigen::Vector3d p0(u(*rng), u(*rng), z(*rng));
    const Eigen::Vector3d p1 = fresh.R * p0 + fresh.t;
    if (p1.z() <= 0.5) continue;
    const Eigen::Vector3d x0 = fresh.K * p0 / p0.z(), x1 = fresh.K * p1 / p1.z();
    const bool out_i = static_cast<int>(fresh.kpts0.size() / 2) < n_out;
    fresh.kpts0.insert(fresh.kpts0.end(), {static_cast<float>(x0.x()), static_cast<float>(x0.y())});
    if (out_i) {
      fresh.kpts1.insert(fresh.kpts1.end(),
                         {static_cast<float>(x(*rng)), static_cast<float>(y(*rng))});
      out.confidence.push_back(c_out(*rng));
    } else {
      fresh.kpts1.insert(fresh.kpts1.end(), {static_cast<float>(x1.x() + g(*rng)),
                                             static_cast<float>(x1.y() + g(*rng))});
      out.confidence.push_back(c_in(*rng));
    }
  }
  out.scene = fresh;
  return out;
}

double MedianOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
}

// The property behind "robust estimators": on noisy matches with outliers (1 px noise,
// 30 % outliers, 1 px threshold, fixed seed, 40 scenes) every USAC method's mean and
// median pose error are below plain RANSAC's. (LMEDS is not among them: it has no
// threshold and its least-median fit of noisy inliers is no better than RANSAC's here.)
TEST(EstimateRelativePose, RobustMethodsBeatPlainRansacOnNoisyMatches) {
  std::mt19937 rng(2024);
  std::map<PoseMethod, std::vector<double>> errors;
  for (int trial = 0; trial < 40; ++trial) {
    const NoisyScene ns = MakeNoisyScene(&rng, 500, 1.0, 0.3);
    for (const PoseMethod m : kAllMethods) {
      PoseEstimatorOptions o;
      o.method = m;
      o.ransac_px = 1.0;
      const auto pose = EstimateRelativePose(ns.scene.kpts0, ns.scene.kpts1, ns.scene.K, ns.scene.K,
                                             o, &ns.confidence, PairRngSeed("trial", trial));
      errors[m].push_back(pose ? RelativePoseError(ns.scene.R, ns.scene.t, pose->cam1_from_cam0_R,
                                                   pose->cam1_from_cam0_t)
                                     .max_deg
                               : 180.0);
    }
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (const double x : v) s += x;
    return s / static_cast<double>(v.size());
  };
  const double ransac_mean = mean(errors[PoseMethod::kRansac]);
  const double ransac_median = MedianOf(errors[PoseMethod::kRansac]);
  EXPECT_GT(ransac_median, 0.3);  // the case is hard enough to separate the methods
  for (const PoseMethod m : {PoseMethod::kUsacDefault, PoseMethod::kUsacAccurate,
                             PoseMethod::kUsacMagsac, PoseMethod::kUsacProsac}) {
    SCOPED_TRACE(PoseMethodName(m));
    EXPECT_LT(mean(errors[m]), ransac_mean);
    EXPECT_LT(MedianOf(errors[m]), ransac_median);
  }
}

// Determinism: the answer depends on the inputs only, not on cv::theRNG()'s state before
// the call nor on the thread; every method.
TEST(EstimateRelativePose, SameAnswerWhateverTheRngStateAndThread) {
  std::mt19937 rng(11);
  const NoisyScene ns = MakeNoisyScene(&rng, 400, 0.8, 0.25);
  const Scene& s = ns.scene;
  for (const PoseMethod m : kAllMethods) {
    SCOPED_TRACE(PoseMethodName(m));
    PoseEstimatorOptions o;
    o.method = m;
    const auto first = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, o, &ns.confidence, 5);
    ASSERT_TRUE(first.has_value());
    // Another state of the caller's generator, and OpenCV's own seeds: same bits.
    cv::theRNG().state = 0x1234567;
    for (const uint64_t seed : {uint64_t{5}, uint64_t{99}, PairRngSeed("a/b", 3)}) {
      const auto again = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, o, &ns.confidence, seed);
      ASSERT_TRUE(again.has_value());
      EXPECT_EQ(again->cam1_from_cam0_R, first->cam1_from_cam0_R);
      EXPECT_EQ(again->cam1_from_cam0_t, first->cam1_from_cam0_t);
      EXPECT_EQ(again->inliers, first->inliers);
    }
    // Four threads at once.
    std::vector<std::optional<PoseEstimate>> got(4);
    std::vector<std::thread> threads;
    for (size_t k = 0; k < got.size(); ++k) {
      threads.emplace_back([&, k] {
        got[k] = EstimateRelativePose(s.kpts0, s.kpts1, s.K, s.K, o, &ns.confidence, 5);
      });
    }
    for (std::thread& t : threads) t.join();
    for (const auto& g : got) {
      ASSERT_TRUE(g.has_value());
      EXPECT_EQ(g->cam1_from_cam0_R, first->cam1_from_cam0_R);
      EXPECT_EQ(g->inliers, first->inliers);
    }
  }
}

TEST(PairRngSeed, FnvOfKeyAndIndex) {
  // FNV-1a 64 by hand for key "" and index 0: eight zero bytes, each h = (h ^ 0) * prime.
  uint64_t h = 14695981039346656037ull;
  for (int i = 0; i < 8; ++i) h *= 1099511628211ull;
  EXPECT_EQ(PairRngSeed("", 0), h);
  // "a" then index 1: 'a' = 0x61, then 0x01 and seven zeros.
  uint64_t a = 14695981039346656037ull;
  a = (a ^ 0x61) * 1099511628211ull;
  a = (a ^ 0x01) * 1099511628211ull;
  for (int i = 0; i < 7; ++i) a *= 1099511628211ull;
  EXPECT_EQ(PairRngSeed("a", 1), a);
  EXPECT_NE(PairRngSeed("scene/1_2", 0), PairRngSeed("scene/1_2", 1));
}

TEST(PoseEstimatorOptions, ChecksAndNames) {
  std::string error;
  PoseEstimatorOptions o;
  EXPECT_TRUE(o.Check(&error));
  EXPECT_EQ(PoseEstimatorName(o), "opencv-ransac 0.5 px conf 0.99999");
  o.method = PoseMethod::kUsacMagsac;
  o.max_iters = 5000;
  o.focal_mean = FocalMean::kAll;
  EXPECT_EQ(PoseEstimatorName(o), "opencv-usac_magsac 0.5 px conf 0.99999 iters 5000 focal all");
  o.max_iters = 0;
  EXPECT_FALSE(o.Check(&error));
  EXPECT_EQ(error.substr(0, 9), "max_iters");
  for (const PoseMethod m : kAllMethods) EXPECT_EQ(ParsePoseMethod(PoseMethodName(m), "f"), m);
  EXPECT_THROW(ParsePoseMethod("magsac", "--estimator"), InputError);
}

// Protocols expand to the settings docs/EVAL.md's table states.
TEST(Protocol, ExpandsAsDocumented) {
  const Protocol loftr = ExpandProtocol(ProtocolName::kLoftr);
  ASSERT_EQ(loftr.estimators.size(), 1u);
  EXPECT_EQ(PoseEstimatorName(loftr.estimators[0]), PoseEstimatorName(PoseEstimatorOptions{}));
  EXPECT_EQ(loftr.selection, Selection::kEvery);
  const Protocol sg = ExpandProtocol(ProtocolName::kSuperglue);
  ASSERT_EQ(sg.estimators.size(), 1u);
  EXPECT_EQ(PoseEstimatorName(sg.estimators[0]), "opencv-ransac 1 px conf 0.99999");
  const Protocol gf = ExpandProtocol(ProtocolName::kGluefactory);
  ASSERT_EQ(gf.estimators.size(), 8u);
  EXPECT_EQ(gf.selection, Selection::kBestOfSweep);
  const std::vector<double> sweep{0.5, 1.5, 2.0, 3.0};
  EXPECT_EQ(GluefactorySweepPx(), sweep);
  for (size_t i = 0; i < 8; ++i) {
    const PoseEstimatorOptions& e = gf.estimators[i];
    EXPECT_EQ(e.ransac_px, sweep[i % 4]);
    EXPECT_EQ(e.focal_mean, FocalMean::kAll);
    if (i < 4) {
      const char* px[] = {"0.5", "1.5", "2", "3"};
      EXPECT_EQ(PoseEstimatorName(e), std::string("opencv-usac_default ") + px[i] +
                                          " px conf 0.9999 iters 100000 focal all");
    } else {
      EXPECT_EQ(e.method, PoseMethod::kRansac);
      EXPECT_EQ(e.confidence, 0.99999);
      EXPECT_EQ(e.max_iters, 1000);
    }
  }
  const Protocol lo = ExpandProtocol(ProtocolName::kEloftrLo);
  ASSERT_EQ(lo.estimators.size(), 1u);
  EXPECT_EQ(lo.estimators[0].method, PoseMethod::kUsacDefault);
  EXPECT_EQ(lo.estimators[0].ransac_px, 2.0);
  EXPECT_EQ(lo.failure_error_deg, 90);
  EXPECT_EQ(ExpandProtocol(ProtocolName::kEloftr).estimators[0].ransac_px, 0.5);
  for (const char* name : {"loftr", "superglue", "gluefactory", "eloftr", "eloftr-lo"}) {
    EXPECT_EQ(ProtocolNameText(ParseProtocolName(name, "--protocol")), std::string(name));
    EXPECT_FALSE(ExpandProtocol(ParseProtocolName(name, "--protocol")).sources.empty());
  }
  EXPECT_THROW(ParseProtocolName("custom", "--protocol"), InputError);
}

// Best-of-sweep on hand-made errors: the threshold with the best mean AUC per group (ties:
// the first), then the best group (ties: the last), as glue-factory's code picks them.
TEST(SelectBestOfSweep, FirstThresholdLastGroupOnTies) {
  EvalResult r;
  r.options.auc_thresholds_deg = {10};
  r.options.estimators.clear();
  PoseEstimatorOptions a, b;
  b.method = PoseMethod::kUsacMagsac;
  for (const double px : {0.5, 1.0, 2.0}) {
    a.ransac_px = px;
    r.options.estimators.push_back(a);
  }
  for (const double px : {0.5, 1.0}) {
    b.ransac_px = px;
    r.options.estimators.push_back(b);
  }
  // Per estimator the same error e on two pairs: the curve (0, 0), (e, 1/2), (e, 1), then
  // flat, so AUC@10 = (e / 4 + 10 - e) / 10 = 1 - 0.075 e.
  const std::vector<double> error = {4, 2, 2, 3, 2};
  for (int i = 0; i < 2; ++i) {
    PairInfo p;
    p.sets.resize(1);
    for (const double e : error) p.sets[0].pose.push_back({e, 0, e});
    r.pairs.push_back(p);
  }
  const SweepSelection sel = SelectBestOfSweep(r, 0);
  ASSERT_EQ(sel.groups.size(), 2u);
  EXPECT_EQ(sel.groups[0], (std::vector<size_t>{0, 1, 2}));
  EXPECT_EQ(sel.groups[1], (std::vector<size_t>{3, 4}));
  EXPECT_EQ(sel.group_best, (std::vector<size_t>{1, 4}));  // 1.0 px before 2.0 px
  EXPECT_EQ(sel.best, 4u);                                 // equal mean AUC: the last group
  EXPECT_NEAR(sel.mean_auc_percent[0], 70, 1e-9);
  EXPECT_NEAR(sel.mean_auc_percent[1], 85, 1e-9);
  // A strictly better first group wins.
  for (auto& p : r.pairs) p.sets[0].pose[0] = {1, 0, 1};
  EXPECT_EQ(SelectBestOfSweep(r, 0).best, 0u);
}

// RecoverPose is cv::recoverPose(E, p0, p1, I, R, t, distanceThresh, mask) computed
// differently, here at LoFTR's 50 (kLoftrRecoverPoseDistance) and at 1e9; the
// slow reference here is OpenCV itself. Every case runs LoFTR's loop on both sides: each
// block of findEssentialMat's E in turn, the mask narrowed from block to block; counts,
// narrowed masks, R and t must be equal, bit for bit.
struct Correspondences {
  std::vector<double> p0, p1;  // normalised, row-major [N, 2]
};

// Points at depths [z_min, z_max] seen by cameras `baseline` apart; a fraction `outliers`
// of random pairs; Gaussian noise (normalised units) on the second image's points.
Correspondences MakeCorrespondences(std::mt19937* rng, int n, double baseline, double z_min,
                                    double z_max, double noise, double outliers,
                                    const Eigen::Matrix3d& R, const Eigen::Vector3d& t_dir) {
  std::uniform_real_distribution<double> u(-0.6, 0.6), z(z_min, z_max), unit(0, 1);
  std::normal_distribution<double> g(0, noise);
  Correspondences c;
  while (static_cast<int>(c.p0.size() / 2) < n) {
    if (unit(*rng) < outliers) {
      c.p0.insert(c.p0.end(), {u(*rng), u(*rng)});
      c.p1.insert(c.p1.end(), {u(*rng), u(*rng)});
      continue;
    }
    const double depth = z(*rng);
    const Eigen::Vector3d p(u(*rng) * depth, u(*rng) * depth, depth);
    const Eigen::Vector3d q = R * p + baseline * t_dir.normalized();
    if (q.z() <= 1e-3) continue;
    c.p0.insert(c.p0.end(), {p.x() / p.z(), p.y() / p.z()});
    c.p1.insert(c.p1.end(), {q.x() / q.z() + g(*rng), q.y() / q.z() + g(*rng)});
  }
  return c;
}

// Runs both on every block of E with the mask carried along; returns the number of
// triangulated points compared.
int64_t ExpectSameAsOpenCV(const Correspondences& c, const cv::Mat& E, const cv::Mat& mask_in,
                           const std::string& what) {
  const int n = static_cast<int>(c.p0.size() / 2);
  cv::Mat p0(n, 2, CV_64F, const_cast<double*>(c.p0.data()));
  cv::Mat p1(n, 2, CV_64F, const_cast<double*>(c.p1.data()));
  int64_t compared = 0;
  for (const double distance : {kLoftrRecoverPoseDistance, 1e9}) {
    cv::Mat mask_cv = mask_in.clone();
    std::vector<uint8_t> mask(mask_cv.data, mask_cv.data + mask_cv.total());
    for (int k = 0; k < E.rows / 3; ++k) {
      SCOPED_TRACE(what + ", block " + std::to_string(k) + ", distance " +
                   std::to_string(distance));
      cv::Mat R_cv, t_cv;
      const int expected =
          cv::recoverPose(E.rowRange(3 * k, 3 * k + 3).clone(), p0, p1, cv::Mat::eye(3, 3, CV_64F),
                          R_cv, t_cv, distance, mask_cv);
      Eigen::Matrix3d block;
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col) block(r, col) = E.at<double>(3 * k + r, col);
      }
      const RecoveredPose got = RecoverPose(block, c.p0, c.p1, distance, &mask);
      EXPECT_EQ(got.inliers, expected);
      if (mask.size() != mask_cv.total()) {
        ADD_FAILURE() << "mask size " << mask.size() << ", OpenCV's " << mask_cv.total();
        return compared;
      }
      EXPECT_TRUE(std::equal(mask.begin(), mask.end(), mask_cv.data));
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col)
          EXPECT_EQ(got.cam1_from_cam0_R(r, col), R_cv.at<double>(r, col));
        EXPECT_EQ(got.cam1_from_cam0_t(r), t_cv.at<double>(r, 0));
      }
      compared += n;
    }
  }
  return compared;
}

TEST(RecoverPose, SameAsOpenCVOnRansacOutput) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(0, 30), axis(-1, 1), unit(0, 1);
  int64_t compared = 0;
  int multi_block = 0;
  for (int scene = 0; scene < 40; ++scene) {
    // Baselines from 1 mm (many points near infinity, depths of either sign) to 1 m;
    // noise up to ~2 px at f = 500; up to half outliers.
    const double baseline = std::pow(10.0, -3 + 3 * unit(rng));
    const Eigen::Matrix3d R = Rot(angle(rng), {axis(rng), axis(rng), axis(rng)});
    const Eigen::Vector3d t_dir(axis(rng), axis(rng), axis(rng));
    // Every fifth scene has 5 points: OpenCV then returns every five-point solution, the
    // case of several blocks.
    const int points = scene % 5 == 4 ? 5 : 300 + scene * 15;
    const Correspondences c = MakeCorrespondences(&rng, points, baseline, 0.5, 20, 4e-3 * unit(rng),
                                                  0.5 * unit(rng), R, t_dir);
    const int n = static_cast<int>(c.p0.size() / 2);
    cv::Mat mask;
    const cv::Mat E =
        cv::findEssentialMat(cv::Mat(n, 2, CV_64F, const_cast<double*>(c.p0.data())),
                             cv::Mat(n, 2, CV_64F, const_cast<double*>(c.p1.data())),
                             cv::Mat::eye(3, 3, CV_64F), cv::RANSAC, 0.999, 1e-3, mask);
    if (E.empty()) continue;
    multi_block += E.rows > 3;
    compared += ExpectSameAsOpenCV(c, E, mask, "scene " + std::to_string(scene));
    // No mask: every point, and the mask comes back 0/255 as OpenCV's.
    compared += ExpectSameAsOpenCV(c, E.rowRange(0, 3), cv::Mat(),
                                   "scene " + std::to_string(scene) + " without mask");
  }
  EXPECT_GT(compared, 20000);
  EXPECT_GT(multi_block, 0) << "no case exercised a second block";
}

TEST(RecoverPose, SameAsOpenCVOnWrongEssentialMatrices) {
  // A random E: the four candidates share the points far more evenly than for a good E,
  // and ties are likely on few points.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(0, 180), axis(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Correspondences c = MakeCorrespondences(&rng, trial % 2 == 0 ? 6 : 300, 0.2, 1, 5, 1e-3,
                                                  0.2, Rot(5, {0, 1, 0}), {1, 0, 0});
    const Eigen::Matrix3d R = Rot(angle(rng), {axis(rng), axis(rng), axis(rng)});
    const Eigen::Vector3d t(axis(rng), axis(rng), axis(rng));
    Eigen::Matrix3d tx;
    tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
    const Eigen::Matrix3d E = tx * R;
    cv::Mat E_cv(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) E_cv.at<double>(r, col) = E(r, col);
    }
    cv::Mat mask(static_cast<int>(c.p0.size() / 2), 1, CV_8U);
    for (int i = 0; i < mask.rows; ++i) mask.at<uint8_t>(i) = (i * 7 + trial) % 3 != 0;
    ExpectSameAsOpenCV(c, E_cv, mask, "trial " + std::to_string(trial));
  }
  // An all-zero mask: every count 0, OpenCV returns (R1, t).
  const Correspondences c =
      MakeCorrespondences(&rng, 20, 0.2, 1, 5, 0, 0, Rot(5, {0, 1, 0}), {1, 0, 0});
  ExpectSameAsOpenCV(c, (cv::Mat_<double>(3, 3) << 0, -1, 0, 1, 0, 0, 0, 0, 0),
                     cv::Mat::zeros(20, 1, CV_8U), "empty mask");
}

// FindEssentialRansac against cv::findEssentialMat(RANSAC) itself, setting by setting:
// equal E and mask, bit for bit, on point counts from 5 (OpenCV's every-solution case) to
// 2000, noise from none to ~2 px, up to 90 % outliers (iteration caps reached), a threshold
// so small that only each sample's own five points count, low confidences and tiny caps
// (early stops at different iterations per setting, the multi-setting loop's hard part).
// (No E at all needs a sample-free case: fewer than five points, EstimateRelativePose's
// tests.)
TEST(FindEssentialRansac, SameAsOpenCVForEverySetting) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> angle(0, 30), axis(-1, 1), unit(0, 1);
  const std::vector<RansacSetting> settings = {
      {0.5 / 500, 0.99999, 1000}, {1.5 / 500, 0.99999, 1000}, {2.0 / 500, 0.99999, 1000},
      {3.0 / 500, 0.99999, 1000}, {1.0 / 500, 0.999, 1000},   {0.5 / 500, 0.5, 1000},
      {2.0 / 500, 0.99999, 40},   {1e-7, 0.99999, 200},       {1.0 / 500, 0.9, 1},
      {4.0 / 500, 0.99, 3}};
  const int counts[] = {5, 6, 7, 9, 30, 300, 2000};
  int with_e = 0, multi_block = 0;
  for (int scene = 0; scene < 21; ++scene) {
    const int points = counts[scene % 7];
    const double outliers = scene % 4 == 3 ? 0.9 : 0.5 * unit(rng);
    const Correspondences c = MakeCorrespondences(
        &rng, points, std::pow(10.0, -2 + 2 * unit(rng)), 0.5, 20, 4e-3 * unit(rng), outliers,
        Rot(angle(rng), {axis(rng), axis(rng), axis(rng)}), {axis(rng), axis(rng), axis(rng)});
    const int n = static_cast<int>(c.p0.size() / 2);
    const std::vector<EssentialEstimate> got = FindEssentialRansac(c.p0, c.p1, settings);
    ASSERT_EQ(got.size(), settings.size());
    for (size_t s = 0; s < settings.size(); ++s) {
      SCOPED_TRACE("scene " + std::to_string(scene) + " (" + std::to_string(n) +
                   " points), setting " + std::to_string(s));
      cv::Mat mask;
      const cv::Mat E = cv::findEssentialMat(
          cv::Mat(n, 2, CV_64F, const_cast<double*>(c.p0.data())),
          cv::Mat(n, 2, CV_64F, const_cast<double*>(c.p1.data())), cv::Mat::eye(3, 3, CV_64F),
          cv::RANSAC, settings[s].confidence, settings[s].threshold, settings[s].max_iters, mask);
      if (E.empty()) {
        EXPECT_TRUE(got[s].E.empty());
        continue;
      }
      ++with_e;
      multi_block += E.rows > 3;
      ASSERT_EQ(got[s].E.size(), E.total());
      EXPECT_TRUE(std::equal(got[s].E.begin(), got[s].E.end(), E.ptr<double>()));
      ASSERT_EQ(got[s].mask.size(), mask.total());
      for (int i = 0; i < n; ++i) EXPECT_EQ(got[s].mask[i] != 0, mask.data[i] != 0) << i;
    }
  }
  EXPECT_GT(with_e, 150);
  EXPECT_GT(multi_block, 0);
}

// EstimateRelativePoses on a list of mixed estimators (gluefactory's 8, LoFTR's, LMEDS,
// PROSAC) against OpenCV alone: cv::findEssentialMat per estimator and cv::recoverPose on
// each block, the mask carried along (LoFTR's loop).
TEST(EstimateRelativePoses, SameAsOpenCVPerEstimator) {
  std::vector<PoseEstimatorOptions> estimators =
      ExpandProtocol(ProtocolName::kGluefactory).estimators;
  estimators.push_back(PoseEstimatorOptions{});
  PoseEstimatorOptions o;
  o.method = PoseMethod::kLmeds;
  estimators.push_back(o);
  o.method = PoseMethod::kUsacProsac;
  estimators.push_back(o);
  o = PoseEstimatorOptions{};
  o.max_iters = 7;
  o.ransac_px = 1.0;
  estimators.push_back(o);
  std::mt19937 rng(5);
  int compared = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const NoisyScene ns =
        MakeNoisyScene(&rng, trial == 0 ? 5 : 300 + 200 * trial, 0.6, 0.2 * (trial % 3));
    const Scene& s = ns.scene;
    std::vector<uint64_t> seeds;
    for (size_t e = 0; e < estimators.size(); ++e) seeds.push_back(PairRngSeed("t", e));
    const auto got =
        EstimateRelativePoses(s.kpts0, s.kpts1, s.K, s.K, estimators, &ns.confidence, seeds);
    ASSERT_EQ(got.size(), estimators.size());
    const int n = static_cast<int>(s.kpts0.size() / 2);
    for (size_t e = 0; e < estimators.size(); ++e) {
      SCOPED_TRACE("trial " + std::to_string(trial) + ", " + PoseEstimatorName(estimators[e]));
      const PoseEstimatorOptions& est = estimators[e];
      std::vector<int> order(n);
      std::iota(order.begin(), order.end(), 0);
      if (est.method == PoseMethod::kUsacProsac) {
        std::stable_sort(order.begin(), order.end(),
                         [&](int a, int b) { return ns.confidence[a] > ns.confidence[b]; });
      }
      cv::Mat p0(n, 2, CV_64F), p1(n, 2, CV_64F);
      for (int i = 0; i < n; ++i) {
        const int j = order[i];
        p0.at<double>(i, 0) = (static_cast<double>(s.kpts0[2 * j]) - s.K(0, 2)) / s.K(0, 0);
        p0.at<double>(i, 1) = (static_cast<double>(s.kpts0[2 * j + 1]) - s.K(1, 2)) / s.K(1, 1);
        p1.at<double>(i, 0) = (static_cast<double>(s.kpts1[2 * j]) - s.K(0, 2)) / s.K(0, 0);
        p1.at<double>(i, 1) = (static_cast<double>(s.kpts1[2 * j + 1]) - s.K(1, 2)) / s.K(1, 1);
      }
      // K0 = K1: both focal means are this one.
      const double focal = (s.K(0, 0) + s.K(1, 1) + s.K(0, 0) + s.K(1, 1)) / 4.0;
      cv::theRNG().state = seeds[e];
      cv::Mat mask;
      const cv::Mat E =
          cv::findEssentialMat(p0, p1, cv::Mat::eye(3, 3, CV_64F), PoseMethodOpenCVFlag(est.method),
                               est.confidence, est.ransac_px / focal, est.max_iters, mask);
      int best = 0;
      cv::Mat best_R, best_t;
      for (int k = 0; !E.empty() && k < E.rows / 3; ++k) {
        cv::Mat R, t;
        const int inliers =
            cv::recoverPose(E.rowRange(3 * k, 3 * k + 3).clone(), p0, p1,
                            cv::Mat::eye(3, 3, CV_64F), R, t, kLoftrRecoverPoseDistance, mask);
        if (inliers > best) {
          best = inliers;
          best_R = R;
          best_t = t;
        }
      }
      if (best == 0) {
        EXPECT_FALSE(got[e].has_value());
        continue;
      }
      ASSERT_TRUE(got[e].has_value());
      EXPECT_EQ(got[e]->inliers, best);
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col)
          EXPECT_EQ(got[e]->cam1_from_cam0_R(r, col), best_R.at<double>(r, col));
        EXPECT_EQ(got[e]->cam1_from_cam0_t(r), best_t.at<double>(r, 0));
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, 50);
}

TEST(SymmetricEpipolarDistances, ZeroOnExactMatchesKnownOffEpipolar) {
  const Scene s = MakeScene(50, 2);
  for (const double d : SymmetricEpipolarDistances(s.kpts0, s.kpts1, s.K, s.K, s.R, s.t)) {
    EXPECT_LT(d, 1e-9);
  }
  // R = I, t = x: epipolar lines are rows; a point moved by dy pixels in image 1 with
  // fx = fy = f has distance (dy/f)^2 * 2 (same line length in both images).
  Eigen::Matrix3d K;
  K << 400, 0, 320, 0, 400, 240, 0, 0, 1;
  const std::vector<double> d = SymmetricEpipolarDistances(
      {100, 200}, {150, 204}, K, K, Eigen::Matrix3d::Identity(), Eigen::Vector3d(1, 0, 0));
  EXPECT_NEAR(d[0], 2 * std::pow(4.0 / 400.0, 2), 1e-12);
}

// Both cameras look at the plane z = 2 m (depth 2 everywhere, 64 x 48, f = 200); camera 1
// moved by 0.2 m along x: a point moves by -f * 0.2 / 2 = -20 px in x.
PairTruthView PlaneTruth(const std::vector<uint8_t>& l01, const std::vector<uint8_t>& l10,
                         const std::vector<float>& depth) {
  PairTruthView t;
  t.width = 64;
  t.height = 48;
  t.patch_stride = 8;
  t.label01 = l01.data();
  t.label10 = l10.data();
  t.depth0 = depth.data();
  t.depth1 = depth.data();
  t.K0 << 200, 0, 31.5, 0, 200, 23.5, 0, 0, 1;
  t.K1 = t.K0;
  t.cam1_from_cam0_R.setIdentity();
  t.cam1_from_cam0_t = Eigen::Vector3d(-0.2, 0, 0);
  return t;
}

TEST(ScoreMatches, FrontoParallelPlane) {
  // Both cameras look at a plane z = 2 m; camera 1 moved by 0.2 m along x: a point moves by
  // -f * 0.2 / 2 = -20 px in x. Right half of image 0: label VISIBLE; left: OCCLUDED.
  const int w = 64, h = 48;
  std::vector<uint8_t> l01(w * h), l10(w * h, 2);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) l01[v * w + u] = u >= 32 ? 2 : 3;
  }
  const std::vector<float> depth(w * h, 2.0f);
  PairTruthView t = PlaneTruth(l01, l10, depth);
  // Ground truth: one vv match from cell (5, 2) and one vo from cell (1, 2).
  const std::vector<int32_t> gt_matches{2 * 8 + 5, 2 * 8 + 3, 2 * 8 + 1, 0};
  const std::vector<uint8_t> gt_types{0, 1};
  t.matches = gt_matches.data();
  t.match_type = gt_types.data();
  t.num_matches = 2;
  // vv exact; vv 5 px off (correct at 8, wrong at 4); vo exact; vo 30 px off.
  const std::vector<float> k0{44, 20, 50, 30, 12, 20, 10, 10};
  const std::vector<float> k1{24, 20, 30, 35, 0, 20, 20, 10};
  std::vector<MatchVerdict> verdicts;
  PairQuality q = ScoreMatches(t, k0, k1, QualityOptions{}, &verdicts);
  // Match by match: the class of its source label and whether it is within 8 px.
  ASSERT_EQ(verdicts.size(), 4u);
  const uint8_t expected_class[] = {kClassVV, kClassVV, kClassVO, kClassVO};
  const bool expected_correct[] = {true, true, true, false};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(verdicts[i].match_class, expected_class[i]) << i;
    EXPECT_EQ(verdicts[i].correct, expected_correct[i]) << i;
  }
  EXPECT_EQ(q.types[kClassVV].predicted, 2);
  EXPECT_EQ(q.types[kClassVV].correct, 2);
  EXPECT_EQ(q.types[kClassVO].predicted, 2);
  EXPECT_EQ(q.types[kClassVO].correct, 1);
  EXPECT_EQ(q.types[kClassVV].truth, 1);
  EXPECT_EQ(q.types[kClassVV].recalled, 1);  // (44, 20) is in cell (5, 2)
  EXPECT_EQ(q.types[kClassVO].recalled, 1);  // (12, 20) is in cell (1, 2)
  QualityOptions tight;
  tight.px = 4;
  q = ScoreMatches(t, k0, k1, tight, &verdicts);
  EXPECT_EQ(q.types[kClassVV].correct, 1);
  EXPECT_TRUE(verdicts[0].correct);
  EXPECT_FALSE(verdicts[1].correct);  // 5 px off
  EXPECT_EQ(q.types[kClassVV].recalled, 1);
  // Without the exact vo match its cell is not recalled.
  q = ScoreMatches(t, {10, 10}, {20, 10}, QualityOptions{});
  EXPECT_EQ(q.types[kClassVO].predicted, 1);
  EXPECT_EQ(q.types[kClassVO].recalled, 0);
  // A source pixel without depth: unscored, counted by its label.
  l01[20 * w + 44] = 0;
  q = ScoreMatches(t, {44, 20}, {24, 20}, QualityOptions{}, &verdicts);
  EXPECT_EQ(q.unscored, 1);
  EXPECT_EQ(q.unscored_by_label[0], 1);
  ASSERT_EQ(verdicts.size(), 1u);
  EXPECT_EQ(verdicts[0].match_class, kClassUnscored);
  EXPECT_FALSE(verdicts[0].correct);
}

TEST(ScoreMatches, VerdictsAddUpToTheCounts) {
  // Random matches over a plane with a random label map: the verdicts, counted by class
  // and correctness, are the pair's counts.
  const int w = 64, h = 48;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> label(0, 5);
  std::uniform_real_distribution<float> ux(-0.5f, w - 0.51f), uy(-0.5f, h - 0.51f);
  std::vector<uint8_t> l01(w * h), l10(w * h);
  for (auto& l : l01) l = static_cast<uint8_t>(label(rng));
  for (auto& l : l10) l = static_cast<uint8_t>(label(rng));
  const std::vector<float> depth(w * h, 2.0f);
  const PairTruthView t = PlaneTruth(l01, l10, depth);
  std::vector<float> k0, k1;
  for (int i = 0; i < 3000; ++i) {
    const float x = ux(rng), y = uy(rng);
    k0.insert(k0.end(), {x, y});
    // Half near the true target (20 px left), half anywhere.
    if (i % 2 == 0) {
      k1.insert(k1.end(), {std::clamp(x - 20.0f + (ux(rng) - 32) / 4, -0.5f, w - 0.51f), y});
    } else {
      k1.insert(k1.end(), {ux(rng), uy(rng)});
    }
  }
  std::vector<MatchVerdict> verdicts;
  const PairQuality q = ScoreMatches(t, k0, k1, QualityOptions{}, &verdicts);
  ASSERT_EQ(verdicts.size(), 3000u);
  std::array<int64_t, 4> predicted{}, correct{};
  for (const MatchVerdict& v : verdicts) {
    ++predicted[v.match_class];
    correct[v.match_class] += v.correct ? 1 : 0;
  }
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(predicted[c], q.types[c].predicted) << c;
    EXPECT_EQ(correct[c], q.types[c].correct) << c;
    EXPECT_GT(q.types[c].predicted, 0) << c;
    EXPECT_GT(q.types[c].correct, 0) << c;
  }
  EXPECT_EQ(predicted[kClassUnscored], q.unscored);
  EXPECT_EQ(correct[kClassUnscored], 0);
  // The same counts without asking for verdicts.
  const PairQuality again = ScoreMatches(t, k0, k1, QualityOptions{});
  for (int c = 0; c < 3; ++c) EXPECT_EQ(again.types[c].correct, q.types[c].correct);
}

}  // namespace
}  // namespace gt::eval

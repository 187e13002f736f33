// The relative-pose protocol's steps on one pair, one thread (docs/EVAL.md "Relative pose";
// issue 21): 2000 matches on normalised points, 80 % inliers with 0.5 px Gaussian noise at
// f = 500 in image 1, 20 % uniform outliers, as tests/bench/eval_bench.py's predictions.
//  - BM_FindEssentialMat: cv::findEssentialMat(RANSAC, 0.99999, 0.5 px), LoFTR's;
//  - BM_CvRecoverPose: cv::recoverPose(E, ..., I, 1e9, mask), the baseline;
//  - BM_RecoverPose: occgt's RecoverPose on the same E and mask (same answer, checked
//    once before timing).
//  - BM_Estimate/<setting>: the whole EstimateRelativePose (findEssentialMat and the
//    recoverPose loop) for each estimator setting of --protocol gluefactory (0-3: usac_default
//    at 0.5, 1.5, 2, 3 px; 4-7: ransac at the same) and LoFTR's (8), on the same pair in
//    pixels (f = 500): what each setting costs against LoFTR's.
//  - BM_FindEssentialMatSettings / BM_FindEssentialRansac, BM_EstimateGluefactory: below.
// The ratio BM_CvRecoverPose / BM_RecoverPose is the speed-up docs/PERFORMANCE.md quotes.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <cstdlib>
#include <opencv2/calib3d.hpp>
#include <random>

#include "libgt/eval/pose.h"
#include "libgt/eval/protocol.h"

namespace {

struct PosePair {
  std::vector<double> p0, p1;  // normalised, row-major [N, 2]
  cv::Mat E, mask;             // findEssentialMat's output on them
};

const PosePair& GetPair() {
  static const PosePair pair = [] {
    PosePair s;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.6, 0.6), z(1, 5), unit(0, 1);
    std::normal_distribution<double> noise(0, 0.5 / 500);
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.1, 1, 0.2).normalized()).toRotationMatrix();
    const Eigen::Vector3d t(0.3, 0.05, 0.1);
    while (s.p0.size() < 4000) {
      if (unit(rng) < 0.2) {
        s.p0.insert(s.p0.end(), {u(rng), u(rng)});
        s.p1.insert(s.p1.end(), {u(rng), u(rng)});
        continue;
      }
      const double d = z(rng);
      const Eigen::Vector3d p(u(rng) * d, u(rng) * d, d), q = R * p + t;
      s.p0.insert(s.p0.end(), {p.x() / p.z(), p.y() / p.z()});
      s.p1.insert(s.p1.end(), {q.x() / q.z() + noise(rng), q.y() / q.z() + noise(rng)});
    }
    s.E = cv::findEssentialMat(cv::Mat(2000, 2, CV_64F, s.p0.data()),
                               cv::Mat(2000, 2, CV_64F, s.p1.data()), cv::Mat::eye(3, 3, CV_64F),
                               cv::RANSAC, 0.99999, 0.5 / 500, s.mask);
    return s;
  }();
  return pair;
}

Eigen::Matrix3d FirstBlock(const cv::Mat& E) {
  Eigen::Matrix3d block;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) block(r, c) = E.at<double>(r, c);
  }
  return block;
}

void BM_FindEssentialMat(benchmark::State& state) {
  PosePair s = GetPair();
  for (auto _ : state) {
    cv::Mat mask;
    cv::Mat E = cv::findEssentialMat(
        cv::Mat(2000, 2, CV_64F, s.p0.data()), cv::Mat(2000, 2, CV_64F, s.p1.data()),
        cv::Mat::eye(3, 3, CV_64F), cv::RANSAC, 0.99999, 0.5 / 500, mask);
    benchmark::DoNotOptimize(E.data);
  }
}
BENCHMARK(BM_FindEssentialMat)->Unit(benchmark::kMillisecond);

void BM_CvRecoverPose(benchmark::State& state) {
  PosePair s = GetPair();
  const cv::Mat block = s.E.rowRange(0, 3).clone();
  for (auto _ : state) {
    cv::Mat mask = s.mask.clone(), R, t;
    const int n = cv::recoverPose(block, cv::Mat(2000, 2, CV_64F, s.p0.data()),
                                  cv::Mat(2000, 2, CV_64F, s.p1.data()), cv::Mat::eye(3, 3, CV_64F),
                                  R, t, 1e9, mask);
    benchmark::DoNotOptimize(n);
  }
}
BENCHMARK(BM_CvRecoverPose)->Unit(benchmark::kMillisecond);

void BM_RecoverPose(benchmark::State& state) {
  const PosePair& s = GetPair();
  const Eigen::Matrix3d block = FirstBlock(s.E);
  {
    // The same answer as OpenCV's before timing it (the unit test covers many more cases).
    cv::Mat mask_cv = s.mask.clone(), R, t;
    PosePair copy = s;
    const int expected = cv::recoverPose(
        s.E.rowRange(0, 3).clone(), cv::Mat(2000, 2, CV_64F, copy.p0.data()),
        cv::Mat(2000, 2, CV_64F, copy.p1.data()), cv::Mat::eye(3, 3, CV_64F), R, t, 1e9, mask_cv);
    std::vector<uint8_t> mask(s.mask.data, s.mask.data + s.mask.total());
    if (gt::eval::RecoverPose(block, s.p0, s.p1, 1e9, &mask).inliers != expected) {
      std::fprintf(stderr, "RecoverPose differs from cv::recoverPose\n");
      std::abort();
    }
  }
  for (auto _ : state) {
    std::vector<uint8_t> mask(s.mask.data, s.mask.data + s.mask.total());
    const gt::eval::RecoveredPose pose = gt::eval::RecoverPose(block, s.p0, s.p1, 1e9, &mask);
    benchmark::DoNotOptimize(pose.inliers);
  }
}
BENCHMARK(BM_RecoverPose)->Unit(benchmark::kMillisecond);

void BM_Estimate(benchmark::State& state) {
  const PosePair& s = GetPair();
  Eigen::Matrix3d K;
  K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  std::vector<float> k0(s.p0.size()), k1(s.p1.size());
  for (size_t i = 0; i < s.p0.size(); i += 2) {
    k0[i] = static_cast<float>(s.p0[i] * 500 + 320);
    k0[i + 1] = static_cast<float>(s.p0[i + 1] * 500 + 240);
    k1[i] = static_cast<float>(s.p1[i] * 500 + 320);
    k1[i + 1] = static_cast<float>(s.p1[i + 1] * 500 + 240);
  }
  const std::vector<gt::eval::PoseEstimatorOptions> settings = [] {
    auto v = gt::eval::ExpandProtocol(gt::eval::ProtocolName::kGluefactory).estimators;
    v.push_back(gt::eval::ExpandProtocol(gt::eval::ProtocolName::kLoftr).estimators[0]);
    return v;
  }();
  const gt::eval::PoseEstimatorOptions& o = settings.at(state.range(0));
  state.SetLabel(gt::eval::PoseEstimatorName(o));
  for (auto _ : state) {
    const auto pose = gt::eval::EstimateRelativePose(k0, k1, K, K, o);
    benchmark::DoNotOptimize(pose);
  }
}
BENCHMARK(BM_Estimate)->DenseRange(0, 8)->Unit(benchmark::kMillisecond);

// OpenCV's RANSAC against occgt's FindEssentialRansac (the same E and mask, checked by
// tests/eval/pose_test.cc), for LoFTR's one setting (range 1) and for glue-factory's four
// RANSAC thresholds (range 4: OpenCV called once per threshold; occgt shares the samples).
std::vector<gt::eval::RansacSetting> SweepSettings(int64_t k) {
  if (k == 1) return {{0.5 / 500, 0.99999, 1000}};
  std::vector<gt::eval::RansacSetting> v;
  for (const double px : {0.5, 1.5, 2.0, 3.0}) v.push_back({px / 500, 0.99999, 1000});
  return v;
}

void BM_FindEssentialMatSettings(benchmark::State& state) {
  PosePair s = GetPair();
  const auto settings = SweepSettings(state.range(0));
  for (auto _ : state) {
    for (const auto& r : settings) {
      cv::Mat mask;
      cv::Mat E = cv::findEssentialMat(
          cv::Mat(2000, 2, CV_64F, s.p0.data()), cv::Mat(2000, 2, CV_64F, s.p1.data()),
          cv::Mat::eye(3, 3, CV_64F), cv::RANSAC, r.confidence, r.threshold, r.max_iters, mask);
      benchmark::DoNotOptimize(E.data);
    }
  }
}
BENCHMARK(BM_FindEssentialMatSettings)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond);

void BM_FindEssentialRansac(benchmark::State& state) {
  const PosePair& s = GetPair();
  const auto settings = SweepSettings(state.range(0));
  for (auto _ : state) {
    const auto found = gt::eval::FindEssentialRansac(s.p0, s.p1, settings);
    benchmark::DoNotOptimize(found.data());
  }
}
BENCHMARK(BM_FindEssentialRansac)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond);

// All 8 settings of --protocol gluefactory in one EstimateRelativePoses call (as `occgt
// eval` runs them); against the sum of BM_Estimate/0..7.
void BM_EstimateGluefactory(benchmark::State& state) {
  const PosePair& s = GetPair();
  Eigen::Matrix3d K;
  K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  std::vector<float> k0(s.p0.size()), k1(s.p1.size());
  for (size_t i = 0; i < s.p0.size(); i += 2) {
    k0[i] = static_cast<float>(s.p0[i] * 500 + 320);
    k0[i + 1] = static_cast<float>(s.p0[i + 1] * 500 + 240);
    k1[i] = static_cast<float>(s.p1[i] * 500 + 320);
    k1[i + 1] = static_cast<float>(s.p1[i + 1] * 500 + 240);
  }
  const auto settings = gt::eval::ExpandProtocol(gt::eval::ProtocolName::kGluefactory).estimators;
  const std::vector<uint64_t> seeds(settings.size(), 1);
  for (auto _ : state) {
    const auto poses = gt::eval::EstimateRelativePoses(k0, k1, K, K, settings, nullptr, seeds);
    benchmark::DoNotOptimize(poses.data());
  }
}
BENCHMARK(BM_EstimateGluefactory)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

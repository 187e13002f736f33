#include "libgt/eval/pose.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>

#include "libgt/core/error.h"

namespace gt::eval {

PoseMethod ParsePoseMethod(const std::string& text, const std::string& field) {
  for (const PoseMethod m :
       {PoseMethod::kRansac, PoseMethod::kLmeds, PoseMethod::kUsacDefault,
        PoseMethod::kUsacAccurate, PoseMethod::kUsacMagsac, PoseMethod::kUsacProsac}) {
    if (text == PoseMethodName(m)) return m;
  }
  throw InputError(field,
                   "expected ransac, lmeds, usac_default, usac_accurate, usac_magsac or "
                   "usac_prosac, got '" +
                       text + "'");
}

const char* PoseMethodName(PoseMethod m) {
  switch (m) {
    case PoseMethod::kRansac:
      return "ransac";
    case PoseMethod::kLmeds:
      return "lmeds";
    case PoseMethod::kUsacDefault:
      return "usac_default";
    case PoseMethod::kUsacAccurate:
      return "usac_accurate";
    case PoseMethod::kUsacMagsac:
      return "usac_magsac";
    case PoseMethod::kUsacProsac:
      return "usac_prosac";
  }
  return "?";
}

int PoseMethodOpenCVFlag(PoseMethod m) {
  switch (m) {
    case PoseMethod::kRansac:
      return cv::RANSAC;
    case PoseMethod::kLmeds:
      return cv::LMEDS;
    case PoseMethod::kUsacDefault:
      return cv::USAC_DEFAULT;
    case PoseMethod::kUsacAccurate:
      return cv::USAC_ACCURATE;
    case PoseMethod::kUsacMagsac:
      return cv::USAC_MAGSAC;
    case PoseMethod::kUsacProsac:
      return cv::USAC_PROSAC;
  }
  return cv::RANSAC;
}

FocalMean ParseFocalMean(const std::string& text, const std::string& field) {
  if (text == "loftr") return FocalMean::kLoftr;
  if (text == "all") return FocalMean::kAll;
  throw InputError(field, "expected loftr or all, got '" + text + "'");
}

const char* FocalMeanName(FocalMean f) { return f == FocalMean::kLoftr ? "loftr" : "all"; }

bool PoseEstimatorOptions::Check(std::string* error) const {
  if (!(ransac_px > 0) || !std::isfinite(ransac_px)) {
    *error = "ransac_px: expected a finite number > 0 (pixels)";
    return false;
  }
  if (!(confidence > 0 && confidence < 1)) {
    *error = "confidence: expected a number in (0, 1)";
    return false;
  }
  if (max_iters < 1) {
    *error = "max_iters: expected an integer >= 1";
    return false;
  }
  if (min_matches < 5) {
    *error = "min_matches: expected an integer >= 5 (the five-point solver's minimum)";
    return false;
  }
  return true;
}

std::string PoseEstimatorName(const PoseEstimatorOptions& e) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "opencv-%s %.6g px conf %.6g", PoseMethodName(e.method),
                e.ransac_px, e.confidence);
  std::string name = buf;
  if (e.max_iters != 1000) name += " iters " + std::to_string(e.max_iters);
  if (e.focal_mean != FocalMean::kLoftr)
    name += std::string(" focal ") + FocalMeanName(e.focal_mean);
  return name;
}

uint64_t PairRngSeed(const std::string& key, uint64_t estimator) {
  uint64_t h = 14695981039346656037ull;
  auto mix = [&h](uint8_t byte) {
    h ^= byte;
    h *= 1099511628211ull;
  };
  for (const char c : key) mix(static_cast<uint8_t>(c));
  for (int b = 0; b < 8; ++b) mix(static_cast<uint8_t>(estimator >> (8 * b)));
  return h == 0 ? 1 : h;
}

namespace {

// [N, 2] pixels -> N normalised points (x - cx) / fx, (y - cy) / fy, in double as LoFTR
// (NumPy float64 after subtracting K's entries); row-major [N, 2].
std::vector<double> Normalise(const std::vector<float>& kpts, const Eigen::Matrix3d& K) {
  std::vector<double> out(kpts.size());
  for (size_t i = 0; i + 1 < kpts.size(); i += 2) {
    out[i] = (static_cast<double>(kpts[i]) - K(0, 2)) / K(0, 0);
    out[i + 1] = (static_cast<double>(kpts[i + 1]) - K(1, 2)) / K(1, 1);
  }
  return out;
}

double AngleDeg(double cosine) { return std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI; }

// OpenCV's triangulation of one point for P0 = [I|0] and P = [R|t] (cvTriangulatePoints):
// the rows x0 P0_2 - P0_0, y0 P0_2 - P0_1, x1 P_2 - P_0, y1 P_2 - P_1, and the right
// singular vector of the smallest singular value, by the routine cv::SVD::compute runs
// (hal::SVD64f on the transposed matrix), hence the same bits.
std::array<double, 4> TriangulateLikeOpenCV(double x0, double y0, double x1, double y1,
                                            const double P[3][4]) {
  static constexpr double P0[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
  alignas(16) double At[16], W[4], Vt[16];  // At[k * 4 + row] = A(row, k)
  for (int k = 0; k < 4; ++k) {
    At[k * 4 + 0] = x0 * P0[2][k] - P0[0][k];
    At[k * 4 + 1] = y0 * P0[2][k] - P0[1][k];
    At[k * 4 + 2] = x1 * P[2][k] - P[0][k];
    At[k * 4 + 3] = y1 * P[2][k] - P[1][k];
  }
  // The last argument: OpenCV 4.6 reads it as the number of left singular vectors to
  // normalise into At afterwards (the header calls it flags); 0 skips that step, which
  // does not touch Vt. Anything above 4 would write past At.
  cv::hal::SVD64f(At, 4 * sizeof(double), W, nullptr, 4 * sizeof(double), Vt, 4 * sizeof(double), 4,
                  4, 0);
  return {Vt[12], Vt[13], Vt[14], Vt[15]};
}

}  // namespace

RecoveredPose RecoverPose(const Eigen::Matrix3d& E, const std::vector<double>& p0,
                          const std::vector<double>& p1, double distance_thresh,
                          std::vector<uint8_t>* mask) {
  GT_ASSERT(p0.size() == p1.size() && p0.size() % 2 == 0);
  const size_t n = p0.size() / 2;
  const bool all = mask->empty();
  GT_ASSERT(all || mask->size() == n);
  cv::Mat E_cv(3, 3, CV_64F), R1, R2, t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) E_cv.at<double>(r, c) = E(r, c);
  }
  cv::decomposeEssentialMat(E_cv, R1, R2, t);
  double P[2][3][4];  // [R1|t], [R2|t]
  for (int k = 0; k < 2; ++k) {
    const cv::Mat& R = k == 0 ? R1 : R2;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) P[k][r][c] = R.at<double>(r, c);
      P[k][r][3] = t.at<double>(r, 0);
    }
  }
  // Bit c of in_front[i]: point i counts for candidate c = (R1, t), (R2, t), (R1, -t), (R2, -t).
  std::vector<uint8_t> in_front(n, 0);
  std::array<int, 4> good{0, 0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    if (!all && (*mask)[i] == 0) continue;
    for (int k = 0; k < 2; ++k) {
      const std::array<double, 4> q =
          TriangulateLikeOpenCV(p0[2 * i], p0[2 * i + 1], p1[2 * i], p1[2 * i + 1], P[k]);
      // As recoverPose: Z W > 0; then Q / W, its depth in camera 0 and, by P, in camera 1,
      // both below distance_thresh and the latter > 0. For [R|-t] every one of these
      // numbers is negated (see the header).
      const double zw = q[2] * q[3];
      const double x = q[0] / q[3], y = q[1] / q[3], z = q[2] / q[3];
      const double z1 =
          P[k][2][0] * x + P[k][2][1] * y + P[k][2][2] * z + P[k][2][3] * (q[3] / q[3]);
      if (zw > 0 && z < distance_thresh && z1 > 0 && z1 < distance_thresh) {
        in_front[i] |= static_cast<uint8_t>(1u << k);
        ++good[k];
      }
      if (-zw > 0 && -z < distance_thresh && -z1 > 0 && -z1 < distance_thresh) {
        in_front[i] |= static_cast<uint8_t>(1u << (k + 2));
        ++good[k + 2];
      }
    }
  }
  int best = 3;  // OpenCV's order: the first candidate with a count >= all others
  for (int c = 0; c < 4; ++c) {
    if (good[c] >= *std::max_element(good.begin(), good.end())) {
      best = c;
      break;
    }
  }
  if (all) mask->assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const bool in = (in_front[i] >> best) & 1u;
    (*mask)[i] = in ? (all ? 255 : (*mask)[i]) : 0;
  }
  RecoveredPose out;
  const cv::Mat& R = best % 2 == 0 ? R1 : R2;
  const double sign = best < 2 ? 1.0 : -1.0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.cam1_from_cam0_R(r, c) = R.at<double>(r, c);
    out.cam1_from_cam0_t(r) = sign * t.at<double>(r, 0);
  }
  out.inliers = good[best];
  return out;
}

namespace {

// OpenCV's RANSACUpdateNumIters (calib3d, not exported): the iterations that reach
// confidence p at outlier ratio ep with samples of model_points, capped at max_iters.
int UpdateIterations(double p, double ep, int model_points, int max_iters) {
  p = std::min(std::max(p, 0.0), 1.0);
  ep = std::min(std::max(ep, 0.0), 1.0);
  double num = std::max(1.0 - p, DBL_MIN);
  double denom = 1.0 - std::pow(1.0 - ep, model_points);
  if (denom < DBL_MIN) return 0;
  num = std::log(num);
  denom = std::log(denom);
  return denom >= 0 || -num >= max_iters * (-denom) ? max_iters : cvRound(num / denom);
}

// The error OpenCV's essential-matrix callback gives match i under E (row-major):
// (x1^T E x0)^2 / ((E x0)_0^2 + (E x0)_1^2 + (E^T x1)_0^2 + (E^T x1)_1^2) in double, stored
// as float; the same operations in the same order (OpenCV's Matx products start from a
// zero, which can change only the sign of an exact zero, and every such number is squared
// before it counts). This file is compiled without FMA contraction (libgt/CMakeLists.txt).
void EssentialErrors(const double* E, const double* p0, const double* p1, size_t n, float* err) {
  for (size_t i = 0; i < n; ++i) {
    const double x0 = p0[2 * i], y0 = p0[2 * i + 1], x1 = p1[2 * i], y1 = p1[2 * i + 1];
    const double ex0 = E[0] * x0 + E[1] * y0 + E[2];
    const double ex1 = E[3] * x0 + E[4] * y0 + E[5];
    const double ex2 = E[6] * x0 + E[7] * y0 + E[8];
    const double etx0 = E[0] * x1 + E[3] * y1 + E[6];
    const double etx1 = E[1] * x1 + E[4] * y1 + E[7];
    const double d = x1 * ex0 + y1 * ex1 + ex2;
    err[i] = static_cast<float>(d * d / (ex0 * ex0 + ex1 * ex1 + etx0 * etx0 + etx1 * etx1));
  }
}

EssentialEstimate FromOpenCV(const cv::Mat& E, const cv::Mat& mask, size_t n) {
  EssentialEstimate out;
  if (E.empty() || E.cols != 3 || E.rows % 3 != 0) return out;
  GT_ASSERT(E.isContinuous() && E.type() == CV_64F);
  out.E.assign(E.ptr<double>(), E.ptr<double>() + E.total());
  GT_ASSERT(mask.isContinuous() && mask.total() == n);
  out.mask.assign(mask.data, mask.data + n);
  return out;
}

// cv::findEssentialMat(RANSAC) itself, on normalised points (K = I).
EssentialEstimate FindEssentialOpenCV(const std::vector<double>& p0, const std::vector<double>& p1,
                                      int method, double confidence, double threshold,
                                      int max_iters) {
  const int n = static_cast<int>(p0.size() / 2);
  cv::Mat mask;
  const cv::Mat E = cv::findEssentialMat(cv::Mat(n, 2, CV_64F, const_cast<double*>(p0.data())),
                                         cv::Mat(n, 2, CV_64F, const_cast<double*>(p1.data())),
                                         cv::Mat::eye(3, 3, CV_64F), method, confidence, threshold,
                                         max_iters, mask);
  return FromOpenCV(E, mask, static_cast<size_t>(n));
}

// R, t of the block of E with most recoverPose inliers, the mask narrowed from block to
// block (LoFTR's loop); nullopt when no block has an inlier.
std::optional<PoseEstimate> PoseFromEssential(const EssentialEstimate& e,
                                              const std::vector<double>& p0,
                                              const std::vector<double>& p1) {
  if (e.E.empty()) return std::nullopt;
  std::vector<uint8_t> mask = e.mask;
  std::optional<PoseEstimate> best;
  int best_inliers = 0;
  for (size_t k = 0; k < e.E.size() / 9; ++k) {
    Eigen::Matrix3d block;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) block(r, c) = e.E[9 * k + 3 * r + c];
    }
    const RecoveredPose pose = RecoverPose(block, p0, p1, kLoftrRecoverPoseDistance, &mask);
    if (pose.inliers > best_inliers) {
      best_inliers = pose.inliers;
      best = PoseEstimate{pose.cam1_from_cam0_R, pose.cam1_from_cam0_t, pose.inliers};
    }
  }
  return best;
}

}  // namespace

std::vector<EssentialEstimate> FindEssentialRansac(const std::vector<double>& p0,
                                                   const std::vector<double>& p1,
                                                   const std::vector<RansacSetting>& settings) {
  GT_ASSERT(p0.size() == p1.size() && p0.size() % 2 == 0);
  const int count = static_cast<int>(p0.size() / 2);
  constexpr int kModelPoints = 5;
  std::vector<EssentialEstimate> out(settings.size());
  if (count <= kModelPoints) {
    // Too few to sample (OpenCV returns every five-point solution on exactly five).
    for (size_t s = 0; s < settings.size(); ++s) {
      out[s] = FindEssentialOpenCV(p0, p1, cv::RANSAC, settings[s].confidence,
                                   settings[s].threshold, settings[s].max_iters);
    }
    return out;
  }
  struct State {
    float t2 = 0;  // OpenCV's float threshold on the squared error
    int niters = 0, max_good = 0;
    std::array<double, 9> best{};
  };
  std::vector<State> states(settings.size());
  for (size_t s = 0; s < settings.size(); ++s) {
    GT_ASSERT(settings[s].confidence > 0 && settings[s].confidence < 1);
    states[s].t2 = static_cast<float>(settings[s].threshold * settings[s].threshold);
    states[s].niters = std::max(settings[s].max_iters, 1);
  }
  cv::RNG rng(~uint64_t{0});
  const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
  std::vector<float> err(count);
  std::vector<size_t> active;
  double s0[2 * kModelPoints], s1[2 * kModelPoints];
  for (int iter = 0;; ++iter) {
    active.clear();
    for (size_t s = 0; s < states.size(); ++s) {
      if (iter < states[s].niters) active.push_back(s);
    }
    if (active.empty()) break;
    // OpenCV's getSubset: five distinct indices, each redrawn while it repeats an earlier
    // one (its callback accepts every sample, so the first attempt is the sample).
    int idx[kModelPoints];
    for (int i = 0; i < kModelPoints; ++i) {
      for (;;) {
        idx[i] = rng.uniform(0, count);
        int j = 0;
        while (j < i && idx[j] != idx[i]) ++j;
        if (j == i) break;
      }
      for (int c = 0; c < 2; ++c) {
        s0[2 * i + c] = p0[2 * idx[i] + c];
        s1[2 * i + c] = p1[2 * idx[i] + c];
      }
    }
    const cv::Mat models = cv::findEssentialMat(cv::Mat(kModelPoints, 2, CV_64F, s0),
                                                cv::Mat(kModelPoints, 2, CV_64F, s1), identity,
                                                cv::RANSAC, 0.99, 1.0, 1000, cv::noArray());
    if (models.empty()) continue;
    GT_ASSERT(models.cols == 3 && models.rows % 3 == 0 && models.isContinuous());
    for (int m = 0; m < models.rows / 3; ++m) {
      const double* E = models.ptr<double>(3 * m);
      EssentialErrors(E, p0.data(), p1.data(), static_cast<size_t>(count), err.data());
      for (const size_t s : active) {
        State& st = states[s];
        int good = 0;
        for (int i = 0; i < count; ++i) good += err[i] <= st.t2;
        if (good > std::max(st.max_good, kModelPoints - 1)) {
          std::copy(E, E + 9, st.best.begin());
          st.max_good = good;
          st.niters =
              UpdateIterations(settings[s].confidence, static_cast<double>(count - good) / count,
                               kModelPoints, st.niters);
        }
      }
    }
  }
  for (size_t s = 0; s < states.size(); ++s) {
    if (states[s].max_good == 0) continue;
    out[s].E.assign(states[s].best.begin(), states[s].best.end());
    EssentialErrors(states[s].best.data(), p0.data(), p1.data(), static_cast<size_t>(count),
                    err.data());
    out[s].mask.resize(count);
    for (int i = 0; i < count; ++i) out[s].mask[i] = err[i] <= states[s].t2;
  }
  return out;
}

std::vector<std::optional<PoseEstimate>> EstimateRelativePoses(
    const std::vector<float>& kpts0, const std::vector<float>& kpts1, const Eigen::Matrix3d& K0,
    const Eigen::Matrix3d& K1, const std::vector<PoseEstimatorOptions>& estimators,
    const std::vector<float>* confidence, const std::vector<uint64_t>& rng_seeds) {
  GT_ASSERT(kpts0.size() == kpts1.size() && kpts0.size() % 2 == 0);
  GT_ASSERT(rng_seeds.size() == estimators.size());
  const int n = static_cast<int>(kpts0.size() / 2);
  std::vector<std::optional<PoseEstimate>> out(estimators.size());
  const std::vector<double> p0 = Normalise(kpts0, K0);
  const std::vector<double> p1 = Normalise(kpts1, K1);
  std::vector<size_t> ransac;
  std::vector<RansacSetting> ransac_settings;
  for (size_t e = 0; e < estimators.size(); ++e) {
    const PoseEstimatorOptions& options = estimators[e];
    if (n < options.min_matches) continue;
    const double focal = options.focal_mean == FocalMean::kLoftr
                             ? (K0(0, 0) + K1(1, 1) + K0(0, 0) + K1(1, 1)) / 4.0
                             : (K0(0, 0) + K0(1, 1) + K1(0, 0) + K1(1, 1)) / 4.0;
    const double threshold = options.ransac_px / focal;
    if (options.method == PoseMethod::kRansac) {
      ransac.push_back(e);
      ransac_settings.push_back({threshold, options.confidence, options.max_iters});
      continue;
    }
    const std::vector<double>* q0 = &p0;
    const std::vector<double>* q1 = &p1;
    std::vector<double> sorted0, sorted1;
    if (options.method == PoseMethod::kUsacProsac) {
      // PROSAC draws from the front of the list first: best confidence first, ties in order.
      GT_ASSERT(confidence != nullptr && confidence->size() == static_cast<size_t>(n));
      std::vector<int> order(n);
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(),
                       [&](int a, int b) { return (*confidence)[a] > (*confidence)[b]; });
      sorted0.resize(p0.size());
      sorted1.resize(p1.size());
      for (int i = 0; i < n; ++i) {
        for (int c = 0; c < 2; ++c) {
          sorted0[2 * i + c] = p0[2 * order[i] + c];
          sorted1[2 * i + c] = p1[2 * order[i] + c];
        }
      }
      q0 = &sorted0;
      q1 = &sorted1;
    }
    cv::theRNG().state = rng_seeds[e];
    out[e] =
        PoseFromEssential(FindEssentialOpenCV(*q0, *q1, PoseMethodOpenCVFlag(options.method),
                                              options.confidence, threshold, options.max_iters),
                          *q0, *q1);
  }
  if (!ransac.empty()) {
    // OpenCV's RANSAC draws from its own generator only; theRNG() as for the others.
    cv::theRNG().state = rng_seeds[ransac.front()];
    const std::vector<EssentialEstimate> found = FindEssentialRansac(p0, p1, ransac_settings);
    for (size_t k = 0; k < ransac.size(); ++k) {
      out[ransac[k]] = PoseFromEssential(found[k], p0, p1);
    }
  }
  return out;
}

std::optional<PoseEstimate> EstimateRelativePose(
    const std::vector<float>& kpts0, const std::vector<float>& kpts1, const Eigen::Matrix3d& K0,
    const Eigen::Matrix3d& K1, const PoseEstimatorOptions& options,
    const std::vector<float>* confidence, uint64_t rng_seed) {
  return EstimateRelativePoses(kpts0, kpts1, K0, K1, {options}, confidence, {rng_seed})[0];
}

PoseError RelativePoseError(const Eigen::Matrix3d& R_gt, const Eigen::Vector3d& t_gt,
                            const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  PoseError e;
  const double norms = t.norm() * t_gt.norm();
  if (t_gt.norm() == 0) {
    e.translation_deg = 0;
  } else if (norms == 0) {
    e.translation_deg = 90;
  } else {
    const double angle = AngleDeg(t.dot(t_gt) / norms);
    e.translation_deg = std::min(angle, 180.0 - angle);
  }
  e.rotation_deg = AngleDeg(((R.transpose() * R_gt).trace() - 1.0) / 2.0);
  e.max_deg = std::max(e.rotation_deg, e.translation_deg);
  return e;
}

PoseError NoPoseError() { return {kInfiniteError, kInfiniteError, kInfiniteError}; }

std::vector<double> PoseAuc(const std::vector<double>& errors,
                            const std::vector<double>& thresholds_deg) {
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const size_t n = sorted.size();
  std::vector<double> aucs;
  for (const double threshold : thresholds_deg) {
    if (n == 0) {
      aucs.push_back(0);
      continue;
    }
    // Points (e_0 = 0, r_0 = 0), (e_k, k / n) for the sorted errors below the threshold,
    // then (threshold, r_last): the trapezoid rule over them.
    double area = 0, prev_e = 0, prev_r = 0;
    size_t k = 0;
    for (; k < n && sorted[k] < threshold; ++k) {
      const double r = static_cast<double>(k + 1) / static_cast<double>(n);
      area += (sorted[k] - prev_e) * (r + prev_r) / 2.0;
      prev_e = sorted[k];
      prev_r = r;
    }
    area += (threshold - prev_e) * prev_r;
    aucs.push_back(area / threshold);
  }
  return aucs;
}

std::vector<double> SymmetricEpipolarDistances(const std::vector<float>& kpts0,
                                               const std::vector<float>& kpts1,
                                               const Eigen::Matrix3d& K0, const Eigen::Matrix3d& K1,
                                               const Eigen::Matrix3d& R_gt,
                                               const Eigen::Vector3d& t_gt) {
  GT_ASSERT(kpts0.size() == kpts1.size() && kpts0.size() % 2 == 0);
  Eigen::Matrix3d t_cross;
  t_cross << 0, -t_gt.z(), t_gt.y(), t_gt.z(), 0, -t_gt.x(), -t_gt.y(), t_gt.x(), 0;
  const Eigen::Matrix3d E = t_cross * R_gt;
  const size_t n = kpts0.size() / 2;
  std::vector<double> d(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d x0((kpts0[2 * i] - K0(0, 2)) / K0(0, 0),
                             (kpts0[2 * i + 1] - K0(1, 2)) / K0(1, 1), 1.0);
    const Eigen::Vector3d x1((kpts1[2 * i] - K1(0, 2)) / K1(0, 0),
                             (kpts1[2 * i + 1] - K1(1, 2)) / K1(1, 1), 1.0);
    const Eigen::Vector3d Ex0 = E * x0;
    const Eigen::Vector3d Etx1 = E.transpose() * x1;
    const double x1Ex0 = x1.dot(Ex0);
    d[i] =
        x1Ex0 * x1Ex0 *
        (1.0 / (Ex0(0) * Ex0(0) + Ex0(1) * Ex0(1)) + 1.0 / (Etx1(0) * Etx1(0) + Etx1(1) * Etx1(1)));
  }
  return d;
}

}  // namespace gt::eval

#include "libgt/core/lens.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <sstream>

namespace gt {
namespace {

constexpr double kHalfPi = 1.57079632679489661923;
constexpr double kInf = std::numeric_limits<double>::infinity();

// d/dr [r * radial(r^2)] for kOpenCv as a function of s = r^2: 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3.
double OpenCvRadialSlope(const std::array<double, 5>& k, double s) {
  return 1.0 + s * (3.0 * k[0] + s * (5.0 * k[1] + s * 7.0 * k[4]));
}
double OpenCvRadialFactor(const std::array<double, 5>& k, double s) {
  return 1.0 + s * (k[0] + s * (k[1] + s * k[4]));
}
// theta_d(theta) and its derivative for kOpenCvFisheye.
double FisheyeThetaD(const std::array<double, 5>& k, double t) {
  const double t2 = t * t;
  return t * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}
double FisheyeSlope(const std::array<double, 5>& k, double t) {
  const double t2 = t * t;
  return 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
}

// The first x in (0, hi] where slope(x) <= 0, or kInf when there is none: a fine scan (the
// slope is a polynomial of degree <= 4 in x^2, so at most 4 sign changes), then bisection.
template <typename Slope>
double FirstNonPositive(Slope slope, double hi, int steps, bool geometric) {
  double prev = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double x = geometric ? hi * std::pow(10.0, -12.0 * (steps - i) / steps)
                               : hi * static_cast<double>(i) / steps;
    if (slope(x) <= 0.0) {
      double lo = prev, up = x;
      for (int it = 0; it < 200 && up - lo > 0.0; ++it) {
        const double mid = 0.5 * (lo + up);
        if (mid <= lo || mid >= up) break;
        (slope(mid) <= 0.0 ? up : lo) = mid;
      }
      return up;
    }
    prev = x;
  }
  return kInf;
}

double ComputeMonotonicLimit(LensModel model, const std::array<double, 5>& k) {
  switch (model) {
    case LensModel::kPinhole:
      return kInf;
    case LensModel::kOpenCv: {
      // Radii up to 1e4 (89.99 degrees off axis); the slope is scanned in s = r^2.
      const double s_max = FirstNonPositive([&](double s) { return OpenCvRadialSlope(k, s); }, 1e8,
                                            4000, /*geometric=*/true);
      return std::isinf(s_max) ? kInf : std::sqrt(s_max);
    }
    case LensModel::kOpenCvFisheye: {
      const double t_max = FirstNonPositive([&](double t) { return FisheyeSlope(k, t); }, kHalfPi,
                                            4000, /*geometric=*/false);
      return std::min(t_max, kHalfPi);
    }
  }
  return kInf;
}

// The limit is a scan of the model's slope: cached per thread for the last lens seen, so that
// undistorting every pixel of an image costs one scan.
double CachedMonotonicLimit(const LensCamera& lens) {
  thread_local LensModel model = LensModel::kPinhole;
  thread_local std::array<double, 5> coeffs{};
  thread_local double limit = kInf;
  if (lens.model != model || lens.coeffs != coeffs) {
    limit = ComputeMonotonicLimit(lens.model, lens.coeffs);
    model = lens.model;
    coeffs = lens.coeffs;
  }
  return limit;
}

// The x in [0, hi] with f(x) = 0 for f increasing on [0, hi], f(0) < 0 < f(hi): Newton's
// method kept inside a shrinking bracket (bisection when a step leaves it), to convergence.
template <typename F, typename DF>
double SolveIncreasing(F f, DF df, double hi, double start) {
  double lo = 0.0, up = hi;
  double x = std::min(std::max(start, lo), up);
  for (int it = 0; it < 200; ++it) {
    const double fx = f(x);
    if (fx == 0.0) return x;
    (fx < 0.0 ? lo : up) = x;
    const double d = df(x);
    double next = (d > 0.0) ? x - fx / d : 0.5 * (lo + up);
    if (!(next > lo && next < up)) next = 0.5 * (lo + up);
    if (next == x || up - lo <= 4.0 * std::numeric_limits<double>::epsilon() * up) {
      return next;
    }
    x = next;
  }
  return x;
}

// The distorted normalised coordinates of kOpenCv and their Jacobian.
Eigen::Vector2d OpenCvDistort(const std::array<double, 5>& k, const Eigen::Vector2d& ab,
                              Eigen::Matrix2d* jacobian) {
  const double a = ab.x(), b = ab.y();
  const double p1 = k[2], p2 = k[3];
  const double s = a * a + b * b;
  const double radial = OpenCvRadialFactor(k, s);
  if (jacobian) {
    const double dradial = k[0] + s * (2.0 * k[1] + s * 3.0 * k[4]);  // d radial / d s
    (*jacobian)(0, 0) = radial + 2.0 * a * a * dradial + 2.0 * p1 * b + 6.0 * p2 * a;
    (*jacobian)(0, 1) = 2.0 * a * b * dradial + 2.0 * p1 * a + 2.0 * p2 * b;
    (*jacobian)(1, 0) = (*jacobian)(0, 1);
    (*jacobian)(1, 1) = radial + 2.0 * b * b * dradial + 6.0 * p1 * b + 2.0 * p2 * a;
  }
  return {a * radial + 2.0 * p1 * a * b + p2 * (s + 2.0 * a * a),
          b * radial + p1 * (s + 2.0 * b * b) + 2.0 * p2 * a * b};
}

std::optional<Eigen::Vector2d> UndistortOpenCv(const LensCamera& lens, const Eigen::Vector2d& t,
                                               double r_max) {
  const auto& k = lens.coeffs;
  // Radial part first (exact, 1-D, inside the monotonic range), then Newton on the full
  // model from there.
  const double rt = t.norm();
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  if (rt > 0.0) {
    auto f = [&](double r) { return r * OpenCvRadialFactor(k, r * r) - rt; };
    auto df = [&](double r) { return OpenCvRadialSlope(k, r * r); };
    double hi = r_max;
    if (std::isinf(hi)) {
      hi = 1.0;
      while (f(hi) <= 0.0 && hi < 1e8) hi *= 2.0;
    }
    if (!(f(hi) > 0.0)) {
      if (k[2] == 0.0 && k[3] == 0.0) return std::nullopt;
      x = t / rt * hi;  // a start at the border of the range; the checks below decide
    } else {
      x = t / rt * SolveIncreasing(f, df, hi, rt);
    }
  }
  if (k[2] != 0.0 || k[3] != 0.0) {
    for (int it = 0; it < 100; ++it) {
      Eigen::Matrix2d jac;
      const Eigen::Vector2d residual = OpenCvDistort(k, x, &jac) - t;
      const double det = jac.determinant();
      if (!(det > 0.0)) return std::nullopt;
      const Eigen::Vector2d step = jac.inverse() * residual;
      x -= step;
      if (!x.allFinite()) return std::nullopt;
      if (step.norm() <= 1e-16 * (1.0 + x.norm())) break;
    }
  }
  Eigen::Matrix2d jac;
  const Eigen::Vector2d residual = OpenCvDistort(k, x, &jac) - t;
  if (!(residual.norm() <= 1e-11 * (1.0 + t.norm()))) return std::nullopt;
  if (!(jac.determinant() > 0.0)) return std::nullopt;
  if (x.norm() > r_max) return std::nullopt;
  return x;
}

std::optional<Eigen::Vector2d> UndistortFisheye(const LensCamera& lens, const Eigen::Vector2d& t,
                                                double theta_max) {
  const auto& k = lens.coeffs;
  const double theta_d = t.norm();
  if (theta_d == 0.0) return Eigen::Vector2d::Zero();
  auto f = [&](double th) { return FisheyeThetaD(k, th) - theta_d; };
  auto df = [&](double th) { return FisheyeSlope(k, th); };
  if (!(f(theta_max) > 0.0)) return std::nullopt;  // beyond the fold (or 90 degrees)
  const double theta = SolveIncreasing(f, df, theta_max, theta_d);
  if (!(theta < kHalfPi)) return std::nullopt;
  return t * (std::tan(theta) / theta_d);
}

}  // namespace

const char* LensModelName(LensModel model) {
  switch (model) {
    case LensModel::kPinhole:
      return "pinhole";
    case LensModel::kOpenCv:
      return "opencv";
    case LensModel::kOpenCvFisheye:
      return "opencv_fisheye";
  }
  return "?";
}

bool LensCamera::Check(std::string* error) const {
  std::string pinhole_error;
  std::ostringstream msg;
  if (!pinhole.Check(&pinhole_error)) {
    msg << pinhole_error;
  } else if (!std::isfinite(coeffs[0]) || !std::isfinite(coeffs[1]) || !std::isfinite(coeffs[2]) ||
             !std::isfinite(coeffs[3]) || !std::isfinite(coeffs[4])) {
    msg << LensModelName(model) << " distortion coefficients must be finite";
  } else if (model == LensModel::kPinhole && (coeffs[0] != 0 || coeffs[1] != 0 || coeffs[2] != 0 ||
                                              coeffs[3] != 0 || coeffs[4] != 0)) {
    msg << "a pinhole camera has no distortion coefficients";
  } else if (model == LensModel::kOpenCvFisheye && coeffs[4] != 0) {
    msg << "an opencv_fisheye camera has 4 coefficients (k1 k2 k3 k4), got a fifth: " << coeffs[4];
  } else if (!UndistortPixel(*this, pinhole.cx, pinhole.cy)) {
    msg << "the principal point has no ray";
  } else {
    return true;
  }
  if (error) *error = msg.str();
  return false;
}

double MonotonicLimit(const LensCamera& lens) { return CachedMonotonicLimit(lens); }

Eigen::Vector2d DistortNormalized(const LensCamera& lens, const Eigen::Vector2d& ab) {
  switch (lens.model) {
    case LensModel::kPinhole:
      return ab;
    case LensModel::kOpenCv:
      return OpenCvDistort(lens.coeffs, ab, nullptr);
    case LensModel::kOpenCvFisheye: {
      const double r = ab.norm();
      if (r == 0.0) return ab;
      const double theta = std::atan(r);
      return ab * (FisheyeThetaD(lens.coeffs, theta) / r);
    }
  }
  return ab;
}

std::optional<Eigen::Vector2d> UndistortPixel(const LensCamera& lens, double u, double v) {
  const Camera& c = lens.pinhole;
  const Eigen::Vector2d t((u - c.cx) / c.fx, (v - c.cy) / c.fy);
  if (!t.allFinite()) return std::nullopt;
  switch (lens.model) {
    case LensModel::kPinhole:
      return t;
    case LensModel::kOpenCv:
      return UndistortOpenCv(lens, t, CachedMonotonicLimit(lens));
    case LensModel::kOpenCvFisheye:
      return UndistortFisheye(lens, t, CachedMonotonicLimit(lens));
  }
  return std::nullopt;
}

std::optional<Eigen::Vector2d> DistortPoint(const LensCamera& lens,
                                            const Eigen::Vector3d& p_in_cam) {
  if (!(p_in_cam.z() > 0.0) || !p_in_cam.allFinite()) return std::nullopt;
  const Eigen::Vector2d d = DistortNormalized(lens, p_in_cam.head<2>() / p_in_cam.z());
  const Camera& c = lens.pinhole;
  return Eigen::Vector2d(c.fx * d.x() + c.cx, c.fy * d.y() + c.cy);
}

}  // namespace gt

#include "boxes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace dqk {

Box intersect_boxes(const BoundRows& lowers, const std::vector<std::int64_t>& lower_ids,
                    const BoundRows& uppers, const std::vector<std::int64_t>& upper_ids,
                    Index n, double pin_rtol) {
  if (lowers.rows() != static_cast<Index>(lower_ids.size()) ||
      uppers.rows() != static_cast<Index>(upper_ids.size()) ||
      (lowers.rows() && lowers.cols() != n) || (uppers.rows() && uppers.cols() != n)) {
    throw std::invalid_argument("intersect_boxes: bounds and ids of different sizes");
  }
  constexpr double INF = std::numeric_limits<double>::infinity();
  Box box;
  box.lower = Vec::Constant(n, -INF);
  box.upper = Vec::Constant(n, INF);
  box.lower_by = IndexVec::Constant(n, -1);
  box.upper_by = IndexVec::Constant(n, -1);
  // The first NaN in the limits' order, lower and upper bounds of one limit together.
  std::int64_t nan_limit = -1;
  auto note_nan = [&nan_limit](std::int64_t id) {
    if (nan_limit < 0 || id < nan_limit) nan_limit = id;
  };
  for (Index k = 0; k < lowers.rows(); ++k) {
    for (Index i = 0; i < n; ++i) {
      const double v = lowers(k, i);
      if (std::isnan(v)) {
        note_nan(lower_ids[k]);
      } else if (v > box.lower(i)) {
        box.lower(i) = v;
        box.lower_by(i) = lower_ids[k];
      }
    }
  }
  for (Index k = 0; k < uppers.rows(); ++k) {
    for (Index i = 0; i < n; ++i) {
      const double v = uppers(k, i);
      if (std::isnan(v)) {
        note_nan(upper_ids[k]);
      } else if (v < box.upper(i)) {
        box.upper(i) = v;
        box.upper_by(i) = upper_ids[k];
      }
    }
  }
  box.nan_limit = nan_limit;
  for (Index i = 0; i < n; ++i) {
    const double lo = box.lower(i), hi = box.upper(i);
    // Only a finite gap is rounding: an infinite one (a lower bound of +inf, an upper
    // one of -inf) keeps the box empty.
    if (hi < lo && std::isfinite(lo) && std::isfinite(hi) &&
        lo - hi <= pin_rtol * std::max(1.0, std::abs(lo))) {
      box.upper(i) = lo;
    }
  }
  return box;
}

void range_box(const Vec& lo, const Vec& hi, const Vec& rec,
               const Eigen::Matrix<bool, Eigen::Dynamic, 1>& off, Vec& lower, Vec& upper) {
  const Index n = lo.size();
  if (hi.size() != n || rec.size() != n || off.size() != n) {
    throw std::invalid_argument("range_box: lo, hi, rec and off of different lengths");
  }
  constexpr double INF = std::numeric_limits<double>::infinity();
  lower.resize(n);
  upper.resize(n);
  for (Index i = 0; i < n; ++i) {
    if (off(i)) {
      lower(i) = -INF;
      upper(i) = INF;
      continue;
    }
    lower(i) = lo(i) > 0.0 ? std::min(lo(i), rec(i)) : lo(i);
    upper(i) = hi(i) < 0.0 ? std::max(hi(i), -rec(i)) : hi(i);
  }
}

Vec centre(const Vec& lo, const Vec& hi, const Eigen::Matrix<bool, Eigen::Dynamic, 1>& centred,
           double shrink) {
  const Index n = lo.size();
  if (hi.size() != n || centred.size() != n) {
    throw std::invalid_argument("centre: lo, hi and centred of different lengths");
  }
  Vec c(n);
  for (Index i = 0; i < n; ++i) {
    const bool bounded = centred(i) && std::isfinite(lo(i)) && std::isfinite(hi(i));
    c(i) = bounded ? 0.5 * (lo(i) + hi(i)) : 0.0;
    if (shrink != 1.0) c(i) *= shrink;
  }
  return c;
}

std::int64_t first_defect(const std::vector<Values>& finite,
                          const std::vector<Values>& not_nan) {
  for (std::size_t k = 0; k < finite.size(); ++k) {
    if (!finite[k].isFinite().all()) return static_cast<std::int64_t>(k);
  }
  for (std::size_t k = 0; k < not_nan.size(); ++k) {
    if (not_nan[k].isNaN().any()) {
      return static_cast<std::int64_t>(finite.size() + k);
    }
  }
  return -1;
}

namespace {
// Python's builtin min(a, b) and max(a, b): b only when it is strictly smaller (larger).
double py_min(double a, double b) { return b < a ? b : a; }
double py_max(double a, double b) { return b > a ? b : a; }
}  // namespace

std::pair<double, double> grasp_rate_range(const Eigen::Vector3d& r, const Eigen::Vector3d& s_star,
                                           const Eigen::Vector3d& r_min,
                                           const Eigen::Vector3d& r_max, double dt) {
  constexpr double INF = std::numeric_limits<double>::infinity();
  double rho_min = -INF, rho_max = INF;
  for (Index i = 0; i < 3; ++i) {
    const double si = s_star(i);
    if (std::abs(si) < 1e-12) continue;
    const double a = (r_min(i) - r(i)) / (si * dt);
    const double b = (r_max(i) - r(i)) / (si * dt);
    rho_min = py_max(rho_min, py_min(a, b));
    rho_max = py_min(rho_max, py_max(a, b));
  }
  return {rho_min, rho_max};
}

std::pair<double, double> grasp_rates(const Eigen::Vector3d& point,
                                      const Eigen::Vector3d& tangent, double sigma,
                                      const Eigen::Vector3d& r_min,
                                      const Eigen::Vector3d& r_max, double sigma_min,
                                      double sigma_max, double dt) {
  const auto [rho_min, rho_max] = grasp_rate_range(point, tangent, r_min, r_max, dt);
  return {py_max(rho_min, (sigma_min - sigma) / dt), py_min(rho_max, (sigma_max - sigma) / dt)};
}

double smallest_singular_value(const Mat& J) {
  if (!J.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const Index m = J.rows(), n = J.cols();
  if (m == 0) return std::numeric_limits<double>::infinity();  // nothing to reach
  if (n < m) return 0.0;
  const double peak = J.cwiseAbs().maxCoeff();
  if (peak == 0.0) return 0.0;
  // A J of extreme size is scaled by a power of two (exact) so that no squared norm or
  // dot product below overflows, nor the squares of its largest rows underflow; any
  // other is taken as it is.
  int exponent = 0;
  if (peak > 0x1p250 || peak < 0x1p-250) std::frexp(peak, &exponent);
  std::vector<double> w(static_cast<size_t>(m * n));  // row-major copy
  for (Index i = 0; i < m; ++i) {
    for (Index k = 0; k < n; ++k) {
      w[static_cast<size_t>(i * n + k)] = exponent ? std::ldexp(J(i, k), -exponent) : J(i, k);
    }
  }
  // One-sided (Hestenes) Jacobi on the rows: plane rotations from the left make every
  // pair of rows orthogonal, sweep after sweep; the rows' norms are then the singular
  // values. A pair counts as orthogonal when |r_p . r_q| <= JACOBI_TOL |r_p| |r_q|, or
  // when either row is zero (or its squared norm underflows).
  constexpr double JACOBI_TOL = 1e-15;
  constexpr int MAX_SWEEPS = 64;
  for (int sweep = 0; sweep < MAX_SWEEPS; ++sweep) {
    bool rotated = false;
    for (Index p = 0; p + 1 < m; ++p) {
      double* rp = &w[static_cast<size_t>(p * n)];
      for (Index q = p + 1; q < m; ++q) {
        double* rq = &w[static_cast<size_t>(q * n)];
        double a = 0.0, b = 0.0, c = 0.0;
        for (Index k = 0; k < n; ++k) {
          a += rp[k] * rp[k];
          b += rq[k] * rq[k];
          c += rp[k] * rq[k];
        }
        // sqrt(a) sqrt(b), not sqrt(a b): the product of two small squared norms may
        // underflow to 0, and a zero tolerance would rotate the pair sweep after sweep.
        if (a == 0.0 || b == 0.0 ||
            !(std::abs(c) > JACOBI_TOL * (std::sqrt(a) * std::sqrt(b)))) {
          continue;
        }
        rotated = true;
        const double zeta = (b - a) / (2.0 * c);
        const double t = std::copysign(1.0, zeta) / (std::abs(zeta) + std::hypot(1.0, zeta));
        const double cs = 1.0 / std::sqrt(1.0 + t * t), sn = cs * t;
        for (Index k = 0; k < n; ++k) {
          const double x = rp[k], y = rq[k];
          rp[k] = cs * x - sn * y;
          rq[k] = sn * x + cs * y;
        }
      }
    }
    if (!rotated) break;
  }
  double least = std::numeric_limits<double>::infinity();
  for (Index i = 0; i < m; ++i) {
    const double* r = &w[static_cast<size_t>(i * n)];
    double s = 0.0;
    for (Index k = 0; k < n; ++k) s += r[k] * r[k];
    least = std::min(least, s);
  }
  return std::ldexp(std::sqrt(least), exponent);
}

}  // namespace dqk

#include "support_line.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace dqk {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

double norm(const Eigen::Vector3d& v) { return std::sqrt(v.dot(v)); }

// v scaled to unit length (_unit, dualarm_qp/task/surfaces.py); false when v is below
// 1e-12.
bool unit(const Eigen::Vector3d& v, Eigen::Vector3d& out) {
  const double n = norm(v);
  if (!(n >= 1e-12)) return false;
  out = v / n;
  return true;
}

// The interval of sigma with lo <= o + sigma s <= hi (_line_box_range, the slab method);
// false when the line misses the box.
bool line_box_range(const Eigen::Vector3d& o, const Eigen::Vector3d& s, const Eigen::Vector3d& lo,
                    const Eigen::Vector3d& hi, double& t_lo, double& t_hi) {
  constexpr double tol = 1e-9;
  t_lo = -INF;
  t_hi = INF;
  for (Eigen::Index i = 0; i < 3; ++i) {
    if (std::abs(s(i)) <= 1e-12) {
      if (!(lo(i) - tol <= o(i) && o(i) <= hi(i) + tol)) return false;
      continue;
    }
    double a = (lo(i) - o(i)) / s(i), b = (hi(i) - o(i)) / s(i);
    if (a > b) std::swap(a, b);
    if (a > t_lo) t_lo = a;
    if (b < t_hi) t_hi = b;
  }
  if (t_lo > t_hi + tol) return false;
  if (t_lo > t_hi) t_hi = t_lo;
  return true;
}

}  // namespace

double SupportLine::push(double sigma) const {
  const double ds = sigma - sigma_inf;
  return ds == 0.0 ? INF : lever / ds;
}

SupportPlane::SupportPlane(double mass, const Eigen::Vector3d& mass_centre,
                           const Eigen::Vector3d& gravity, const Eigen::Vector3d& r1,
                           const Eigen::Vector3d& normal, double offset,
                           const Eigen::Vector3d& r_min, const Eigen::Vector3d& r_max,
                           double gravity_min)
    : args_{mass, mass_centre, gravity, r1, normal, offset, r_min, r_max, gravity_min},
      mass_(mass),
      centre_(mass_centre),
      gravity_(gravity),
      r1_(r1),
      offset_(offset),
      r_min_(r_min),
      r_max_(r_max),
      gravity_min_(gravity_min) {
  if (!(std::isfinite(mass) && mass > 0.0 && mass_centre.allFinite() && gravity.allFinite() &&
        r1.allFinite() && normal.allFinite() && std::isfinite(offset) && !r_min.hasNaN() &&
        !r_max.hasNaN() && gravity_min >= 0.0))
    throw std::invalid_argument(
        "SupportPlane: a finite mass > 0, mass centre, gravity, hand point, normal and "
        "offset, a box without NaN and gravity_min >= 0");
  if (!unit(normal, normal_)) throw std::invalid_argument("SupportPlane: a zero normal");
}

SupportLine SupportPlane::line(const Eigen::Matrix3d& R_world_object) const {
  SupportLine out;
  const Eigen::Vector3d g = R_world_object.transpose() * gravity_;
  out.gravity = g;
  if (!(std::abs(g(0)) > gravity_min_ * norm(g))) return out;  // no weight along the push
  // support_line: c = M (r1 - r_c) x g~, solvable when c . a* = 0.
  const Eigen::Vector3d g_tilde(g(0), 0.0, 0.0);
  const Eigen::Vector3d& a = normal_;
  const Eigen::Vector3d c = mass_ * (r1_ - centre_).cross(g_tilde);
  const double scale = std::max(norm(c), 1e-300);
  if (std::abs(c.dot(a)) > 1e-9 * scale) return out;
  const Eigen::Vector3d axc = a.cross(c);
  const double lever = norm(axc);
  if (lever < 1e-12 * std::max(1.0, mass_ * norm(g_tilde))) return out;  // degenerate
  const Eigen::Vector3d s = axc / lever;
  const Eigen::Vector3d r_inf = r1_ - (a.dot(r1_) - offset_) * a;
  const Eigen::Vector3d origin = r_inf - r_inf.dot(s) * s;
  const double sigma_inf = s.dot(r_inf - origin);
  double lo = 0.0, hi = 0.0;
  if (!line_box_range(origin, s, r_min_, r_max_, lo, hi)) return out;
  lo = std::max(lo, sigma_inf);
  if (lo > hi || hi <= sigma_inf || !std::isfinite(hi)) return out;
  // The line as a PlaneBar: its sliding direction and normal made unit again, orthogonal.
  Eigen::Vector3d s_unit, a_unit;
  if (!unit(s, s_unit) || !unit(a, a_unit) || std::abs(s_unit.dot(a_unit)) > 1e-9) return out;
  double box_lo = 0.0, box_hi = 0.0;
  if (!line_box_range(origin, s_unit, r_min_, r_max_, box_lo, box_hi)) return out;
  out.held = true;
  out.origin = origin;
  out.direction = s_unit;
  out.sigma_min = lo;
  out.sigma_max = hi;
  out.sigma_inf = sigma_inf;
  out.lever = lever;
  out.pose0.block<3, 1>(0, 0) = s_unit;
  out.pose0.block<3, 1>(0, 1) = a_unit.cross(s_unit);
  out.pose0.block<3, 1>(0, 2) = a_unit;
  out.pose0.block<3, 1>(0, 3) = origin;
  return out;
}

}  // namespace dqk

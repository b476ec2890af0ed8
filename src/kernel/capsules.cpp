#include "capsules.hpp"

#include <cmath>

namespace dqk {

namespace {

// Clip to [0, 1]; NaN stays NaN.
double unit_clip(double x) {
  if (x < 0.0) x = 0.0;
  if (x > 1.0) x = 1.0;
  return x;
}

// Sums in the order x, y, z.
double dot(const Point& u, const Point& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }

Point cross(const Point& x, const Point& y) {
  return Point(x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]);
}

// A fixed unit vector perpendicular to axis: the cross product of the unit axis with the
// coordinate axis it is least aligned with (the first on a tie), normalised; +z for a
// zero axis.
Point perpendicular(const Point& axis) {
  const double length = std::sqrt(dot(axis, axis));
  if (!(length > 0.0)) return Point(0.0, 0.0, 1.0);
  const Point u = axis / length;
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(u[i]) < std::abs(u[k])) k = i;
  Point helper = Point::Zero();
  helper[k] = 1.0;
  const Point v = cross(u, helper);
  return v / std::sqrt(dot(v, v));
}

// The normal of two capsules whose axes meet (the rule of distance.py's docstring).
Point meeting_normal(const Point& a0, const Point& a1, const Point& b0, const Point& b1) {
  const Point d1 = a1 - a0, d2 = b1 - b0;
  const Point n = cross(d1, d2);
  const double n_len = std::sqrt(dot(n, n));
  const double len1 = std::sqrt(dot(d1, d1)), len2 = std::sqrt(dot(d2, d2));
  if (n_len > 1e-9 * len1 * len2) {
    const Point w = b0 + b1 - a0 - a1;
    // Scaled by its largest component first: the cross product of a very short axis
    // squares into subnormal numbers.
    Point nc = n / n.cwiseAbs().maxCoeff();
    nc /= std::sqrt(dot(nc, nc));
    // Axes that truly cross lie in one plane: w . nc is then zero but for rounding, and
    // a tie (within MEETING_TIE of the coordinates' size) keeps +nc.
    const double size = a0.cwiseAbs().sum() + a1.cwiseAbs().sum() + b0.cwiseAbs().sum() +
                        b1.cwiseAbs().sum();
    return dot(w, nc) < -MEETING_TIE * size ? Point(-nc) : nc;
  }
  return perpendicular(len1 > 0.0 ? d1 : d2);
}

}  // namespace

SegmentPoints closest_points(const Point& p0, const Point& p1, const Point& q0,
                             const Point& q1) {
  const Point d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = dot(d1, d1), e = dot(d2, d2), b = dot(d1, d2);
  const double c = dot(d1, r), f = dot(d2, r);
  const double a_safe = a == 0.0 ? 1.0 : a;  // a == 0: b = c = 0, s stays 0
  const double e_safe = e == 0.0 ? 1.0 : e;  // e == 0: b = f = 0, t stays 0
  // The lines' stationary t, from r and d2 with their parts along d1 removed.
  const Point perp = d2 - (b / a_safe) * d1;
  const double pp = dot(perp, perp);
  double t = unit_clip(dot(r - (c / a_safe) * d1, perp) / (pp == 0.0 ? 1.0 : pp));
  double s = unit_clip((t * b - c) / a_safe);
  t = unit_clip((s * b + f) / e_safe);
  s = unit_clip((t * b - c) / a_safe);
  return {s, t, p0 + s * d1, q0 + t * d2};
}

CapsuleProximity capsule_proximity(const Point& a0, const Point& a1, double ra,
                                   const Point& b0, const Point& b1, double rb) {
  const SegmentPoints c = closest_points(a0, a1, b0, b1);
  const Point gap = c.y - c.x;
  const double axis = std::sqrt(dot(gap, gap));
  CapsuleProximity out;
  out.distance = axis - ra - rb;
  out.normal = axis <= TOUCH_TOL ? meeting_normal(a0, a1, b0, b1) : Point(gap / axis);
  out.point_a = c.x + ra * out.normal;
  out.point_b = c.y - rb * out.normal;
  return out;
}

void capsule_proximities(const Eigen::Ref<const Points>& a0, const Eigen::Ref<const Points>& a1,
                         const Eigen::Ref<const Eigen::VectorXd>& ra,
                         const Eigen::Ref<const Points>& b0, const Eigen::Ref<const Points>& b1,
                         const Eigen::Ref<const Eigen::VectorXd>& rb,
                         Eigen::Ref<Eigen::VectorXd> distance, Eigen::Ref<Points> point_a,
                         Eigen::Ref<Points> point_b, Eigen::Ref<Points> normal) {
  for (Eigen::Index k = 0; k < ra.size(); ++k) {
    const CapsuleProximity p = capsule_proximity(a0.row(k).transpose(), a1.row(k).transpose(),
                                                 ra[k], b0.row(k).transpose(),
                                                 b1.row(k).transpose(), rb[k]);
    distance[k] = p.distance;
    point_a.row(k) = p.point_a.transpose();
    point_b.row(k) = p.point_b.transpose();
    normal.row(k) = p.normal.transpose();
  }
}

}  // namespace dqk

// Closest points of segments and the proximity of capsules: the closed form of
// dualarm_qp/geometry/distance.py (its module docstring states the conventions and the
// rule for the normal when two axes meet), one pair at a time and over many pairs.
#pragma once

#include <Eigen/Dense>

namespace dqk {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Point = Eigen::Vector3d;

// Axis distance [m] at or below which two capsule axes count as meeting.
constexpr double TOUCH_TOL = 1e-12;
// Two meeting axes' midpoint offset along their common perpendicular counts as zero
// (a tie) within this times the sum of the endpoints' absolute coordinates: sixteen
// ulps of rounding.
constexpr double MEETING_TIE = 16.0 * 2.220446049250313e-16;

struct SegmentPoints {
  double s;  // parameter in [0, 1] of x on [p0, p1]
  double t;  // parameter in [0, 1] of y on [q0, q1]
  Point x;
  Point y;
};

// Closest points of the segments [p0, p1] and [q0, q1] (Lumelsky's clamping sequence
// from the lines' common perpendicular; parts along d1 removed first). NaN in, NaN out.
SegmentPoints closest_points(const Point& p0, const Point& p1, const Point& q0,
                             const Point& q1);

struct CapsuleProximity {
  double distance;  // axis distance minus both radii [m]
  Point point_a;    // on a's surface
  Point point_b;    // on b's surface
  Point normal;     // unit, from a to b
};

// The proximity of the capsules (a0, a1, ra) and (b0, b1, rb). Radii and finiteness are
// the caller's to check (a NaN anywhere gives a NaN distance).
CapsuleProximity capsule_proximity(const Point& a0, const Point& a1, double ra,
                                   const Point& b0, const Point& b1, double rb);

// Row k of each output is pair k's: distance (k), point_a, point_b, normal (k x 3).
void capsule_proximities(const Eigen::Ref<const Points>& a0, const Eigen::Ref<const Points>& a1,
                         const Eigen::Ref<const Eigen::VectorXd>& ra,
                         const Eigen::Ref<const Points>& b0, const Eigen::Ref<const Points>& b1,
                         const Eigen::Ref<const Eigen::VectorXd>& rb,
                         Eigen::Ref<Eigen::VectorXd> distance, Eigen::Ref<Points> point_a,
                         Eigen::Ref<Points> point_b, Eigen::Ref<Points> normal);

}  // namespace dqk

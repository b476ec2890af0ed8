#include "coal_pairs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <coal/math/transform.h>
#include <coal/shape/geometric_shapes.h>

namespace dqk {

namespace {

std::shared_ptr<coal::CollisionGeometry> geometry(int kind, const Point& p) {
  switch (kind) {
    case COAL_NONE:
      return nullptr;
    case COAL_BOX:
      return std::make_shared<coal::Box>(p(0), p(1), p(2));
    case COAL_CAPSULE:
      return std::make_shared<coal::Capsule>(p(0), p(1));
    case COAL_SPHERE:
      return std::make_shared<coal::Sphere>(p(0));
    default:
      throw std::invalid_argument("CoalPairs: a body's kind is 0 (none) to 3 (sphere)");
  }
}

// _fallback_normal: the witness points' direction signed by the distance, else the
// direction between the origins, else +z.
Point fallback_normal(const Point& gap, double distance, const Point& centres) {
  const Point first = gap * (distance >= 0.0 ? 1.0 : -1.0);
  for (const Point* v : {&first, &centres}) {
    const double length = std::sqrt(v->dot(*v));
    if (length > TOUCH_TOL) return *v / length;
  }
  return Point(0.0, 0.0, 1.0);
}

// A lower bound of the distance from the capsule c to the box of pose T (world) and
// half sizes h, when the bound is positive (CoalPairs::lower_bound), else -inf: the
// gaps between their intervals along the box's axes, less c's radius.
double slab_bound(const Eigen::Matrix4d& T, const Point& h, const WorldCapsule& c) {
  const auto R = T.block<3, 3>(0, 0);
  const Point o = T.block<3, 1>(0, 3);
  const Point l0 = R.transpose() * (c.p0 - o), l1 = R.transpose() * (c.p1 - o);
  const Point gap = (l0.cwiseMin(l1) - h).cwiseMax(-h - l0.cwiseMax(l1)).cwiseMax(0.0);
  const double apart = gap.norm() - c.r;
  return apart > 0.0 ? apart : -std::numeric_limits<double>::infinity();
}

}  // namespace

CoalPairs::CoalPairs(const std::vector<int>& kinds, const Eigen::Ref<const Points>& params,
                     const Eigen::Ref<const RowMat>& local, const std::vector<int>& ia,
                     const std::vector<int>& ib, const std::vector<bool>& boxed,
                     double gjk_tol, double epa_tol)
    : kinds_(kinds), ia_(ia), ib_(ib) {
  const auto nb = static_cast<Eigen::Index>(kinds.size());
  if (params.rows() != nb || local.rows() != 4 * nb || local.cols() != 4 ||
      ia.size() != ib.size() || boxed.size() != ia.size())
    throw std::invalid_argument("CoalPairs: arrays of inconsistent shapes");
  geoms_.reserve(kinds.size());
  local_.reserve(kinds.size());
  half_.reserve(kinds.size());
  for (Eigen::Index i = 0; i < nb; ++i) {
    const int kind = kinds[static_cast<size_t>(i)];
    geoms_.push_back(geometry(kind, params.row(i).transpose()));
    local_.emplace_back(local.block<4, 4>(4 * i, 0));
    half_.push_back(kind == COAL_BOX ? Point(0.5 * params.row(i).transpose()) : Point::Zero());
  }
  request_.gjk_tolerance = gjk_tol;
  request_.epa_tolerance = epa_tol;
  solvers_.resize(ia.size());
  for (size_t k = 0; k < ia.size(); ++k) {
    if (!boxed[k]) continue;
    const int a = ia[k], b = ib[k];
    if (a < 0 || a >= nb || b < 0 || b >= nb)
      throw std::invalid_argument("CoalPairs: no such body");
    if (!geoms_[size_t(a)] || !geoms_[size_t(b)])
      throw std::invalid_argument("CoalPairs: a pair with a box needs both bodies' geometry");
    solvers_[k] = std::make_unique<coal::ComputeDistance>(geoms_[size_t(a)].get(),
                                                          geoms_[size_t(b)].get());
  }
}

CapsuleProximity CoalPairs::measure(size_t pair, const Eigen::Matrix4d& frame_a,
                                    const Eigen::Matrix4d& frame_b) const {
  if (pair >= solvers_.size() || !solvers_[pair])
    throw std::invalid_argument("CoalPairs: not a pair with a box");
  const Eigen::Matrix4d T_a = frame_a * local_[size_t(ia_[pair])];
  const Eigen::Matrix4d T_b = frame_b * local_[size_t(ib_[pair])];
  const coal::Transform3s tf_a(Eigen::Matrix3d(T_a.block<3, 3>(0, 0)),
                               Eigen::Vector3d(T_a.block<3, 1>(0, 3)));
  const coal::Transform3s tf_b(Eigen::Matrix3d(T_b.block<3, 3>(0, 0)),
                               Eigen::Vector3d(T_b.block<3, 1>(0, 3)));
  coal::DistanceResult result;
  CapsuleProximity out;
  out.distance = (*solvers_[pair])(tf_a, tf_b, request_, result);
  out.point_a = result.nearest_points[0];
  out.point_b = result.nearest_points[1];
  const Point normal = result.normal;
  const double length = std::sqrt(normal.dot(normal));  // NaN for a non-finite normal
  if (!(std::abs(length - 1.0) <= 1e-6)) {
    out.normal = fallback_normal(out.point_b - out.point_a, out.distance,
                                 T_b.block<3, 1>(0, 3) - T_a.block<3, 1>(0, 3));
  } else {
    out.normal = normal / length;
  }
  return out;
}

double CoalPairs::lower_bound(size_t pair, const Eigen::Matrix4d& frame_a,
                              const Eigen::Matrix4d& frame_b, const WorldCapsule& a,
                              const WorldCapsule& b) const {
  if (pair >= solvers_.size() || !solvers_[pair])
    throw std::invalid_argument("CoalPairs: not a pair with a box");
  const size_t ia = size_t(ia_[pair]), ib = size_t(ib_[pair]);
  double bound = -std::numeric_limits<double>::infinity();
  if (kinds_[ia] == COAL_BOX) bound = slab_bound(frame_a * local_[ia], half_[ia], b);
  if (kinds_[ib] == COAL_BOX)
    bound = std::max(bound, slab_bound(frame_b * local_[ib], half_[ib], a));
  return bound;
}

}  // namespace dqk

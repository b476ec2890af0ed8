#include "standard_parts.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "boxes.hpp"

namespace dqk {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

// numpy's maximum and minimum: a NaN in either argument passes through, and on a tie the
// second argument is returned (which decides the sign of a zero: np.maximum(0.0, -0.0)
// is -0.0).
double larger(double a, double b) {
  if (std::isnan(a)) return a;
  if (std::isnan(b)) return b;
  return a > b ? a : b;
}
double smaller(double a, double b) {
  if (std::isnan(a)) return a;
  if (std::isnan(b)) return b;
  return a < b ? a : b;
}

}  // namespace

Equality ObjectPathTask::equality(const Context& ctx) const {
  const Index n_l = ctx.n_l, n_f = ctx.n_f, k = ctx.k;
  Equality eq;
  eq.A.resize(6, ctx.n);
  eq.A.leftCols(n_l) = ctx.J_object.leftCols(n_l);
  eq.A.middleCols(n_l, n_f).setZero();
  eq.A.rightCols(k) = ctx.J_object.rightCols(k);
  eq.b = ctx.scale_max * ctx.twist + gain * ctx.leader_error;
  eq.names = {"object vx", "object vy", "object vz", "object wx", "object wy", "object wz"};
  return eq;
}

Equality GraspClosureTask::equality(const Context& ctx) const {
  const Index n_l = ctx.n_l, n_f = ctx.n_f, k = ctx.k;
  Equality eq;
  eq.A.resize(6, ctx.n);
  eq.A.leftCols(n_l) = -ctx.J_target.leftCols(n_l);
  eq.A.middleCols(n_l, n_f) = ctx.J_f;
  eq.A.rightCols(k) = -ctx.J_target.rightCols(k);
  if (!exact_orientation) eq.A.bottomRows<3>().col(n_l + n_f).setZero();
  eq.b = gain * ctx.closure_error;
  eq.names = {"closure vx", "closure vy", "closure vz",
              "closure wx", "closure wy", "closure wz"};
  return eq;
}

CentringCost::CentringCost(Vec weights, BoolVec centred, double shrink)
    : w_(std::move(weights)), centred_(std::move(centred)), shrink_(shrink) {
  if (centred_.size() != w_.size() || !(w_.array() > 0.0).all() || !std::isfinite(shrink))
    throw std::invalid_argument(
        "CentringCost: one positive weight and one centred flag per variable, a finite shrink");
}

Quadratic CentringCost::quadratic(const Context& ctx) const {
  if (w_.size() != ctx.n) throw std::invalid_argument("CentringCost: sized for another step");
  Quadratic q;
  q.w = w_;
  q.center = centre(ctx.rate_lo, ctx.rate_hi, centred_, shrink_);
  return q;
}

RangeLimit::RangeLimit(Vec rec, BoolVec off) : rec_(std::move(rec)), off_(std::move(off)) {
  if (rec_.size() != off_.size())
    throw std::invalid_argument("RangeLimit: one recovery rate and one flag per variable");
}

Constraint RangeLimit::constraint(const Context& ctx) const {
  if (rec_.size() != ctx.n) throw std::invalid_argument("RangeLimit: sized for another step");
  Constraint c;
  c.has_lower = c.has_upper = true;
  range_box(ctx.rate_lo, ctx.rate_hi, rec_, off_, c.lower, c.upper);
  return c;
}

Constraint SpeedLimit::constraint(const Context& ctx) const {
  if (v_.size() != ctx.n) throw std::invalid_argument("SpeedLimit: sized for another step");
  Constraint c;
  c.has_lower = c.has_upper = true;
  c.lower = -v_;
  c.upper = v_;
  return c;
}

double braking_bound(double D, double delta, double dt) {
  if (!(std::isfinite(D) && std::isfinite(delta))) return INF;
  const double Dd = larger(D, 0.0);
  const double n = std::floor(0.5 * (-1.0 + std::sqrt(1.0 + 8.0 * Dd / (delta * dt))));
  return (Dd / dt + delta * n * (n + 1.0) / 2.0) / (n + 1.0);
}

Constraint AccelerationLimit::constraint(const Context& ctx) const {
  const Index n = ctx.n;
  if (delta_.size() != n || ctx.x_applied.size() != n)
    throw std::invalid_argument("AccelerationLimit: sized for another step");
  const double dt = ctx.dt;
  Constraint c;
  c.has_lower = c.has_upper = true;
  c.lower.resize(n);
  c.upper.resize(n);
  for (Index i = 0; i < n; ++i) {
    const double delta = delta_(i);
    const double d_up = ctx.rate_hi(i) * dt;
    const double d_lo = -ctx.rate_lo(i) * dt;
    const double v_up = d_up >= 0.0 ? braking_bound(d_up, delta, dt) : INF;
    const double v_lo = d_lo >= 0.0 ? braking_bound(d_lo, delta, dt) : INF;
    c.lower(i) = larger(ctx.x_applied(i) - delta, -v_lo);
    c.upper(i) = smaller(ctx.x_applied(i) + delta, v_up);
  }
  return c;
}

CollisionLimit::CollisionLimit(const DamperScene* damper, std::vector<std::string> names,
                               std::string nonfinite)
    : damper_(damper), names_(std::move(names)), nonfinite_(std::move(nonfinite)) {
  if (damper_ == nullptr) throw std::invalid_argument("CollisionLimit: no damper");
}

Constraint CollisionLimit::constraint(const Context& ctx) const {
  if (ctx.leader == nullptr || ctx.follower == nullptr)
    throw std::invalid_argument("CollisionLimit: a context without the arms' chains");
  DamperRows r = damper_->rows(*ctx.leader, *ctx.follower, ctx.J_object, RowMat(ctx.T_object));
  Constraint c;
  if (!r.finite) {
    c.nonfinite = nonfinite_;
    return c;
  }
  c.G = std::move(r.G);
  c.h = std::move(r.h);
  c.row_names.reserve(r.pairs.size());
  for (int pair : r.pairs) c.row_names.push_back(names_.at(static_cast<size_t>(pair)));
  return c;
}

}  // namespace dqk

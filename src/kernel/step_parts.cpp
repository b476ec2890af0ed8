#include "step_parts.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "boxes.hpp"
#include "step_kinematics.hpp"

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

double braking_bound(double D, double delta, double dt) {
  if (!(std::isfinite(D) && std::isfinite(delta))) return INF;
  const double Dd = larger(D, 0.0);
  const double n = std::floor(0.5 * (-1.0 + std::sqrt(1.0 + 8.0 * Dd / (delta * dt))));
  return (Dd / dt + delta * n * (n + 1.0) / 2.0) / (n + 1.0);
}

void limit_box(const BoxForm& form, const Vec& lo, const Vec& hi, const Vec& x_applied,
               double dt, Vec& lower, Vec& upper) {
  const Index n = lo.size();
  if (hi.size() != n || x_applied.size() != n || form.p.size() != n ||
      (form.kind == RANGE && form.off.size() != n)) {
    throw std::invalid_argument("limit_box: lo, hi, x_applied and the form of different lengths");
  }
  switch (form.kind) {
    case RANGE:
      range_box(lo, hi, form.p, form.off, lower, upper);
      return;
    case SPEED:
      lower = -form.p;
      upper = form.p;
      return;
    case ACCELERATION: {
      lower.resize(n);
      upper.resize(n);
      for (Index i = 0; i < n; ++i) {
        const double delta = form.p(i);
        const double d_up = hi(i) * dt;
        const double d_lo = -lo(i) * dt;
        const double v_up = d_up >= 0.0 ? braking_bound(d_up, delta, dt) : INF;
        const double v_lo = d_lo >= 0.0 ? braking_bound(d_lo, delta, dt) : INF;
        lower(i) = larger(x_applied(i) - delta, -v_lo);
        upper(i) = smaller(x_applied(i) + delta, v_up);
      }
      return;
    }
    default:
      throw std::invalid_argument("limit_box: unknown kind of box");
  }
}

StepParts::StepParts(Index n_l, Index n_f, std::vector<int> carry_frames, int follower_tool,
                     std::vector<int> cols, Vec q_min, Vec q_max, double dt,
                     BoolVec centred, double shrink, BoolVec ranged, double pin_rtol)
    : n_l_(n_l),
      n_f_(n_f),
      k_(static_cast<Index>(cols.size()) - n_l),
      n_(n_l + n_f + k_),
      carry_frames_(std::move(carry_frames)),
      follower_tool_(follower_tool),
      cols_(std::move(cols)),
      q_min_(std::move(q_min)),
      q_max_(std::move(q_max)),
      dt_(dt),
      centred_(std::move(centred)),
      shrink_(shrink),
      ranged_(std::move(ranged)),
      pin_rtol_(pin_rtol) {
  if (n_l < 0 || n_f < 0 || k_ < 0 || carry_frames_.size() != 3 || q_min_.size() != n_l + n_f ||
      q_max_.size() != n_l + n_f || centred_.size() != n_ || ranged_.size() != n_ ||
      !(dt > 0.0) || !(pin_rtol >= 0.0)) {
    throw std::invalid_argument(
        "StepParts: three carry frames, ranges of both arms' joints, one centred and one "
        "ranged flag per variable, dt > 0 and pin_rtol >= 0");
  }
  for (int c : cols_) {
    if (c < 0) throw std::invalid_argument("StepParts: a negative column");
  }
}

void StepParts::add_form(int kind, const Vec& p, const BoolVec& off, std::int64_t limit) {
  if (kind != RANGE && kind != SPEED && kind != ACCELERATION)
    throw std::invalid_argument("StepParts.add_form: kind is RANGE, SPEED or ACCELERATION");
  if (p.size() != n_ || (kind == RANGE && off.size() != n_))
    throw std::invalid_argument("StepParts.add_form: one value per variable");
  if (limit < 0 || (!forms_.empty() && limit <= forms_.back().limit))
    throw std::invalid_argument(
        "StepParts.add_form: the limits' indices are >= 0 and increase from form to form");
  forms_.push_back(BoxForm{kind, p, off, limit});
}

void StepParts::add_rows(const DamperScene* damper, std::int64_t limit) {
  if (damper == nullptr) throw std::invalid_argument("StepParts.add_rows: no damper");
  if (limit < 0 || (!damper_limits_.empty() && limit <= damper_limits_.back()))
    throw std::invalid_argument(
        "StepParts.add_rows: the limits' indices are >= 0 and increase from one to the next");
  dampers_.push_back(damper);
  damper_limits_.push_back(limit);
}

void StepParts::add_grasp_line(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                               const Eigen::Vector3d& r_min, const Eigen::Vector3d& r_max,
                               double sigma_min, double sigma_max) {
  if (static_cast<Index>(lines_.size()) >= k_)
    throw std::invalid_argument("StepParts.add_grasp_line: one line per grasp at most");
  lines_.push_back(GraspLine{origin, direction, r_min, r_max, sigma_min, sigma_max});
}

StepPartsOut StepParts::prepare(Chain& carry, const Eigen::VectorXd& q_carry,
                                const Vec& col_rate, Chain& follower,
                                const Eigen::VectorXd& q_f, const Pose& T_D, const Vec6& twist,
                                const Vec& sigmas, const Vec& grasp_lo, const Vec& grasp_hi,
                                const Vec& x_applied, double scale_max, double leader_gain,
                                double correction_gain, bool exact_orientation) const {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const Index nq = carry.nq();
  const bool lines = grasp_lines();
  if (q_carry.size() != nq || q_f.size() != n_f_ || follower.nq() != n_f_ ||
      col_rate.size() != static_cast<Index>(cols_.size()) || sigmas.size() != k_ ||
      (!lines && (grasp_lo.size() != k_ || grasp_hi.size() != k_)) || x_applied.size() != n_) {
    throw std::invalid_argument(
        "StepParts.prepare: q_carry, col_rate, q_f, sigmas, grasp_lo, grasp_hi or x_applied "
        "of a wrong length");
  }
  for (int c : cols_) {
    if (c >= nq) throw std::invalid_argument("StepParts.prepare: a column past the chain's");
  }
  StepPartsOut o;
  o.T.resize(16, 4);
  RowMat J(18, nq);
  o.J_f.resize(6, n_f_);
  o.e.resize(12);
  Vec no_sv(0);  // the arms' smallest singular values: computed when read (Python)
  step_kinematics(carry, q_carry, carry_frames_, follower, q_f, follower_tool_, T_D, n_l_, o.T,
                  J, o.J_f, o.e, no_sv);
  const Index nd = static_cast<Index>(cols_.size());
  o.J_tool = J.block(0, 0, 6, n_l_);
  o.J_object.resize(6, nd);
  o.J_target.resize(6, nd);
  for (Index j = 0; j < nd; ++j) {
    o.J_object.col(j) = J.block(6, cols_[j], 6, 1) * col_rate(j);
    o.J_target.col(j) = J.block(12, cols_[j], 6, 1) * col_rate(j);
  }
  o.lo.resize(n_);
  o.hi.resize(n_);
  for (Index i = 0; i < n_l_ + n_f_; ++i) {
    const double q = i < n_l_ ? q_carry(i) : q_f(i - n_l_);
    o.lo(i) = (q_min_(i) - q) / dt_;
    o.hi(i) = (q_max_(i) - q) / dt_;
  }
  if (lines) {
    for (Index g = 0; g < k_; ++g) {
      const GraspLine& line = lines_[static_cast<size_t>(g)];
      const double sigma = sigmas(g);
      Eigen::Vector3d point;
      for (Index i = 0; i < 3; ++i) point(i) = line.origin(i) + sigma * line.direction(i);
      const auto [lo, hi] = grasp_rates(point, line.direction, sigma, line.r_min, line.r_max,
                                        line.sigma_min, line.sigma_max, dt_);
      o.lo(n_l_ + n_f_ + g) = lo;
      o.hi(n_l_ + n_f_ + g) = hi;
    }
  } else {
    o.lo.tail(k_) = grasp_lo;
    o.hi.tail(k_) = grasp_hi;
  }
  o.kinematics_seconds = std::chrono::duration<double>(clock::now() - start).count();

  o.A.resize(12, n_);
  o.b.resize(12);
  const Vec6 e_l = o.e.head<6>(), e_c = o.e.tail<6>();
  o.equality_finite = carry_equality(n_l_, o.J_object, o.J_target, o.J_f, twist, e_l, e_c,
                                     scale_max, leader_gain, correction_gain, exact_orientation,
                                     o.A, o.b);
  o.center = centre(o.lo, o.hi, centred_, shrink_);
  const Index m = forms();
  o.lowers.resize(m, n_);
  o.uppers.resize(m, n_);
  Vec lower, upper;
  std::vector<std::int64_t> ids(static_cast<size_t>(m));
  for (Index f = 0; f < m; ++f) {
    const BoxForm& form = forms_[static_cast<size_t>(f)];
    limit_box(form, o.lo, o.hi, x_applied, dt_, lower, upper);
    o.lowers.row(f) = lower.transpose();
    o.uppers.row(f) = upper.transpose();
    ids[static_cast<size_t>(f)] = form.limit;
  }
  o.box = intersect_boxes(o.lowers, ids, o.uppers, ids, n_, pin_rtol_);
  o.recovering.resize(n_);
  for (Index i = 0; i < n_; ++i) {
    o.recovering(i) = ranged_(i) && (o.lo(i) > 0.0 || o.hi(i) < 0.0);
    o.any_recovering = o.any_recovering || o.recovering(i);
  }
  // The compiled row limits at the kinematics the chains now hold (what their
  // constraint(ctx) computes from the same chains, J_object and T_object).
  for (const DamperScene* damper : dampers_)
    o.rows.push_back(damper->rows(carry, follower, o.J_object, o.T.middleRows(4, 4)));
  return o;
}

}  // namespace dqk

#include "step.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "boxes.hpp"
#include "step_kinematics.hpp"

namespace dqk {

std::pair<double, double> StepOut::sigma_min() {
  if (!sigma_known_) {
    sigma_min_ = {smallest_singular_value(Mat(context.J_tool)),
                  smallest_singular_value(Mat(context.J_f))};
    sigma_known_ = true;
  }
  return sigma_min_;
}

Step::Step(Index n_l, Index n_f, std::vector<int> carry_frames, int follower_tool,
           std::vector<int> cols, Vec q_min, Vec q_max, double dt, BoolVec ranged,
           double pin_rtol)
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
      ranged_(std::move(ranged)),
      pin_rtol_(pin_rtol) {
  if (n_l < 0 || n_f < 0 || k_ < 0 || carry_frames_.size() != 3 || q_min_.size() != n_l + n_f ||
      q_max_.size() != n_l + n_f || ranged_.size() != n_ || !(dt > 0.0) || !(pin_rtol >= 0.0)) {
    throw std::invalid_argument(
        "Step: three carry frames, ranges of both arms' joints, one ranged flag per "
        "variable, dt > 0 and pin_rtol >= 0");
  }
  for (int c : cols_) {
    if (c < 0) throw std::invalid_argument("Step: a negative column");
  }
}

void Step::add_task(const Task* task) {
  if (task == nullptr) throw std::invalid_argument("Step.add_task: no task");
  tasks_.push_back(task);
}

void Step::add_cost(const CostTerm* cost) {
  if (cost == nullptr) throw std::invalid_argument("Step.add_cost: no cost term");
  costs_.push_back(cost);
}

void Step::add_limit(const Limit* limit) {
  if (limit == nullptr) throw std::invalid_argument("Step.add_limit: no limit");
  limits_.push_back(limit);
}

void Step::add_grasp_line(const GraspLine& line) {
  if (static_cast<Index>(lines_.size()) >= k_)
    throw std::invalid_argument("Step.add_grasp_line: one line per grasp at most");
  lines_.push_back(line);
}

void Step::set_grasp_line(Index g, const GraspLine& line) {
  if (g < 0 || g >= static_cast<Index>(lines_.size()))
    throw std::invalid_argument("Step.set_grasp_line: no line of that grasp to replace");
  lines_[static_cast<size_t>(g)] = line;
}

void Step::context(Context& ctx, Chain& carry, const Eigen::VectorXd& q_carry,
                   const Vec& col_rate, Chain& follower, const Eigen::VectorXd& q_f,
                   const Pose& T_D, const Vec& sigmas, const Vec& grasp_lo,
                   const Vec& grasp_hi) const {
  const Index nq = carry.nq();
  RowMat T(16, 4), J(18, nq);
  ctx.J_f.resize(6, n_f_);
  Eigen::VectorXd e(12);
  Eigen::VectorXd no_sv(0);  // the arms' smallest singular values: computed when asked
  step_kinematics(carry, q_carry, carry_frames_, follower, q_f, follower_tool_, T_D, n_l_, T,
                  J, ctx.J_f, e, no_sv);
  ctx.T_tool = T.middleRows<4>(0);
  ctx.T_object = T.middleRows<4>(4);
  ctx.T_target = T.middleRows<4>(8);
  ctx.T_f = T.middleRows<4>(12);
  ctx.leader_error = e.head<6>();
  ctx.closure_error = e.tail<6>();
  const Index nd = static_cast<Index>(cols_.size());
  ctx.J_tool = J.block(0, 0, 6, n_l_);
  ctx.J_object.resize(6, nd);
  ctx.J_target.resize(6, nd);
  for (Index j = 0; j < nd; ++j) {
    ctx.J_object.col(j) = J.block(6, cols_[j], 6, 1) * col_rate(j);
    ctx.J_target.col(j) = J.block(12, cols_[j], 6, 1) * col_rate(j);
  }
  ctx.positions.resize(n_);
  ctx.rate_lo.resize(n_);
  ctx.rate_hi.resize(n_);
  for (Index i = 0; i < n_l_ + n_f_; ++i) {
    const double q = i < n_l_ ? q_carry(i) : q_f(i - n_l_);
    ctx.positions(i) = q;
    ctx.rate_lo(i) = (q_min_(i) - q) / dt_;
    ctx.rate_hi(i) = (q_max_(i) - q) / dt_;
  }
  ctx.positions.tail(k_) = sigmas;
  if (grasp_lines()) {
    for (Index g = 0; g < k_; ++g) {
      const GraspLine& line = lines_[static_cast<size_t>(g)];
      const double sigma = sigmas(g);
      Eigen::Vector3d point;
      for (Index i = 0; i < 3; ++i) point(i) = line.origin(i) + sigma * line.direction(i);
      const auto [lo, hi] = grasp_rates(point, line.direction, sigma, line.r_min, line.r_max,
                                        line.sigma_min, line.sigma_max, dt_);
      ctx.rate_lo(n_l_ + n_f_ + g) = lo;
      ctx.rate_hi(n_l_ + n_f_ + g) = hi;
    }
  } else {
    ctx.rate_lo.tail(k_) = grasp_lo;
    ctx.rate_hi.tail(k_) = grasp_hi;
  }
}

bool Step::tasks(StepOut& out) const {
  const Context& ctx = out.context;
  std::vector<Equality> rows;
  rows.reserve(tasks_.size());
  Index m = 0;
  RowMat W_sum;
  Vec g_sum;
  for (size_t i = 0; i < tasks_.size(); ++i) {
    Equality eq = tasks_[i]->equality(ctx);
    if (eq.A.cols() != n_ || eq.A.rows() != eq.b.size() ||
        (!eq.names.empty() && static_cast<Index>(eq.names.size()) != eq.b.size()))
      throw std::invalid_argument("Step: task " + std::to_string(i) +
                                  " gave rows of a wrong shape");
    if (!(eq.A.allFinite() && eq.b.allFinite())) {
      out.failed_part = static_cast<std::int64_t>(i);
      out.failed_kind = "task";
      return false;
    }
    const double weight = tasks_[i]->weight;
    if (std::isfinite(weight)) {  // a weighted task: weight |A x - b|^2 joins the cost
      if (W_sum.size() == 0) {
        W_sum = RowMat::Zero(n_, n_);
        g_sum = Vec::Zero(n_);
      }
      W_sum.noalias() += weight * eq.A.transpose() * eq.A;
      g_sum.noalias() += weight * eq.A.transpose() * eq.b;
      continue;
    }
    m += eq.A.rows();
    rows.push_back(std::move(eq));
  }
  if (rows.size() == 1) {
    out.A = std::move(rows[0].A);
    out.b = std::move(rows[0].b);
    out.eq_names = std::move(rows[0].names);
  } else {
    out.A.resize(m, n_);
    out.b.resize(m);
    out.eq_names.clear();
    Index at = 0;
    for (Equality& eq : rows) {
      out.A.middleRows(at, eq.A.rows()) = eq.A;
      out.b.segment(at, eq.b.size()) = eq.b;
      for (std::string& name : eq.names) out.eq_names.push_back(std::move(name));
      at += eq.A.rows();
    }
  }
  // The weighted tasks' sum, kept for the cost (costs() adds the cost terms).
  out.W = std::move(W_sum);
  out.center = std::move(g_sum);
  return true;
}

bool Step::costs(StepOut& out) const {
  const Context& ctx = out.context;
  // With no weighted task and one cost term (the paper's centring alone), the term is
  // the cost as it is; otherwise the terms are summed: W = sum W_i and W c = sum W_i c_i
  // (+ sum weight A^T b of the weighted tasks, held in out.W and out.center so far).
  RowMat W = std::move(out.W);
  Vec g = std::move(out.center);
  const bool weighted = W.size() != 0;
  bool diagonal = !weighted;
  Vec w_sum, wc_sum;
  for (size_t i = 0; i < costs_.size(); ++i) {
    Quadratic q = costs_[i]->quadratic(ctx);
    const bool ok_shape = q.center.size() == n_ &&
                          (q.diagonal() ? q.w.size() == n_
                                        : (q.W.rows() == n_ && q.W.cols() == n_));
    if (!ok_shape)
      throw std::invalid_argument("Step: cost term " + std::to_string(i) +
                                  " gave weights or a centre of a wrong shape");
    if (!(q.center.allFinite() && (q.diagonal() ? q.w.allFinite() : q.W.allFinite()))) {
      out.failed_part = static_cast<std::int64_t>(i);
      out.failed_kind = "cost";
      return false;
    }
    if (!weighted && costs_.size() == 1) {
      out.w = std::move(q.w);
      out.W = std::move(q.W);
      out.center = std::move(q.center);
      return true;
    }
    if (diagonal && q.diagonal()) {
      if (w_sum.size() == 0) {
        w_sum = Vec::Zero(n_);
        wc_sum = Vec::Zero(n_);
      }
      w_sum += q.w;
      wc_sum += q.w.cwiseProduct(q.center);
      continue;
    }
    if (W.size() == 0) {
      W = RowMat::Zero(n_, n_);
      g = Vec::Zero(n_);
    }
    if (diagonal && w_sum.size() != 0) {  // the diagonal terms so far join the full sum
      W.diagonal() += w_sum;
      g += wc_sum;
      w_sum.resize(0);
    }
    diagonal = false;
    if (q.diagonal()) {
      W.diagonal() += q.w;
      g += q.w.cwiseProduct(q.center);
    } else {
      W += q.W;
      g.noalias() += q.W * q.center;
    }
  }
  if (diagonal) {
    if (w_sum.size() == 0)
      throw std::invalid_argument("Step: no cost term (the step's cost is not defined)");
    out.center = wc_sum.cwiseQuotient(w_sum);
    out.w = std::move(w_sum);
    out.W.resize(0, 0);
    return true;
  }
  Eigen::LLT<Mat> llt{Mat(W)};
  if (llt.info() != Eigen::Success) {
    out.failed_part = -2;  // the sum, not one part
    out.failed_kind = "cost";
    out.failure = "the cost (its terms and weighted tasks summed) is not positive definite";
    return false;
  }
  out.center = llt.solve(g);
  out.W = std::move(W);
  out.w.resize(0);
  return true;
}

bool Step::limits(StepOut& out) const {
  const Context& ctx = out.context;
  const size_t count = limits_.size();
  std::vector<Constraint> given;
  given.reserve(count);
  Index lowers = 0, uppers = 0, p = 0;
  for (size_t k = 0; k < count; ++k) {
    Constraint c = limits_[k]->constraint(ctx);
    if (!c.nonfinite.empty()) {
      out.failed_part = static_cast<std::int64_t>(k);
      out.failed_kind = "limit";
      out.failure = std::move(c.nonfinite);
      return false;
    }
    if ((c.has_lower && c.lower.size() != n_) || (c.has_upper && c.upper.size() != n_) ||
        c.G.rows() != c.h.size() || (c.G.rows() > 0 && c.G.cols() != n_) ||
        (!c.row_names.empty() && static_cast<Index>(c.row_names.size()) != c.h.size()))
      throw std::invalid_argument("Step: limit " + std::to_string(k) +
                                  " gave bounds or rows of a wrong shape");
    lowers += c.has_lower;
    uppers += c.has_upper;
    p += c.h.size();
    given.push_back(std::move(c));
  }
  BoundRows L(lowers, n_), U(uppers, n_);
  std::vector<std::int64_t> lower_ids, upper_ids;
  out.G.resize(p, n_);
  out.h.resize(p);
  out.row_names.clear();
  out.row_limit.clear();
  Index at = 0;
  for (size_t k = 0; k < count; ++k) {
    Constraint& c = given[k];
    if (c.has_lower) {
      L.row(static_cast<Index>(lower_ids.size())) = c.lower.transpose();
      lower_ids.push_back(static_cast<std::int64_t>(k));
    }
    if (c.has_upper) {
      U.row(static_cast<Index>(upper_ids.size())) = c.upper.transpose();
      upper_ids.push_back(static_cast<std::int64_t>(k));
    }
    const Index rows = c.h.size();
    if (rows == 0) continue;
    out.G.middleRows(at, rows) = c.G;
    out.h.segment(at, rows) = c.h;
    for (Index r = 0; r < rows; ++r) {
      out.row_limit.push_back(static_cast<std::int64_t>(k));
      out.row_names.push_back(c.row_names.empty() ? std::string()
                                                  : std::move(c.row_names[size_t(r)]));
    }
    at += rows;
  }
  out.box = intersect_boxes(L, lower_ids, U, upper_ids, n_, pin_rtol_);
  if (out.box.nan_limit >= 0) {
    out.failed_part = out.box.nan_limit;
    out.failed_kind = "limit";
    return false;
  }
  return true;
}

void Step::build(StepOut& out, Chain& carry, const Eigen::VectorXd& q_carry,
                 const Vec& col_rate, Chain& follower, const Eigen::VectorXd& q_f,
                 const Pose& T_D, const Vec6& twist, const Vec& sigmas, const Vec& grasp_lo,
                 const Vec& grasp_hi, const Vec& x_applied, double t, double scale_max,
                 void* user) const {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const Index nq = carry.nq();
  if (q_carry.size() != nq || q_f.size() != n_f_ || follower.nq() != n_f_ ||
      col_rate.size() != static_cast<Index>(cols_.size()) || sigmas.size() != k_ ||
      (!grasp_lines() && (grasp_lo.size() != k_ || grasp_hi.size() != k_)) ||
      x_applied.size() != n_) {
    throw std::invalid_argument(
        "Step.build: q_carry, col_rate, q_f, sigmas, grasp_lo, grasp_hi or x_applied of a "
        "wrong length");
  }
  for (int c : cols_) {
    if (c >= nq) throw std::invalid_argument("Step.build: a column past the chain's");
  }
  out.labels = labels_;
  out.failed_part = -1;
  out.failed_kind.clear();
  out.failure.clear();
  Context& ctx = out.context;
  ctx.n_l = n_l_;
  ctx.n_f = n_f_;
  ctx.k = k_;
  ctx.n = n_;
  ctx.t = t;
  ctx.dt = dt_;
  ctx.scale_max = scale_max;
  ctx.twist = twist;
  ctx.x_applied = x_applied;
  ctx.leader = &carry;
  ctx.follower = &follower;
  ctx.user = user;
  context(ctx, carry, q_carry, col_rate, follower, q_f, T_D, sigmas, grasp_lo, grasp_hi);
  out.kinematics_seconds = std::chrono::duration<double>(clock::now() - start).count();
  out.recovering.resize(n_);
  out.any_recovering = false;
  for (Index i = 0; i < n_; ++i) {
    out.recovering(i) = ranged_(i) && (ctx.rate_lo(i) > 0.0 || ctx.rate_hi(i) < 0.0);
    out.any_recovering = out.any_recovering || out.recovering(i);
  }
  if (tasks(out) && costs(out)) limits(out);
  ctx.user = nullptr;  // valid during the build only
  out.seconds = std::chrono::duration<double>(clock::now() - start).count();
}

}  // namespace dqk

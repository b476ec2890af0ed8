#include "nullspace.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "constants.hpp"
#include "dense_qp.hpp"

namespace dqk {

bool interval(const Vec& c, const Vec& f, double t_free, double tol, double* t,
              Index* lo_row, Index* hi_row) {
  constexpr double INF = std::numeric_limits<double>::infinity();
  double t_hi = INF, t_lo = -INF;
  Index i_hi = -1, i_lo = -1;
  for (Index i = 0; i < c.size(); ++i) {
    const double ratio = f(i) / c(i);
    if (c(i) > 0.0) {
      if (i_hi < 0 || ratio < t_hi) {  // first minimum, as argmin
        t_hi = ratio;
        i_hi = i;
      }
    } else if (i_lo < 0 || ratio > t_lo) {  // first maximum, as argmax
      t_lo = ratio;
      i_lo = i;
    }
  }
  if (t_lo > t_hi) {
    if (t_lo - t_hi > 2.0 * tol) {
      *t = 0.0;
      *lo_row = i_lo;
      *hi_row = i_hi;
      return false;
    }
    *t = 0.5 * (t_lo + t_hi);
    return true;
  }
  *t = std::min(std::max(t_free, t_lo), t_hi);
  return true;
}

StepAnswer solve_nullspace(const Mat& A, const Vec& b, const Basis& fa, const Mat& C,
                           const Vec& e, const Cost& cost, double feas_tol,
                           Index max_iter) {
  StepAnswer out{StepCode::optimal, Vec(), {}, -1, -1};
  const auto x0_opt = affine_point(A, b, fa);
  if (!x0_opt) {
    out.code = StepCode::inconsistent;
    out.x = Vec::Zero(A.cols());
    return out;
  }
  const Vec& x0 = *x0_opt;
  const Mat& N = fa.N;
  const Index d = fa.nullity();
  out.nullity = d;
  const Mat M = C * N;
  const Vec f = e - C * x0;
  std::vector<Index> rows;
  rows.reserve(static_cast<std::size_t>(C.rows()));
  for (Index i = 0; i < C.rows(); ++i) {
    const double size = d ? M.row(i).cwiseAbs().maxCoeff() : 0.0;
    if (size > RANK_RTOL) {
      rows.push_back(i);
    } else if (f(i) < -feas_tol) {
      out.conflicts.push_back(i);
    }
  }
  if (!out.conflicts.empty()) {
    out.code = StepCode::infeasible;
    out.x = Vec::Zero(A.cols());
    return out;
  }
  if (d == 0) {
    out.x = x0;
    return out;
  }
  const Mat RN = cost.root_times(N);
  const Vec r = cost.root_times(Vec(cost.center - x0));
  Mat Rt;
  const Vec t_free = qr_lstsq(RN, r, &Rt);
  const Index k = static_cast<Index>(rows.size());
  Mat Mr(k, d);
  Vec fr(k);
  for (Index j = 0; j < k; ++j) {
    Mr.row(j) = M.row(rows[j]);
    fr(j) = f(rows[j]);
  }
  if (d == 1) {
    double t;
    Index lo, hi;
    if (!interval(Mr.col(0), fr, t_free(0), feas_tol, &t, &lo, &hi)) {
      out.code = StepCode::infeasible;
      // Ascending: the order must not depend on the sign the SVD gave the null vector.
      out.conflicts = {std::min(rows[lo], rows[hi]), std::max(rows[lo], rows[hi])};
      out.x = Vec::Zero(A.cols());
      return out;
    }
    out.x = x0 + N.col(0) * t;
    return out;
  }
  const DenseQPResult qp = solve_dense_qp(Rt, t_free, Mr, fr, feas_tol, max_iter);
  out.iterations = qp.iterations;
  if (qp.status == QPStatus::max_iter) {
    out.code = StepCode::max_iter;
    out.x = Vec::Zero(A.cols());
    return out;
  }
  if (qp.status == QPStatus::infeasible) {
    out.code = StepCode::infeasible;
    for (Index a : qp.active) out.conflicts.push_back(rows[a]);
    out.conflicts.push_back(rows[qp.blocking]);
    out.x = Vec::Zero(A.cols());
    return out;
  }
  out.x = x0 + N * qp.t;
  return out;
}

}  // namespace dqk

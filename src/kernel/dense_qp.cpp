#include "dense_qp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "constants.hpp"

namespace dqk {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

DenseQPResult result(QPStatus status, const Vec& t, const std::vector<Index>& active,
                     const std::vector<double>& u, Index blocking, Index iterations) {
  std::vector<double> mult(u.size());
  for (size_t j = 0; j < u.size(); ++j) mult[j] = std::max(u[j], 0.0);
  return {status, t, active, mult, blocking, iterations};
}

}  // namespace

DenseQPResult solve_dense_qp(const Mat& R, const Vec& t_free, const Mat& M, const Vec& f,
                             double feas_tol, Index max_iter) {
  const Index d = t_free.size();
  const Index k = M.rows();
  const Index limit = max_iter < 0 ? 10 * (k + d) + 10 : max_iter;
  // J0 = R^-1, so that J0 J0^T = (R^T R)^-1: the inverse Hessian, factored.
  const Mat J0 = d ? upper_solve(R, Mat::Identity(d, d)) : Mat(0, 0);
  Vec t = t_free;
  std::vector<Index> active;
  std::vector<double> u;
  active.reserve(static_cast<std::size_t>(k));
  u.reserve(static_cast<std::size_t>(k));
  Index iterations = 0;
  Mat J1, J2, Ra;
  while (k > 0) {
    Vec viol = M * t - f;
    for (Index a : active) viol(a) = -INF;
    double worst = -INF;
    bool nan = false;
    for (Index i = 0; i < k; ++i) {
      if (std::isnan(viol(i))) nan = true;
      else worst = std::max(worst, viol(i));
    }
    if (nan) break;  // as numpy's max: NaN is never "violated"
    if (!(worst > feas_tol)) break;
    // Most violated, lowest index among ties (stated anti-cycling rule).
    const double tie = worst - TIE_RTOL * std::max(1.0, std::abs(worst));
    Index p = 0;
    while (!(viol(p) >= tie)) ++p;
    const Vec n_p = M.row(p).transpose();
    double u_p = 0.0;
    while (true) {
      ++iterations;
      if (iterations > limit) {
        return result(QPStatus::max_iter, t, active, u, -1, iterations);
      }
      // J = J0 Q split as [J1 J2], from J0^T N_A = Q [R_a; 0].
      const Index q = static_cast<Index>(active.size());
      if (q == 0) {
        J1.resize(d, 0);
        J2 = J0;
        Ra.resize(0, 0);
      } else {
        Mat NA(d, q);
        for (Index j = 0; j < q; ++j) NA.col(j) = M.row(active[j]).transpose();
        const Mat B = J0.transpose() * NA;
        Eigen::HouseholderQR<Mat> qr(B);
        const Mat Q = qr.householderQ();
        const Mat J = J0 * Q;
        J1 = J.leftCols(q);
        J2 = J.rightCols(d - q);
        Ra = qr.matrixQR().topRows(q).triangularView<Eigen::Upper>();
      }
      const Vec v = J0.transpose() * n_p;
      const Vec w2 = J2.transpose() * n_p;
      const Vec z = J2 * w2;
      Vec r = q ? Vec(upper_solve(Ra, J1.transpose() * n_p)) : Vec(0);
      // Partial step: the largest dual step keeping every multiplier >= 0.
      double t1 = INF;
      Index drop = -1;
      if (r.size()) {
        const double r_tol = RANK_RTOL * r.cwiseAbs().maxCoeff();
        for (Index j = 0; j < r.size(); ++j) {
          if (r(j) > r_tol && u[j] / r(j) < t1) {
            t1 = u[j] / r(j);
            drop = j;
          }
        }
      }
      // Full step: the primal step that makes row p active.
      const bool dependent = w2.dot(w2) <= (RANK_RTOL * RANK_RTOL) * v.dot(v);
      const double s_p = n_p.dot(t) - f(p);  // > 0: violated
      const double t2 = dependent ? INF : s_p / z.dot(n_p);
      if (t1 == INF && t2 == INF) {
        return result(QPStatus::infeasible, t, active, u, p, iterations);
      }
      if (t2 == INF) {  // step in the dual only, then drop the blocking row
        for (Index j = 0; j < r.size(); ++j) u[j] -= t1 * r(j);
        u_p += t1;
        active.erase(active.begin() + drop);
        u.erase(u.begin() + drop);
        continue;
      }
      const double step = std::min(t1, t2);
      t -= step * z;
      for (Index j = 0; j < r.size(); ++j) u[j] -= step * r(j);
      u_p += step;
      if (step >= t2) {
        active.push_back(p);
        u.push_back(u_p);
        break;
      }
      active.erase(active.begin() + drop);
      u.erase(u.begin() + drop);
    }
  }
  return result(QPStatus::optimal, t, active, u, -1, iterations);
}

}  // namespace dqk

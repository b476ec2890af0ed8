#include "certify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "constants.hpp"
#include "nnls.hpp"

namespace dqk {

namespace {

double max_abs(const Vec& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

}  // namespace

Residuals residuals(const Mat& A, const Vec& b, const Vec& lower, const Vec& upper,
                    const Mat& G, const Vec& h, const Vec& x) {
  if (!x.allFinite()) {  // as numpy: a residual of a non-finite x is not a number
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  Residuals r{0.0, 0.0, 0.0};
  if (A.rows()) r.eq = (A * x - b).cwiseAbs().maxCoeff();
  for (Index i = 0; i < x.size(); ++i) {
    r.box = std::max(r.box, std::max(lower(i) - x(i), x(i) - upper(i)));
  }
  if (G.rows()) {
    const Vec gx = G * x;
    double worst = -std::numeric_limits<double>::infinity();
    bool any = false;
    for (Index j = 0; j < G.rows(); ++j) {
      const double norm = G.row(j).norm();
      const double gap = (gx(j) - h(j)) / (norm > 0.0 ? norm : 1.0);
      if (!std::isnan(gap)) {  // as nanmax
        worst = std::max(worst, gap);
        any = true;
      }
    }
    r.row = any ? std::max(0.0, worst) : 0.0;
  }
  return r;
}

bool kkt_holds(const Mat& A, const Vec& b, const Basis& fa, const Mat& C, const Vec& e,
               const Cost& cost, const Vec& x, bool bounds) {
  const Mat& Z = fa.N;
  const Index d = Z.cols();
  const Vec x0 = fa.solve(b);  // the minimum-norm solution of the equality
  std::vector<Index> act;
  act.reserve(static_cast<std::size_t>(C.rows()));
  if (bounds) {
    const Vec gap = C * x - e;
    for (Index i = 0; i < C.rows(); ++i) {
      if (gap(i) >= -ACTIVE_TOL * std::max(1.0, std::abs(e(i)))) act.push_back(i);
    }
  }
  const Index q = static_cast<Index>(act.size());
  Mat C_act(q, C.cols());
  Vec e_act(q);
  for (Index j = 0; j < q; ++j) {
    C_act.row(j) = C.row(act[j]);
    e_act(j) = e(act[j]);
  }
  const Mat RZ = cost.root_times(Z);
  const Vec r0 = cost.root_times(Vec(cost.center - x0));
  // x* = x0 + Z t*: the minimiser of Eq. 37 on A x = b with the active limits held.
  Vec t_star;
  if (d == 0) {
    t_star = Vec::Zero(0);
  } else if (q) {
    const Mat M = C_act * Z;
    const Basis fm = basis(M);  // the rank as factor(M) decides it (QR proof, else SVD)
    t_star = fm.solve(e_act - C_act * x0);
    if (fm.nullity()) {
      const Mat RN = RZ * fm.N;
      const Vec u = qr_lstsq(RN, r0 - RZ * t_star);
      t_star += fm.N * u;
    }
  } else {
    t_star = qr_lstsq(RZ, r0);
  }
  const Vec x_star = x0 + Z * t_star;
  if (!x_star.allFinite()) return false;
  const Vec grad = cost.gradient(x_star);
  const Mat H = RZ.transpose() * RZ;
  double lam_min = 1.0;
  if (d == 1) {
    lam_min = H(0, 0);
  } else if (d > 1) {
    Eigen::SelfAdjointEigenSolver<Mat> eig(H, Eigen::EigenvaluesOnly);
    lam_min = eig.eigenvalues()(0);
  }
  const double tol = STEP_RTOL * std::max(1.0, max_abs(x)) +
                     ROUNDING * max_abs(grad) / std::max(lam_min, 1e-300);
  if (max_abs(x - x_star) > tol) return false;
  if (d == 0) return true;
  Vec g = Z.transpose() * grad;
  Eigen::LLT<Mat> llt(H);
  if (llt.info() != Eigen::Success) return false;
  if (q) {
    const Mat Mz = Z.transpose() * C_act.transpose();  // the projected active normals
    const auto L = llt.matrixL();
    const Mat LM = L.solve(Mz);
    const Vec Lg = -L.solve(g);
    const NNLSResult mu = nnls(LM, Lg, 50 * (q + 1));
    g += Mz * mu.x;
  }
  const Vec step = Z * llt.solve(g);  // the Newton step that would make x* stationary
  return max_abs(step) <= tol;
}

Certificate certificate(const Mat& A, const Vec& b, const Vec& lower, const Vec& upper,
                        const Mat& G, const Vec& h, const Basis& fa, const Mat& C,
                        const Vec& e, const Eigen::Matrix<std::int8_t, Eigen::Dynamic, 1>& kind,
                        const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>& index,
                        const Cost& cost, const Vec& x, bool bounds, double eq_rtol,
                        double bounds_tol, bool ask_kkt) {
  Certificate out;
  const Index n = x.size();
  out.finite = x.allFinite();
  out.active_lower.setZero(n);
  out.active_upper.setZero(n);
  if (!out.finite) return out;
  out.res = residuals(A, b, lower, upper, G, h, x);
  out.eq_limit = eq_rtol * std::max(1.0, max_abs(b));
  if (ask_kkt && out.res.eq <= out.eq_limit &&
      std::max(out.res.box, out.res.row) <= bounds_tol) {
    out.kkt = kkt_holds(A, b, fa, C, e, cost, x, bounds) ? 1 : 0;
  }
  for (Index i = 0; i < n; ++i) {
    out.active_lower(i) = lower(i) - x(i) >= -ACTIVE_TOL;
    out.active_upper(i) = x(i) - upper(i) >= -ACTIVE_TOL;
  }
  if (G.rows()) {
    for (Index i = 0; i < C.rows(); ++i) {
      if (kind(i) == 0 && C.row(i).dot(x) - e(i) >= -ACTIVE_TOL)
        out.active_rows.push_back(static_cast<Index>(index(i)));  // its row of G
    }
  }
  const Vec d = x - cost.center;
  out.objective = cost.diagonal ? d.dot(cost.w.cwiseProduct(d)) : d.dot(cost.W * d);
  return out;
}

}  // namespace dqk

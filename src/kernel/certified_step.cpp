#include "certified_step.hpp"

namespace dqk {

CertifiedStep solve_certified(const Mat& A, const Vec& b, const Vec& lower, const Vec& upper,
                              const Mat& G, const Vec& h, const Cost& cost, double feas_tol,
                              Index max_iter, bool bounds, double eq_rtol, double bounds_tol) {
  CertifiedStep out;
  if ((lower.array() > upper.array()).any()) {
    out.empty_box = true;
    out.answer = StepAnswer{StepCode::infeasible, Vec::Zero(A.cols()), {}, -1, -1};
    return out;
  }
  out.basis = basis(A);
  out.rows = inequalities(lower, upper, G, h);
  out.answer = solve_nullspace(A, b, out.basis, out.rows.C, out.rows.e, cost, feas_tol, max_iter);
  if (out.answer.code == StepCode::optimal) {
    out.cert = certificate(A, b, lower, upper, G, h, out.basis, out.rows.C, out.rows.e,
                           out.rows.kind, out.rows.index, cost, out.answer.x, bounds, eq_rtol,
                           bounds_tol, true);
    out.certified = true;
  }
  return out;
}

}  // namespace dqk

// The exact step and its certificate in one call: A's basis and the limits' rows are
// computed once and shared by the solve and the certificate (the algorithm is stated in
// dualarm_qp/solvers/nullspace.py, the certificate in dualarm_qp/solvers/certify.py,
// which keeps the verdict).
#pragma once

#include <cstdint>

#include "certify.hpp"
#include "linalg.hpp"
#include "nullspace.hpp"
#include "rows.hpp"

namespace dqk {

// The answer code of a problem with an empty box (after StepCode's 0 to 3).
constexpr int EMPTY_BOX_CODE = 4;

struct CertifiedStep {
  bool empty_box = false;  // some lower(i) > upper(i): not solved (answer.x zero, the
                           // basis and the rows empty)
  Basis basis;         // of A (what basis(A) gives)
  Rows rows;           // every finite limit as unit-norm rows (inequalities(...))
  StepAnswer answer;   // the exact step (solve_nullspace)
  bool certified = false;  // cert is of answer.x (the answer is an optimum claim)
  Certificate cert;
};

// solve_nullspace on A's basis and the problem's rows, then, for an optimum, the
// certificate of its x with the KKT test (certificate(..., ask_kkt = true)). A problem
// with an empty box (lower(i) > upper(i) for some i; a NaN compares false, as numpy's
// lower > upper) is not solved: empty_box is set and the caller names the boxes.
CertifiedStep solve_certified(const Mat& A, const Vec& b, const Vec& lower, const Vec& upper,
                              const Mat& G, const Vec& h, const Cost& cost, double feas_tol,
                              Index max_iter, bool bounds, double eq_rtol, double bounds_tol);

}  // namespace dqk

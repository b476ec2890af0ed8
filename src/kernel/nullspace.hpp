// The exact solver of the step QP by parametrising the null space of A (the algorithm
// is stated in dualarm_qp/solvers/nullspace.py).
#pragma once

#include <vector>

#include "linalg.hpp"

namespace dqk {

enum class StepCode { optimal = 0, infeasible = 1, inconsistent = 2, max_iter = 3 };

struct StepAnswer {
  StepCode code;
  Vec x;
  std::vector<Index> conflicts;  // rows of C (infeasible)
  Index nullity;                 // -1 when A x = b has no solution
  Index iterations;              // active-set additions and drops (d >= 2), else -1
};

// The minimiser of |R (x - c)|^2 subject to A x = b and C x <= e (unit-norm rows).
StepAnswer solve_nullspace(const Mat& A, const Vec& b, const Basis& fa, const Mat& C,
                           const Vec& e, const Cost& cost, double feas_tol,
                           Index max_iter);

// Clamp t_free to {t : c_i t <= f_i}; returns false and the two conflicting rows when
// the interval is empty by more than 2 tol.
bool interval(const Vec& c, const Vec& f, double t_free, double tol, double* t,
              Index* lo_row, Index* hi_row);

}  // namespace dqk

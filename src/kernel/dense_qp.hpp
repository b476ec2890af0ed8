// A small dense strictly convex QP, min 1/2 |R (t - t_free)|^2 s.t. M t <= f, by the
// dual active-set method of Goldfarb and Idnani (rules stated in solvers/_dense_qp.py).
#pragma once

#include <vector>

#include "linalg.hpp"

namespace dqk {

enum class QPStatus { optimal = 0, infeasible = 1, max_iter = 2 };

struct DenseQPResult {
  QPStatus status;
  Vec t;
  std::vector<Index> active;
  std::vector<double> multipliers;  // clipped at zero
  Index blocking;
  Index iterations;
};

// max_iter < 0: the default 10 (k + d) + 10.
DenseQPResult solve_dense_qp(const Mat& R, const Vec& t_free, const Mat& M, const Vec& f,
                             double feas_tol, Index max_iter);

}  // namespace dqk

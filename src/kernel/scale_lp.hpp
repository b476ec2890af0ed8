// The task-scale LP: maximise s subject to M t + a s <= g, s_lo <= s <= s_hi,
// solved through its dual by a revised simplex with Bland's rule (see
// dualarm_qp/solvers/_scale.py for the derivation).
#pragma once

#include <vector>

#include "constants.hpp"
#include "linalg.hpp"

namespace dqk {

enum class LPStatus { Optimal = 0, Infeasible = 1, IterationLimit = 2 };

struct ScaleLPResult {
  LPStatus status = LPStatus::IterationLimit;
  Vec t;                   // the null-space coordinates at the optimum (d)
  double s = 0.0;          // the largest scale
  std::vector<Index> rows; // the rows of the final basis, or of the dual ray
};

ScaleLPResult scale_lp(const Mat& M, const Vec& a, const Vec& g, double s_lo, double s_hi);

}  // namespace dqk

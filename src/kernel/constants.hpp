// The numeric constants of the exact solver and the certificate: defined here only.
// Python reads them from the extension (dualarm_qp._kernel); their meaning is
// documented where Python exposes them (solvers/_affine.py, solvers/certify.py).
#pragma once

#include <limits>

namespace dqk {

// Relative rank tolerance of every singular value decision.
constexpr double RANK_RTOL = 1e-9;
// Relative residual above which A x = b is inconsistent.
constexpr double CONSISTENCY_TOL = 1e-9;
// Distance (units of x, unit-norm rows) within which a limit is active.
constexpr double ACTIVE_TOL = 1e-9;
// Relative distance of a claimed optimum from the exact one on its active set.
constexpr double STEP_RTOL = 1e-8;
// Rounding allowance of the stationarity check: a thousand ulps.
constexpr double ROUNDING = 1e3 * std::numeric_limits<double>::epsilon();
// Relative agreement of two violations counted as a tie in the active-set method.
constexpr double TIE_RTOL = 1e-14;
// Task-scale LP: a row violated by at most PRICE_TOL (1 + |g_j|) (units of x, unit-norm
// rows), i.e. a reduced cost above minus that, counts as met.
constexpr double PRICE_TOL = 1e-9;
// Task-scale LP: pivots below this share of the column's largest entry are never taken.
constexpr double PIVOT_TOL = 1e-11;

}  // namespace dqk

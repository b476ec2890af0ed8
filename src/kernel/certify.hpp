// The certificate's numeric core: residuals and the KKT test (stated in
// dualarm_qp/solvers/certify.py).
#pragma once

#include <cstdint>
#include <vector>

#include "linalg.hpp"

namespace dqk {

struct Residuals {
  double eq;   // max |A x - b|
  double box;  // largest box violation (>= 0)
  double row;  // largest violation of a general row, divided by its norm (>= 0)
};

Residuals residuals(const Mat& A, const Vec& b, const Vec& lower, const Vec& upper,
                    const Mat& G, const Vec& h, const Vec& x);

// Whether x is the minimiser of |R (x - c)|^2 on A x = b and C x <= e (bounds: hold
// the active rows of C; otherwise the equality alone).
bool kkt_holds(const Mat& A, const Vec& b, const Basis& fa, const Mat& C, const Vec& e,
               const Cost& cost, const Vec& x, bool bounds);

// Everything certify reads of x, in one pass (dualarm_qp/solvers/certify.py decides).
struct Certificate {
  bool finite = true;  // x holds no NaN or infinity (else nothing below is computed)
  Residuals res{0.0, 0.0, 0.0};
  double eq_limit = 0.0;  // eq_rtol * max(1, max |b|)
  int kkt = -1;  // -1 not asked (or x breaks a limit), 0 fails, 1 holds
  double objective = 0.0;  // (x - c)^T W (x - c)
  Eigen::Matrix<bool, Eigen::Dynamic, 1> active_lower;  // lower - x >= -ACTIVE_TOL
  Eigen::Matrix<bool, Eigen::Dynamic, 1> active_upper;  // x - upper >= -ACTIVE_TOL
  std::vector<Index> active_rows;  // rows of G (their rows of C, of kind 0) within ACTIVE_TOL
};

// The residuals, the equality's limit, the active bounds and rows and the objective of
// x; the KKT test too when ask_kkt and x meets the equality (eq <= eq_limit) and every
// limit (box and row violation <= bounds_tol).
Certificate certificate(const Mat& A, const Vec& b, const Vec& lower, const Vec& upper,
                        const Mat& G, const Vec& h, const Basis& fa, const Mat& C,
                        const Vec& e, const Eigen::Matrix<std::int8_t, Eigen::Dynamic, 1>& kind,
                        const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>& index,
                        const Cost& cost, const Vec& x, bool bounds, double eq_rtol,
                        double bounds_tol, bool ask_kkt);

}  // namespace dqk

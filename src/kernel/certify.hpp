// The certificate's numeric core: residuals and the KKT test (stated in
// dualarm_qp/solvers/certify.py).
#pragma once

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
bool kkt_holds(const Mat& A, const Vec& b, const Factor& fa, const Mat& C, const Vec& e,
               const Cost& cost, const Vec& x, bool bounds);

}  // namespace dqk

// Lawson and Hanson, "Solving Least Squares Problems" (1974), Ch. 23, algorithm NNLS:
// the passive set P grows by the variable of largest positive dual w_j = a_j^T (b - A x);
// an unconstrained least-squares solve on P that leaves a variable non-positive is cut
// back by an interpolation step and that variable returns to the active set.
#include "nnls.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace dqk {

namespace {

// Least squares on the columns in P (full column rank by construction).
Vec passive_solve(const Mat& A, const Vec& b, const std::vector<Index>& P) {
  Mat AP(A.rows(), static_cast<Index>(P.size()));
  for (size_t j = 0; j < P.size(); ++j) AP.col(static_cast<Index>(j)) = A.col(P[j]);
  return AP.colPivHouseholderQr().solve(b);
}

}  // namespace

NNLSResult nnls(const Mat& A, const Vec& b, Index max_iter) {
  const Index m = A.rows(), n = A.cols();
  const Index limit = max_iter < 0 ? 3 * n : max_iter;
  Vec x = Vec::Zero(n);
  std::vector<bool> passive(n, false);
  // Dual feasibility tolerance: MATLAB's lsqnonneg's (10 eps |A|_1 max(m, n)), times the
  // size of the terms whose difference the residual b - A x is (at least 1): with a
  // large x the rounding of A x alone exceeds the fixed tolerance and the method would
  // keep adding columns to a residual that is zero to rounding.
  const double col_max = n ? A.cwiseAbs().colwise().sum().maxCoeff() : 0.0;
  const double base = 10.0 * std::numeric_limits<double>::epsilon() * col_max *
                      static_cast<double>(std::max(m, n));
  const double b_max = m ? b.cwiseAbs().maxCoeff() : 0.0;
  auto tolerance = [&](const Vec& x_now) {
    const double x_max = n ? x_now.cwiseAbs().maxCoeff() : 0.0;
    return base * std::max({1.0, b_max, col_max * x_max});
  };
  Vec w = A.transpose() * (b - A * x);
  Index iterations = 0;
  bool converged = true;
  while (true) {
    Index j_max = -1;
    double w_max = tolerance(x);
    for (Index j = 0; j < n; ++j) {
      if (!passive[j] && w(j) > w_max) {
        w_max = w(j);
        j_max = j;
      }
    }
    if (j_max < 0) break;
    if (++iterations > limit) {
      converged = false;
      break;
    }
    passive[j_max] = true;
    while (true) {
      std::vector<Index> P;
      P.reserve(static_cast<std::size_t>(n));
      for (Index j = 0; j < n; ++j) {
        if (passive[j]) P.push_back(j);
      }
      const Vec s = passive_solve(A, b, P);
      double alpha = std::numeric_limits<double>::infinity();
      Index cut = -1;  // the variable that reaches zero first
      for (size_t i = 0; i < P.size(); ++i) {
        if (s(static_cast<Index>(i)) <= 0.0) {
          const double xi = x(P[i]);
          const double a = xi / (xi - s(static_cast<Index>(i)));
          if (a < alpha) {
            alpha = a;
            cut = P[i];
          }
        }
      }
      if (alpha == std::numeric_limits<double>::infinity()) {  // s > 0 on P: accept
        x.setZero();
        for (size_t i = 0; i < P.size(); ++i) x(P[i]) = s(static_cast<Index>(i));
        break;
      }
      for (size_t i = 0; i < P.size(); ++i) {
        x(P[i]) += alpha * (s(static_cast<Index>(i)) - x(P[i]));
      }
      x(cut) = 0.0;
      for (size_t i = 0; i < P.size(); ++i) {
        if (x(P[i]) <= 0.0) {
          x(P[i]) = 0.0;
          passive[P[i]] = false;
        }
      }
      if (++iterations > limit) {
        converged = false;
        break;
      }
    }
    if (!converged) break;
    w = A.transpose() * (b - A * x);
  }
  return {x, (A * x - b).norm(), converged};
}

}  // namespace dqk

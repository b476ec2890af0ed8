// Non-negative least squares, min |A x - b| subject to x >= 0 (Lawson and Hanson).
#pragma once

#include "linalg.hpp"

namespace dqk {

struct NNLSResult {
  Vec x;
  double rnorm;
  bool converged;
};

// max_iter < 0: the default 3 n.
NNLSResult nnls(const Mat& A, const Vec& b, Index max_iter);

}  // namespace dqk

// The step's limits as unit-norm rows C x <= e (the order of StepProblem.inequalities).
#pragma once

#include <cstdint>

#include "linalg.hpp"

namespace dqk {

struct Rows {
  Mat C;
  Vec e;
  Eigen::Matrix<std::int8_t, Eigen::Dynamic, 1> kind;  // +1 upper box, -1 lower, 0 row
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1> index;  // variable or row of G
};

// Finite upper boxes (+e_i), finite lower boxes (-e_i), then the rows of G with a
// finite h divided by their Euclidean norm (zero rows kept as they are).
Rows inequalities(const Vec& lower, const Vec& upper, const Mat& G, const Vec& h);

}  // namespace dqk

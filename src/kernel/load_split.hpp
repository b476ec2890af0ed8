// The minimum-norm split of a load's weight between the hands as a linear map of gravity,
// w = K g (split_operator, dualarm_qp/task/torques.py, whose docstring states the rule).
#pragma once

#include <vector>

#include "capsules.hpp"
#include "linalg.hpp"

namespace dqk {

// Hands i = 0..h-1 at points.row(i) [m] with free twists free[i] (6 x k_i, [v; w] about
// the point; k_i = 0: rigid); the load's mass centre [m] and mass [kg]. Moments are
// weighed by the distance of the first two points (fallback_length below 1e-9 m);
// eigenvalues of the balance matrix below rcond_min of the largest are left out.
// Returns K (6h x 3) [per m/s^2].
Mat split_operator(const Points& points, const std::vector<Mat>& free,
                   const Eigen::Vector3d& centre, double mass, double fallback_length,
                   double rcond_min);

}  // namespace dqk

// The step's box: the intersection of the boxes its limits give (StepBuilder.build).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "linalg.hpp"

namespace dqk {

using IndexVec = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>;
using BoundRows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Box {
  Vec lower;
  Vec upper;
  IndexVec lower_by;  // the limit that set each lower bound (-1: none)
  IndexVec upper_by;  // the limit that set each upper bound (-1: none)
  std::int64_t nan_limit = -1;  // the first limit whose bounds hold NaN (-1: none)
};

// Row k of lowers is limit lower_ids[k]'s lower bounds (likewise the uppers), in the
// limits' order. Each bound is the largest lower and the smallest upper; a tie keeps the
// earlier limit. A box then empty by at most pin_rtol * max(1, |lower|) (both ends
// finite) is rounding and is pinned at its lower end (upper = lower). A NaN bound is
// reported, not intersected.
Box intersect_boxes(const BoundRows& lowers, const std::vector<std::int64_t>& lower_ids,
                    const BoundRows& uppers, const std::vector<std::int64_t>& upper_ids,
                    Index n, double pin_rtol);

// The rate box of a range limit (Eqs. 34-36 with recovery): [lo, hi] are the rates
// that reach the ends of each variable's range in one sample. Below its range (lo > 0)
// a variable may not move further down and must come back at least at rec (the
// recovery rate, >= 0): lower = min(lo, rec); above it, mirrored. off marks the
// variables the limit does not bound (-inf, inf).
void range_box(const Vec& lo, const Vec& hi, const Vec& rec,
               const Eigen::Matrix<bool, Eigen::Dynamic, 1>& off, Vec& lower, Vec& upper);

// The centre rates of Eqs. 38-40: the middle of [lo, hi] for a centred variable with a
// finite range, 0 otherwise, times shrink (dt over the centring horizon).
Vec centre(const Vec& lo, const Vec& hi, const Eigen::Matrix<bool, Eigen::Dynamic, 1>& centred,
           double shrink);

// Eqs. 30-31: the sliding rates (rho_min, rho_max) [m/s] over one sample dt that keep
// the hand's point r (object frame) in the surface box [r_min, r_max] when it slides
// along s_star; a component with |s*_i| < 1e-12 does not move and is skipped. Python's
// min and max decide (a tie or a NaN keeps the first argument), as the Python step
// stated them.
std::pair<double, double> grasp_rate_range(const Eigen::Vector3d& r, const Eigen::Vector3d& s_star,
                                           const Eigen::Vector3d& r_min,
                                           const Eigen::Vector3d& r_max, double dt);

// One grasp's rates to the ends of its range [m/s]: Eqs. 30-31 at its point and tangent,
// cut by the rates that reach sigma_min and sigma_max from sigma in one sample.
std::pair<double, double> grasp_rates(const Eigen::Vector3d& point,
                                      const Eigen::Vector3d& tangent, double sigma,
                                      const Eigen::Vector3d& r_min,
                                      const Eigen::Vector3d& r_max, double sigma_min,
                                      double sigma_max, double dt);

// Index of the first array that holds a value it may not: NaN or infinity in
// finite[k], NaN in not_nan[k]; the finite arrays are numbered first (-1: none).
using Values = Eigen::Map<const Eigen::ArrayXd>;  // an array's values, in any shape
std::int64_t first_defect(const std::vector<Values>& finite,
                          const std::vector<Values>& not_nan);

// Smallest singular value of J (m x n); 0 when n < m (a Jacobian with fewer joints than
// task rows has a direction it cannot move in), +inf when m == 0, NaN for a non-finite J.
// One-sided Jacobi on J's rows (plain loops, one fixed order of every sum): about twice
// as fast as a two-sided Jacobi SVD on a 6 x 6 or 6 x 7 Jacobian, and as accurate.
double smallest_singular_value(const Mat& J);

}  // namespace dqk

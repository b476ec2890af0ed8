// Rank-revealing SVD, the affine set of A x = b and the step's cost (the geometry).
#pragma once

#include <Eigen/Dense>
#include <optional>

namespace dqk {

using Eigen::Index;
using Mat = Eigen::MatrixXd;
using Vec = Eigen::VectorXd;

// A ~= U diag(sigma) V^T truncated at RANK_RTOL; N spans the numerical null space.
struct Factor {
  Mat U;
  Vec sigma;
  Mat V;
  Mat N;
  Index rank() const { return sigma.size(); }
  Index nullity() const { return N.cols(); }
  // Minimum-norm least-squares solution of A x = b.
  Vec solve(const Vec& b) const;
  // Minimum-norm least-squares solution of A^T y = g.
  Vec solve_transposed(const Vec& g) const;
};

Factor factor(const Mat& A);

// x0 (minimum norm) of A x = b, or nothing when the equality is inconsistent.
std::optional<Vec> affine_point(const Mat& A, const Vec& b, const Factor& f);

// Eq. 37 as |R (x - c)|^2: a diagonal cost (R = sqrt(w)) or a full one (R given).
struct Cost {
  bool diagonal = true;
  Vec w;  // diagonal weights (diagonal cost)
  Vec root_diag;  // sqrt(w)
  Mat W;  // full weighting matrix
  Mat R;  // its upper Cholesky factor
  Vec center;
  Cost(const Vec& weights_diag, const Mat& weights_full, const Mat& root_full,
       const Vec& c);
  Mat root_times(const Mat& M) const;  // R M
  Vec root_times(const Vec& v) const;  // R v
  Vec gradient(const Vec& x) const;    // W (x - c)
};

// R^{-1} B for an upper triangular R (minimum-norm least squares on a zero pivot).
Mat upper_solve(const Mat& R, const Mat& B);

// Thin Householder QR of a full-column-rank M and the least-squares solution of
// min |M t - r|: returns t.
Vec qr_lstsq(const Mat& M, const Vec& r, Mat* R_out = nullptr);

}  // namespace dqk

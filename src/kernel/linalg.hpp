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

// Householder QR of M (rows >= cols) in place, as LAPACK's dgeqr2 and Eigen's
// HouseholderQR compute it: R in the upper triangle, below the diagonal the reflectors
// H_k = I - tau(k) v_k v_k^T (v_k = (0, ..., 0, 1, M(k+1:, k))), Q = H_0 H_1 ...
// Plain loops without allocation: at the step's sizes (A^T of 13 x 12) Eigen's
// HouseholderQR took 2.2 us against 0.7 us here, in a basis() of 5.7 us.
void householder_qr(Mat& M, Vec& tau);

// X <- Q X for the Q of householder_qr(QR, tau) (X has QR.rows() rows).
void apply_q(const Mat& QR, const Vec& tau, Mat& X);
// X <- Q^T X likewise.
void apply_qt(const Mat& QR, const Vec& tau, Mat& X);

// What the exact solver and the certificate need of A: its pseudo-inverse P (n x m), a
// basis N of its null space and its rank, decided as factor() decides it. A with full
// row rank proven by its QR factorisation (A^T = Q R; Frobenius bounds give
// sigma_min >= 1 / |R^-1|_F > RANK_RTOL |R|_F >= RANK_RTOL sigma_max) takes the QR
// path: P = Q_1 R^-T, N = Q_2. Any other A (wider than tall, near-singular, rank
// deficient) takes the SVD of factor().
//
// On the QR path P is kept factored (the reflectors of Q and R^-1): solve(b) applies
// them to b, and P itself is formed only when asked (pinv()), which the step never does.
struct Basis {
  Mat N;
  Index rank = 0;
  double sigma_max = 0.0;  // the SVD's largest singular value; |R|_F on the QR path
  bool qr = false;         // which path was taken
  Index nullity() const { return N.cols(); }
  Index equations() const { return m_; }  // A's rows
  // Whether this is a basis of an A of that shape (the kernel's functions check it).
  bool fits(Index rows, Index cols) const {
    return m_ == rows && N.rows() == cols && rank >= 0 && rank + N.cols() == cols;
  }
  Vec solve(const Vec& b) const;  // P b: the minimum-norm least-squares solution
  Mat pinv() const;               // P (n x m), formed
  void set_pinv(Mat P);           // P given as a matrix (the SVD path)
  // The QR path: A^T = Q R with Q's reflectors in QR (below its diagonal) and tau.
  void set_factors(Mat QR, Vec tau, Mat R_inv);

 private:
  Mat P_;             // P, given (empty on the QR path)
  Mat QR_, R_inv_;    // the QR path's factors
  Vec tau_;
  Index m_ = 0;
};

Basis basis(const Mat& A);

// x0 (minimum norm) of A x = b, or nothing when the equality is inconsistent.
std::optional<Vec> affine_point(const Mat& A, const Vec& b, const Factor& f);
std::optional<Vec> affine_point(const Mat& A, const Vec& b, const Basis& f);

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

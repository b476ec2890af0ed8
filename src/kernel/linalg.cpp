#include "linalg.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "constants.hpp"

namespace dqk {

Vec Factor::solve(const Vec& b) const {
  Vec y = U.transpose() * b;
  y.array() /= sigma.array();
  return V * y;
}

Vec Factor::solve_transposed(const Vec& g) const {
  Vec y = V.transpose() * g;
  y.array() /= sigma.array();
  return U * y;
}

void householder_qr(Mat& M, Vec& tau) {
  const Index rows = M.rows(), cols = M.cols();
  tau.resize(cols);
  for (Index k = 0; k < cols; ++k) {
    double tail = 0.0;  // |M(k+1:, k)|^2
    for (Index i = k + 1; i < rows; ++i) tail += M(i, k) * M(i, k);
    const double head = M(k, k);
    if (tail <= std::numeric_limits<double>::min()) {  // nothing below: H_k = I
      tau(k) = 0.0;
      continue;
    }
    // H_k = I - tau v v^T maps column k to (beta, 0, ...): v = (1, M(k+1:, k) / (head -
    // beta)), beta of the sign opposite to head's (no cancellation in head - beta).
    const double beta = head >= 0.0 ? -std::sqrt(head * head + tail)
                                     : std::sqrt(head * head + tail);
    tau(k) = (beta - head) / beta;
    const double scale = 1.0 / (head - beta);
    for (Index i = k + 1; i < rows; ++i) M(i, k) *= scale;
    M(k, k) = beta;
    for (Index j = k + 1; j < cols; ++j) {  // H_k on the columns to the right
      double w = M(k, j);
      for (Index i = k + 1; i < rows; ++i) w += M(i, k) * M(i, j);
      w *= tau(k);
      M(k, j) -= w;
      for (Index i = k + 1; i < rows; ++i) M(i, j) -= w * M(i, k);
    }
  }
}

namespace {

// X <- H_k X, with H_k = I - tau_k v v^T and v = (0, ..., 0, 1, QR(k+1:, k)).
void reflect(const Mat& QR, const Vec& tau, Index k, Mat& X) {
  const Index rows = QR.rows();
  for (Index j = 0; j < X.cols(); ++j) {
    double w = X(k, j);
    for (Index i = k + 1; i < rows; ++i) w += QR(i, k) * X(i, j);
    w *= tau(k);
    X(k, j) -= w;
    for (Index i = k + 1; i < rows; ++i) X(i, j) -= w * QR(i, k);
  }
}

}  // namespace

void apply_q(const Mat& QR, const Vec& tau, Mat& X) {
  // Q X = H_0 (H_1 (... (H_last X)))
  for (Index k = tau.size() - 1; k >= 0; --k) reflect(QR, tau, k, X);
}

void apply_qt(const Mat& QR, const Vec& tau, Mat& X) {
  // Q^T X = H_last (... (H_1 (H_0 X)))
  for (Index k = 0; k < tau.size(); ++k) reflect(QR, tau, k, X);
}

Factor factor(const Mat& A) {
  const Index m = A.rows(), n = A.cols();
  Factor f;
  if (m == 0 || n == 0) {
    f.U = Mat::Zero(m, 0);
    f.sigma = Vec::Zero(0);
    f.V = Mat::Zero(n, 0);
    f.N = Mat::Identity(n, n);
    return f;
  }
  Eigen::JacobiSVD<Mat, Eigen::ColPivHouseholderQRPreconditioner> svd(
      A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vec& sv = svd.singularValues();
  const double cut = RANK_RTOL * sv(0);
  Index rank = 0;
  for (Index i = 0; i < sv.size(); ++i) {
    if (sv(i) > cut) ++rank;
  }
  f.U = svd.matrixU().leftCols(rank);
  f.sigma = sv.head(rank);
  f.V = svd.matrixV().leftCols(rank);
  f.N = svd.matrixV().rightCols(n - rank);
  return f;
}

Vec Basis::solve(const Vec& b) const {
  if (!qr) return P_ * b;
  // P b = Q [R^-T b; 0]
  const Index m = R_inv_.rows();
  Mat y = Mat::Zero(QR_.rows(), 1);
  y.topRows(m) = R_inv_.transpose() * b;
  apply_q(QR_, tau_, y);
  return y.col(0);
}

Mat Basis::pinv() const {
  if (!qr) return P_;
  // P = Q [R^-T; 0]
  const Index m = R_inv_.rows();
  Mat P = Mat::Zero(QR_.rows(), m);
  P.topRows(m) = R_inv_.transpose();
  apply_q(QR_, tau_, P);
  return P;
}

void Basis::set_pinv(Mat P) {
  m_ = P.cols();
  P_ = std::move(P);
  qr = false;
}

void Basis::set_factors(Mat QR, Vec tau, Mat R_inv) {
  m_ = R_inv.rows();
  QR_ = std::move(QR);
  tau_ = std::move(tau);
  R_inv_ = std::move(R_inv);
  qr = true;
}

Basis basis(const Mat& A) {
  const Index m = A.rows(), n = A.cols();
  Basis out;
  if (m == 0 || n == 0) {
    out.set_pinv(Mat::Zero(n, m));
    out.N = Mat::Identity(n, n);
    return out;
  }
  if (m <= n && A.allFinite()) {
    Mat QR = A.transpose();  // A^T = Q R: R in its upper triangle, Q's reflectors below
    Vec tau;
    householder_qr(QR, tau);
    const Mat R = QR.topRows(m).triangularView<Eigen::Upper>();
    if ((R.diagonal().array() != 0.0).all()) {
      Mat R_inv = Mat::Identity(m, m);
      R.triangularView<Eigen::Upper>().solveInPlace(R_inv);
      const double lo = 1.0 / R_inv.norm(), hi = R.norm();
      if (std::isfinite(lo) && std::isfinite(hi) && lo > RANK_RTOL * hi) {
        // N = Q [0; I], Q applied without being formed; P = Q [R^-T; 0] kept factored.
        out.N = Mat::Zero(n, n - m);
        out.N.bottomRows(n - m).setIdentity();
        apply_q(QR, tau, out.N);
        out.rank = m;
        out.sigma_max = hi;
        out.set_factors(std::move(QR), std::move(tau), std::move(R_inv));
        return out;
      }
    }
  }
  const Factor f = factor(A);
  out.set_pinv(f.V * f.sigma.cwiseInverse().asDiagonal() * f.U.transpose());
  out.N = f.N;
  out.rank = f.rank();
  out.sigma_max = f.rank() ? f.sigma(0) : 0.0;
  return out;
}

namespace {

// x0 when A x0 = b holds (always at full row rank), else nothing.
std::optional<Vec> checked_point(const Mat& A, const Vec& b, Vec x0, Index rank,
                                 double sigma_max) {
  if (rank < A.rows()) {
    double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
    if (rank > 0 && x0.size() > 0) {
      scale = std::max(scale, sigma_max * x0.cwiseAbs().maxCoeff());
    }
    const double res = (A * x0 - b).cwiseAbs().maxCoeff();
    if (!(res <= CONSISTENCY_TOL * scale)) return std::nullopt;
  }
  return x0;
}

}  // namespace

std::optional<Vec> affine_point(const Mat& A, const Vec& b, const Basis& f) {
  return checked_point(A, b, f.solve(b), f.rank, f.sigma_max);
}

std::optional<Vec> affine_point(const Mat& A, const Vec& b, const Factor& f) {
  return checked_point(A, b, f.solve(b), f.rank(), f.rank() ? f.sigma(0) : 0.0);
}

Cost::Cost(const Vec& weights_diag, const Mat& weights_full, const Mat& root_full,
           const Vec& c)
    : diagonal(weights_full.size() == 0), center(c) {
  if (diagonal) {
    w = weights_diag;
    root_diag = w.array().sqrt();
  } else {
    W = weights_full;
    R = root_full;
  }
}

Mat Cost::root_times(const Mat& M) const {
  if (diagonal) return root_diag.asDiagonal() * M;
  return R * M;
}

Vec Cost::root_times(const Vec& v) const {
  if (diagonal) return root_diag.cwiseProduct(v);
  return R * v;
}

Vec Cost::gradient(const Vec& x) const {
  const Vec d = x - center;
  if (diagonal) return w.cwiseProduct(d);
  return W * d;
}

Mat upper_solve(const Mat& R, const Mat& B) {
  for (Index i = 0; i < R.rows(); ++i) {
    if (R(i, i) == 0.0) {
      return R.completeOrthogonalDecomposition().solve(B);
    }
  }
  return R.triangularView<Eigen::Upper>().solve(B);
}

Vec qr_lstsq(const Mat& M, const Vec& r, Mat* R_out) {
  Mat QR = M;
  Vec tau;
  householder_qr(QR, tau);
  const Index d = M.cols();
  Mat R = QR.topRows(d).triangularView<Eigen::Upper>();
  Mat qtr = r;
  apply_qt(QR, tau, qtr);
  Vec t = upper_solve(R, qtr.topRows(d));
  if (R_out != nullptr) *R_out = R;
  return t;
}

}  // namespace dqk

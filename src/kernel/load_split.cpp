#include "load_split.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

namespace dqk {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0;
  return S;
}

}  // namespace

Mat split_operator(const Points& points, const std::vector<Mat>& free,
                   const Eigen::Vector3d& centre, double mass, double fallback_length,
                   double rcond_min) {
  const Index h = points.rows();
  if (h < 1 || static_cast<Index>(free.size()) != h)
    throw std::invalid_argument("split_operator: one free-twist block per hand");
  // A hand's free twists: 6 x k with k <= 6 (fixed-size storage, no allocation).
  using Free = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>;
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  for (const Mat& T : free) {
    if (T.rows() != 6 || T.cols() > 6)
      throw std::invalid_argument("split_operator: free twists are 6 x k, k <= 6");
    if (!T.allFinite()) throw std::invalid_argument("split_operator: a free twist is not finite");
    if (T.cols() > 0 && Eigen::FullPivLU<Free>(Free(T)).rank() < T.cols())
      throw std::invalid_argument("split_operator: a hand's free twists are not independent");
  }
  if (!points.allFinite() || !centre.allFinite() || !std::isfinite(mass))
    throw std::invalid_argument("split_operator: the hands' points, the centre and the mass "
                                "must be finite");
  const Eigen::Vector3d about = points.row(0).transpose();
  const double gap = h > 1 ? (points.row(0) - points.row(1)).norm() : 0.0;
  const double L = gap > 1e-9 ? gap : fallback_length;
  // The balance is 6 x 6 whatever the number of hands: fixed-size matrices (no allocation).
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  Eigen::Matrix<double, 6, 1> u;
  u << 1.0, 1.0, 1.0, L, L, L;
  Mat MP(6, 6 * h);
  for (Index i = 0; i < h; ++i) {
    Mat6 M = Mat6::Identity();  // S A_i U = [I 0; [p_i - about]x / L  I]
    M.block<3, 3>(3, 0) = skew((points.row(i).transpose() - about) / L);
    const Free T = u.asDiagonal() * free[static_cast<size_t>(i)];  // U T_i
    if (T.cols() > 0) {  // M P_i, P_i = I - T (T^T T)^-1 T^T
      const Free MT = M * T;
      const Small TtT = T.transpose() * T;
      M -= MT * TtT.partialPivLu().solve(T.transpose());
    }
    MP.middleCols(6 * i, 6) = M;
  }
  const Mat6 N = MP * MP.transpose();
  // b = S (-mass [g; (c - about) x g]), per unit g
  Mat63 B;
  B.topRows<3>() = Eigen::Matrix3d::Identity();
  B.bottomRows<3>() = skew(centre - about);
  B = (-mass) * (u.cwiseInverse().asDiagonal() * B);
  // The eigenvalues alone decide; the eigenvectors (the same eigenvalues, to the bit) only
  // where the balance spans fewer than 6 directions.
  Eigen::SelfAdjointEigenSolver<Mat6> eig(N, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success)
    throw std::invalid_argument("split_operator: the balance matrix's eigenvalues failed");
  Mat scaled;
  if (eig.eigenvalues()[0] > rcond_min * eig.eigenvalues()[5]) {  // ascending
    scaled = MP.transpose() * N.partialPivLu().solve(B);
  } else {  // fewer than 6 balance directions: least squares on the kept eigenvectors
    eig.compute(N, Eigen::ComputeEigenvectors);
    if (eig.info() != Eigen::Success)
      throw std::invalid_argument("split_operator: the balance matrix's eigenvectors failed");
    const auto& lam = eig.eigenvalues();
    Mat63 VtB = eig.eigenvectors().transpose() * B;
    for (Index k = 0; k < 6; ++k) {
      if (lam[k] > rcond_min * lam[5])
        VtB.row(k) /= lam[k];
      else
        VtB.row(k).setZero();
    }
    scaled = MP.transpose() * (eig.eigenvectors() * VtB);
  }
  for (Index i = 0; i < h; ++i) scaled.middleRows(6 * i, 6) = u.asDiagonal() * scaled.middleRows(6 * i, 6);
  return scaled;
}

}  // namespace dqk

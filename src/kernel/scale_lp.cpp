#include "scale_lp.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

namespace dqk {

namespace {

// The dual in standard form: columns 0..k-1 the rows, k the cap (s <= s_hi), k+1 the
// floor (-s <= -s_lo), then d artificial columns (held at zero); d + 1 equality rows.
struct Dual {
  Mat E;
  Vec cost;
};

Dual dual_of(const Mat& M, const Vec& a, const Vec& g, double s_lo, double s_hi) {
  const Index k = M.rows();
  const Index d = M.cols();
  Dual out{Mat::Zero(d + 1, k + 2 + d), Vec::Zero(k + 2 + d)};
  out.E.topLeftCorner(d, k) = M.transpose();
  out.E.block(d, 0, 1, k) = a.transpose();
  out.E(d, k) = 1.0;
  out.E(d, k + 1) = -1.0;
  out.E.block(0, k + 2, d, d).setIdentity();
  out.cost.head(k) = g;
  out.cost(k) = s_hi;
  out.cost(k + 1) = -s_lo;
  return out;
}

// The rounding of the multipliers pi = B^-T c_B: |d pi|_1 <= eps cond_1(B) |pi|_1, so the
// reduced cost of column j is known to this times |E_j|_1 at best. A basis of nearly
// parallel or opposite rows (a degenerate vertex) has a large condition: a violation at
// this level is rounding, and entering it cycles or ends in a ray made of rounding.
double multiplier_noise(const Mat& B, const Eigen::PartialPivLU<Mat>& lu, const Vec& pi) {
  const Mat B_inv = lu.inverse();
  return std::numeric_limits<double>::epsilon() * B.cwiseAbs().colwise().sum().maxCoeff() *
         B_inv.cwiseAbs().colwise().sum().maxCoeff() * pi.lpNorm<1>();
}

}  // namespace

ScaleLPResult scale_lp(const Mat& M, const Vec& a, const Vec& g, double s_lo, double s_hi) {
  const Index k = M.rows();
  const Index d = M.cols();
  const Index real = k + 2;
  const Dual lp = dual_of(M, a, g, s_lo, s_hi);
  const Mat& E = lp.E;
  const Vec& cost = lp.cost;
  std::vector<Index> basis;
  for (Index j = 0; j < d; ++j) basis.push_back(k + 2 + j);
  basis.push_back(k);
  Vec y = Vec::Zero(d + 1);
  y(d) = 1.0;
  Vec slack_tol(real);
  for (Index j = 0; j < real; ++j) slack_tol(j) = PRICE_TOL * (1.0 + std::abs(cost(j)));
  const double inf = std::numeric_limits<double>::infinity();
  Mat B(d + 1, d + 1);
  Vec cb(d + 1);
  ScaleLPResult out;
  for (Index iter = 0; iter < 50 * (k + d + 2); ++iter) {
    for (Index p = 0; p <= d; ++p) {
      B.col(p) = E.col(basis[p]);
      cb(p) = cost(basis[p]);
    }
    const Eigen::PartialPivLU<Mat> lu(B);
    const Vec pi = lu.transpose().solve(cb);  // simplex multipliers = (t, s)
    Vec reduced = cost.head(real) - E.leftCols(real).transpose() * pi;
    for (Index j : basis)
      if (j < real) reduced(j) = 0.0;
    const double noise = multiplier_noise(B, lu, pi);
    Index q = -1;
    for (Index j = 0; j < real; ++j)
      if (reduced(j) < -(slack_tol(j) + noise * E.col(j).lpNorm<1>())) {
        q = j;  // Bland: the smallest index enters
        break;
      }
    if (q < 0) {
      out.status = LPStatus::Optimal;
      out.t = pi.head(d);
      out.s = pi(d);
      for (Index j : basis)
        if (j < k) out.rows.push_back(j);
      return out;
    }
    const Vec w = lu.solve(Vec(E.col(q)));
    const double tiny = PIVOT_TOL * std::max(1.0, w.cwiseAbs().maxCoeff());
    Index leave = -1;
    double best = inf;
    for (Index pos = 0; pos <= d; ++pos) {
      const Index j = basis[pos];
      double ratio;
      if (j >= real) {  // an artificial, held at zero: any nonzero pivot blocks
        ratio = std::abs(w(pos)) > tiny ? 0.0 : inf;
      } else {
        ratio = w(pos) > tiny ? std::max(y(pos), 0.0) / w(pos) : inf;
      }
      // Bland: the smallest ratio leaves, the smallest index among ties.
      if (ratio < best || (ratio == best && best < inf && j < basis[leave])) {
        leave = pos;
        best = ratio;
      }
    }
    if (leave < 0) {  // a dual ray: no (t, s) meets every row
      out.status = LPStatus::Infeasible;
      out.t = Vec::Zero(d);
      out.s = 0.0;
      if (q < k) out.rows.push_back(q);
      for (Index pos = 0; pos <= d; ++pos)
        if (basis[pos] < k && w(pos) < -tiny) out.rows.push_back(basis[pos]);
      return out;
    }
    y -= best * w;
    y(leave) = best;
    basis[leave] = q;
  }
  out.status = LPStatus::IterationLimit;
  return out;
}

}  // namespace dqk

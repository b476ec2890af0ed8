#include "scale_lp.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

namespace dqk {

ScaleLPResult scale_lp(const Mat& M, const Vec& a, const Vec& g, double s_lo, double s_hi) {
  const Index k = M.rows();
  const Index d = M.cols();
  const Index real = k + 2;
  const Index cols = k + 2 + d;
  // Columns: 0..k-1 the rows, k the cap (s <= s_hi), k+1 the floor (-s <= -s_lo),
  // then d artificial columns (held at zero).
  Mat E = Mat::Zero(d + 1, cols);
  E.topLeftCorner(d, k) = M.transpose();
  E.block(d, 0, 1, k) = a.transpose();
  E(d, k) = 1.0;
  E(d, k + 1) = -1.0;
  E.block(0, k + 2, d, d).setIdentity();
  Vec cost = Vec::Zero(cols);
  cost.head(k) = g;
  cost(k) = s_hi;
  cost(k + 1) = -s_lo;
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
    Index q = -1;
    for (Index j = 0; j < real; ++j)
      if (reduced(j) < -slack_tol(j)) {
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

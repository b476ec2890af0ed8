#include "rows.hpp"

#include <cmath>
#include <vector>

namespace dqk {

Rows inequalities(const Vec& lower, const Vec& upper, const Mat& G, const Vec& h) {
  const Index n = lower.size();
  std::vector<Index> up, lo, gen;  // reserved: no reallocation while they fill
  up.reserve(static_cast<std::size_t>(n));
  lo.reserve(static_cast<std::size_t>(n));
  gen.reserve(static_cast<std::size_t>(h.size()));
  for (Index i = 0; i < n; ++i) {
    if (std::isfinite(upper(i))) up.push_back(i);
  }
  for (Index i = 0; i < n; ++i) {
    if (std::isfinite(lower(i))) lo.push_back(i);
  }
  for (Index j = 0; j < h.size(); ++j) {
    if (std::isfinite(h(j))) gen.push_back(j);
  }
  const Index k_up = static_cast<Index>(up.size()), k_lo = static_cast<Index>(lo.size());
  const Index k = k_up + k_lo + static_cast<Index>(gen.size());
  Rows r{Mat::Zero(k, n), Vec(k), decltype(Rows::kind)(k), decltype(Rows::index)(k)};
  for (Index i = 0; i < k_up; ++i) {
    r.C(i, up[i]) = 1.0;
    r.e(i) = upper(up[i]);
    r.kind(i) = 1;
    r.index(i) = up[i];
  }
  for (Index i = 0; i < k_lo; ++i) {
    r.C(k_up + i, lo[i]) = -1.0;
    r.e(k_up + i) = -lower(lo[i]);
    r.kind(k_up + i) = -1;
    r.index(k_up + i) = lo[i];
  }
  for (size_t j = 0; j < gen.size(); ++j) {
    const Index i = k_up + k_lo + static_cast<Index>(j);
    const double norm = G.row(gen[j]).norm();
    const double safe = norm > 0.0 ? norm : 1.0;
    r.C.row(i) = G.row(gen[j]) / safe;
    r.e(i) = h(gen[j]) / safe;
    r.kind(i) = 0;
    r.index(i) = gen[j];
  }
  return r;
}

}  // namespace dqk

#include "clearance.hpp"

#include <cmath>
#include <stdexcept>

namespace dqk {

Proximities scene_proximities(const Eigen::Ref<const RowMat>& frames,
                              const std::vector<int>& body_frame,
                              const Eigen::Ref<const Points>& a_local,
                              const Eigen::Ref<const Points>& b_local,
                              const Eigen::Ref<const Eigen::VectorXd>& r,
                              const Eigen::Ref<const Eigen::VectorXd>& sphere,
                              const std::vector<int>& ia, const std::vector<int>& ib,
                              double within, const CoalPairs* exact) {
  const auto nb = static_cast<Eigen::Index>(body_frame.size());
  if (frames.cols() != 4 || frames.rows() % 4 != 0 || a_local.rows() != nb ||
      b_local.rows() != nb || r.size() != nb || sphere.size() != nb || ia.size() != ib.size() ||
      (exact != nullptr &&
       (exact->n_bodies() != size_t(nb) || exact->n_pairs() != ia.size())))
    throw std::invalid_argument("scene_proximities: arrays of inconsistent shapes");
  const Eigen::Index n_frames = frames.rows() / 4;
  // Every body's axis in the world.
  Points A(nb, 3), B(nb, 3);
  for (Eigen::Index i = 0; i < nb; ++i) {
    const int f = body_frame[static_cast<size_t>(i)];
    if (f < 0 || f >= n_frames) throw std::invalid_argument("scene_proximities: no such frame");
    const auto R = frames.block<3, 3>(4 * f, 0);
    const Point p = frames.block<3, 1>(4 * f, 3);
    A.row(i) = (R * a_local.row(i).transpose() + p).transpose();
    B.row(i) = (R * b_local.row(i).transpose() + p).transpose();
  }
  Proximities out;
  const bool all = !std::isfinite(within);
  for (size_t k = 0; k < ia.size(); ++k) {
    const int a = ia[k], b = ib[k];
    if (a < 0 || a >= nb || b < 0 || b >= nb)
      throw std::invalid_argument("scene_proximities: no such body");
    if (!all) {
      const Point gap = 0.5 * (A.row(a) + B.row(a) - A.row(b) - B.row(b)).transpose();
      if (!(gap.norm() - sphere[a] - sphere[b] < within)) continue;
    }
    out.pairs.push_back(static_cast<int>(k));
  }
  const auto m = static_cast<Eigen::Index>(out.pairs.size());
  out.distance.resize(m);
  out.point_a.resize(m, 3);
  out.point_b.resize(m, 3);
  out.normal.resize(m, 3);
  for (Eigen::Index j = 0; j < m; ++j) {
    const size_t k = static_cast<size_t>(out.pairs[static_cast<size_t>(j)]);
    const int a = ia[k], b = ib[k];
    const CapsuleProximity p =
        capsule_proximity(A.row(a).transpose(), B.row(a).transpose(), r[a],
                          A.row(b).transpose(), B.row(b).transpose(), r[b]);
    out.distance[j] = p.distance;
    out.point_a.row(j) = p.point_a.transpose();
    out.point_b.row(j) = p.point_b.transpose();
    out.normal.row(j) = p.normal.transpose();
  }
  out.finite = std::isfinite(out.distance.sum());
  if (exact == nullptr || !out.finite) return out;
  // The pairs with a box: coal where the bound is below within, else dropped.
  Eigen::Index kept = 0;
  for (Eigen::Index j = 0; j < m; ++j) {
    const size_t k = static_cast<size_t>(out.pairs[static_cast<size_t>(j)]);
    if (exact->boxed(k)) {
      if (!(out.distance[j] < within)) {
        if (!all) continue;
      } else {
        const int fa = body_frame[size_t(ia[k])], fb = body_frame[size_t(ib[k])];
        const Eigen::Matrix4d T_a = frames.block<4, 4>(4 * fa, 0);
        const Eigen::Matrix4d T_b = frames.block<4, 4>(4 * fb, 0);
        const CapsuleProximity p = exact->measure(k, T_a, T_b);
        out.distance[j] = p.distance;
        out.point_a.row(j) = p.point_a.transpose();
        out.point_b.row(j) = p.point_b.transpose();
        out.normal.row(j) = p.normal.transpose();
      }
    }
    if (kept != j) {
      out.pairs[static_cast<size_t>(kept)] = out.pairs[static_cast<size_t>(j)];
      out.distance[kept] = out.distance[j];
      out.point_a.row(kept) = out.point_a.row(j);
      out.point_b.row(kept) = out.point_b.row(j);
      out.normal.row(kept) = out.normal.row(j);
    }
    ++kept;
  }
  out.pairs.resize(static_cast<size_t>(kept));
  out.distance.conservativeResize(kept);
  out.point_a.conservativeResize(kept, 3);
  out.point_b.conservativeResize(kept, 3);
  out.normal.conservativeResize(kept, 3);
  return out;
}

namespace {

// Add sign * n^T J(p) of one body to row `row` of G: J = [J_v; J_w] at origin o maps the columns
// cols (chain or J_object column c to decision column cols[c]).
void add_body(RowMat& G, Eigen::Index row, const RowMat& J, const Point& origin, const Point& p,
              const Point& n, double sign, const std::vector<Eigen::Index>& cols) {
  const Point w = (p - origin).cross(n);
  for (size_t c = 0; c < cols.size(); ++c) {
    const auto j = static_cast<Eigen::Index>(c);
    G(row, cols[c]) += sign * (n.dot(J.block<3, 1>(0, j)) + w.dot(J.block<3, 1>(3, j)));
  }
}

}  // namespace

RowMat damper_rows(const Chain& leader, const Chain& follower,
                   const Eigen::Ref<const RowMat>& J_object, const Point& object_origin,
                   const std::vector<int>& owners, const std::vector<int>& frames,
                   const Eigen::Ref<const Points>& point_a,
                   const Eigen::Ref<const Points>& point_b,
                   const Eigen::Ref<const Points>& normal, Eigen::Index n_l, Eigen::Index n_f,
                   Eigen::Index grasp_start, Eigen::Index n) {
  const Eigen::Index k = normal.rows();
  const Eigen::Index n_grasp = J_object.cols() - n_l;
  if (point_a.rows() != k || point_b.rows() != k || owners.size() != 2 * size_t(k) ||
      frames.size() != owners.size() || J_object.rows() != 6 || n_grasp < 0 || n_l < 0 ||
      n_f < 0 || leader.nq() < n_l || follower.nq() != n_f || grasp_start < n_l + n_f ||
      grasp_start + n_grasp > n)
    throw std::invalid_argument("damper_rows: arrays of inconsistent shapes");
  std::vector<Eigen::Index> leader_cols(static_cast<size_t>(n_l)),
      follower_cols(static_cast<size_t>(n_f)), object_cols(static_cast<size_t>(n_l + n_grasp));
  for (Eigen::Index c = 0; c < n_l; ++c) leader_cols[size_t(c)] = object_cols[size_t(c)] = c;
  for (Eigen::Index c = 0; c < n_f; ++c) follower_cols[size_t(c)] = n_l + c;
  for (Eigen::Index c = 0; c < n_grasp; ++c) object_cols[size_t(n_l + c)] = grasp_start + c;
  const RowMat J_obj = J_object;
  RowMat G = RowMat::Zero(k, n);
  RowMat J_leader(6, leader.nq()), J_follower(6, follower.nq());
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T;
  for (Eigen::Index row = 0; row < k; ++row) {
    const Point nrm = normal.row(row).transpose();
    for (int side = 0; side < 2; ++side) {
      const size_t i = 2 * size_t(row) + size_t(side);
      const Point p = (side == 0 ? point_a : point_b).row(row).transpose();
      const double sign = side == 0 ? 1.0 : -1.0;
      switch (owners[i]) {
        case LEADER:
        case FOLLOWER: {
          const bool lead = owners[i] == LEADER;
          const Chain& chain = lead ? leader : follower;
          RowMat& J = lead ? J_leader : J_follower;
          chain.frame_jacobian(frames[i], J);
          chain.frame_poses({frames[i]}, T);
          add_body(G, row, J, T.block<3, 1>(0, 3), p, nrm, sign,
                   lead ? leader_cols : follower_cols);
          break;
        }
        case OBJECT:
          add_body(G, row, J_obj, object_origin, p, nrm, sign, object_cols);
          break;
        case WORLD:
          break;
        default:
          throw std::invalid_argument("damper_rows: an owner is 0 to 3");
      }
    }
  }
  return G;
}

}  // namespace dqk

#include "load_torques.hpp"

#include <cmath>
#include <stdexcept>

#include "chain_impl.hpp"

namespace dqk {

namespace {

// Each hand's wrench, w = K g, as rows of (2, 6).
RowMat split_of(const HandSet& set, const Eigen::Vector3d& g, double mass, double fallback,
                double rcond) {
  const Mat K = split_operator(set.points, set.free, set.centre, mass, fallback, rcond);
  const Vec flat = K * g;
  RowMat w(2, 6);
  for (Index i = 0; i < 2; ++i) w.row(i) = flat.segment(6 * i, 6).transpose();
  return w;
}

// The wrench [f; m] about `from` as the same wrench about `to`.
Vec6 about(const Vec6& w, const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  Vec6 out = w;
  out.tail<3>() += (from - to).cross(Eigen::Vector3d(w.head<3>()));
  return out;
}

// The origin of frame `frame` at the chain's last kinematics (static_torques' q).
Eigen::Vector3d tool_point(Chain& chain, int frame) {
  return chain.impl().data.oMf[static_cast<std::size_t>(frame)].translation();
}

}  // namespace

LoadTorques load_torques(Chain& leader, int leader_tool, Chain& follower, int follower_tool,
                         const Vec& q_l, const Vec& q_f, const Eigen::Vector3d& gravity,
                         double mass, const std::vector<HandSet>& sets, double grasp_step,
                         double fallback_length, double rcond_min) {
  const Index n_l = leader.nq(), n_f = follower.nq();
  const auto n_g = static_cast<Index>(sets.size()) - 1;
  if (n_g < 1 || n_g > 2)
    throw std::invalid_argument("load_torques: the state and one set per sliding grasp");
  if (!(grasp_step > 0.0 && std::isfinite(grasp_step)))
    throw std::invalid_argument("load_torques: grasp_step must be a positive number [m]");
  // The arms hold their links under their chains' gravity; the split uses `gravity`.
  for (const Chain* chain : {&leader, &follower})
    if (!(chain->impl().model.gravity.linear() - gravity).isZero(0.0))
      throw std::invalid_argument("load_torques: the chains' gravity (set_gravity) is not the "
                                  "load's");
  for (const HandSet& s : sets)
    if (s.points.rows() != 2 || s.free.size() != 2)
      throw std::invalid_argument("load_torques: two hands per set");
  const Mat K = split_operator(sets[0].points, sets[0].free, sets[0].centre, mass,
                               fallback_length, rcond_min);
  const Vec flat = K * gravity;
  LoadTorques out;
  out.w.resize(2, 6);
  for (Index i = 0; i < 2; ++i) out.w.row(i) = flat.segment(6 * i, 6).transpose();
  // Each hand's force acts at its grasp point c_i (the leader's tool point, the
  // follower's contact point on the object); the arm's Jacobian is its tool point p_i's.
  const Eigen::Vector3d c[2] = {sets[0].points.row(0).transpose(),
                                sets[0].points.row(1).transpose()};
  Vec tau_l(n_l), tau_f(n_f);
  RowMat dl(n_l, n_l), df(n_f, n_f), J_l(6, n_l), J_f(6, n_f);
  static_torques(leader, q_l, leader_tool, out.w.row(0).transpose(), c[0], tau_l, true, dl, J_l);
  static_torques(follower, q_f, follower_tool, out.w.row(1).transpose(), c[1], tau_f, true, df,
                 J_f);
  const Eigen::Vector3d p[2] = {tool_point(leader, leader_tool),
                                tool_point(follower, follower_tool)};
  out.tau.resize(n_l + n_f);
  out.tau << tau_l, tau_f;
  out.D = RowMat::Zero(n_l + n_f, n_l + n_f + n_g);
  out.D.topLeftCorner(n_l, n_l) = dl;
  out.D.block(n_l, n_l, n_f, n_f) = df;
  // The leader's joints turn the whole set-up (not gravity) with the tool's omega_j: the
  // wrench about its moving grasp point by the rotation identity, the grasp point itself
  // with the object (velocity v_j + omega_j x (c - p_l)); the moment is about p_i.
  Mat turned_g(3, n_l);
  for (Index j = 0; j < n_l; ++j)
    turned_g.col(j) = Eigen::Vector3d(J_l.block<3, 1>(3, j)).cross(gravity);
  const Mat Kg = K * turned_g;  // 12 x n_l
  for (Index i = 0; i < 2; ++i) {
    Mat dq(6, n_l);
    const Eigen::Vector3d f = out.w.row(i).head<3>().transpose();
    const Eigen::Vector3d m = out.w.row(i).tail<3>().transpose();
    for (Index j = 0; j < n_l; ++j) {
      const Eigen::Vector3d omega = J_l.block<3, 1>(3, j);
      const Eigen::Vector3d v = J_l.block<3, 1>(0, j);
      Vec6 dw;
      dw << omega.cross(f), omega.cross(m);
      dw -= Kg.block(6 * i, j, 6, 1);
      dq.col(j) = about(dw, c[i], p[i]);
      dq.block<3, 1>(3, j) += (v + omega.cross(c[i] - p[0])).cross(f);  // d c x f
    }
    const RowMat& J = i == 0 ? J_l : J_f;
    out.D.block(i == 0 ? 0 : n_l, 0, i == 0 ? n_l : n_f, n_l) += J.transpose() * dq;
  }
  // The grasps: forward differences of the split, each wrench moved from its grasp point
  // (which the grasp moves) to the fixed tool point.
  for (Index g = 0; g < n_g; ++g) {
    const HandSet& set = sets[static_cast<size_t>(1 + g)];
    const RowMat moved = split_of(set, gravity, mass, fallback_length, rcond_min);
    for (Index i = 0; i < 2; ++i) {
      const Vec6 w_now = about(out.w.row(i).transpose(), c[i], p[i]);
      const Vec6 w_moved = about(moved.row(i).transpose(), set.points.row(i).transpose(), p[i]);
      const Vec ds = (w_moved - w_now) / grasp_step;
      const RowMat& J = i == 0 ? J_l : J_f;
      out.D.block(i == 0 ? 0 : n_l, n_l + n_f + g, i == 0 ? n_l : n_f, 1) += J.transpose() * ds;
    }
  }
  return out;
}

}  // namespace dqk

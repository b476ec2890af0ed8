#include "clearance.hpp"

#include "coal_pairs.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

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
  if (!A.allFinite() || !B.allFinite()) {  // a body off the numbers: nothing is measured
    out.finite = false;
    return out;
  }
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
  // The pairs with a box: coal where both bounds are below within (every one when
  // within = inf), else dropped.
  Eigen::Index kept = 0;
  for (Eigen::Index j = 0; j < m; ++j) {
    const size_t k = static_cast<size_t>(out.pairs[static_cast<size_t>(j)]);
    if (exact->boxed(k)) {
      const int a = ia[k], b = ib[k];
      const Eigen::Matrix4d T_a = frames.block<4, 4>(4 * body_frame[size_t(a)], 0);
      const Eigen::Matrix4d T_b = frames.block<4, 4>(4 * body_frame[size_t(b)], 0);
      if (!all && !(out.distance[j] < within &&
                    exact->lower_bound(k, T_a, T_b, {A.row(a), B.row(a), r[a]},
                                       {A.row(b), B.row(b), r[b]}) < within))
        continue;
      const CapsuleProximity p = exact->measure(k, T_a, T_b);
      out.distance[j] = p.distance;
      out.point_a.row(j) = p.point_a.transpose();
      out.point_b.row(j) = p.point_b.transpose();
      out.normal.row(j) = p.normal.transpose();
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
  // Each arm link's Jacobian and origin once, however many rows it is in (a link near
  // the shelf and the other arm is in several).
  struct Link {
    int owner, frame;
    RowMat J;
    Point origin;
  };
  std::vector<Link> links;
  links.reserve(owners.size());
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T;
  const auto link = [&](int owner, int frame) -> const Link& {
    for (const Link& l : links)
      if (l.owner == owner && l.frame == frame) return l;
    const Chain& chain = owner == LEADER ? leader : follower;
    Link& l = links.emplace_back(Link{owner, frame, RowMat(6, chain.nq()), Point()});
    chain.frame_jacobian(frame, l.J);
    chain.frame_poses({frame}, T);
    l.origin = T.block<3, 1>(0, 3);
    return l;
  };
  for (Eigen::Index row = 0; row < k; ++row) {
    const Point nrm = normal.row(row).transpose();
    for (int side = 0; side < 2; ++side) {
      const size_t i = 2 * size_t(row) + size_t(side);
      const Point p = (side == 0 ? point_a : point_b).row(row).transpose();
      const double sign = side == 0 ? 1.0 : -1.0;
      switch (owners[i]) {
        case LEADER:
        case FOLLOWER: {
          const Link& l = link(owners[i], frames[i]);
          add_body(G, row, l.J, l.origin, p, nrm, sign,
                   owners[i] == LEADER ? leader_cols : follower_cols);
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

DamperScene::DamperScene(std::vector<int> body_frame, Points a_local, Points b_local,
                         Eigen::VectorXd r, Eigen::VectorXd sphere, std::vector<int> ia,
                         std::vector<int> ib, const CoalPairs* exact, std::vector<int> owner,
                         std::vector<int> model_frame, std::vector<int> leader_frames,
                         std::vector<int> follower_frames, double d_i, double d_s,
                         double gain, double zero_row, Eigen::Index n_l, Eigen::Index n_f,
                         Eigen::Index grasp_start, Eigen::Index n)
    : body_frame_(std::move(body_frame)), a_local_(std::move(a_local)),
      b_local_(std::move(b_local)), r_(std::move(r)), sphere_(std::move(sphere)),
      ia_(std::move(ia)), ib_(std::move(ib)), exact_(exact), owner_(std::move(owner)),
      model_frame_(std::move(model_frame)), leader_frames_(std::move(leader_frames)),
      follower_frames_(std::move(follower_frames)), d_i_(d_i), d_s_(d_s), gain_(gain),
      zero_row_(zero_row), n_l_(n_l), n_f_(n_f), grasp_start_(grasp_start), n_(n) {
  if (owner_.size() != body_frame_.size() || model_frame_.size() != body_frame_.size())
    throw std::invalid_argument("DamperScene: arrays of inconsistent shapes");
  for (int o : owner_)
    if (o < LEADER || o > WORLD) throw std::invalid_argument("DamperScene: an owner is 0 to 3");
}

DamperRows DamperScene::rows(const Chain& leader, const Chain& follower,
                             const Eigen::Ref<const RowMat>& J_object,
                             const Eigen::Ref<const RowMat>& T_object) const {
  if (T_object.rows() != 4 || T_object.cols() != 4)
    throw std::invalid_argument("DamperScene: T_object must be (4, 4)");
  const auto n_lf = static_cast<Eigen::Index>(leader_frames_.size());
  const auto n_ff = static_cast<Eigen::Index>(follower_frames_.size());
  RowMat frames(4 * (n_lf + n_ff + 2), 4);
  leader.frame_poses(leader_frames_, frames.middleRows(0, 4 * n_lf));
  follower.frame_poses(follower_frames_, frames.middleRows(4 * n_lf, 4 * n_ff));
  frames.middleRows<4>(4 * (n_lf + n_ff)) = T_object;
  frames.middleRows<4>(4 * (n_lf + n_ff + 1)).setIdentity();
  Proximities p = scene_proximities(frames, body_frame_, a_local_, b_local_, r_, sphere_, ia_,
                                    ib_, d_i_, exact_);
  DamperRows out;
  out.finite = p.finite;
  if (!p.finite) return out;
  std::vector<Eigen::Index> near;
  for (Eigen::Index j = 0; j < p.distance.size(); ++j)
    if (p.distance[j] < d_i_) near.push_back(j);
  const auto k = static_cast<Eigen::Index>(near.size());
  Points pa(k, 3), pb(k, 3), nrm(k, 3);
  std::vector<int> owners(2 * near.size()), model_frames(2 * near.size());
  for (Eigen::Index row = 0; row < k; ++row) {
    const Eigen::Index j = near[size_t(row)];
    const size_t pair = static_cast<size_t>(p.pairs[size_t(j)]);
    pa.row(row) = p.point_a.row(j);
    pb.row(row) = p.point_b.row(j);
    nrm.row(row) = p.normal.row(j);
    const int a = ia_[pair], b = ib_[pair];
    owners[2 * size_t(row)] = owner_[size_t(a)];
    owners[2 * size_t(row) + 1] = owner_[size_t(b)];
    model_frames[2 * size_t(row)] = model_frame_[size_t(a)];
    model_frames[2 * size_t(row) + 1] = model_frame_[size_t(b)];
  }
  const RowMat G = damper_rows(leader, follower, J_object, T_object.block<3, 1>(0, 3), owners,
                               model_frames, pa, pb, nrm, n_l_, n_f_, grasp_start_, n_);
  if (!G.allFinite()) {  // a non-finite Jacobian: no row can be judged
    out.finite = false;
    return out;
  }
  // Only the rows that move: n^T (J_a - J_b) x <= gain (d - d_s).
  std::vector<Eigen::Index> moving;
  for (Eigen::Index row = 0; row < k; ++row)
    if (G.row(row).cwiseAbs().maxCoeff() > zero_row_) moving.push_back(row);
  const auto m = static_cast<Eigen::Index>(moving.size());
  out.G.resize(m, n_);
  out.h.resize(m);
  out.pairs.resize(moving.size());
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index row = moving[size_t(i)], j = near[size_t(row)];
    out.G.row(i) = G.row(row);
    out.h[i] = gain_ * (p.distance[j] - d_s_);
    out.pairs[size_t(i)] = p.pairs[size_t(j)];
  }
  return out;
}

}  // namespace dqk

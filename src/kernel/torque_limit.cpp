#include "torque_limit.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "statics.hpp"

namespace dqk {

namespace {

// The free twists of a frictionless sliding grasp (sliding_statics, loads.py): the slide
// [s; turn] and the spin [0; s], s the sliding direction normalised.
Mat sliding_free(const Eigen::Vector3d& sliding, const Eigen::Vector3d& turn) {
  const double n = std::sqrt(sliding.dot(sliding));
  if (!(n > 0.0)) throw std::invalid_argument("TorqueLimit: a sliding direction is zero");
  const Eigen::Vector3d s = sliding / n;
  Mat free = Mat::Zero(6, 2);
  free.block<3, 1>(0, 0) = s;
  free.block<3, 1>(3, 0) = turn;
  free.block<3, 1>(3, 1) = s;
  return free;
}

// The inverse of a rigid motion (pinocchio's SE3 inverse: R^T, -R^T p).
Pose inverse(const Pose& T) {
  Pose out = Pose::Identity();
  const Eigen::Matrix3d Rt = T.topLeftCorner<3, 3>().transpose();
  out.topLeftCorner<3, 3>() = Rt;
  out.topRightCorner<3, 1>() = -(Rt * T.topRightCorner<3, 1>());
  return out;
}

}  // namespace

Pose SlidePath::at(double sigma) const {
  const double theta = rate * sigma;
  Pose M = Pose::Identity();
  if (revolute) {
    const double c = std::cos(theta), s = std::sin(theta);
    if (axis == 0)
      M.topLeftCorner<3, 3>() << 1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c;
    else
      M.topLeftCorner<3, 3>() << c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c;
  } else {
    M(axis, 3) = theta;
  }
  const Pose PM = P * M;
  return PM * C;
}

Eigen::Vector3d SlidePath::turn() const {
  if (!revolute) return Eigen::Vector3d::Zero();
  return rate * P.block<3, 1>(0, axis);
}

TorqueLimit::TorqueLimit(Chain* leader, int leader_tool, Chain* follower, int follower_tool,
                         Vec tau_max, std::vector<std::string> row_names,
                         std::optional<double> mass, const Eigen::Vector3d& mass_centre,
                         const Eigen::Vector3d& gravity, SlidePath follower_path,
                         std::optional<SlidePath> leader_path, double grasp_step,
                         double fallback_length, double rcond_min)
    : leader_(leader),
      leader_tool_(leader_tool),
      follower_(follower),
      follower_tool_(follower_tool),
      tau_max_(std::move(tau_max)),
      row_names_(std::move(row_names)),
      loaded_(mass.has_value()),
      mass_(mass.value_or(0.0)),
      centre_(mass_centre),
      gravity_(gravity),
      follower_path_(std::move(follower_path)),
      leader_path_(std::move(leader_path)),
      grasp_step_(grasp_step),
      fallback_length_(fallback_length),
      rcond_min_(rcond_min) {
  if (leader_ == nullptr || follower_ == nullptr)
    throw std::invalid_argument("TorqueLimit: both arms' statics chains");
  leader_->check_frame(leader_tool_);
  follower_->check_frame(follower_tool_);
  if (tau_max_.size() != leader_->nq() + follower_->nq())
    throw std::invalid_argument("TorqueLimit: one tau_max per joint of both arms");
  for (Index j = 0; j < tau_max_.size(); ++j) {
    if (!(tau_max_(j) > 0.0))
      throw std::invalid_argument("TorqueLimit: every tau_max > 0 N m (inf: none)");
    if (std::isfinite(tau_max_(j))) rows_.push_back(j);
  }
  if (row_names_.size() != 2 * rows_.size())
    throw std::invalid_argument("TorqueLimit: two row names per limited joint");
  if (loaded_ && !(std::isfinite(mass_) && mass_ > 0.0 && centre_.allFinite() &&
                   gravity_.allFinite()))
    throw std::invalid_argument("TorqueLimit: a finite mass > 0, mass centre and gravity");
  for (const SlidePath* path : {&follower_path_, leader_path_ ? &*leader_path_ : nullptr}) {
    if (path != nullptr && ((path->axis != 0 && path->axis != 1) || !std::isfinite(path->rate) ||
                            !path->P.allFinite() || !path->C.allFinite()))
      throw std::invalid_argument("TorqueLimit: a path's joint axis is x (0) or y (1), its "
                                  "placements and rate finite");
  }
  if (!(grasp_step_ > 0.0 && std::isfinite(grasp_step_)))
    throw std::invalid_argument("TorqueLimit: grasp_step must be a positive number [m]");
}

Pose TorqueLimit::object_at(const Pose& T_tool, double sigma_l) const {
  // The object in the leader's sliding grasp: T_tool G_l(sigma_l)^-1.
  return T_tool * inverse(leader_path_->at(sigma_l));
}

HandSet TorqueLimit::hands(const Pose& T_tool, const Pose& T_object, double sigma,
                           double sigma_l) const {
  const Eigen::Matrix3d R = T_object.topLeftCorner<3, 3>();
  const Eigen::Vector3d p = T_object.topRightCorner<3, 1>();
  HandSet set;
  set.points.resize(2, 3);
  set.points.row(0) = T_tool.topRightCorner<3, 1>().transpose();
  set.free.resize(2);
  if (leader_path_) {
    const Pose G = leader_path_->at(sigma_l);
    set.free[0] = sliding_free(R * G.block<3, 1>(0, 0), R * leader_path_->turn());
  } else {
    set.free[0] = Mat(6, 0);
  }
  const Pose H = follower_path_.at(sigma);
  const Eigen::Vector3d point = R * H.block<3, 1>(0, 3) + p;
  set.points.row(1) = point.transpose();
  set.free[1] = sliding_free(R * H.block<3, 1>(0, 0), R * follower_path_.turn());
  set.centre = R * centre_ + p;
  return set;
}

LoadTorques TorqueLimit::own_weight(const Vec& q_l, const Vec& q_f, Index k) const {
  const Index n_l = q_l.size(), n_f = q_f.size();
  Vec tau_l(n_l), tau_f(n_f);
  RowMat dl(n_l, n_l), df(n_f, n_f), J_l(6, n_l), J_f(6, n_f);
  static_torques(*leader_, q_l, leader_tool_, Vec6::Zero(), std::nullopt, tau_l, true, dl, J_l);
  static_torques(*follower_, q_f, follower_tool_, Vec6::Zero(), std::nullopt, tau_f, true, df,
                 J_f);
  LoadTorques out;
  out.tau.resize(n_l + n_f);
  out.tau << tau_l, tau_f;
  out.D = RowMat::Zero(n_l + n_f, n_l + n_f + k);
  out.D.topLeftCorner(n_l, n_l) = dl;
  out.D.block(n_l, n_l, n_f, n_f) = df;
  out.w = RowMat::Zero(2, 6);
  return out;
}

LoadTorques TorqueLimit::linearised(const Context& ctx) const {
  const Index n_l = leader_->nq(), n_f = follower_->nq();
  const Index k = leader_path_ ? 2 : 1;
  if (ctx.n_l != n_l || ctx.n_f != n_f || ctx.k != k || ctx.positions.size() != n_l + n_f + k)
    throw std::invalid_argument(
        "TorqueLimit: a context of another layout, or without the step's joints and grasps");
  const Vec q_l = ctx.positions.head(n_l);
  const Vec q_f = ctx.positions.segment(n_l, n_f);
  if (!loaded_) return own_weight(q_l, q_f, k);
  const double sigma = ctx.positions(n_l + n_f);
  const double sigma_l = k == 2 ? ctx.positions(n_l + n_f + 1) : 0.0;
  // The hands at the state, with the follower's grasp moved, with the leader's moved
  // (which moves the object). A sliding leader's object is computed from the tool for
  // the state too, so that the difference is of one formula.
  const Pose T_object = leader_path_ ? object_at(ctx.T_tool, sigma_l) : ctx.T_object;
  std::vector<HandSet> sets;
  sets.reserve(static_cast<size_t>(1 + k));
  sets.push_back(hands(ctx.T_tool, T_object, sigma, sigma_l));
  sets.push_back(hands(ctx.T_tool, T_object, sigma + grasp_step_, sigma_l));
  if (k == 2) {
    const double moved = sigma_l + grasp_step_;
    sets.push_back(hands(ctx.T_tool, object_at(ctx.T_tool, moved), sigma, moved));
  }
  return load_torques(*leader_, leader_tool_, *follower_, follower_tool_, q_l, q_f, gravity_,
                      mass_, sets, grasp_step_, fallback_length_, rcond_min_);
}

void TorqueLimit::set_approach(double seconds) {
  if (!(std::isfinite(seconds) && seconds >= 0.0))
    throw std::invalid_argument("TorqueLimit: approach must be a finite number of seconds >= 0");
  approach_ = seconds;
}

Constraint TorqueLimit::constraint(const Context& ctx) const {
  Constraint c;
  const auto p = static_cast<Index>(rows_.size());
  if (p == 0) return c;
  const LoadTorques st = linearised(ctx);
  c.G.resize(2 * p, ctx.n);
  c.h.resize(2 * p);
  for (Index r = 0; r < p; ++r) {
    const Index j = rows_[static_cast<size_t>(r)];
    c.G.row(r) = ctx.dt * st.D.row(j);
    c.G.row(p + r) = -c.G.row(r);
    c.h(r) = tau_max_(j) - st.tau(j);
    c.h(p + r) = tau_max_(j) + st.tau(j);
  }
  if (approach_ > 0.0) {  // a joint inside its limit closes a share of its margin
    const double share = std::min(1.0, ctx.dt / approach_);
    c.h = (c.h.array() > 0.0).select(share * c.h.array(), c.h.array()).matrix();
  }
  if (!(c.G.allFinite() && c.h.allFinite())) {
    Constraint failed;
    failed.nonfinite = "the rows of the limit 'torque' (a joint's torque or its derivative)";
    return failed;
  }
  c.row_names = row_names_;
  return c;
}

}  // namespace dqk

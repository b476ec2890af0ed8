// The joint torque limit of a step (TorqueLimit, dualarm_qp/step/limits/torque.py): both
// arms' quasi-static torques tau and their derivative D over the decision variables,
// computed from the step's context (the joints, the grasps, the leader's tool and the
// object's pose), then two rows per limited joint:
//   dt D x <= tau_max - tau,    -dt D x <= tau_max + tau.
// The statics are the kernel's (load_torques, static_torques); the hands' geometry at the
// state and at each moved grasp is computed here, as LoadTorques.linearised computes it
// (dualarm_qp/task/torques.py, hand_statics in dualarm_qp/task/loads.py).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "load_torques.hpp"
#include "parts.hpp"

namespace dqk {

// A sliding path as one joint (SlideJoint, dualarm_qp/task/surfaces.py): the hand's pose
// on the object at sigma [m] is H(sigma) = P M(rate sigma) C, M the motion of a one-dof
// joint about or along the x (axis 0) or y (axis 1) axis of its frame.
struct SlidePath {
  bool revolute = false;
  int axis = 0;
  Pose P = Pose::Identity();
  Pose C = Pose::Identity();
  double rate = 1.0;
  // H(sigma), object coordinates [m].
  Pose at(double sigma) const;
  // kappa [rad/m] with dR/dsigma = skew(kappa) R, object coordinates (zero when prismatic).
  Eigen::Vector3d turn() const;
};

// Without a load each arm holds only itself (zero wrenches). With one, the split between
// the hands (split_operator) holds the follower's sliding grasp on follower_path and the
// leader's rigid grasp or its sliding one on leader_path; the grasps' columns by forward
// differences of the split over grasp_step [m], fallback_length and rcond_min those of
// split_operator.
class TorqueLimit : public Limit {
 public:
  // leader, follower: each arm's statics chain (its model with inertias and gravity, the
  // caller keeps it alive) and its tool frame; tau_max (n_l + n_f) [N m], inf: none;
  // row_names: two per limited joint (the maxima, then the minima). mass [kg], none:
  // no load; mass_centre [m] (object coordinates) and gravity [m/s^2] (world frame, the
  // statics chains' gravity too) the load's.
  TorqueLimit(Chain* leader, int leader_tool, Chain* follower, int follower_tool, Vec tau_max,
              std::vector<std::string> row_names, std::optional<double> mass,
              const Eigen::Vector3d& mass_centre, const Eigen::Vector3d& gravity,
              SlidePath follower_path, std::optional<SlidePath> leader_path, double grasp_step,
              double fallback_length, double rcond_min);
  Constraint constraint(const Context& ctx) const override;
  // Both arms' torques, their derivative over the decision variables and the hands'
  // wrenches at the context's state (LoadTorques.linearised).
  LoadTorques linearised(const Context& ctx) const;
  const Vec& tau_max() const { return tau_max_; }
  // The time constant [s] with which a torque may approach its limit: a joint inside
  // it closes at most dt / approach of its margin per sample (0: all of it at once).
  void set_approach(double seconds);
  double approach() const { return approach_; }

 private:
  HandSet hands(const Pose& T_tool, const Pose& T_object, double sigma, double sigma_l) const;
  Pose object_at(const Pose& T_tool, double sigma_l) const;
  LoadTorques own_weight(const Vec& q_l, const Vec& q_f, Index k) const;

  Chain* leader_;
  int leader_tool_;
  Chain* follower_;
  int follower_tool_;
  Vec tau_max_;
  std::vector<Index> rows_;
  std::vector<std::string> row_names_;
  bool loaded_;
  double mass_;
  Eigen::Vector3d centre_, gravity_;
  SlidePath follower_path_;
  std::optional<SlidePath> leader_path_;
  double grasp_step_, fallback_length_, rcond_min_;
  double approach_ = 0.0;
};

}  // namespace dqk

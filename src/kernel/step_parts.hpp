// The standard parts of one step in one call (StepBuilder.build): both arms' kinematics
// (step_kinematics, without the smallest singular values: computed when read), the
// Jacobians in decision order, the rates that reach each
// variable's range ends, the equality (carry_equality), the centring cost's centres
// (centre), the boxes of the standard limits that declare a compiled form (range,
// speed, acceleration; limit_box) and the rows of those that compute them here (the
// collision scene's damper). The Python layer wraps the outputs without copies and
// stacks the limits that have no compiled form (torque, a user's own).
#pragma once

#include <cstdint>
#include <vector>

#include "boxes.hpp"
#include "clearance.hpp"
#include "equality.hpp"
#include "kinematics.hpp"
#include "linalg.hpp"

namespace dqk {

using BoolVec = Eigen::Matrix<bool, Eigen::Dynamic, 1>;

// A standard limit's box, as its compiled form computes it (dualarm_qp/step/limits):
//   RANGE (p: recovery rates, off: variables it does not bound): range_box(lo, hi, p, off);
//   SPEED (p: v_max): [-p, p];
//   ACCELERATION (p: delta = a dt): [x_applied - p, x_applied + p] cut by the braking
//   bound of the distance to each range end (braking_bound).
enum BoxKind : int { RANGE = 0, SPEED = 1, ACCELERATION = 2 };

struct BoxForm {
  int kind = RANGE;
  Vec p;
  BoolVec off;
  std::int64_t limit = 0;  // the limit's index in the step's order (what bounds name)
};

// A grasp whose path is a straight line in the object frame (a PlaneBar): its point is
// origin + sigma direction, its tangent direction; r_min, r_max its surface box and
// [sigma_min, sigma_max] its range (dualarm_qp/task/surfaces.py).
struct GraspLine {
  Eigen::Vector3d origin, direction, r_min, r_max;
  double sigma_min = 0.0, sigma_max = 0.0;
};

// The largest rate from which a stop within the distance D [rad or m] is possible when
// the rate may change by delta per sample (dualarm_qp/step/limits/acceleration.py):
// V(D) = (D / dt + delta n (n + 1) / 2) / (n + 1), n = floor((-1 + sqrt(1 + 8 D /
// (delta dt))) / 2); inf where D or delta is infinite, D < 0 read as 0.
double braking_bound(double D, double delta, double dt);

// The box of one compiled form at the rates lo, hi to the range ends (n each) and the
// last applied command x_applied (n).
void limit_box(const BoxForm& form, const Vec& lo, const Vec& hi, const Vec& x_applied,
               double dt, Vec& lower, Vec& upper);

struct StepPartsOut {
  RowMat T;         // (16, 4): the leader's tool, the object, the target, the follower's tool
  RowMat J_tool;    // (6, n_l) the leader's tool Jacobian
  RowMat J_object;  // (6, n_l + k) in decision order, grasp columns as sliding speeds
  RowMat J_target;  // (6, n_l + k) likewise
  RowMat J_f;       // (6, n_f)
  Vec e;            // (12) the object's error to D(t), the follower tool's to its target
  Vec lo, hi;       // (n) the rates to the ends of each variable's range
  RowMat A;         // (12, n)
  Vec b;            // (12)
  bool equality_finite = true;
  Vec center;       // (n)
  RowMat lowers;    // (forms, n) each compiled form's lower bounds, in the forms' order
  RowMat uppers;    // (forms, n)
  Box box;          // the compiled forms' boxes intersected (intersect_boxes, pin_rtol)
  BoolVec recovering;  // (n) ranged variables outside their range (lo > 0 or hi < 0)
  bool any_recovering = false;  // recovering holds a true
  std::vector<DamperRows> rows;  // each compiled row limit's rows, in the limits' order
  double kinematics_seconds = 0.0;  // the kinematics' share of the call
};

class StepParts {
 public:
  // n_l, n_f joints and k = cols.size() - n_l grasps: column j of the decision-order
  // Jacobians is column cols[j] of the carry chain's (times col_rate[j], given with each
  // state: a support re-places the follower's grasp joint). q_min, q_max: both arms'
  // joint ranges (n_l + n_f); centred, shrink: the centring cost's; ranged: the
  // variables whose range the step imposes (recovering); pin_rtol: intersect_boxes's.
  StepParts(Index n_l, Index n_f, std::vector<int> carry_frames, int follower_tool,
            std::vector<int> cols, Vec q_min, Vec q_max, double dt, BoolVec centred,
            double shrink, BoolVec ranged, double pin_rtol);

  // A limit's compiled box form; limit is its index in the step's order (increasing).
  void add_form(int kind, const Vec& p, const BoolVec& off, std::int64_t limit);
  // The next grasp's straight path (in the grasps' order). With every grasp's line
  // given, prepare computes the grasps' rates to their range ends from sigmas itself.
  void add_grasp_line(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      const Eigen::Vector3d& r_min, const Eigen::Vector3d& r_max,
                      double sigma_min, double sigma_max);
  // A limit whose rows the kernel computes with the parts: a collision scene's damper
  // (which must outlive this); limit is its index in the step's order (increasing).
  void add_rows(const DamperScene* damper, std::int64_t limit);
  Index forms() const { return static_cast<Index>(forms_.size()); }
  Index row_forms() const { return static_cast<Index>(dampers_.size()); }
  Index n() const { return n_; }
  bool grasp_lines() const { return static_cast<Index>(lines_.size()) == k_; }

  // The parts at one state: q_carry the carry chain's joints, col_rate the columns'
  // rates, q_f the follower's joints, T_D and twist the path's pose and twist at t,
  // sigmas the grasp coordinates (k), grasp_lo and grasp_hi the grasps' rates to their
  // range ends (k each, from the surfaces; ignored, and may be empty, when every grasp
  // has a line), x_applied the last applied command.
  StepPartsOut prepare(Chain& carry, const Eigen::VectorXd& q_carry, const Vec& col_rate,
                       Chain& follower, const Eigen::VectorXd& q_f, const Pose& T_D,
                       const Vec6& twist, const Vec& sigmas,
                       const Vec& grasp_lo, const Vec& grasp_hi, const Vec& x_applied,
                       double scale_max, double leader_gain, double correction_gain,
                       bool exact_orientation) const;

 private:
  Index n_l_, n_f_, k_, n_;
  std::vector<int> carry_frames_;
  int follower_tool_;
  std::vector<int> cols_;
  Vec q_min_, q_max_;
  double dt_;
  BoolVec centred_;
  double shrink_;
  BoolVec ranged_;
  double pin_rtol_;
  std::vector<BoxForm> forms_;
  std::vector<GraspLine> lines_;
  std::vector<const DamperScene*> dampers_;
  std::vector<std::int64_t> damper_limits_;
};

}  // namespace dqk

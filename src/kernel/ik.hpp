// Numerical inverse kinematics of one arm's tool frame: damped least squares
// (Levenberg-Marquardt), as dualarm_qp/kinematics/ik.py states it. The Python function
// checks the input and reports; every iteration runs here.
#pragma once

#include <Eigen/Dense>
#include <cstdint>

#include "kinematics.hpp"

namespace dqk {

// Why the iteration stopped.
enum IKStop : int {
  IK_CONVERGED = 0,  // both tolerances met
  IK_MAX_ITER = 1,   // the iteration limit
  IK_LOCAL_MIN = 2,  // the step vanished: a local minimum of the error, or the limits
  IK_NO_DESCENT = 3  // no damping lowers the error any more
};

struct IKAnswer {
  std::int64_t iterations;  // linear solves performed
  double position_error;  // |p* - p(q)| [m]
  double rotation_error;  // angle of R* R(q)^T [rad]
  IKStop stop;
};

// Damped least squares from q (clipped into [lo, hi] first; infinite bounds for none)
// toward the pose T_target of frame `tool` of `chain`; the best iterate is written back
// into q. Each iteration solves (J_F^T J_F + mu |e|^2 I) dq_F = J_F^T e over the joints
// F not pushed past a limit they rest on, clips q + dq into the limits and keeps the
// step only if it lowers |e|^2; mu adapts to the ratio of actual to predicted decrease
// (x10 after a rejected step, x2 below 0.25, /3 above 0.75, within [mu_min, mu_max]).
IKAnswer ik_dls(Chain& chain, int tool, const Pose& T_target, Eigen::Ref<Eigen::VectorXd> q,
                const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, double tol_pos,
                double tol_rot, std::int64_t max_iter, double damping, double mu_min,
                double mu_max);

}  // namespace dqk

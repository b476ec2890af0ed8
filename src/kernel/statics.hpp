// One arm's quasi-static joint torques tau = g(q) + J(q)^T w and their derivative over q at
// a fixed world wrench (ArmStatics, dualarm_qp/task/torques.py, whose docstring derives
// the correction of Pinocchio's body-fixed force), on a Chain given inertias and gravity.
#pragma once

#include "kinematics.hpp"

namespace dqk {

using Vec6 = Eigen::Matrix<double, 6, 1>;

// The body of joint j (1..n): mass [kg], lever (its mass centre in the joint's frame) [m]
// and rotational inertia about the mass centre (3 x 3) [kg m^2].
void set_inertia(Chain& chain, int j, double mass, const Eigen::Vector3d& lever,
                 const Eigen::Matrix3d& inertia);
// Gravity [m/s^2], world frame.
void set_gravity(Chain& chain, const Eigen::Vector3d& g);

// The joint torques [N m] that hold the chain at q while the hand at frame `frame` applies
// `wrench` = [f; m] to the object (world axes, moment about the frame's origin), into tau
// (nq). With derivatives: d tau / d q at that world wrench into dtau (nq x nq) and the
// frame's Jacobian (LOCAL_WORLD_ALIGNED, [v; w]) into J (6 x nq).
void static_torques(Chain& chain, const Eigen::VectorXd& q, int frame, const Vec6& wrench,
                    Eigen::Ref<Eigen::VectorXd> tau, bool derivatives, Eigen::Ref<RowMat> dtau,
                    Eigen::Ref<RowMat> J);

}  // namespace dqk

// One arm's quasi-static joint torques tau = g(q) + J(q)^T w and their derivative over q at
// a fixed world wrench (ArmStatics, dualarm_qp/task/torques.py, whose docstring derives
// the correction of Pinocchio's body-fixed force), on a Chain given inertias and gravity.
#pragma once

#include <optional>

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
// `wrench` = [f; m] to the object at the world point `point` (world axes, the moment about
// `point`; none: the frame's origin p), into tau (nq): tau = g(q) + J(q)^T [f; m_p] with
// J the frame's Jacobian and m_p = m + (point - p) x f the moment moved to p. With
// derivatives: d tau / d q with the wrench and `point` fixed in the world into dtau
// (nq x nq) and J (LOCAL_WORLD_ALIGNED, [v; w]) into J (6 x nq); tau then comes from the
// derivatives' pass (world frame), which may differ in the last bits from tau without
// derivatives (Pinocchio's computeStaticTorque, joint frames).
void static_torques(Chain& chain, const Eigen::VectorXd& q, int frame, const Vec6& wrench,
                    const std::optional<Eigen::Vector3d>& point,
                    Eigen::Ref<Eigen::VectorXd> tau, bool derivatives, Eigen::Ref<RowMat> dtau,
                    Eigen::Ref<RowMat> J);

}  // namespace dqk

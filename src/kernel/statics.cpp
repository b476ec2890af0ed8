#include "statics.hpp"

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "chain_impl.hpp"

namespace dqk {

namespace pin = pinocchio;

void set_inertia(Chain& chain, int j, double mass, const Eigen::Vector3d& lever,
                 const Eigen::Matrix3d& inertia) {
  if (j < 1 || j >= chain.njoints()) throw std::out_of_range("no joint " + std::to_string(j));
  if (!(std::isfinite(mass) && mass >= 0.0 && lever.allFinite() && inertia.allFinite() &&
        (inertia - inertia.transpose()).cwiseAbs().maxCoeff() <=
            1e-12 * std::max(1.0, inertia.cwiseAbs().maxCoeff())))
    throw std::invalid_argument("set_inertia: a finite mass >= 0, lever and symmetric inertia");
  chain.impl().model.inertias[static_cast<std::size_t>(j)] =
      pin::Inertia(mass, lever, pin::Symmetric3(inertia));
}

void set_gravity(Chain& chain, const Eigen::Vector3d& g) {
  chain.impl().model.gravity = pin::Motion(g, Eigen::Vector3d::Zero());
}

void static_torques(Chain& chain, const Eigen::VectorXd& q, int frame, const Vec6& wrench,
                    const std::optional<Eigen::Vector3d>& point,
                    Eigen::Ref<Eigen::VectorXd> tau, bool derivatives, Eigen::Ref<RowMat> dtau,
                    Eigen::Ref<RowMat> J) {
  pin::Model& model = chain.impl().model;
  pin::Data& data = chain.impl().data;
  const Eigen::Index n = model.nv;
  chain.check_frame(frame);
  if (q.size() != n || tau.size() != n)
    throw std::invalid_argument("static_torques: q and tau must have nq entries");
  if (derivatives && (dtau.rows() != n || dtau.cols() != n || J.rows() != 6 || J.cols() != n))
    throw std::invalid_argument("static_torques: dtau must be (nq, nq) and J (6, nq)");
  if (point && !point->allFinite())
    throw std::invalid_argument("static_torques: point must be finite");
  const auto f_id = static_cast<pin::FrameIndex>(frame);
  pin::forwardKinematics(model, data, q);
  const Eigen::Vector3d p = pin::updateFramePlacement(model, data, f_id).translation();
  // The hand's wrench about the tool point p: its force acts at `point` (default p).
  const Eigen::Vector3d force = wrench.head<3>();
  const Eigen::Vector3d arm = point ? Eigen::Vector3d(*point - p) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d moment = wrench.tail<3>() + arm.cross(force);
  // -wrench on the hand, about the world origin, then in the hand's joint frame.
  const Eigen::Vector3d f = -force, m = -moment;
  const pin::Force at_origin(f, m + p.cross(f));
  const pin::JointIndex joint = model.frames[f_id].parentJoint;
  std::vector<pin::Force> fext(static_cast<std::size_t>(model.njoints), pin::Force::Zero());
  fext[joint] = data.oMi[joint].actInv(at_origin);
  if (!derivatives) {
    tau = pin::computeStaticTorque(model, data, q, fext);
    return;
  }
  // One pass for the torques, their derivatives and the joints' Jacobians: the derivatives'
  // backward pass leaves the static torques in data.tau and its forward pass the joints'
  // world Jacobians in data.J (what computeJointJacobians fills, by the same products).
  Eigen::MatrixXd dq = Eigen::MatrixXd::Zero(n, n);
  pin::computeStaticTorqueDerivatives(model, data, q, fext, dq);
  tau = data.tau;
  pin::Data::Matrix6x Jf = pin::Data::Matrix6x::Zero(6, n);
  pin::getFrameJacobian(model, data, f_id, pin::LOCAL_WORLD_ALIGNED, Jf);
  // A world-fixed force does not turn with the body: column j gains
  // -J^T [omega_j x f_w; omega_j x m_w] = J^T [f_w x omega_j; m_w x omega_j]. Its point
  // stays in the world while p moves by v_j: m_p gains -v_j x f_w = f_w x v_j (zero for a
  // wrench about p itself, which moves with the hand).
  Eigen::MatrixXd turned(6, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::Vector3d omega = Jf.block<3, 1>(3, j);
    turned.block<3, 1>(0, j) = -force.cross(omega);
    turned.block<3, 1>(3, j) = -moment.cross(omega);
    if (point) turned.block<3, 1>(3, j) -= force.cross(Eigen::Vector3d(Jf.block<3, 1>(0, j)));
  }
  dtau = dq - Jf.transpose() * turned;
  J = Jf;
}

}  // namespace dqk

#include "ik.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "step_kinematics.hpp"

namespace dqk {

namespace {

struct Error {
  Eigen::Matrix<double, 6, 1> e;
  double pos, rot, cost;
};

Error error_at(const Pose& T_target, const Pose& T) {
  Error out;
  pose_error(T_target, T, out.e);
  const auto& e = out.e;
  out.pos = std::sqrt(e(0) * e(0) + e(1) * e(1) + e(2) * e(2));
  out.rot = std::sqrt(e(3) * e(3) + e(4) * e(4) + e(5) * e(5));
  out.cost = out.pos * out.pos + out.rot * out.rot;
  return out;
}

}  // namespace

IKAnswer ik_dls(Chain& chain, int tool, const Pose& T_target, Eigen::Ref<Eigen::VectorXd> q,
                const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, double tol_pos,
                double tol_rot, std::int64_t max_iter, double damping, double mu_min,
                double mu_max) {
  const Eigen::Index n = chain.nq();
  if (q.size() != n || lo.size() != n || hi.size() != n) {
    throw std::invalid_argument("ik_dls: q, lo and hi hold one number per joint of the chain");
  }
  chain.check_frame(tool);
  const std::vector<int> frames{tool};
  const std::vector<int> none;
  RowMat T_rows(4, 4), J(6, n), no_J(0, n);
  for (Eigen::Index i = 0; i < n; ++i) q(i) = std::min(std::max(q(i), lo(i)), hi(i));
  chain.compute(q, frames, frames, T_rows, J);
  Error err = error_at(T_target, Pose(T_rows));
  double mu = damping;
  IKAnswer answer{0, err.pos, err.rot, IK_MAX_ITER};
  Eigen::VectorXd q_new(n), step(n), dq(n);
  std::vector<Eigen::Index> free;
  free.reserve(static_cast<std::size_t>(n));
  while (!(err.pos <= tol_pos && err.rot <= tol_rot)) {
    if (answer.iterations >= max_iter) break;
    ++answer.iterations;
    const Eigen::VectorXd g = J.transpose() * err.e;
    free.clear();
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!((q(i) <= lo(i) && g(i) < 0.0) || (q(i) >= hi(i) && g(i) > 0.0))) free.push_back(i);
    }
    const auto k = static_cast<Eigen::Index>(free.size());
    dq.setZero();
    if (k > 0) {
      RowMat J_free(6, k);
      Eigen::VectorXd g_free(k);
      for (Eigen::Index j = 0; j < k; ++j) {
        J_free.col(j) = J.col(free[j]);
        g_free(j) = g(free[j]);
      }
      Eigen::MatrixXd A = J_free.transpose() * J_free;
      A.diagonal().array() += mu * err.cost;
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(A);
      if ((lu.matrixLU().diagonal().array() == 0.0).any()) {  // singular: damp more
        mu *= 10.0;
        continue;
      }
      const Eigen::VectorXd d = lu.solve(g_free);
      for (Eigen::Index j = 0; j < k; ++j) dq(free[j]) = d(j);
    }
    double step_max = 0.0, q_max = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      q_new(i) = std::min(std::max(q(i) + dq(i), lo(i)), hi(i));
      step(i) = q_new(i) - q(i);
      step_max = std::max(step_max, std::abs(step(i)));
      q_max = std::max(q_max, std::abs(q(i)));
    }
    if (!(step_max > 1e-15 * (1.0 + q_max))) {
      answer.stop = IK_LOCAL_MIN;
      break;
    }
    chain.compute(q_new, frames, none, T_rows, no_J);  // the Jacobian only if kept
    const Error next = error_at(T_target, Pose(T_rows));
    if (next.cost < err.cost) {
      if (!(next.pos <= tol_pos && next.rot <= tol_rot)) {  // adapt mu for the next step
        const Eigen::Matrix<double, 6, 1> Js = J * step;
        const double predicted = 2.0 * err.e.dot(Js) - Js.dot(Js);  // model decrease
        const double rho = predicted > 0.0 ? (err.cost - next.cost) / predicted : 0.0;
        if (rho > 0.75) {
          mu = std::max(mu / 3.0, mu_min);
        } else if (rho < 0.25) {
          mu = std::min(mu * 2.0, mu_max);
        }
        chain.frame_jacobian(tool, J);  // the kinematics at q_new: computed above
      }
      q = q_new;
      err = next;
    } else {
      mu *= 10.0;
      if (mu > mu_max) {
        answer.stop = IK_NO_DESCENT;
        break;
      }
    }
  }
  answer.position_error = err.pos;
  answer.rotation_error = err.rot;
  if (err.pos <= tol_pos && err.rot <= tol_rot) answer.stop = IK_CONVERGED;
  return answer;
}

}  // namespace dqk

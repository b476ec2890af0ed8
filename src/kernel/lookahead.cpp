#include "lookahead.hpp"

#include <cmath>
#include <stdexcept>

#include "step_kinematics.hpp"

namespace dqk {

bool predicted_errors(Chain& carry, const std::vector<int>& carry_frames, Chain& follower,
                      int follower_tool, const Eigen::VectorXd& q_l,
                      const Eigen::VectorXd& q_f, double sigma_f, double sigma_l,
                      const Eigen::VectorXd& x, const Eigen::VectorXd& col_rate, double dt,
                      const Pose& T_D, Eigen::Ref<Eigen::VectorXd> e) {
  const Eigen::Index n_l = q_l.size(), n_f = q_f.size();
  const Eigen::Index n_grasp = x.size() - n_l - n_f;
  if (n_grasp < 1 || n_grasp > 2 || carry.nq() != n_l + n_grasp ||
      follower.nq() != n_f || col_rate.size() != x.size() - n_f || e.size() != 12) {
    throw std::invalid_argument(
        "predicted_errors: x holds the arms' joint rates and one or two grasp speeds, "
        "the carry chain the leader's joints and the grasps, col_rate one rate per "
        "carry column, e (12)");
  }
  bool finite = true;
  Eigen::VectorXd q_carry(carry.nq()), q_f_next(n_f);
  for (Eigen::Index i = 0; i < n_l; ++i) {
    const double step = dt * x(i);
    q_carry(i) = q_l(i) + step;
    finite = finite && std::isfinite(x(i));
  }
  for (Eigen::Index i = 0; i < n_f; ++i) {
    const double step = dt * x(n_l + i);
    q_f_next(i) = q_f(i) + step;
    finite = finite && std::isfinite(x(n_l + i));
  }
  const Eigen::Index k = n_l + n_f;
  const double sigma_f_next = sigma_f + dt * x(k);
  const double sigma_l_next = sigma_l + (n_grasp == 2 ? dt * x(k + 1) : 0.0);
  finite = finite && std::isfinite(x(k)) && (n_grasp == 1 || std::isfinite(x(k + 1))) &&
           std::isfinite(sigma_f_next) && std::isfinite(sigma_l_next);
  if (!finite) return false;
  if (n_grasp == 2) {
    q_carry(n_l) = col_rate(n_l + 1) * sigma_l_next;
    q_carry(n_l + 1) = col_rate(n_l) * sigma_f_next;
  } else {
    q_carry(n_l) = col_rate(n_l) * sigma_f_next;
  }
  step_errors(carry, q_carry, carry_frames, follower, q_f_next, follower_tool, T_D, e);
  return true;
}

}  // namespace dqk

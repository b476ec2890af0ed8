#include "lookahead.hpp"

#include <cmath>
#include <stdexcept>

#include "step_kinematics.hpp"

namespace dqk {

PredictedErrors predicted_errors(Chain& carry, const std::vector<int>& carry_frames,
                                 Chain& follower, int follower_tool, const Eigen::VectorXd& q_l,
                                 const Eigen::VectorXd& q_f, double sigma_f, double sigma_l,
                                 const Eigen::VectorXd& x, const Eigen::VectorXd& col_rate,
                                 double dt, const Pose& T_D) {
  const Eigen::Index n_l = q_l.size(), n_f = q_f.size();
  const Eigen::Index n_grasp = x.size() - n_l - n_f;
  if (n_grasp < 1 || n_grasp > 2 || carry.nq() != n_l + n_grasp ||
      follower.nq() != n_f || col_rate.size() != x.size() - n_f) {
    throw std::invalid_argument(
        "predicted_errors: x holds the arms' joint rates and one or two grasp speeds, "
        "the carry chain the leader's joints and the grasps, col_rate one rate per "
        "carry column");
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
  PredictedErrors out;
  if (!finite) return out;
  if (n_grasp == 2) {
    q_carry(n_l) = col_rate(n_l + 1) * sigma_l_next;
    q_carry(n_l + 1) = col_rate(n_l) * sigma_f_next;
  } else {
    q_carry(n_l) = col_rate(n_l) * sigma_f_next;
  }
  Eigen::Matrix<double, 12, 1> e;
  step_errors(carry, q_carry, carry_frames, follower, q_f_next, follower_tool, T_D, e);
  out.finite = true;
  out.tracking_position = std::hypot(e(0), e(1), e(2));
  out.tracking_rotation = std::hypot(e(3), e(4), e(5));
  out.closure_position = std::hypot(e(6), e(7), e(8));
  out.closure_rotation = std::hypot(e(9), e(10), e(11));
  return out;
}

bool negligible(const Eigen::VectorXd& x, Eigen::Index n_l, Eigen::Index n_f, double dt,
                const Pose& T_tool, const Pose& T_target,
                double length_l, double length_f, double budget_pos, double budget_rot,
                double share) {
  if (n_l < 0 || n_f < 0 || n_l + n_f > x.size()) {
    throw std::invalid_argument("negligible: x holds the leader's and the follower's rates");
  }
  const auto travel = [&x](Eigen::Index from, Eigen::Index to) {
    double sum = 0.0;
    for (Eigen::Index i = from; i < to; ++i) sum += std::abs(x(i));
    return sum;
  };
  const double turn_l = dt * travel(0, n_l);
  const double turn_f = dt * travel(n_l, n_l + n_f);
  const double grasps = dt * travel(n_l + n_f, x.size());
  const Eigen::Vector3d d = T_target.block<3, 1>(0, 3) - T_tool.block<3, 1>(0, 3);
  const double lever = std::sqrt(d(0) * d(0) + d(1) * d(1) + d(2) * d(2));
  double pos = 0.5 * (turn_l * turn_l * (length_l + lever) + turn_f * turn_f * length_f);
  const double rot = 0.5 * (turn_l * turn_l + turn_f * turn_f);
  // A grasp sliding on a curved path turns with it: its travel counts as a turn of the
  // object's length (a straight path adds nothing at second order but is counted too).
  pos += 0.5 * grasps * grasps + turn_l * grasps;
  return pos <= share * budget_pos && rot <= share * budget_rot;
}

}  // namespace dqk

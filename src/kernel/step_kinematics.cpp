#include "step_kinematics.hpp"

#include <pinocchio/spatial.hpp>
#include <stdexcept>

#include "boxes.hpp"

namespace dqk {

void pose_error(const Pose& T_star, const Pose& T, Eigen::Ref<Eigen::VectorXd> e) {
  e.head<3>() = T_star.block<3, 1>(0, 3) - T.block<3, 1>(0, 3);
  const Eigen::Matrix3d R = T_star.block<3, 3>(0, 0) * T.block<3, 3>(0, 0).transpose();
  e.tail<3>() = pinocchio::log3(R);
}

void step_kinematics(Chain& carry, const Eigen::VectorXd& q_carry,
                     const std::vector<int>& carry_frames, Chain& follower,
                     const Eigen::VectorXd& q_f, int follower_tool, const Pose& T_D,
                     Eigen::Index n_l, Eigen::Ref<RowMat> T, Eigen::Ref<RowMat> J,
                     Eigen::Ref<RowMat> J_f, Eigen::Ref<Eigen::VectorXd> e,
                     Eigen::Ref<Eigen::VectorXd> sv) {
  if (carry_frames.size() != 3 || T.rows() != 16 || T.cols() != 4 || e.size() != 12 ||
      (sv.size() != 2 && sv.size() != 0) || n_l < 0 || n_l > J.cols()) {
    throw std::invalid_argument(
        "step_kinematics: three carry frames, T (16, 4), e (12), sv (2 or 0), n_l <= nq");
  }
  carry.compute(q_carry, carry_frames, carry_frames, T.topRows(12), J);
  const std::vector<int> tool{follower_tool};
  follower.compute(q_f, tool, tool, T.bottomRows(4), J_f);
  const Pose T_tool_f = T.bottomRows(4);
  const Pose T_object = T.middleRows(4, 4);
  const Pose T_target = T.middleRows(8, 4);
  pose_error(T_D, T_object, e.head(6));
  pose_error(T_target, T_tool_f, e.tail(6));
  if (sv.size() == 0) return;
  sv(0) = smallest_singular_value(J.topLeftCorner(6, n_l));
  sv(1) = smallest_singular_value(J_f);
}

void step_errors(Chain& carry, const Eigen::VectorXd& q_carry,
                 const std::vector<int>& carry_frames, Chain& follower,
                 const Eigen::VectorXd& q_f, int follower_tool, const Pose& T_D,
                 Eigen::Ref<Eigen::VectorXd> e) {
  if (carry_frames.size() != 3 || e.size() != 12) {
    throw std::invalid_argument("step_errors: three carry frames, e (12)");
  }
  RowMat T(16, 4);
  carry.poses_at(q_carry, carry_frames, T.topRows(12));
  const std::vector<int> tool{follower_tool};
  follower.poses_at(q_f, tool, T.bottomRows(4));
  pose_error(T_D, T.middleRows(4, 4), e.head(6));
  pose_error(T.middleRows(8, 4), T.bottomRows(4), e.tail(6));
}

}  // namespace dqk

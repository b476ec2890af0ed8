// The step's equality block from the carried-object kinematics (Eqs. 14 and 25-27).
#pragma once

#include "kinematics.hpp"

namespace dqk {

using Vec6 = Eigen::Matrix<double, 6, 1>;

// Rows 0-5, the object follows D(t):  J_o [ql_dot; m] = scale V_o + K_l e_l.
// Rows 6-11, the grasp stays closed:   J_f qf_dot - J_t [ql_dot; m] = K e_c.
// J_object and J_target are (6, n_l + k) over [q_l (n_l), grasps in decision order], J_f is
// (6, n_f); A (12, n_l + n_f + k) and b (12) are written, x = [ql_dot, qf_dot, m...].
// Without exact_orientation the follower grasp's column of the closure's angular rows
// is zero (the paper's frozen grasp orientation). Returns whether A and b are finite.
bool carry_equality(Eigen::Index n_l, const Eigen::Ref<const RowMat>& J_object,
                    const Eigen::Ref<const RowMat>& J_target, const Eigen::Ref<const RowMat>& J_f,
                    const Vec6& twist, const Vec6& e_l, const Vec6& e_c, double scale,
                    double gain_l, double gain_c, bool exact_orientation, Eigen::Ref<RowMat> A,
                    Eigen::Ref<Eigen::VectorXd> b);

}  // namespace dqk

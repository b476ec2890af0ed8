// Both arms' quasi-static joint torques holding a load split by the minimum-norm rule, and
// their derivative over the decision variables (LoadTorques.linearised for grasps,
// dualarm_qp/task/torques.py; docs/derivation.md, "Joint torques", derives each part).
#pragma once

#include <vector>

#include "load_split.hpp"
#include "statics.hpp"

namespace dqk {

// The hands and the load's mass centre at one state (world frame): hand 0 the leader's.
struct HandSet {
  Points points;           // 2 x 3 [m]
  std::vector<Mat> free;   // 6 x k_i free twists per hand
  Eigen::Vector3d centre;  // [m]
};

struct LoadTorques {
  Vec tau;     // n_l + n_f: the leader's joint torques, then the follower's [N m]
  RowMat D;    // (n_l + n_f) x (n_l + n_f + n_grasp): d tau / d (q_l, q_f, grasps)
  RowMat w;    // 2 x 6: each hand's wrench on the object [N, N m], about its grasp point
};

// sets[0] is the state; sets[1 + i] the state with grasp i (decision order: the
// follower's, then a sliding leader's) moved by grasp_step [m]. The split is K g
// (split_operator), each hand's force acting at its grasp point (sets[0].points) and its
// moment moved to the tool point, whose Jacobian carries it; the leader's columns by the
// rotation identity d w / d q_j = omega_j x w - K (omega_j x g) with the grasp points
// carried by the object, the grasps' by forward differences of the moved wrenches.
LoadTorques load_torques(Chain& leader, int leader_tool, Chain& follower, int follower_tool,
                         const Vec& q_l, const Vec& q_f, const Eigen::Vector3d& gravity,
                         double mass, const std::vector<HandSet>& sets, double grasp_step,
                         double fallback_length, double rcond_min);

}  // namespace dqk

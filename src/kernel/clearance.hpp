// The collision scene's proximities and the velocity damper's rows (CollisionScene.measure
// and CollisionLimit.constraint, dualarm_qp/collision/scene.py and
// dualarm_qp/step/limits/collision.py, whose docstrings state the rules).
#pragma once

#include <vector>

#include "capsules.hpp"
#include "coal_pairs.hpp"
#include "kinematics.hpp"

namespace dqk {

// Owners of a body, in the order of the scene's frame stack.
enum Owner : int { LEADER = 0, FOLLOWER = 1, OBJECT = 2, WORLD = 3 };

struct Proximities {
  std::vector<int> pairs;  // indices of the measured pairs
  bool finite = true;      // every capsule distance was finite (their sum is)
  Eigen::VectorXd distance;
  Points point_a, point_b, normal;
};

// Every body is a capsule (a_local, b_local, r) in frame body_frame of the stack frames
// (4F x 4, the frames' world poses); sphere is the radius of its bounding sphere about
// the axis' midpoint. Pairs (ia[k], ib[k]) whose bounding spheres are at least within
// apart are skipped (within = inf measures every pair); the others get their capsule
// proximity, in the pairs' order. With exact (the same bodies and pairs), a pair with a
// box (whose capsule contains the box: its distance is a lower bound) is measured by
// coal when its capsule distance is below within, and dropped otherwise (kept at its
// bound when within = inf, which only a non-finite distance is not below).
Proximities scene_proximities(const Eigen::Ref<const RowMat>& frames,
                              const std::vector<int>& body_frame,
                              const Eigen::Ref<const Points>& a_local,
                              const Eigen::Ref<const Points>& b_local,
                              const Eigen::Ref<const Eigen::VectorXd>& r,
                              const Eigen::Ref<const Eigen::VectorXd>& sphere,
                              const std::vector<int>& ia, const std::vector<int>& ib,
                              double within, const CoalPairs* exact = nullptr);

// The damper's rows: row k is n_k^T (J_a(p_a,k) - J_b(p_b,k)) over the decision vector
// (n entries: the leader's n_l joints, the follower's n_f, then the sliding grasps from
// grasp_start). Body a of row k is owned by owners[2k] in model frame frames[2k], body b
// by owners[2k + 1] in frames[2k + 1]. A leader link reads the carried-object chain
// (leader's joints in its first n_l columns), a follower link the follower's chain, the
// object J_object (6 x (n_l + grasps), decision order, at object_origin), the world
// nothing. The chains hold this step's kinematics.
RowMat damper_rows(const Chain& leader, const Chain& follower,
                   const Eigen::Ref<const RowMat>& J_object, const Point& object_origin,
                   const std::vector<int>& owners, const std::vector<int>& frames,
                   const Eigen::Ref<const Points>& point_a,
                   const Eigen::Ref<const Points>& point_b,
                   const Eigen::Ref<const Points>& normal, Eigen::Index n_l, Eigen::Index n_f,
                   Eigen::Index grasp_start, Eigen::Index n);

}  // namespace dqk

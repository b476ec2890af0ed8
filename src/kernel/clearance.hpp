// The collision scene's proximities and the velocity damper's rows (CollisionScene.measure
// and CollisionLimit.constraint, dualarm_qp/collision/scene.py and
// dualarm_qp/step/limits/collision.py, whose docstrings state the rules).
#pragma once

#include <vector>

#include "capsules.hpp"
#include "kinematics.hpp"

namespace dqk {

class CoalPairs;  // coal_pairs.hpp

// Owners of a body, in the order of the scene's frame stack.
enum Owner : int { LEADER = 0, FOLLOWER = 1, OBJECT = 2, WORLD = 3 };

struct Proximities {
  std::vector<int> pairs;  // indices of the measured pairs
  bool finite = true;      // every body's axis and every capsule distance was finite (when
                           // false nothing else is filled in)
  Eigen::VectorXd distance;
  Points point_a, point_b, normal;
};

// Every body is a capsule (a_local, b_local, r) in frame body_frame of the stack frames
// (4F x 4, the frames' world poses); sphere is the radius of its bounding sphere about
// the axis' midpoint. Pairs (ia[k], ib[k]) whose bounding spheres are at least within
// apart are skipped (within = inf measures every pair); the others get their capsule
// proximity, in the pairs' order. A body placed off the finite numbers makes the answer
// not finite, whatever within (its pairs are never skipped as far). With exact (the same
// bodies and pairs), a pair with a box (whose capsule contains the box: its distance is
// a lower bound) is measured by coal when its capsule distance is below within and so
// is the box's bound (CoalPairs::lower_bound, of the other body's capsule against the
// box, along the box's axes), and dropped otherwise (within = inf: every one by coal).
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

// The velocity damper of a collision scene at one step (CollisionLimit.constraint): the
// frame stack (the leader's link frames, the follower's, the object frame, the world),
// the proximities of the pairs within d_i (scene_proximities), and for each pair closer
// than d_i the row n^T (J_a - J_b) (damper_rows) and its bound gain (d - d_s); a row
// whose largest entry is at most zero_row is left out (no variable moves the pair).
struct DamperRows {
  bool finite = true;      // the scene and the rows were finite (else nothing else)
  std::vector<int> pairs;  // the scene's pair of each row
  RowMat G;
  Eigen::VectorXd h;
};

// Not to be used from two threads at once (coal's solvers keep a mutable state): the
// bindings hold the GIL.
class DamperScene {
 public:
  // Bodies and pairs as scene_proximities reads them (exact: null, or the scene's
  // CoalPairs, which must outlive this); per body its owner (Owner) and model frame
  // (an arm's link; -1 for the object and the world); the arms' link frames in the
  // order of the stack; the damper's numbers and the decision vector's layout.
  DamperScene(std::vector<int> body_frame, Points a_local, Points b_local,
              Eigen::VectorXd r, Eigen::VectorXd sphere, std::vector<int> ia,
              std::vector<int> ib, const CoalPairs* exact, std::vector<int> owner,
              std::vector<int> model_frame, std::vector<int> leader_frames,
              std::vector<int> follower_frames, double d_i, double d_s, double gain,
              double zero_row, Eigen::Index n_l, Eigen::Index n_f, Eigen::Index grasp_start,
              Eigen::Index n);

  // The rows at this step: the chains hold its kinematics, J_object (6 x (n_l +
  // grasps)) and T_object (4 x 4) are the carried object's.
  DamperRows rows(const Chain& leader, const Chain& follower,
                  const Eigen::Ref<const RowMat>& J_object,
                  const Eigen::Ref<const RowMat>& T_object) const;

 private:
  std::vector<int> body_frame_;
  Points a_local_, b_local_;
  Eigen::VectorXd r_, sphere_;
  std::vector<int> ia_, ib_;
  const CoalPairs* exact_;
  std::vector<int> owner_, model_frame_, leader_frames_, follower_frames_;
  double d_i_, d_s_, gain_, zero_row_;
  Eigen::Index n_l_, n_f_, grasp_start_, n_;
};

}  // namespace dqk

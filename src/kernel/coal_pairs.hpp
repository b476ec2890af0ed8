// The collision scene's pairs with a box, measured by coal (the library that ships with
// Pinocchio) in the kernel: the rules are those of coal_proximity and
// CollisionScene.measure (dualarm_qp/geometry/distance.py, dualarm_qp/collision/scene.py).
#pragma once

#include <memory>
#include <vector>

#include <coal/collision_data.h>
#include <coal/distance.h>

#include "capsules.hpp"
#include "kinematics.hpp"

namespace dqk {

// A body's coal geometry (coal_parts in dualarm_qp/geometry/distance.py): a box of
// sizes (x, y, z) centred on its pose, a capsule of (radius, length) along its local z
// axis centred on its origin, or a sphere of (radius).
enum CoalKind : int { COAL_NONE = 0, COAL_BOX = 1, COAL_CAPSULE = 2, COAL_SPHERE = 3 };

// A capsule in the world: the segment [p0, p1] swept by a ball of radius r [m].
struct WorldCapsule {
  Point p0, p1;
  double r;
};

// The bodies' coal geometries and one coal solver per pair that has a box. Not to be
// used from two threads at once: coal's solver keeps a mutable state (its GJK solver)
// behind a const call; the bindings hold the GIL, and must keep holding it.
class CoalPairs {
 public:
  // Body i is kinds[i] with the numbers params.row(i) (unused ones ignored), posed by
  // local rows 4i to 4i + 3 in its frame; pair k is (ia[k], ib[k]) and is measured by
  // coal when boxed[k]. gjk_tol and epa_tol are coal's DistanceRequest tolerances.
  CoalPairs(const std::vector<int>& kinds, const Eigen::Ref<const Points>& params,
            const Eigen::Ref<const RowMat>& local, const std::vector<int>& ia,
            const std::vector<int>& ib, const std::vector<bool>& boxed, double gjk_tol,
            double epa_tol);
  CoalPairs(const CoalPairs&) = delete;
  CoalPairs& operator=(const CoalPairs&) = delete;

  size_t n_bodies() const { return geoms_.size(); }
  size_t n_pairs() const { return solvers_.size(); }
  bool boxed(size_t pair) const { return solvers_[pair] != nullptr; }

  // Coal's proximity of pair k with body i at world pose frame_pose(i) * local(i);
  // a normal that is not of unit length (a touching or non-finite answer) is replaced
  // by the witness points' direction (signed by the distance), else the direction
  // between the bodies' origins, else +z.
  CapsuleProximity measure(size_t pair, const Eigen::Matrix4d& frame_a,
                           const Eigen::Matrix4d& frame_b) const;

  // A certain lower bound of pair k's signed distance, its bodies posed as by measure
  // and contained in the capsules a and b (in the world: a capsule's own, a box's
  // containing one). For each body that is a box, the other's segment in the box's frame
  // spans an interval along each box axis j, g_j beyond the box's [-h_j, h_j] (0 where
  // they overlap): every point of the segment is at least |g| from the box, so when |g|
  // exceeds the other's radius the pair is apart, by at least |g| minus that radius
  // (else nothing is certain: they may overlap by any depth, -inf). The larger of the
  // two when both are boxes; -inf when neither is. Exact, while they are apart, for a
  // sphere or a capsule along one of the box's axes against the box.
  double lower_bound(size_t pair, const Eigen::Matrix4d& frame_a,
                     const Eigen::Matrix4d& frame_b, const WorldCapsule& a,
                     const WorldCapsule& b) const;

 private:
  std::vector<std::shared_ptr<coal::CollisionGeometry>> geoms_;
  std::vector<Eigen::Matrix4d> local_;
  std::vector<int> kinds_;
  std::vector<Point> half_;  // a box's half sizes [m] (zero for the other kinds)
  std::vector<int> ia_, ib_;
  std::vector<std::unique_ptr<coal::ComputeDistance>> solvers_;  // null: a capsule pair
  coal::DistanceRequest request_;
};

}  // namespace dqk

// The library's own parts of a step (parts.hpp): the two carry tasks, the paper's
// centring cost and the range, speed, acceleration and collision limits. Each is what
// its Python class in dualarm_qp/step states (its docstring has the equations).
#pragma once

#include <string>
#include <vector>

#include "clearance.hpp"
#include "parts.hpp"

namespace dqk {

// The object follows D(t) (Eq. 14 differentiated):
//   J_o [ql_dot; m] = scale_max V_o + gain e_l    (six rows; the follower's joints 0).
class ObjectPathTask : public Task {
 public:
  explicit ObjectPathTask(double gain) : gain(gain) {}
  Equality equality(const Context& ctx) const override;
  double gain;  // K_l [1/s]
};

// The follower's grasp stays closed (Eqs. 25-27):
//   J_f qf_dot - J_t [ql_dot; m] = gain e_c      (six rows). Without exact_orientation
// the follower grasp's column of the angular rows is zero (the paper's frozen grasp
// orientation, Sec. 3.3).
class GraspClosureTask : public Task {
 public:
  GraspClosureTask(double gain, bool exact_orientation)
      : gain(gain), exact_orientation(exact_orientation) {}
  Equality equality(const Context& ctx) const override;
  double gain;  // K [1/s]
  bool exact_orientation;
};

// Eqs. 37-40: (x - c)^T diag(w) (x - c) with c the middle of each centred variable's
// finite rate range (0 otherwise), scaled by shrink (dt over the centring horizon).
class CentringCost : public CostTerm {
 public:
  CentringCost(Vec weights, BoolVec centred, double shrink);
  Quadratic quadratic(const Context& ctx) const override;
  const Vec& weights() const { return w_; }
  const BoolVec& centred() const { return centred_; }
  double shrink() const { return shrink_; }

 private:
  Vec w_;
  BoolVec centred_;
  double shrink_;
};

// [rate_lo, rate_hi] on the variables it bounds (not off), opened towards the range for
// a variable outside it, with the recovery rates rec (range_box, boxes.hpp).
class RangeLimit : public Limit {
 public:
  RangeLimit(Vec rec, BoolVec off);
  Constraint constraint(const Context& ctx) const override;
  const Vec& recovery() const { return rec_; }
  const BoolVec& off() const { return off_; }

 private:
  Vec rec_;
  BoolVec off_;
};

// [-v_max, v_max] (inf: no limit).
class SpeedLimit : public Limit {
 public:
  explicit SpeedLimit(Vec v_max) : v_(std::move(v_max)) {}
  Constraint constraint(const Context& ctx) const override;
  const Vec& v_max() const { return v_; }

 private:
  Vec v_;
};

// The largest rate from which a stop within the distance D [rad or m] is possible when
// the rate may change by delta per sample (dualarm_qp/step/limits/acceleration.py):
// V(D) = (D / dt + delta n (n + 1) / 2) / (n + 1), n = floor((-1 + sqrt(1 + 8 D /
// (delta dt))) / 2); inf where D or delta is infinite, D < 0 read as 0.
double braking_bound(double D, double delta, double dt);

// [x_applied - delta, x_applied + delta], delta = a dt, cut by the braking bound of the
// distance to each range end (none towards an end the variable is already beyond).
class AccelerationLimit : public Limit {
 public:
  explicit AccelerationLimit(Vec delta) : delta_(std::move(delta)) {}
  Constraint constraint(const Context& ctx) const override;
  const Vec& delta() const { return delta_; }

 private:
  Vec delta_;
};

// The velocity damper of a collision scene (DamperScene, clearance.hpp): one row per
// pair closer than its influence distance, named names[pair]. damper must outlive this.
class CollisionLimit : public Limit {
 public:
  CollisionLimit(const DamperScene* damper, std::vector<std::string> names,
                 std::string nonfinite);
  Constraint constraint(const Context& ctx) const override;

 private:
  const DamperScene* damper_;
  std::vector<std::string> names_;
  std::string nonfinite_;
};

}  // namespace dqk

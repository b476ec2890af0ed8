// The parts a step is made of, and what every part reads (dualarm_qp/step/parts.py).
//
// A step is one loop (Step, step.hpp): the context (both arms' kinematics, once), then
// each task, each cost term and each limit asked in turn for its piece, then the pieces
// stacked into one problem. A part is an object of one of three abstract classes, each
// with one virtual method:
//   Task::equality(ctx)      rows A x = b (an equality task) or, for a task with a
//                            weight, the term weight |A x - b|^2 of the cost;
//   CostTerm::quadratic(ctx) a term (x - c)^T W (x - c) of the cost;
//   Limit::constraint(ctx)   boxes lower <= x <= upper and/or rows G x <= h.
// The library's standard parts are C++ classes derived from these (standard_parts.hpp);
// a part written in Python is a Python subclass (bound with a trampoline, bind_step.cpp)
// and the loop asks it through the same virtual.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "kinematics.hpp"
#include "linalg.hpp"

namespace dqk {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using BoolVec = Eigen::Matrix<bool, Eigen::Dynamic, 1>;

// The step's state and its kinematics, computed once by the step before any part is
// asked. World frame, Jacobians [v; w], columns in the decision vector's order.
struct Context {
  Index n_l = 0, n_f = 0, k = 0, n = 0;  // joints, grasps, decision variables
  double t = 0.0;          // path time [s]
  double dt = 0.0;         // sampling interval [s]
  double scale_max = 1.0;  // share of the path's feed-forward asked for
  Pose T_tool = Pose::Identity();    // the leader's tool
  Pose T_object = Pose::Identity();  // the object frame
  Pose T_target = Pose::Identity();  // the follower's target on the object
  Pose T_f = Pose::Identity();       // the follower's tool
  RowMat J_tool;    // (6, n_l)
  RowMat J_object;  // (6, n_l + k): the leader's joints, then the grasps' sliding speeds
  RowMat J_target;  // (6, n_l + k)
  RowMat J_f;       // (6, n_f)
  Vec6 leader_error = Vec6::Zero();   // [dp; dw] from the object frame to D(t) [m, rad]
  Vec6 closure_error = Vec6::Zero();  // [dp; dw] from the follower's tool to its target
  Vec6 twist = Vec6::Zero();          // D(t)'s twist [m/s, rad/s]
  Vec positions;  // (n) what the variables are rates of: joints [rad], grasps [m]
  Vec rate_lo;    // (n) the rates that reach each variable's range ends in one sample
  Vec rate_hi;    // (n)
  Vec x_applied;  // (n) the last command applied [rad/s, m/s]
  const Chain* leader = nullptr;    // the carried-object chain at this step's joints
  const Chain* follower = nullptr;  // the follower's chain at this step's joints
  void* user = nullptr;  // what a part written in Python reads instead (its context)
};

// A task's rows: A x = b, one name per row (given by the task), all finite or not.
struct Equality {
  RowMat A;  // (m, n)
  Vec b;     // (m)
  std::vector<std::string> names;
};

// A cost term (x - center)^T W (x - center): W by its diagonal w (n), or whole (n, n).
struct Quadratic {
  Vec w;       // the diagonal; empty for a full W
  RowMat W;    // the whole matrix; empty for a diagonal one
  Vec center;  // (n)
  bool diagonal() const { return W.size() == 0; }
};

// What a limit asks of x: boxes and/or rows. A missing box is (-inf, inf).
struct Constraint {
  bool has_lower = false, has_upper = false;
  Vec lower, upper;  // (n) each when given
  RowMat G;          // (p, n)
  Vec h;             // (p)
  std::vector<std::string> row_names;  // one per row
  // A compiled part that could not compute its piece at this state (a non-finite frame
  // or Jacobian) says what, here; the step stops there (dualarm_qp raises it as a
  // NonFiniteError naming it). Empty: the piece is computed.
  std::string nonfinite;
};

class Task {
 public:
  virtual ~Task() = default;
  // The task's rows at this step. With a finite weight (set by the part, >= 0) they
  // are the cost term weight |A x - b|^2, else equality rows.
  virtual Equality equality(const Context& ctx) const = 0;
  double weight = std::numeric_limits<double>::infinity();
};

class CostTerm {
 public:
  virtual ~CostTerm() = default;
  virtual Quadratic quadratic(const Context& ctx) const = 0;
};

class Limit {
 public:
  virtual ~Limit() = default;
  virtual Constraint constraint(const Context& ctx) const = 0;
};

}  // namespace dqk

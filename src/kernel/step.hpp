// One step as one loop (StepBuilder.build, dualarm_qp/step/build.py): the context
// (both arms' kinematics once, the rates to every range end), then every task, every
// cost term and every limit asked in turn (parts.hpp), then their pieces stacked into
// one problem: the equality tasks' rows one under the other, the weighted tasks and the
// cost terms summed into one cost, the limits' boxes intersected (each bound remembers
// the limit that set it) and their rows stacked in the limits' order.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "boxes.hpp"
#include "parts.hpp"

namespace dqk {

// A grasp whose path is a straight line in the object frame (a PlaneBar): its point is
// origin + sigma direction, its tangent direction; r_min, r_max its surface box and
// [sigma_min, sigma_max] its range (dualarm_qp/task/surfaces.py).
struct GraspLine {
  Eigen::Vector3d origin, direction, r_min, r_max;
  double sigma_min = 0.0, sigma_max = 0.0;
};

// The step's problem and everything computed on the way (what Step::build fills).
struct StepOut {
  Context context;
  RowMat A;    // (m, n): the equality tasks' rows, in the tasks' order
  Vec b;       // (m)
  std::vector<std::string> eq_names;  // (m)
  Vec w;       // (n) the cost's diagonal, or empty when the cost is a full matrix
  RowMat W;    // (n, n) the full cost matrix, or empty
  Vec center;  // (n)
  Box box;     // the limits' boxes intersected; lower_by, upper_by: limit indices
  RowMat G;    // (p, n): the limits' rows, in the limits' order
  Vec h;       // (p)
  std::vector<std::string> row_names;  // (p)
  std::vector<std::int64_t> row_limit;  // (p) the limit of each row
  BoolVec recovering;  // (n) ranged variables outside their range
  bool any_recovering = false;
  // A part that could not give its piece: which (-1: none), what kind of part
  // ("task", "cost", "limit") and what it says (a NaN or an infinity, named).
  std::int64_t failed_part = -1;
  std::string failed_kind;
  std::string failure;
  std::shared_ptr<const std::vector<std::string>> labels;  // the step's limits' names
  double kinematics_seconds = 0.0;  // the context's share of the build
  double seconds = 0.0;             // the whole build
  // The arms' smallest singular values (of J_tool and J_f), computed when first asked.
  std::pair<double, double> sigma_min();

 private:
  bool sigma_known_ = false;
  std::pair<double, double> sigma_min_{0.0, 0.0};
};

class Step {
 public:
  // n_l, n_f joints and k = cols.size() - n_l grasps: column j of the decision-order
  // Jacobians is column cols[j] of the carry chain's (times col_rate[j], given with each
  // state: a Case 2 support re-places the follower's grasp joint). carry_frames: the
  // carry chain's leader tool, object and target frames; follower_tool: the follower's
  // tool frame. q_min, q_max: both arms' joint ranges (n_l + n_f); ranged: the
  // variables whose range the step imposes (the recovering flags); pin_rtol: the box
  // intersection's (intersect_boxes).
  Step(Index n_l, Index n_f, std::vector<int> carry_frames, int follower_tool,
       std::vector<int> cols, Vec q_min, Vec q_max, double dt, BoolVec ranged,
       double pin_rtol);

  // The parts, asked in the order they are added (tasks, then cost terms, then
  // limits). The step keeps pointers: the caller keeps the parts alive.
  void add_task(const Task* task);
  void add_cost(const CostTerm* cost);
  void add_limit(const Limit* limit);
  // The next grasp's straight path (in the grasps' order). With every grasp's line
  // given, build computes the grasps' rates to their range ends from sigmas itself.
  void add_grasp_line(const GraspLine& line);
  // The limits' names, in the order added: what a bound's and a row's source is called.
  void set_labels(std::vector<std::string> labels) {
    labels_ = std::make_shared<const std::vector<std::string>>(std::move(labels));
  }
  // Replace grasp g's line (a Case 2 support's moves with the object's orientation).
  void set_grasp_line(Index g, const GraspLine& line);

  Index n() const { return n_; }
  bool grasp_lines() const { return static_cast<Index>(lines_.size()) == k_; }

  // The step at one state into out: q_carry the carry chain's joints, col_rate the
  // columns' rates, q_f the follower's joints, T_D and twist the path's pose and twist
  // at t, sigmas the grasp coordinates (k), grasp_lo and grasp_hi the grasps' rates to
  // their range ends (k each; ignored, and may be empty, when every grasp has a line),
  // x_applied the last applied command, user what parts written in Python read.
  void build(StepOut& out, Chain& carry, const Eigen::VectorXd& q_carry, const Vec& col_rate,
             Chain& follower, const Eigen::VectorXd& q_f, const Pose& T_D, const Vec6& twist,
             const Vec& sigmas, const Vec& grasp_lo, const Vec& grasp_hi,
             const Vec& x_applied, double t, double scale_max, void* user) const;

 private:
  void context(Context& ctx, Chain& carry, const Eigen::VectorXd& q_carry, const Vec& col_rate,
               Chain& follower, const Eigen::VectorXd& q_f, const Pose& T_D,
               const Vec& sigmas, const Vec& grasp_lo, const Vec& grasp_hi) const;
  bool tasks(StepOut& out) const;
  bool costs(StepOut& out) const;
  bool limits(StepOut& out) const;

  Index n_l_, n_f_, k_, n_;
  std::vector<int> carry_frames_;
  int follower_tool_;
  std::vector<int> cols_;
  Vec q_min_, q_max_;
  double dt_;
  BoolVec ranged_;
  double pin_rtol_;
  std::vector<const Task*> tasks_;
  std::vector<const CostTerm*> costs_;
  std::vector<const Limit*> limits_;
  std::vector<GraspLine> lines_;
  std::shared_ptr<const std::vector<std::string>> labels_;
};

}  // namespace dqk

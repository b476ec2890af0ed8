// One kinematic chain (a tree of one-dof joints with frames) on Pinocchio's C++ API.
// The Python layer builds the model with Pinocchio (URDF or DH, base folded in, tool and
// link frames added) and hands its description over as arrays; the kernel rebuilds the
// same pinocchio::Model (header-only: no libpinocchio is linked) and runs the forward
// kinematics and the frame Jacobians on it. Pinocchio stays out of this header.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <memory>
#include <vector>

namespace dqk {

using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Pose = Eigen::Matrix<double, 4, 4, Eigen::RowMajor>;

// Joint kinds, Pinocchio's one-dof joints: revolute about x, y, z or an axis, prismatic
// along x, y, z or an axis.
enum JointKind : int { RX = 0, RY, RZ, RAXIS, PX, PY, PZ, PAXIS };

// What a Chain is made of, as it is now (what its pickle holds): the constructor's
// arguments with the placements as set since, frame 0's placement, each joint's body
// and gravity.
struct ChainState {
  std::vector<int> parents, kinds;
  RowMat axes, placements;         // n x 3; 4n x 4
  std::vector<int> frame_parents;  // frames 1..m
  RowMat frame_placements;         // 4m x 4
  Pose universe;                   // frame 0's placement
  std::vector<double> masses;      // joints 1..n [kg]
  RowMat levers;                   // n x 3: mass centres in the joint frames [m]
  RowMat inertias;                 // 3n x 3: rotational inertias about them [kg m^2]
  Eigen::Vector3d gravity;         // [m/s^2], world frame
};

class Chain {
 public:
  // Joints 1..n (the universe, joint 0, is implied): parents[i] is the parent of joint
  // i + 1, kinds[i] its JointKind, axes row i its unit axis (RAXIS, PAXIS), placements
  // rows 4i..4i+3 its placement in the parent joint. Frames 1..m likewise (frame 0 is
  // the universe): the parent joint and the placement in it. Throws
  // std::invalid_argument on malformed input.
  Chain(const std::vector<int>& parents, const std::vector<int>& kinds, const RowMat& axes,
        const RowMat& placements, const std::vector<int>& frame_parents,
        const RowMat& frame_placements);
  // The chain of a state() (an unpickled chain).
  explicit Chain(const ChainState& state);
  ~Chain();
  Chain(const Chain&) = delete;
  Chain& operator=(const Chain&) = delete;

  int nq() const;
  int njoints() const;  // with the universe
  int nframes() const;  // with the universe
  std::uint64_t updates() const { return updates_; }
  ChainState state() const;
  const Eigen::VectorXd& q() const { return q_; }

  // Replace the placement of joint j (1..n) or frame f (0..m: the universe's too) in its
  // parent joint.
  void set_joint_placement(int j, const Pose& T);
  void set_frame_placement(int f, const Pose& T);

  // Forward kinematics, every joint's Jacobian and every frame's placement at q.
  void update(const Eigen::VectorXd& q);
  // update(q), then the world poses of pose_frames stacked into T (4k x 4) and the
  // LOCAL_WORLD_ALIGNED Jacobians [v; w] of jac_frames stacked into J (6m x nq). The
  // outputs are the caller's arrays: returning fresh ones costs more than the kinematics.
  void compute(const Eigen::VectorXd& q, const std::vector<int>& pose_frames,
               const std::vector<int>& jac_frames, Eigen::Ref<RowMat> T, Eigen::Ref<RowMat> J);
  // The world poses of frames at q into T (4k x 4), forward kinematics only, in a
  // workspace of their own: the chain's kinematics (update's: q(), frame_poses,
  // frame_jacobian) stay those of its last update. What the look-ahead asks. Writes that
  // workspace: not to be called from two threads at once (the bindings hold the GIL).
  void poses_at(const Eigen::VectorXd& q, const std::vector<int>& frames,
                Eigen::Ref<RowMat> T) const;
  // After update: the world poses of frames into T (4k x 4), the Jacobian of frame f
  // into J (6 x nq).
  void frame_poses(const std::vector<int>& frames, Eigen::Ref<RowMat> T) const;
  void frame_jacobian(int f, Eigen::Ref<RowMat> J) const;

  // The Pinocchio model and data (chain_impl.hpp; for the kernel's other algorithms on
  // the same model, statics.cpp).
  struct Impl;
  Impl& impl() { return *impl_; }
  const Impl& impl() const { return *impl_; }
  void check_frame(int f) const;

 private:
  std::unique_ptr<Impl> impl_;
  std::vector<int> kinds_;  // the constructor's, for state()
  RowMat axes_;
  Eigen::VectorXd q_;
  std::uint64_t updates_ = 0;
};

// The Pinocchio version of the headers the kernel was compiled with.
const char* pinocchio_version();

}  // namespace dqk

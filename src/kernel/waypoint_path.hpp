// The desired object path of dualarm_qp/task/trajectory.py's WaypointTrajectory: rest to
// rest through SE(3) waypoints with minimum-jerk timing, a straight line in position and
// a geodesic in rotation per segment. The Python class checks the waypoints and holds
// one of these; every evaluation runs here, with a fixed order of every sum (no BLAS
// kernel chosen by the machine, no fused multiply-adds: the file is compiled without
// them), so the path is the same on every machine.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "kinematics.hpp"

namespace dqk {

// s = 10 tau^3 - 15 tau^4 + 6 tau^5 and its first two derivatives in tau, evaluated as
// the Python min_jerk evaluates them.
Eigen::Vector3d min_jerk(double tau);

class WaypointPath {
 public:
  // times (N >= 2, strictly increasing) and the poses T_world_object stacked (4N x 4).
  // Throws std::invalid_argument on other shapes or on times not increasing.
  WaypointPath(const std::vector<double>& times, const RowMat& poses);

  double t0() const { return times_.front(); }
  const std::vector<double>& times() const { return times_; }
  // The waypoints' poses stacked (4N x 4), as given.
  RowMat poses() const;
  double tf() const { return times_.back(); }

  // T_world_object(t) into T (4 x 4), the first or last waypoint outside [t0, tf].
  void pose(double t, Eigen::Ref<RowMat> T) const;
  // The order-th time derivative (1: the twist [v; w], 2: the acceleration) into out (6),
  // zero outside [t0, tf].
  void derivative(double t, int order, Eigen::Ref<Eigen::VectorXd> out) const;

 private:
  struct Segment {
    Eigen::Vector3d p, dp, w, w_world;
    Eigen::Matrix3d R;
    double duration;
  };
  // The segment holding t in [t0, tf] and tau in [0, 1]; -1 outside.
  int locate(double t, double& tau) const;

  std::vector<double> times_;
  std::vector<Pose> poses_;
  std::vector<Segment> segments_;
};

}  // namespace dqk

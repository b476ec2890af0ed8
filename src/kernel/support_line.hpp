// Case 2: the follower supports the object on a plane, pushing along its normal
// (SupportContact, dualarm_qp/task/contact.py). Its path is the support line of the
// object's orientation (SupportLine, dualarm_qp/task/support.py, whose docstring derives
// it): the points of the plane where a push h > 0 along the normal and a pure force of
// the leader's hand hold the weight. computed here as there, once per step.
#pragma once

#include <Eigen/Dense>

#include "kinematics.hpp"

namespace dqk {

// The support line at one orientation, object coordinates.
struct SupportLine {
  // False: no line with h > 0 inside the box at this orientation (or gravity along the
  // push is nil); the library's SupportContact.line says why.
  bool held = false;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // in object coordinates [m/s^2]
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();   // point(sigma) = origin + sigma direction
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // s*, unit
  double sigma_min = 0.0, sigma_max = 0.0;  // the range with h > 0 inside the box [m]
  double sigma_inf = 0.0;                   // where h is infinite [m]
  double lever = 0.0;                       // |a* x c| [N m]
  Pose pose0 = Pose::Identity();  // the hand's pose at sigma = 0: [s*, a* x s*, a*; origin]
  // The push h [N] at sigma: lever / (sigma - sigma_inf), inf at sigma_inf.
  double push(double sigma) const;
};

// A SupportPlane's constructor arguments, as given (what its pickle holds).
struct SupportPlaneArgs {
  double mass;
  Eigen::Vector3d mass_centre, gravity, r1, normal;
  double offset;
  Eigen::Vector3d r_min, r_max;
  double gravity_min;
};

class SupportPlane {
 public:
  // mass [kg], mass_centre and r1 (the leader's hand) [m] in object coordinates, gravity
  // [m/s^2] in the world frame; the plane normal . r = offset [m] (the follower pushes
  // along +normal) and its box [r_min, r_max] [m]; gravity_min: |g_x| at or below this
  // share of |g| holds nothing.
  SupportPlane(double mass, const Eigen::Vector3d& mass_centre, const Eigen::Vector3d& gravity,
               const Eigen::Vector3d& r1, const Eigen::Vector3d& normal, double offset,
               const Eigen::Vector3d& r_min, const Eigen::Vector3d& r_max, double gravity_min);
  // The line for the object's orientation R_world_object.
  SupportLine line(const Eigen::Matrix3d& R_world_object) const;
  const SupportPlaneArgs& args() const { return args_; }

 private:
  SupportPlaneArgs args_;
  double mass_;
  Eigen::Vector3d centre_, gravity_, r1_, normal_;
  double offset_;
  Eigen::Vector3d r_min_, r_max_;
  double gravity_min_;
};

}  // namespace dqk

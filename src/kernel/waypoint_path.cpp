#include "waypoint_path.hpp"

#include <algorithm>
#include <cmath>
#include <pinocchio/spatial.hpp>
#include <stdexcept>

namespace dqk {

namespace {

// a b for 3 x 3 matrices, each entry summed left to right.
Eigen::Matrix3d product(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
    }
  }
  return out;
}

// a^T b for 3 x 3 matrices, each entry summed left to right.
Eigen::Matrix3d transposed_product(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out(i, j) = a(0, i) * b(0, j) + a(1, i) * b(1, j) + a(2, i) * b(2, j);
    }
  }
  return out;
}

}  // namespace

Eigen::Vector3d min_jerk(double tau) {
  const double t2 = tau * tau;
  return {t2 * tau * (10.0 + tau * (-15.0 + 6.0 * tau)),
          t2 * (30.0 + tau * (-60.0 + 30.0 * tau)),
          tau * (60.0 + tau * (-180.0 + 120.0 * tau))};
}

RowMat WaypointPath::poses() const {
  RowMat out(4 * static_cast<Eigen::Index>(poses_.size()), 4);
  for (std::size_t k = 0; k < poses_.size(); ++k)
    out.middleRows(4 * static_cast<Eigen::Index>(k), 4) = poses_[k];
  return out;
}

WaypointPath::WaypointPath(const std::vector<double>& times, const RowMat& poses)
    : times_(times) {
  const auto n = static_cast<Eigen::Index>(times.size());
  if (n < 2 || poses.rows() != 4 * n || poses.cols() != 4) {
    throw std::invalid_argument("WaypointPath: N >= 2 times and the poses stacked (4N x 4)");
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    poses_.emplace_back(poses.middleRows(4 * k, 4));
    if (k > 0 && !(times[k] > times[k - 1])) {
      throw std::invalid_argument("WaypointPath: times must be strictly increasing");
    }
  }
  for (Eigen::Index k = 0; k + 1 < n; ++k) {
    const Pose& a = poses_[k];
    const Pose& b = poses_[k + 1];
    Segment s;
    s.R = a.topLeftCorner<3, 3>();
    s.p = a.topRightCorner<3, 1>();
    s.dp = b.topRightCorner<3, 1>() - s.p;
    s.w = pinocchio::log3(transposed_product(s.R, b.topLeftCorner<3, 3>()));
    for (int i = 0; i < 3; ++i) {
      s.w_world(i) = s.R(i, 0) * s.w(0) + s.R(i, 1) * s.w(1) + s.R(i, 2) * s.w(2);
    }
    s.duration = times[k + 1] - times[k];
    segments_.push_back(s);
  }
}

int WaypointPath::locate(double t, double& tau) const {
  if (!(t0() <= t && t <= tf())) return -1;
  // bisect_right(times, t) - 1, the last segment at t = tf
  const auto upper = std::upper_bound(times_.begin(), times_.end(), t);
  const int k = std::min(static_cast<int>(upper - times_.begin()) - 1,
                         static_cast<int>(segments_.size()) - 1);
  tau = (t - times_[static_cast<std::size_t>(k)]) / segments_[static_cast<std::size_t>(k)].duration;
  return k;
}

void WaypointPath::pose(double t, Eigen::Ref<RowMat> T) const {
  if (T.rows() != 4 || T.cols() != 4) throw std::invalid_argument("pose: T must be (4, 4)");
  if (std::isnan(t)) throw std::invalid_argument("pose: t is NaN");
  double tau = 0.0;
  const int k = locate(t, tau);
  if (k < 0) {
    T = t < t0() ? poses_.front() : poses_.back();
    return;
  }
  const Segment& s = segments_[static_cast<std::size_t>(k)];
  const double sk = min_jerk(tau)(0);
  const Eigen::Vector3d v = sk * s.w;
  T.setIdentity();
  T.topLeftCorner<3, 3>() = product(s.R, pinocchio::exp3(v));
  for (int i = 0; i < 3; ++i) T(i, 3) = s.p(i) + sk * s.dp(i);
}

void WaypointPath::derivative(double t, int order, Eigen::Ref<Eigen::VectorXd> out) const {
  if (out.size() != 6 || (order != 1 && order != 2)) {
    throw std::invalid_argument("derivative: order 1 or 2, out (6)");
  }
  if (std::isnan(t)) throw std::invalid_argument("derivative: t is NaN");
  double tau = 0.0;
  const int k = locate(t, tau);
  out.setZero();
  if (k < 0) return;
  const Segment& s = segments_[static_cast<std::size_t>(k)];
  const double rate =
      order == 1 ? min_jerk(tau)(1) / s.duration : min_jerk(tau)(2) / std::pow(s.duration, 2.0);
  out.head<3>() = rate * s.dp;
  out.tail<3>() = rate * s.w_world;
}

}  // namespace dqk

// The chain's kinematics: Pinocchio's header-only algorithms on a model rebuilt from
// arrays (see kinematics.hpp).
#include "kinematics.hpp"

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/multibody.hpp>
#include <stdexcept>
#include <string>

#include "chain_impl.hpp"

#ifdef PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION
#error "the kernel uses Pinocchio header-only: do not link pinocchio's CMake targets"
#endif

namespace dqk {

namespace pin = pinocchio;

namespace {

pin::SE3 se3_at(const RowMat& rows, Eigen::Index i) {
  const Eigen::Matrix4d T = rows.block<4, 4>(4 * i, 0);
  return pin::SE3(Eigen::Matrix3d(T.topLeftCorner<3, 3>()), Eigen::Vector3d(T.topRightCorner<3, 1>()));
}

pin::SE3 se3_of(const Pose& T) {
  return pin::SE3(Eigen::Matrix3d(T.topLeftCorner<3, 3>()), Eigen::Vector3d(T.topRightCorner<3, 1>()));
}

pin::JointModel joint_of(int kind, const Eigen::Vector3d& axis) {
  switch (kind) {
    case RX: return pin::JointModelRX();
    case RY: return pin::JointModelRY();
    case RZ: return pin::JointModelRZ();
    case RAXIS: return pin::JointModelRevoluteUnaligned(axis);
    case PX: return pin::JointModelPX();
    case PY: return pin::JointModelPY();
    case PZ: return pin::JointModelPZ();
    case PAXIS: return pin::JointModelPrismaticUnaligned(axis);
    default: throw std::invalid_argument("unknown joint kind " + std::to_string(kind));
  }
}

}  // namespace

Chain::Chain(const std::vector<int>& parents, const std::vector<int>& kinds, const RowMat& axes,
             const RowMat& placements, const std::vector<int>& frame_parents,
             const RowMat& frame_placements)
    : impl_(std::make_unique<Impl>()), kinds_(kinds), axes_(axes) {
  const auto n = static_cast<Eigen::Index>(parents.size());
  if (static_cast<Eigen::Index>(kinds.size()) != n || axes.rows() != n || axes.cols() != 3 ||
      placements.rows() != 4 * n || placements.cols() != 4)
    throw std::invalid_argument("joints: parents (n), kinds (n), axes (n, 3), placements (4n, 4)");
  const auto m = static_cast<Eigen::Index>(frame_parents.size());
  if (frame_placements.rows() != 4 * m || frame_placements.cols() != 4)
    throw std::invalid_argument("frames: parents (m), placements (4m, 4)");
  pin::Model& model = impl_->model;
  for (Eigen::Index i = 0; i < n; ++i) {
    const int parent = parents[i];
    if (parent < 0 || parent > i)
      throw std::invalid_argument("joint " + std::to_string(i + 1) + ": parent " +
                                  std::to_string(parent) + " does not precede it");
    const pin::JointModel joint = joint_of(kinds[i], axes.row(i).transpose());
    model.addJoint(static_cast<pin::JointIndex>(parent), joint, se3_at(placements, i),
                   "joint" + std::to_string(i + 1));
  }
  if (model.nq != model.nv || model.nq != n)
    throw std::invalid_argument("every joint must have one coordinate");
  for (Eigen::Index f = 0; f < m; ++f) {
    const int parent = frame_parents[f];
    if (parent < 0 || parent > n)
      throw std::invalid_argument("frame " + std::to_string(f + 1) + ": no joint " +
                                  std::to_string(parent));
    // Unique names: Model::addFrame returns an existing frame of the same name and type.
    model.addFrame(pin::Frame("frame" + std::to_string(f + 1), static_cast<pin::JointIndex>(parent),
                              0, se3_at(frame_placements, f), pin::OP_FRAME));
  }
  impl_->data = pin::Data(model);
  impl_->ahead = pin::Data(model);
  q_ = Eigen::VectorXd::Zero(model.nq);
}

Chain::Chain(const ChainState& s)
    : Chain(s.parents, s.kinds, s.axes, s.placements, s.frame_parents, s.frame_placements) {
  pin::Model& model = impl_->model;
  const auto n = static_cast<Eigen::Index>(s.parents.size());
  if (static_cast<Eigen::Index>(s.masses.size()) != n || s.levers.rows() != n ||
      s.levers.cols() != 3 || s.inertias.rows() != 3 * n || s.inertias.cols() != 3)
    throw std::invalid_argument("chain state: masses (n), levers (n, 3), inertias (3n, 3)");
  set_frame_placement(0, s.universe);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Matrix3d I = s.inertias.block<3, 3>(3 * i, 0);
    model.inertias[static_cast<std::size_t>(i + 1)] =
        pin::Inertia(s.masses[static_cast<std::size_t>(i)], s.levers.row(i).transpose(),
                     pin::Symmetric3(I));
  }
  model.gravity = pin::Motion(s.gravity, Eigen::Vector3d::Zero());
}

ChainState Chain::state() const {
  const pin::Model& model = impl_->model;
  const auto n = static_cast<Eigen::Index>(model.njoints - 1);
  const auto m = static_cast<Eigen::Index>(model.nframes - 1);
  ChainState s;
  s.kinds = kinds_;
  s.axes = axes_;
  s.placements.resize(4 * n, 4);
  s.masses.resize(static_cast<std::size_t>(n));
  s.levers.resize(n, 3);
  s.inertias.resize(3 * n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto j = static_cast<std::size_t>(i + 1);
    s.parents.push_back(static_cast<int>(model.parents[j]));
    s.placements.block<4, 4>(4 * i, 0) = model.jointPlacements[j].toHomogeneousMatrix();
    const pin::Inertia& body = model.inertias[j];
    s.masses[j - 1] = body.mass();
    s.levers.row(i) = body.lever().transpose();
    s.inertias.block<3, 3>(3 * i, 0) = body.inertia().matrix();
  }
  s.frame_placements.resize(4 * m, 4);
  for (Eigen::Index f = 0; f < m; ++f) {
    const pin::Frame& frame = model.frames[static_cast<std::size_t>(f + 1)];
    s.frame_parents.push_back(static_cast<int>(frame.parentJoint));
    s.frame_placements.block<4, 4>(4 * f, 0) = frame.placement.toHomogeneousMatrix();
  }
  s.universe = model.frames[0].placement.toHomogeneousMatrix();
  s.gravity = model.gravity.linear();
  return s;
}

Chain::~Chain() = default;

int Chain::nq() const { return impl_->model.nq; }
int Chain::njoints() const { return impl_->model.njoints; }
int Chain::nframes() const { return static_cast<int>(impl_->model.nframes); }

void Chain::set_joint_placement(int j, const Pose& T) {
  if (j < 1 || j >= njoints()) throw std::out_of_range("no joint " + std::to_string(j));
  impl_->model.jointPlacements[static_cast<std::size_t>(j)] = se3_of(T);
}

void Chain::set_frame_placement(int f, const Pose& T) {
  if (f < 0 || f >= nframes()) throw std::out_of_range("no frame " + std::to_string(f));
  impl_->model.frames[static_cast<std::size_t>(f)].placement = se3_of(T);
}

void Chain::check_frame(int f) const {
  if (f < 0 || f >= nframes()) throw std::out_of_range("no frame " + std::to_string(f));
}

void Chain::update(const Eigen::VectorXd& q) {
  if (q.size() != nq())
    throw std::invalid_argument("q has " + std::to_string(q.size()) + " entries, the chain " +
                                std::to_string(nq()) + " joints");
  q_ = q;
  pin::computeJointJacobians(impl_->model, impl_->data, q_);
  pin::updateFramePlacements(impl_->model, impl_->data);
  ++updates_;
}

void Chain::frame_poses(const std::vector<int>& frames, Eigen::Ref<RowMat> T) const {
  if (T.rows() != 4 * static_cast<Eigen::Index>(frames.size()) || T.cols() != 4)
    throw std::invalid_argument("T must be (4k, 4) for k frames");
  for (int f : frames) check_frame(f);
  for (std::size_t k = 0; k < frames.size(); ++k)
    T.middleRows<4>(4 * static_cast<Eigen::Index>(k)) =
        impl_->data.oMf[static_cast<std::size_t>(frames[k])].toHomogeneousMatrix();
}

void Chain::poses_at(const Eigen::VectorXd& q, const std::vector<int>& frames,
                     Eigen::Ref<RowMat> T) const {
  if (q.size() != nq())
    throw std::invalid_argument("q has " + std::to_string(q.size()) + " entries, the chain " +
                                std::to_string(nq()) + " joints");
  if (T.rows() != 4 * static_cast<Eigen::Index>(frames.size()) || T.cols() != 4)
    throw std::invalid_argument("T must be (4k, 4) for k frames");
  for (int f : frames) check_frame(f);
  pin::Data& ahead = impl_->ahead;
  // The same products as update's pass (oMi, then each frame's oMf): the same poses.
  pin::forwardKinematics(impl_->model, ahead, q);
  for (std::size_t k = 0; k < frames.size(); ++k)
    T.middleRows<4>(4 * static_cast<Eigen::Index>(k)) =
        pin::updateFramePlacement(impl_->model, ahead, static_cast<pin::FrameIndex>(frames[k]))
            .toHomogeneousMatrix();
}

void Chain::frame_jacobian(int f, Eigen::Ref<RowMat> J) const {
  check_frame(f);
  if (J.rows() != 6 || J.cols() != nq()) throw std::invalid_argument("J must be (6, nq)");
  pin::Data::Matrix6x Jf = pin::Data::Matrix6x::Zero(6, nq());
  pin::getFrameJacobian(impl_->model, impl_->data, static_cast<pin::FrameIndex>(f),
                        pin::LOCAL_WORLD_ALIGNED, Jf);
  J = Jf;
}

void Chain::compute(const Eigen::VectorXd& q, const std::vector<int>& pose_frames,
                    const std::vector<int>& jac_frames, Eigen::Ref<RowMat> T,
                    Eigen::Ref<RowMat> J) {
  if (T.rows() != 4 * static_cast<Eigen::Index>(pose_frames.size()) || T.cols() != 4)
    throw std::invalid_argument("T must be (4k, 4) for k pose frames");
  if (J.rows() != 6 * static_cast<Eigen::Index>(jac_frames.size()) || J.cols() != nq())
    throw std::invalid_argument("J must be (6m, nq) for m Jacobian frames");
  for (int f : pose_frames) check_frame(f);
  for (int f : jac_frames) check_frame(f);
  update(q);
  frame_poses(pose_frames, T);
  pin::Data::Matrix6x Jf(6, nq());
  for (std::size_t k = 0; k < jac_frames.size(); ++k) {
    Jf.setZero();
    pin::getFrameJacobian(impl_->model, impl_->data, static_cast<pin::FrameIndex>(jac_frames[k]),
                          pin::LOCAL_WORLD_ALIGNED, Jf);
    J.middleRows(6 * static_cast<Eigen::Index>(k), 6) = Jf;
  }
}

const char* pinocchio_version() { return PINOCCHIO_VERSION; }

}  // namespace dqk

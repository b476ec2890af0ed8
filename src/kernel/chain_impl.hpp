// The Pinocchio model and data behind a Chain (kinematics.hpp keeps Pinocchio out of its
// interface; the kernel's sources that run Pinocchio's algorithms include this).
#pragma once

#include <pinocchio/multibody.hpp>

#include "kinematics.hpp"

namespace dqk {

struct Chain::Impl {
  pinocchio::Model model;
  pinocchio::Data data;
  pinocchio::Data ahead;  // poses_at's workspace (the chain's kinematics stay in data)
  Impl() : model(), data(model), ahead(model) {}
};

}  // namespace dqk

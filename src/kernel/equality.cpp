// The step's equality block (see equality.hpp).
#include "equality.hpp"

#include <stdexcept>

namespace dqk {

bool carry_equality(Eigen::Index n_l, const Eigen::Ref<const RowMat>& J_object,
                    const Eigen::Ref<const RowMat>& J_target, const Eigen::Ref<const RowMat>& J_f,
                    const Vec6& twist, const Vec6& e_l, const Vec6& e_c, double scale,
                    double gain_l, double gain_c, bool exact_orientation, Eigen::Ref<RowMat> A,
                    Eigen::Ref<Eigen::VectorXd> b) {
  const Eigen::Index n_f = J_f.cols();
  const Eigen::Index k = J_object.cols() - n_l;  // sliding grasps
  if (n_l < 0 || k < 1 || J_object.rows() != 6 || J_target.rows() != 6 ||
      J_target.cols() != J_object.cols() || J_f.rows() != 6 || A.rows() != 12 ||
      A.cols() != n_l + n_f + k || b.size() != 12)
    throw std::invalid_argument(
        "carry_equality: J_object, J_target (6, n_l + k) with k >= 1, J_f (6, n_f), "
        "A (12, n_l + n_f + k), b (12)");
  const Eigen::Index grasps = n_l + n_f;
  A.topRows<6>().leftCols(n_l) = J_object.leftCols(n_l);
  A.topRows<6>().middleCols(n_l, n_f).setZero();
  A.topRows<6>().rightCols(k) = J_object.rightCols(k);
  A.bottomRows<6>().leftCols(n_l) = -J_target.leftCols(n_l);
  A.bottomRows<6>().middleCols(n_l, n_f) = J_f;
  A.bottomRows<6>().rightCols(k) = -J_target.rightCols(k);
  if (!exact_orientation) A.bottomRows<3>().col(grasps).setZero();
  b.head<6>() = scale * twist + gain_l * e_l;
  b.tail<6>() = gain_c * e_c;
  return A.allFinite() && b.allFinite();
}

}  // namespace dqk

// dualarm_qp._kernel: the compiled exact solver, the certificate's numeric core and the
// arms' kinematics (Pinocchio's C++ API, header-only).
// Every function takes numpy arrays (float64) and returns numpy arrays and Python
// scalars; the Python wrappers (dualarm_qp/solvers) map them to the library's types.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "certify.hpp"
#include "constants.hpp"
#include "dense_qp.hpp"
#include "equality.hpp"
#include "kinematics.hpp"
#include "linalg.hpp"
#include "nnls.hpp"
#include "nullspace.hpp"
#include "rows.hpp"
#include "scale_lp.hpp"

#ifndef DQK_SOURCE_HASH
#error "DQK_SOURCE_HASH must be defined by the build (CMakeLists.txt)"
#endif

namespace nb = nanobind;
using namespace nb::literals;
using dqk::Index;
using dqk::Mat;
using dqk::Vec;

namespace {

nb::tuple factor_tuple(const dqk::Factor& f) {
  return nb::make_tuple(f.U, f.sigma, f.V, f.N);
}

dqk::Factor factor_from(const Mat& U, const Vec& sigma, const Mat& V, const Mat& N) {
  return dqk::Factor{U, sigma, V, N};
}

}  // namespace

NB_MODULE(_kernel, m) {
  m.doc() = "The compiled exact step solver, the certificate's numeric core and the arms' kinematics.";
  // Arms hold their Chain for the life of the process (module-level experiments and
  // caches included); nanobind would list those still alive at exit as leaks.
  nb::set_leak_warnings(false);
  m.attr("SOURCE_HASH") = DQK_SOURCE_HASH;
  m.attr("RANK_RTOL") = dqk::RANK_RTOL;
  m.attr("CONSISTENCY_TOL") = dqk::CONSISTENCY_TOL;
  m.attr("ACTIVE_TOL") = dqk::ACTIVE_TOL;
  m.attr("STEP_RTOL") = dqk::STEP_RTOL;
  m.attr("ROUNDING") = dqk::ROUNDING;
  m.attr("TIE_RTOL") = dqk::TIE_RTOL;
  m.attr("PRICE_TOL") = dqk::PRICE_TOL;
  m.attr("PIVOT_TOL") = dqk::PIVOT_TOL;
  m.attr("PINOCCHIO_VERSION") = dqk::pinocchio_version();

  nb::class_<dqk::Chain>(m, "Chain",
                         "A chain of one-dof joints with frames, rebuilt as a pinocchio::Model.")
      .def(nb::init<const std::vector<int>&, const std::vector<int>&, const dqk::RowMat&,
                    const dqk::RowMat&, const std::vector<int>&, const dqk::RowMat&>(),
           "parents"_a, "kinds"_a, "axes"_a, "placements"_a, "frame_parents"_a,
           "frame_placements"_a)
      .def_prop_ro("nq", &dqk::Chain::nq)
      .def_prop_ro("njoints", &dqk::Chain::njoints)
      .def_prop_ro("nframes", &dqk::Chain::nframes)
      .def_prop_ro("updates", &dqk::Chain::updates, "How many times update ran.")
      .def_prop_ro("q", &dqk::Chain::q, "The joints of the last update.")
      .def("set_joint_placement", &dqk::Chain::set_joint_placement, "joint"_a, "T"_a)
      .def("set_frame_placement", &dqk::Chain::set_frame_placement, "frame"_a, "T"_a)
      .def("update", &dqk::Chain::update, "q"_a,
           "Forward kinematics, every joint's Jacobian and every frame's pose at q.")
      .def("compute", &dqk::Chain::compute, "q"_a, "pose_frames"_a, "jac_frames"_a,
           "T"_a.noconvert(), "J"_a.noconvert(),
           "update(q); then the poses of pose_frames into T (4k, 4) and the Jacobians of "
           "jac_frames into J (6m, nq), C-contiguous float64 arrays.")
      .def("frame_poses", &dqk::Chain::frame_poses, "frames"_a, "T"_a.noconvert(),
           "The poses of frames at the last update into T (4k, 4).")
      .def("frame_jacobian", &dqk::Chain::frame_jacobian, "frame"_a, "J"_a.noconvert(),
           "The Jacobian of frame at the last update into J (6, nq).");

  m.def("factor", [](const Mat& A) { return factor_tuple(dqk::factor(A)); }, "A"_a,
        "Truncated SVD of A: (U, sigma, V, N).");

  m.def(
      "affine",
      [](const Mat& A, const Vec& b) -> nb::object {
        const dqk::Factor f = dqk::factor(A);
        const auto x0 = dqk::affine_point(A, b, f);
        if (!x0) return nb::none();
        return nb::make_tuple(*x0, f.U, f.sigma, f.V, f.N);
      },
      "A"_a, "b"_a, "(x0, U, sigma, V, N) of A x = b, or None if inconsistent.");

  m.def(
      "inequalities",
      [](const Vec& lower, const Vec& upper, const Mat& G, const Vec& h) {
        const dqk::Rows r = dqk::inequalities(lower, upper, G, h);
        return nb::make_tuple(r.C, r.e, r.kind, r.index);
      },
      "lower"_a, "upper"_a, "G"_a, "h"_a,
      "Every finite limit as unit-norm rows: (C, e, kind, index).");

  m.def(
      "least_distance",
      [](const Mat& N, const Vec& x0, const Vec& w_diag, const Mat& w_full,
         const Mat& root_full, const Vec& center) -> Vec {
        if (N.cols() == 0) return x0;
        const dqk::Cost cost(w_diag, w_full, root_full, center);
        const Vec t = dqk::qr_lstsq(cost.root_times(N), cost.root_times(Vec(center - x0)));
        return x0 + N * t;
      },
      "N"_a, "x0"_a, "w_diag"_a, "w_full"_a, "root_full"_a, "center"_a,
      "The minimiser of |R (x - c)|^2 over x = x0 + N t.");

  m.def(
      "solve_nullspace",
      [](const Mat& A, const Vec& b, const Mat& C, const Vec& e, const Vec& w_diag,
         const Mat& w_full, const Mat& root_full, const Vec& center, double feas_tol,
         Index max_iter, nb::object known) {
        // The problem's factor when it is already known (the same computation, so the
        // same arrays), else computed here.
        dqk::Factor f;
        if (known.is_none()) {
          f = dqk::factor(A);
        } else {
          const nb::tuple t = nb::cast<nb::tuple>(known);
          f = factor_from(nb::cast<Mat>(t[0]), nb::cast<Vec>(t[1]), nb::cast<Mat>(t[2]),
                          nb::cast<Mat>(t[3]));
        }
        const dqk::Cost cost(w_diag, w_full, root_full, center);
        const dqk::StepAnswer s =
            dqk::solve_nullspace(A, b, f, C, e, cost, feas_tol, max_iter);
        return nb::make_tuple(static_cast<int>(s.code), s.x, s.conflicts, s.nullity,
                              s.iterations, known.is_none() ? factor_tuple(f) : known);
      },
      "A"_a, "b"_a, "C"_a, "e"_a, "w_diag"_a, "w_full"_a, "root_full"_a, "center"_a,
      "feas_tol"_a, "max_iter"_a, "factor"_a.none(),
      "The exact step: (code, x, conflicts, nullity, iterations, factor); factor, when "
      "given, is (U, sigma, V, N) of A.");

  m.def(
      "dense_qp",
      [](const Mat& R, const Vec& t_free, const Mat& M, const Vec& f, double feas_tol,
         Index max_iter) {
        const dqk::DenseQPResult r = dqk::solve_dense_qp(R, t_free, M, f, feas_tol, max_iter);
        return nb::make_tuple(static_cast<int>(r.status), r.t, r.active, r.multipliers,
                              r.blocking, r.iterations);
      },
      "R"_a, "t_free"_a, "M"_a, "f"_a, "feas_tol"_a, "max_iter"_a,
      "Goldfarb-Idnani: (status, t, active, multipliers, blocking, iterations).");

  m.def(
      "nnls",
      [](const Mat& A, const Vec& b, Index max_iter) {
        const dqk::NNLSResult r = dqk::nnls(A, b, max_iter);
        return nb::make_tuple(r.x, r.rnorm, r.converged);
      },
      "A"_a, "b"_a, "max_iter"_a, "Lawson-Hanson NNLS: (x, rnorm, converged).");

  m.def(
      "residuals",
      [](const Mat& A, const Vec& b, const Vec& lower, const Vec& upper, const Mat& G,
         const Vec& h, const Vec& x) {
        const dqk::Residuals r = dqk::residuals(A, b, lower, upper, G, h, x);
        return nb::make_tuple(r.eq, r.box, r.row);
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "x"_a,
      "(max |A x - b|, box violation, row violation) of x.");

  m.def(
      "kkt_holds",
      [](const Mat& A, const Vec& b, const Mat& U, const Vec& sigma, const Mat& V,
         const Mat& N, const Mat& C, const Vec& e, const Vec& w_diag, const Mat& w_full,
         const Mat& root_full, const Vec& center, const Vec& x, bool bounds) {
        const dqk::Cost cost(w_diag, w_full, root_full, center);
        return dqk::kkt_holds(A, b, factor_from(U, sigma, V, N), C, e, cost, x, bounds);
      },
      "A"_a, "b"_a, "U"_a, "sigma"_a, "V"_a, "N"_a, "C"_a, "e"_a, "w_diag"_a, "w_full"_a,
      "root_full"_a, "center"_a, "x"_a, "bounds"_a,
      "Whether x is the step's minimiser (the KKT test of certify).");

  m.def("carry_equality", &dqk::carry_equality, "n_l"_a, "J_object"_a, "J_target"_a, "J_f"_a,
        "twist"_a, "e_l"_a, "e_c"_a, "scale"_a, "gain_l"_a, "gain_c"_a,
        "exact_orientation"_a, "A"_a.noconvert(), "b"_a.noconvert(),
        "The step's equality block into A (12, n) and b (12): the object follows D(t), "
        "the grasp stays closed. Returns whether both are finite.");

  m.def(
      "scale_lp",
      [](const Mat& M, const Vec& a, const Vec& g, double s_lo, double s_hi) {
        const dqk::ScaleLPResult r = dqk::scale_lp(M, a, g, s_lo, s_hi);
        return nb::make_tuple(static_cast<int>(r.status), r.t, r.s, r.rows);
      },
      "M"_a, "a"_a, "g"_a, "s_lo"_a, "s_hi"_a,
      "Largest s with M t + a s <= g, s_lo <= s <= s_hi: (status, t, s, rows); status 0 "
      "optimal (rows: the final basis), 1 infeasible (rows: the dual ray), 2 iteration "
      "limit.");
}

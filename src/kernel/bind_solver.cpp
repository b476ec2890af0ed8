// dualarm_qp._kernel's exact solver, factorisations, certificate, boxes and the task-scale
// LP (module.cpp makes the module).
#include "binding.hpp"

#include "boxes.hpp"
#include "certified_step.hpp"
#include "dense_qp.hpp"
#include "equality.hpp"
#include "lookahead.hpp"
#include "nnls.hpp"
#include "nullspace.hpp"
#include "scale_lp.hpp"
#include "step_kinematics.hpp"

namespace dqk_binding {

using namespace nb::literals;

void bind_solver(nb::module_& m) {
  m.def("factor", [](In A) { return factor_tuple(dqk::factor(A)); }, "A"_a,
        "Truncated SVD of A: (U, sigma, V, N).");

  m.def(
      "affine",
      [](In A, const Vec& b) -> nb::object {
        const dqk::Factor f = dqk::factor(A);
        const auto x0 = dqk::affine_point(A, b, f);
        if (!x0) return nb::none();
        return nb::make_tuple(out(Vec(*x0)), out(Mat(f.U)), out(Vec(f.sigma)), out(Mat(f.V)),
                              out(Mat(f.N)));
      },
      "A"_a, "b"_a, "(x0, U, sigma, V, N) of A x = b, or None if inconsistent.");

  m.def(
      "inequalities",
      [](const Vec& lower, const Vec& upper, In G, const Vec& h) {
        return rows_tuple(dqk::inequalities(lower, upper, G, h));
      },
      "lower"_a, "upper"_a, "G"_a, "h"_a,
      "Every finite limit as unit-norm rows: (C, e, kind, index).");

  m.def(
      "least_distance",
      [](In N, const Vec& x0, const Vec& w_diag, In w_full,
         In root_full, const Vec& center) {
        if (N.cols() == 0) return out(Vec(x0));
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        const Vec t = dqk::qr_lstsq(cost.root_times(Mat(N)), cost.root_times(Vec(center - x0)));
        return out(Vec(x0 + N * t));
      },
      "N"_a, "x0"_a, "w_diag"_a, "w_full"_a, "root_full"_a, "center"_a,
      "The minimiser of |R (x - c)|^2 over x = x0 + N t.");

  m.def(
      "basis",
      [](In A) {
        return basis_tuple(dqk::basis(A));
      },
      "A"_a,
      "(P, N, rank, sigma_max, qr): the pseudo-inverse of A, a basis of its null space, "
      "its rank, its largest singular value (or a bound) and whether the QR path proved "
      "full row rank.");

  m.def(
      "solve_nullspace",
      [](In A, const Vec& b, In P, In N, Index rank, double sigma_max, In C, const Vec& e,
         const Vec& w_diag, In w_full, In root_full, const Vec& center, double feas_tol,
         Index max_iter) {
        require(b.size() == A.rows() && C.cols() == A.cols() && e.size() == C.rows() &&
                    center.size() == A.cols(),
                "solve_nullspace: arguments of inconsistent sizes");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        dqk::StepAnswer s = dqk::solve_nullspace(
            A, b, basis_from(A, P, N, rank, sigma_max), C, e, cost, feas_tol, max_iter);
        return nb::make_tuple(static_cast<int>(s.code), out(std::move(s.x)), s.conflicts,
                              s.nullity, s.iterations);
      },
      "A"_a, "b"_a, "P"_a, "N"_a, "rank"_a, "sigma_max"_a, "C"_a, "e"_a, "w_diag"_a,
      "w_full"_a, "root_full"_a, "center"_a, "feas_tol"_a, "max_iter"_a,
      "The exact step on A's basis (P, N, rank, sigma_max): (code, x, conflicts, "
      "nullity, iterations).");

  m.def(
      "solve_certified",
      [](In A_, const Vec& b, const Vec& lower, const Vec& upper, In G_, const Vec& h,
         const Vec& w_diag, In w_full, In root_full, const Vec& center, double feas_tol,
         Index max_iter, bool bounds, double eq_rtol, double bounds_tol) {
        const Mat A(A_), G(G_);
        const Index n = A.cols();
        require(b.size() == A.rows() && lower.size() == n && upper.size() == n &&
                    G.cols() == n && h.size() == G.rows() && center.size() == n,
                "solve_certified: arguments of inconsistent sizes");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        return certified_tuple(dqk::solve_certified(A, b, lower, upper, G, h, cost, feas_tol,
                                                    max_iter, bounds, eq_rtol, bounds_tol));
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "w_diag"_a, "w_full"_a,
      "root_full"_a, "center"_a, "feas_tol"_a, "max_iter"_a, "bounds"_a, "eq_rtol"_a,
      "bounds_tol"_a,
      "The exact step and its certificate in one call: (code, x, conflicts, nullity, "
      "iterations, basis, rows, certificate); basis is basis(A)'s tuple, rows "
      "inequalities(...)'s, certificate certificate(...)'s (with the KKT test) for an "
      "optimum, else None. A problem with an empty box (some lower > upper) is not "
      "solved: code EMPTY_BOX_CODE, x zero, no conflicts, an empty basis and rows.");

  m.def(
      "dense_qp",
      [](In R, const Vec& t_free, In M, const Vec& f, double feas_tol,
         Index max_iter) {
        dqk::DenseQPResult r = dqk::solve_dense_qp(R, t_free, M, f, feas_tol, max_iter);
        return nb::make_tuple(static_cast<int>(r.status), out(std::move(r.t)), r.active,
                              r.multipliers,
                              r.blocking, r.iterations);
      },
      "R"_a, "t_free"_a, "M"_a, "f"_a, "feas_tol"_a, "max_iter"_a,
      "Goldfarb-Idnani: (status, t, active, multipliers, blocking, iterations).");

  m.def(
      "nnls",
      [](In A, const Vec& b, Index max_iter) {
        dqk::NNLSResult r = dqk::nnls(A, b, max_iter);
        return nb::make_tuple(out(std::move(r.x)), r.rnorm, r.converged);
      },
      "A"_a, "b"_a, "max_iter"_a, "Lawson-Hanson NNLS: (x, rnorm, converged).");

  m.def(
      "residuals",
      [](In A, const Vec& b, const Vec& lower, const Vec& upper, In G,
         const Vec& h, const Vec& x) {
        const dqk::Residuals r = dqk::residuals(A, b, lower, upper, G, h, x);
        return nb::make_tuple(r.eq, r.box, r.row);
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "x"_a,
      "(max |A x - b|, box violation, row violation) of x.");

  m.def(
      "kkt_holds",
      [](In A, const Vec& b, In P, In N, Index rank, double sigma_max, In C, const Vec& e,
         const Vec& w_diag, In w_full, In root_full, const Vec& center, const Vec& x,
         bool bounds) {
        require(b.size() == A.rows() && C.cols() == A.cols() && e.size() == C.rows() &&
                    center.size() == A.cols() && x.size() == A.cols(),
                "kkt_holds: arguments of inconsistent sizes");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        return dqk::kkt_holds(A, b, basis_from(A, P, N, rank, sigma_max), C, e, cost, x,
                              bounds);
      },
      "A"_a, "b"_a, "P"_a, "N"_a, "rank"_a, "sigma_max"_a, "C"_a, "e"_a, "w_diag"_a,
      "w_full"_a, "root_full"_a, "center"_a, "x"_a, "bounds"_a,
      "Whether x is the step's minimiser (the KKT test of certify).");

  m.def(
      "certificate",
      [](In A, const Vec& b, const Vec& lower, const Vec& upper, In G,
         const Vec& h, In P, In N, Index rank, double sigma_max,
         In C, const Vec& e, const Eigen::Matrix<std::int8_t, Eigen::Dynamic, 1>& kind,
         const Vec& w_diag, In w_full, In root_full, const Vec& center,
         const Vec& x, bool bounds, double eq_rtol, double bounds_tol, bool ask_kkt) {
        const Index n = A.cols();
        require(b.size() == A.rows() && lower.size() == n && upper.size() == n &&
                    G.cols() == n && h.size() == G.rows() && C.cols() == n &&
                    e.size() == C.rows() && kind.size() == C.rows() &&
                    center.size() == n && x.size() == n,
                "certificate: arguments of inconsistent sizes");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        return certificate_tuple(
            dqk::certificate(A, b, lower, upper, G, h,
                             ask_kkt ? basis_from(A, P, N, rank, sigma_max) : dqk::Basis{}, C, e,
                             kind, cost, x, bounds, eq_rtol, bounds_tol, ask_kkt));
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "P"_a, "N"_a, "rank"_a,
      "sigma_max"_a, "C"_a, "e"_a, "kind"_a, "w_diag"_a, "w_full"_a, "root_full"_a,
      "center"_a, "x"_a, "bounds"_a, "eq_rtol"_a, "bounds_tol"_a, "ask_kkt"_a,
      "Everything certify reads of x: (finite, eq, box, row, eq_limit, kkt, objective, "
      "active_lower, active_upper, active_rows); kkt is -1 when not asked or x breaks a "
      "limit.");

  m.def("carry_equality", &dqk::carry_equality, "n_l"_a, "J_object"_a, "J_target"_a, "J_f"_a,
        "twist"_a, "e_l"_a, "e_c"_a, "scale"_a, "gain_l"_a, "gain_c"_a,
        "exact_orientation"_a, "A"_a.noconvert(), "b"_a.noconvert(),
        "The step's equality block into A (12, n) and b (12): the object follows D(t), "
        "the grasp stays closed. Returns whether both are finite.");

  m.def(
      "intersect_boxes",
      [](const dqk::BoundRows& lowers, const std::vector<std::int64_t>& lower_ids,
         const dqk::BoundRows& uppers, const std::vector<std::int64_t>& upper_ids, Index n,
         double pin_rtol) {
        dqk::Box b =
            dqk::intersect_boxes(lowers, lower_ids, uppers, upper_ids, n, pin_rtol);
        return nb::make_tuple(out(std::move(b.lower)), out(std::move(b.upper)),
                              out(std::move(b.lower_by)), out(std::move(b.upper_by)), b.nan_limit);
      },
      "lowers"_a, "lower_ids"_a, "uppers"_a, "upper_ids"_a, "n"_a, "pin_rtol"_a,
      "The step's box from its limits' boxes: (lower, upper, lower_by, upper_by, "
      "nan_limit); see StepBuilder.build.");

  m.def(
      "first_defect",
      [](const std::vector<nb::ndarray<const double, nb::c_contig, nb::device::cpu>>& finite,
         const std::vector<nb::ndarray<const double, nb::c_contig, nb::device::cpu>>& not_nan) {
        auto values = [](const auto& arrays) {
          std::vector<dqk::Values> spans;
          spans.reserve(arrays.size());
          for (const auto& a : arrays) spans.emplace_back(a.data(), static_cast<Index>(a.size()));
          return spans;
        };
        return dqk::first_defect(values(finite), values(not_nan));
      },
      "finite"_a, "not_nan"_a,
      "Index of the first array with NaN or infinity (finite) or NaN (not_nan, numbered "
      "after the finite ones); -1 when none.");

  m.def(
      "range_box",
      [](const Vec& lo, const Vec& hi, const Vec& rec,
         const Eigen::Matrix<bool, Eigen::Dynamic, 1>& off) {
        Vec lower, upper;
        dqk::range_box(lo, hi, rec, off, lower, upper);
        return nb::make_tuple(out(std::move(lower)), out(std::move(upper)));
      },
      "lo"_a, "hi"_a, "rec"_a, "off"_a,
      "A range limit's rate box (lower, upper) from the rates to the range's ends.");

  m.def(
      "centre",
      [](const Vec& lo, const Vec& hi, const Eigen::Matrix<bool, Eigen::Dynamic, 1>& centred,
         double shrink) { return out(dqk::centre(lo, hi, centred, shrink)); },
      "lo"_a, "hi"_a, "centred"_a, "shrink"_a,
      "The centre rates of Eqs. 38-40 from the rates to the range's ends.");

  m.def("smallest_singular_value", [](In J) { return dqk::smallest_singular_value(Mat(J)); },
        "J"_a,
        "Smallest singular value of J (0 with fewer columns than rows, inf with no rows, NaN "
        "for a non-finite J).");

  m.def(
      "smallest_singular_values",
      [](In J_leader, In J_follower) {
        return nb::make_tuple(dqk::smallest_singular_value(Mat(J_leader)),
                              dqk::smallest_singular_value(Mat(J_follower)));
      },
      "J_leader"_a, "J_follower"_a,
      "Both arms' smallest singular values in one call: (leader, follower), as "
      "smallest_singular_value gives each.");

  m.def(
      "scale_lp",
      [](In M, const Vec& a, const Vec& g, double s_lo, double s_hi) {
        dqk::ScaleLPResult r = dqk::scale_lp(M, a, g, s_lo, s_hi);
        return nb::make_tuple(static_cast<int>(r.status), out(std::move(r.t)), r.s, r.rows);
      },
      "M"_a, "a"_a, "g"_a, "s_lo"_a, "s_hi"_a,
      "Largest s with M t + a s <= g, s_lo <= s <= s_hi: (status, t, s, rows); status 0 "
      "optimal (rows: the final basis), 1 infeasible (rows: the dual ray), 2 iteration "
      "limit.");
}

}  // namespace dqk_binding

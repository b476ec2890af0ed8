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

namespace {

// affine's answer: the minimum-norm solution of A x = b and the SVD it came from.
struct Affine {
  Vec x0;
  dqk::Factor factor;
};

// range_box's answer: a range limit's rate box.
struct RateBox {
  Vec lower;
  Vec upper;
};

// smallest_singular_values's answer: both arms' smallest singular values.
struct SingularValues {
  double leader;
  double follower;
};

// The classes of the answers below, each field a named read-only property (an array a
// view of the answer's memory).
void bind_geometry_results(nb::module_& m) {
  auto factor = nb::class_<dqk::Factor>(
      m, "Factor", "A ~= U diag(sigma) V^T truncated at RANK_RTOL (factor's answer).");
  array_property(factor, "U", &dqk::Factor::U, "(m, r): the numerical range.");
  array_property(factor, "sigma", &dqk::Factor::sigma, "(r): the kept singular values.");
  array_property(factor, "V", &dqk::Factor::V, "(n, r): the numerical row space.");
  array_property(factor, "N", &dqk::Factor::N, "(n, n - r): the numerical null space.");

  auto affine = nb::class_<Affine>(
      m, "Affine", "Every solution x0 + N t of A x = b (affine's answer).");
  array_property(affine, "x0", &Affine::x0, "(n): the minimum-norm solution.");
  affine.def_prop_ro(
      "factor", [](Affine& a) -> dqk::Factor& { return a.factor; },
      nb::rv_policy::reference_internal, "A's truncated SVD (N: the null space).");

  auto basis = nb::class_<dqk::Basis>(
      m, "Basis", "What the exact solver and the certificate need of A (basis's answer).");
  basis.def_prop_ro("P", [](const dqk::Basis& f) { return f.pinv(); },
                    "(n, m): the pseudo-inverse of A (formed when read).");
  array_property(basis, "N", &dqk::Basis::N, "(n, n - rank): a basis of A's null space.");
  basis.def_ro("rank", &dqk::Basis::rank, "A's numerical rank.")
      .def_prop_ro("nullity", &dqk::Basis::nullity, "n - rank: the null space's dimension.")
      .def_ro("sigma_max", &dqk::Basis::sigma_max,
              "A's largest singular value (SVD path) or its bound |R|_F (QR path).")
      .def_ro("qr", &dqk::Basis::qr, "Whether the QR path proved full row rank.");

  auto rows = nb::class_<dqk::Rows>(
      m, "Rows", "Every finite limit as a unit-norm row C x <= e (inequalities's answer).");
  array_property(rows, "C", &dqk::Rows::C, "(k, n)");
  array_property(rows, "e", &dqk::Rows::e, "(k)");
  array_property(rows, "kind", &dqk::Rows::kind, "(k) int8: +1 upper box, -1 lower, 0 row.");
  array_property(rows, "index", &dqk::Rows::index, "(k) int64: the variable or row of G.");

  nb::class_<dqk::Residuals>(m, "Residuals", "The residuals of x (residuals's answer).")
      .def_ro("eq", &dqk::Residuals::eq, "max |A x - b|.")
      .def_ro("box", &dqk::Residuals::box, "The largest box violation (>= 0).")
      .def_ro("row", &dqk::Residuals::row,
              "The largest violation of a general row over its norm (>= 0).");
}

void bind_certificate(nb::module_& m) {
  using C = dqk::Certificate;
  auto cert = nb::class_<C>(m, "Certificate",
                            "Everything certify reads of x (certificate's answer).");
  cert.def_ro("finite", &C::finite, "x holds no NaN or infinity (else nothing is computed).")
      .def_prop_ro("eq", [](const C& c) { return c.res.eq; }, "max |A x - b|.")
      .def_prop_ro("box", [](const C& c) { return c.res.box; }, "The largest box violation.")
      .def_prop_ro("row", [](const C& c) { return c.res.row; },
                   "The largest violation of a unit-norm general row.")
      .def_ro("eq_limit", &C::eq_limit, "eq_rtol * max(1, max |b|).")
      .def_ro("kkt", &C::kkt, "The KKT test: -1 not asked (or x breaks a limit), 0 fails, 1 "
                              "holds.")
      .def_ro("objective", &C::objective, "(x - c)^T W (x - c).");
  array_property(cert, "active_lower", &C::active_lower, "(n) bool: lower - x >= -ACTIVE_TOL.");
  array_property(cert, "active_upper", &C::active_upper, "(n) bool: x - upper >= -ACTIVE_TOL.");
  cert.def_ro("active_rows", &C::active_rows,
              "The general rows within ACTIVE_TOL of binding, as rows of G (from the rows' "
              "index).");

  using A = dqk::StepAnswer;
  auto answer = nb::class_<A>(m, "StepAnswer", "The exact step (solve_nullspace's answer).");
  answer.def_prop_ro("code", [](const A& a) { return static_cast<int>(a.code); },
                     "0 optimal, 1 infeasible, 2 inconsistent A x = b, 3 iteration limit.");
  array_property(answer, "x", &A::x, "(n): the step (an optimum's).");
  answer.def_ro("conflicts", &A::conflicts, "The conflicting rows of C (infeasible).")
      .def_ro("nullity", &A::nullity, "A's null-space dimension (-1: inconsistent).")
      .def_ro("iterations", &A::iterations,
              "The active set's additions and drops (nullity >= 2), else -1.");

  using S = dqk::CertifiedStep;
  auto step = nb::class_<S>(
      m, "CertifiedStep",
      "The exact step and its certificate (solve_certified's answer); an empty box: code "
      "EMPTY_BOX_CODE, x zero, no conflicts, an empty basis and rows.");
  step.def_prop_ro(
      "code",
      [](const S& s) {
        return s.empty_box ? dqk::EMPTY_BOX_CODE : static_cast<int>(s.answer.code);
      },
      "StepAnswer's code, or EMPTY_BOX_CODE (not solved).");
  array_property(step, "x", [](const S& s) -> const Vec& { return s.answer.x; }, "(n)");
  step.def_prop_ro("conflicts", [](const S& s) { return s.answer.conflicts; },
                   "The conflicting rows of rows (infeasible).")
      .def_prop_ro("nullity", [](const S& s) { return s.answer.nullity; })
      .def_prop_ro("iterations", [](const S& s) { return s.answer.iterations; })
      .def_prop_ro(
          "basis", [](S& s) -> dqk::Basis& { return s.basis; },
          nb::rv_policy::reference_internal, "A's basis (basis(A)'s answer).")
      .def_prop_ro(
          "rows", [](S& s) -> dqk::Rows& { return s.rows; }, nb::rv_policy::reference_internal,
          "The limits' unit-norm rows (inequalities(...)'s answer).")
      .def_prop_ro(
          "certificate",
          [](S& s) -> dqk::Certificate* { return s.certified ? &s.cert : nullptr; },
          nb::rv_policy::reference_internal,
          "certificate(...)'s answer for x with the KKT test (an optimum), else None.");
}

void bind_qp_results(nb::module_& m) {
  using D = dqk::DenseQPResult;
  auto qp = nb::class_<D>(m, "DenseQPResult", "Goldfarb-Idnani's answer (dense_qp).");
  qp.def_prop_ro("status", [](const D& r) { return static_cast<int>(r.status); },
                 "0 optimal, 1 infeasible, 2 iteration limit.");
  array_property(qp, "t", &D::t, "(d): the minimiser.");
  qp.def_ro("active", &D::active, "The active rows.")
      .def_ro("multipliers", &D::multipliers, "Their multipliers (clipped at zero).")
      .def_ro("blocking", &D::blocking, "The row that could not be added (infeasible).")
      .def_ro("iterations", &D::iterations, "Additions and drops.");

  using N = dqk::NNLSResult;
  auto nnls = nb::class_<N>(m, "NNLSResult", "Lawson-Hanson's answer (nnls).");
  array_property(nnls, "x", &N::x, "(n): the minimiser, x >= 0.");
  nnls.def_ro("rnorm", &N::rnorm, "|A x - b|.").def_ro("converged", &N::converged);

  using L = dqk::ScaleLPResult;
  auto lp = nb::class_<L>(m, "ScaleLPResult", "The task-scale LP's answer (scale_lp).");
  lp.def_prop_ro("status", [](const L& r) { return static_cast<int>(r.status); },
                 "0 optimal, 1 infeasible, 2 iteration limit.");
  array_property(lp, "t", &L::t, "(d): the null-space coordinates at the optimum.");
  lp.def_ro("s", &L::s, "The largest scale.")
      .def_ro("rows", &L::rows, "The final basis's rows (optimal) or the dual ray's.");

  using B = dqk::Box;
  auto box = nb::class_<B>(m, "Box", "The step's box from its limits' (intersect_boxes).");
  array_property(box, "lower", &B::lower, "(n)");
  array_property(box, "upper", &B::upper, "(n)");
  array_property(box, "lower_by", &B::lower_by,
                 "(n) int64: the limit that set each lower bound (-1: none).");
  array_property(box, "upper_by", &B::upper_by,
                 "(n) int64: the limit that set each upper bound (-1: none).");
  box.def_ro("nan_limit", &B::nan_limit, "The first limit whose bounds hold NaN (-1: none).");

  auto rate = nb::class_<RateBox>(m, "RateBox", "A range limit's rate box (range_box).");
  array_property(rate, "lower", &RateBox::lower, "(n)");
  array_property(rate, "upper", &RateBox::upper, "(n)");

  nb::class_<SingularValues>(m, "SingularValues",
                             "Both arms' smallest singular values (smallest_singular_values).")
      .def_ro("leader", &SingularValues::leader, "The leader's tool Jacobian's.")
      .def_ro("follower", &SingularValues::follower, "The follower's tool Jacobian's.");
}

}  // namespace

void bind_solver(nb::module_& m) {
  bind_geometry_results(m);
  bind_certificate(m);
  bind_qp_results(m);

  m.def("factor", [](In A) { return dqk::factor(A); }, "A"_a,
        "Truncated SVD of A (a Factor).");

  m.def(
      "affine",
      [](In A, const Vec& b) -> nb::object {
        dqk::Factor f = dqk::factor(A);
        auto x0 = dqk::affine_point(A, b, f);
        if (!x0) return nb::none();
        return nb::cast(Affine{std::move(*x0), std::move(f)}, nb::rv_policy::move);
      },
      "A"_a, "b"_a, "Every solution of A x = b (an Affine), or None if inconsistent.");

  m.def(
      "inequalities",
      [](const Vec& lower, const Vec& upper, In G, const Vec& h) {
        return dqk::inequalities(lower, upper, G, h);
      },
      "lower"_a, "upper"_a, "G"_a, "h"_a, "Every finite limit as unit-norm rows (a Rows).");

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
      [](In A) { return dqk::basis(A); }, "A"_a,
      "A's pseudo-inverse, a basis of its null space, its rank, its largest singular value "
      "(or a bound) and whether the QR path proved full row rank (a Basis).");

  m.def(
      "solve_nullspace",
      [](In A, const Vec& b, const dqk::Basis& basis, In C, const Vec& e,
         const Vec& w_diag, In w_full, In root_full, const Vec& center, double feas_tol,
         Index max_iter) {
        require(b.size() == A.rows() && C.cols() == A.cols() && e.size() == C.rows() &&
                    center.size() == A.cols(),
                "solve_nullspace: arguments of inconsistent sizes");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        return dqk::solve_nullspace(A, b, basis_of(A, basis), C, e, cost, feas_tol, max_iter);
      },
      "A"_a, "b"_a, "basis"_a, "C"_a, "e"_a, "w_diag"_a,
      "w_full"_a, "root_full"_a, "center"_a, "feas_tol"_a, "max_iter"_a,
      "The exact step on A's basis (basis(A)'s answer): a StepAnswer.");

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
        return dqk::solve_certified(A, b, lower, upper, G, h, cost, feas_tol, max_iter, bounds,
                                    eq_rtol, bounds_tol);
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "w_diag"_a, "w_full"_a,
      "root_full"_a, "center"_a, "feas_tol"_a, "max_iter"_a, "bounds"_a, "eq_rtol"_a,
      "bounds_tol"_a,
      "The exact step and its certificate in one call (a CertifiedStep): its basis is "
      "basis(A)'s, its rows inequalities(...)'s, its certificate certificate(...)'s (with "
      "the KKT test) for an optimum, else None. A problem with an empty box (some lower > "
      "upper) is not solved: code EMPTY_BOX_CODE, x zero, no conflicts, an empty basis "
      "and rows.");

  m.def(
      "dense_qp",
      [](In R, const Vec& t_free, In M, const Vec& f, double feas_tol,
         Index max_iter) {
        return dqk::solve_dense_qp(R, t_free, M, f, feas_tol, max_iter);
      },
      "R"_a, "t_free"_a, "M"_a, "f"_a, "feas_tol"_a, "max_iter"_a,
      "Goldfarb-Idnani (a DenseQPResult).");

  m.def(
      "nnls",
      [](In A, const Vec& b, Index max_iter) { return dqk::nnls(A, b, max_iter); }, "A"_a,
      "b"_a, "max_iter"_a, "Lawson-Hanson NNLS (an NNLSResult).");

  m.def(
      "residuals",
      [](In A, const Vec& b, const Vec& lower, const Vec& upper, In G,
         const Vec& h, const Vec& x) {
        return dqk::residuals(A, b, lower, upper, G, h, x);
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "x"_a,
      "max |A x - b|, the box violation and the row violation of x (a Residuals).");

  m.def(
      "kkt_holds",
      [](In A, const Vec& b, const dqk::Basis& basis, In C, const Vec& e,
         const Vec& w_diag, In w_full, In root_full, const Vec& center, const Vec& x,
         bool bounds) {
        require(b.size() == A.rows() && C.cols() == A.cols() && e.size() == C.rows() &&
                    center.size() == A.cols() && x.size() == A.cols(),
                "kkt_holds: arguments of inconsistent sizes");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        return dqk::kkt_holds(A, b, basis_of(A, basis), C, e, cost, x, bounds);
      },
      "A"_a, "b"_a, "basis"_a, "C"_a, "e"_a, "w_diag"_a,
      "w_full"_a, "root_full"_a, "center"_a, "x"_a, "bounds"_a,
      "Whether x is the step's minimiser (the KKT test of certify).");

  m.def(
      "certificate",
      [](In A, const Vec& b, const Vec& lower, const Vec& upper, In G,
         const Vec& h, const dqk::Basis* basis,
         In C, const Vec& e, const Eigen::Matrix<std::int8_t, Eigen::Dynamic, 1>& kind,
         const Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>& index, const Vec& w_diag,
         In w_full, In root_full, const Vec& center,
         const Vec& x, bool bounds, double eq_rtol, double bounds_tol, bool ask_kkt) {
        const Index n = A.cols();
        require(b.size() == A.rows() && lower.size() == n && upper.size() == n &&
                    G.cols() == n && h.size() == G.rows() && C.cols() == n &&
                    e.size() == C.rows() && kind.size() == C.rows() &&
                    index.size() == C.rows() &&
                    center.size() == n && x.size() == n,
                "certificate: arguments of inconsistent sizes");
        require(!ask_kkt || basis != nullptr, "certificate: the KKT test needs A's basis");
        for (Index i = 0; i < kind.size(); ++i)
          require(kind(i) != 0 || (index(i) >= 0 && index(i) < G.rows()),
                  "certificate: a general row's index is a row of G");
        const dqk::Cost cost = cost_of(w_diag, w_full, root_full, center);
        static const dqk::Basis none;  // not read: no KKT test asked
        const dqk::Basis& fa = ask_kkt ? basis_of(A, *basis) : none;
        return dqk::certificate(A, b, lower, upper, G, h, fa, C, e, kind, index, cost, x,
                                bounds, eq_rtol, bounds_tol, ask_kkt);
      },
      "A"_a, "b"_a, "lower"_a, "upper"_a, "G"_a, "h"_a, "basis"_a.none(), "C"_a, "e"_a,
      "kind"_a, "index"_a, "w_diag"_a, "w_full"_a, "root_full"_a, "center"_a, "x"_a, "bounds"_a, "eq_rtol"_a, "bounds_tol"_a, "ask_kkt"_a,
      "Everything certify reads of x (a Certificate); its kkt is -1 when not asked or x "
      "breaks a limit.");

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
        return dqk::intersect_boxes(lowers, lower_ids, uppers, upper_ids, n, pin_rtol);
      },
      "lowers"_a, "lower_ids"_a, "uppers"_a, "upper_ids"_a, "n"_a, "pin_rtol"_a,
      "The step's box from its limits' boxes (a Box).");

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
        RateBox box;
        dqk::range_box(lo, hi, rec, off, box.lower, box.upper);
        return box;
      },
      "lo"_a, "hi"_a, "rec"_a, "off"_a,
      "A range limit's rate box (a RateBox) from the rates to the range's ends.");

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
        return SingularValues{dqk::smallest_singular_value(Mat(J_leader)),
                              dqk::smallest_singular_value(Mat(J_follower))};
      },
      "J_leader"_a, "J_follower"_a,
      "Both arms' smallest singular values in one call (a SingularValues), as "
      "smallest_singular_value gives each.");

  m.def(
      "scale_lp",
      [](In M, const Vec& a, const Vec& g, double s_lo, double s_hi) {
        return dqk::scale_lp(M, a, g, s_lo, s_hi);
      },
      "M"_a, "a"_a, "g"_a, "s_lo"_a, "s_hi"_a,
      "Largest s with M t + a s <= g, s_lo <= s <= s_hi (a ScaleLPResult): status 0 "
      "optimal (rows: the final basis), 1 infeasible (rows: the dual ray), 2 iteration "
      "limit.");
}

}  // namespace dqk_binding

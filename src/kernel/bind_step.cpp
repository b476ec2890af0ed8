// dualarm_qp._kernel's step: the standard parts of one step (StepParts, prepare) and the
// step built, solved and certified in one call (prepare_solved) with the look-ahead's
// bound (module.cpp makes the module).
#include "binding.hpp"

#include <chrono>

#include "certified_step.hpp"
#include "lookahead.hpp"
#include "step_parts.hpp"

namespace dqk_binding {

using namespace nb::literals;

namespace {

// The compiled row limits' rows, one DamperScene.rows tuple each.
nb::list rows_list(std::vector<dqk::DamperRows>& rows) {
  nb::list out_rows;
  for (dqk::DamperRows& r : rows) out_rows.append(damper_tuple(std::move(r)));
  return out_rows;
}

// StepParts.prepare's answer as dualarm_qp/step/build.py reads it (the docstring of
// "prepare" below names the items).
nb::tuple parts_tuple(dqk::StepPartsOut&& o) {
  dqk::Box& box = o.box;
  return nb::make_tuple(
      out(std::move(o.T)), out(std::move(o.J_tool)), out(std::move(o.J_object)),
      out(std::move(o.J_target)), out(std::move(o.J_f)), out(std::move(o.e)),
      out(std::move(o.lo)), out(std::move(o.hi)), out(std::move(o.A)), out(std::move(o.b)),
      o.equality_finite, out(std::move(o.center)), out(std::move(o.lowers)),
      out(std::move(o.uppers)),
      nb::make_tuple(out(std::move(box.lower)), out(std::move(box.upper)),
                     out(std::move(box.lower_by)), out(std::move(box.upper_by)),
                     box.nan_limit),
      out(std::move(o.recovering)), o.any_recovering, rows_list(o.rows), o.kinematics_seconds);
}

}  // namespace

void bind_step(nb::module_& m) {
  nb::class_<dqk::StepParts>(m, "StepParts",
                             "The standard parts of one step in one call (StepBuilder).")
      .def(nb::init<Index, Index, std::vector<int>, int, std::vector<int>, Vec, Vec, double,
                    dqk::BoolVec, double, dqk::BoolVec, double>(),
           "n_l"_a, "n_f"_a, "carry_frames"_a, "follower_tool"_a, "cols"_a, "q_min"_a,
           "q_max"_a, "dt"_a, "centred"_a, "shrink"_a, "ranged"_a, "pin_rtol"_a)
      .def("add_form", &dqk::StepParts::add_form, "kind"_a, "p"_a, "off"_a, "limit"_a)
      .def("add_grasp_line", &dqk::StepParts::add_grasp_line, "origin"_a, "direction"_a,
           "r_min"_a, "r_max"_a, "sigma_min"_a, "sigma_max"_a)
      .def(
          "add_rows",
          [](dqk::StepParts& self, const dqk::DamperScene& damper, std::int64_t limit) {
            self.add_rows(&damper, limit);
          },
          "damper"_a, "limit"_a, nb::keep_alive<1, 2>(),
          "A limit whose rows prepare computes: a collision scene's damper (kept alive with "
          "this object); limit is its index in the step's order (increasing).")
      .def_prop_ro("forms", &dqk::StepParts::forms)
      .def_prop_ro("row_forms", &dqk::StepParts::row_forms)
      .def_prop_ro("n", &dqk::StepParts::n)
      .def_prop_ro("grasp_lines", &dqk::StepParts::grasp_lines)
      .def(
          "prepare",
          [](const dqk::StepParts& self, dqk::Chain& carry, const Eigen::VectorXd& q_carry,
             const Vec& col_rate, dqk::Chain& follower, const Eigen::VectorXd& q_f,
             const dqk::Pose& T_D, const dqk::Vec6& twist, const Vec& sigmas,
             const Vec& grasp_lo, const Vec& grasp_hi, const Vec& x_applied, double scale_max,
             double leader_gain, double correction_gain, bool exact_orientation) {
            return parts_tuple(self.prepare(carry, q_carry, col_rate, follower, q_f, T_D,
                                            twist, sigmas, grasp_lo, grasp_hi, x_applied,
                                            scale_max, leader_gain, correction_gain,
                                            exact_orientation));
          },
          "carry"_a, "q_carry"_a, "col_rate"_a, "follower"_a, "q_f"_a, "T_D"_a, "twist"_a,
          "sigmas"_a, "grasp_lo"_a, "grasp_hi"_a, "x_applied"_a, "scale_max"_a,
          "leader_gain"_a, "correction_gain"_a, "exact_orientation"_a,
          "(T, J_tool, J_object, J_target, J_f, e, lo, hi, A, b, equality_finite, "
          "center, lowers, uppers, box, recovering, any_recovering, rows, "
          "kinematics_seconds) at one state; box is intersect_boxes's tuple of the compiled "
          "forms' boxes, rows a list of DamperScene.rows's tuple per compiled row limit.")
      .def(
          "prepare_solved",
          [](const dqk::StepParts& self, dqk::Chain& carry, const Eigen::VectorXd& q_carry,
             const Vec& col_rate, dqk::Chain& follower, const Eigen::VectorXd& q_f,
             const dqk::Pose& T_D, const dqk::Vec6& twist, const Vec& sigmas,
             const Vec& grasp_lo, const Vec& grasp_hi, const Vec& x_applied, double scale_max,
             double leader_gain, double correction_gain, bool exact_orientation,
             const dqk::ExactSolve& exact, const dqk::LookaheadBound* bound) {
            require(exact.n() == self.n(), "prepare_solved: the solve's cost has another size");
            dqk::StepPartsOut o =
                self.prepare(carry, q_carry, col_rate, follower, q_f, T_D, twist, sigmas,
                             grasp_lo, grasp_hi, x_applied, scale_max, leader_gain,
                             correction_gain, exact_orientation);
            // A step the Python layer refuses (a non-finite equality, box or rows) is not
            // solved.
            bool finite = o.equality_finite && o.box.nan_limit < 0;
            Index p = 0;
            for (const dqk::DamperRows& r : o.rows) {
              finite = finite && r.finite;
              p += r.G.rows();
            }
            nb::object solved = nb::none();
            if (finite) {
              using clock = std::chrono::steady_clock;
              const auto start = clock::now();
              const Index n = self.n();
              Mat G(p, n);  // the rows stacked in the limits' order (LimitStack.rows)
              Vec h(p);
              Index at = 0;
              for (const dqk::DamperRows& r : o.rows) {
                G.middleRows(at, r.G.rows()) = r.G;
                h.segment(at, r.h.size()) = r.h;
                at += r.G.rows();
              }
              dqk::CertifiedStep s = exact.solve(Mat(o.A), o.b, o.box.lower, o.box.upper, G, h,
                                                 o.center);
              const double seconds = std::chrono::duration<double>(clock::now() - start).count();
              // With a bound, for an optimum: whether the look-ahead may skip its prediction
              // for the command the controller applies, x clipped to the box (the bound
              // reads |x| only, so the clip's signs of zero do not matter to it).
              nb::object skip = nb::none();
              if (bound != nullptr && s.answer.code == dqk::StepCode::optimal && s.certified) {
                const Vec clipped = s.answer.x.cwiseMax(o.box.lower).cwiseMin(o.box.upper);
                skip = nb::bool_((*bound)(clipped, dqk::Pose(o.T.middleRows(0, 4)),
                                          dqk::Pose(o.T.middleRows(8, 4))));
              }
              solved = nb::make_tuple(certified_tuple(std::move(s)), seconds, skip);
            }
            return nb::make_tuple(parts_tuple(std::move(o)), solved);
          },
          "carry"_a, "q_carry"_a, "col_rate"_a, "follower"_a, "q_f"_a, "T_D"_a, "twist"_a,
          "sigmas"_a, "grasp_lo"_a, "grasp_hi"_a, "x_applied"_a, "scale_max"_a,
          "leader_gain"_a, "correction_gain"_a, "exact_orientation"_a, "exact"_a,
          "bound"_a.none() = nb::none(),
          "(parts, solved): prepare's tuple and, for a step with no other limit, the step "
          "solved and certified on its equality, its box (the compiled forms') and the "
          "compiled limits' rows: (solve_certified's tuple, its seconds, skip), or None "
          "where the equality, the box or the rows are not finite. skip: for an optimum "
          "and a bound, whether the bound skips the look-ahead's prediction for its x "
          "clipped to the box; else None.");

  nb::class_<dqk::LookaheadBound>(
      m, "LookaheadBound",
      "negligible's numbers of one controller but the command and the poses "
      "(StepParts.prepare_solved).")
      .def("__init__",
           [](dqk::LookaheadBound* self, Index n_l, Index n_f, double dt, double length_l,
              double length_f, double budget_pos, double budget_rot, double share) {
             new (self) dqk::LookaheadBound{n_l, n_f, dt, length_l, length_f, budget_pos,
                                            budget_rot, share};
           },
           "n_l"_a, "n_f"_a, "dt"_a, "length_l"_a, "length_f"_a, "budget_pos"_a,
           "budget_rot"_a, "share"_a);
}

}  // namespace dqk_binding

// dualarm_qp._kernel's step: the context every part reads, the three kinds of part
// (Task, CostTerm, Limit) with the library's own, and the step that asks them in turn
// (module.cpp makes the module). A Python subclass of a part class overrides its one
// method (equality, quadratic or constraint: a trampoline below), and the step's loop
// asks it as it asks a compiled part.
#include "binding.hpp"

#include <nanobind/stl/optional.h>
#include <nanobind/trampoline.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "standard_parts.hpp"
#include "step.hpp"
#include "support_line.hpp"
#include "torque_limit.hpp"

namespace dqk_binding {

using namespace nb::literals;

namespace {

nb::tuple names_tuple(const std::vector<std::string>& names) {
  nb::list out;
  for (const std::string& s : names) out.append(nb::str(s.data(), s.size()));
  return nb::tuple(out);
}

// The Python object a part written in Python reads (the step's user handle).
nb::handle user_of(const dqk::Context& ctx) {
  if (ctx.user == nullptr)
    throw std::invalid_argument("a part written in Python was asked without its context");
  return nb::handle(static_cast<PyObject*>(ctx.user));
}

// What a part written in Python gave, in the kernel's form: its answer as it is when
// it is one (a kernel Equality, Quadratic or Constraint), else converted and checked by
// dualarm_qp/step/python_parts.py (kernel_equality, ...), which names the part.
template <typename Value>
Value taken(nb::object answer, nb::handle self, const dqk::Context& ctx, const char* convert) {
  if (!nb::isinstance<Value>(answer)) {
    // The converters' module, looked up at the first Python part's answer and kept (an
    // import statement's lookup is about 0.5 us, measured from Python, on every answer
    // of every Python part); its reference is never given back, as the interpreter
    // keeps its modules to the end.
    static const nb::handle converters =
        nb::module_::import_("dualarm_qp.step.python_parts").release();
    nb::object name = nb::getattr(self, "name", nb::str(Py_TYPE(self.ptr())->tp_name));
    answer = converters.attr(convert)(answer, name, ctx.n);
  }
  return std::move(nb::cast<Value&>(answer));
}

// The trampolines: a Python subclass's method, called with the Python context, whose
// answer is taken over; a subclass of a library part that does not override the method
// runs the part's own.
template <typename Base>
struct PyTask : Base {
  NB_TRAMPOLINE(Base);
  dqk::Equality equality(const dqk::Context& ctx) const override {
    nb::detail::ticket t(nb_trampoline, "equality", nb::detail::str_hash("equality"),
                         std::is_abstract_v<Base>);
    if constexpr (!std::is_abstract_v<Base>) {
      if (!t.key.is_valid()) return Base::equality(ctx);
    }
    nb::handle self = nb_trampoline.base();
    return taken<dqk::Equality>(self.attr(t.key)(user_of(ctx)), self, ctx, "kernel_equality");
  }
};

template <typename Base>
struct PyCost : Base {
  NB_TRAMPOLINE(Base);
  dqk::Quadratic quadratic(const dqk::Context& ctx) const override {
    nb::detail::ticket t(nb_trampoline, "quadratic", nb::detail::str_hash("quadratic"),
                         std::is_abstract_v<Base>);
    if constexpr (!std::is_abstract_v<Base>) {
      if (!t.key.is_valid()) return Base::quadratic(ctx);
    }
    nb::handle self = nb_trampoline.base();
    return taken<dqk::Quadratic>(self.attr(t.key)(user_of(ctx)), self, ctx,
                                 "kernel_quadratic");
  }
};

template <typename Base>
struct PyLimit : Base {
  NB_TRAMPOLINE(Base);
  dqk::Constraint constraint(const dqk::Context& ctx) const override {
    nb::detail::ticket t(nb_trampoline, "constraint", nb::detail::str_hash("constraint"),
                         std::is_abstract_v<Base>);
    if constexpr (!std::is_abstract_v<Base>) {
      if (!t.key.is_valid()) return Base::constraint(ctx);
    }
    nb::handle self = nb_trampoline.base();
    return taken<dqk::Constraint>(self.attr(t.key)(user_of(ctx)), self, ctx,
                                  "kernel_constraint");
  }
};

// The kernel context of a Python context (its attribute kernel_context), or a kernel
// context itself, for a compiled part asked on its own (part.constraint(ctx) from Python).
const dqk::Context& kernel_context(nb::handle py_ctx) {
  if (nb::isinstance<dqk::Context>(py_ctx)) return nb::cast<const dqk::Context&>(py_ctx);
  return nb::cast<const dqk::Context&>(py_ctx.attr("kernel_context"));
}

using OptVec = std::optional<Vec>;
using OptMat = std::optional<dqk::RowMat>;

void bind_values(nb::module_& m) {
  auto eq = nb::class_<dqk::Equality>(m, "Equality", "A task's rows A x = b (kernel form).");
  eq.def(
      "__init__",
      [](dqk::Equality* self, const dqk::RowMat& A, const Vec& b,
         const std::vector<std::string>& names) {
        require(A.rows() == b.size() && (names.empty() || names.size() == size_t(b.size())),
                "Equality: A (m, n), b (m) and m names (or none)");
        new (self) dqk::Equality{A, b, names};
      },
      "A"_a, "b"_a, "names"_a = std::vector<std::string>());
  array_property(eq, "A", [](const dqk::Equality& e) -> const dqk::RowMat& { return e.A; },
                 "(m, n)");
  array_property(eq, "b", [](const dqk::Equality& e) -> const Vec& { return e.b; }, "(m)");
  eq.def_prop_ro("names", [](const dqk::Equality& e) { return names_tuple(e.names); });

  auto quad = nb::class_<dqk::Quadratic>(
      m, "Quadratic", "A cost term (x - center)^T W (x - center) (kernel form).");
  quad.def(
      "__init__",
      [](dqk::Quadratic* self, const OptVec& w, const OptMat& W, const Vec& center) {
        require(w.has_value() != W.has_value(), "Quadratic: the diagonal w or the matrix W");
        new (self) dqk::Quadratic{w ? *w : Vec(), W ? *W : dqk::RowMat(), center};
      },
      "w"_a.none() = nb::none(), "W"_a.none() = nb::none(), "center"_a);
  quad.def_prop_ro("weights", [](nb::handle self) {
    const auto& q = nb::cast<const dqk::Quadratic&>(self);
    return q.diagonal() ? view(q.w, self) : view(q.W, self);
  });
  array_property(quad, "center", [](const dqk::Quadratic& q) -> const Vec& { return q.center; },
                 "(n)");

  auto con = nb::class_<dqk::Constraint>(
      m, "Constraint", "What a limit asks of x: boxes and/or rows (kernel form).");
  con.def(
      "__init__",
      [](dqk::Constraint* self, const OptVec& lower, const OptVec& upper, const OptMat& G,
         const OptVec& h, const std::vector<std::string>& row_names) {
        require(G.has_value() == h.has_value() && (!G || G->rows() == h->size()) &&
                    (row_names.empty() || (h && row_names.size() == size_t(h->size()))),
                "Constraint: rows G (p, n) and h (p) together, p row names (or none)");
        auto* c = new (self) dqk::Constraint();
        c->has_lower = lower.has_value();
        c->has_upper = upper.has_value();
        if (lower) c->lower = *lower;
        if (upper) c->upper = *upper;
        if (G) {
          c->G = *G;
          c->h = *h;
        }
        c->row_names = row_names;
      },
      "lower"_a.none() = nb::none(), "upper"_a.none() = nb::none(), "G"_a.none() = nb::none(),
      "h"_a.none() = nb::none(), "row_names"_a = std::vector<std::string>());
  con.def_prop_ro("lower", [](nb::handle self) -> nb::object {
    const auto& c = nb::cast<const dqk::Constraint&>(self);
    return c.has_lower ? view(c.lower, self) : nb::none();
  });
  con.def_prop_ro("upper", [](nb::handle self) -> nb::object {
    const auto& c = nb::cast<const dqk::Constraint&>(self);
    return c.has_upper ? view(c.upper, self) : nb::none();
  });
  con.def_prop_ro("G", [](nb::handle self) -> nb::object {
    const auto& c = nb::cast<const dqk::Constraint&>(self);
    return c.h.size() ? view(c.G, self) : nb::none();
  });
  con.def_prop_ro("h", [](nb::handle self) -> nb::object {
    const auto& c = nb::cast<const dqk::Constraint&>(self);
    return c.h.size() ? view(c.h, self) : nb::none();
  });
  con.def_prop_ro("row_names",
                  [](const dqk::Constraint& c) { return names_tuple(c.row_names); });
  con.def_ro("nonfinite", &dqk::Constraint::nonfinite,
             "What a compiled part could not compute (empty: computed).");
}

void bind_context(nb::module_& m) {
  auto ctx = nb::class_<dqk::Context>(
      m, "Context", "A step's state and kinematics, computed once, as every part reads them.");
  ctx.def(
         "__init__",
         [](dqk::Context* self, const Vec& rate_lo, const Vec& rate_hi,
            const std::optional<Vec>& x_applied, double dt, double scale_max) {
           require(rate_lo.size() == rate_hi.size() &&
                       (!x_applied || x_applied->size() == rate_lo.size()) && dt > 0.0,
                   "Context: rate_lo, rate_hi (and x_applied) of one length, dt > 0");
           auto* c = new (self) dqk::Context();
           c->n = rate_lo.size();
           c->rate_lo = rate_lo;
           c->rate_hi = rate_hi;
           c->x_applied = x_applied ? *x_applied : Vec::Zero(c->n);
           c->positions = Vec::Zero(c->n);
           c->dt = dt;
           c->scale_max = scale_max;
         },
         "rate_lo"_a, "rate_hi"_a, "x_applied"_a.none() = nb::none(), "dt"_a = 1.0,
         "scale_max"_a = 1.0,
         "A context of the rates to the range ends alone (what the box limits read), to ask "
         "a limit on its own.")
      .def_ro("n_l", &dqk::Context::n_l)
      .def_ro("n_f", &dqk::Context::n_f)
      .def_ro("k", &dqk::Context::k)
      .def_ro("n", &dqk::Context::n)
      .def_ro("t", &dqk::Context::t, "Path time [s].")
      .def_ro("dt", &dqk::Context::dt, "Sampling interval [s].")
      .def_ro("scale_max", &dqk::Context::scale_max);
  using C = dqk::Context;
  array_property(ctx, "T_tool", [](const C& c) -> const dqk::Pose& { return c.T_tool; },
                 "The leader's tool pose (4, 4) [m].");
  array_property(ctx, "T_object", [](const C& c) -> const dqk::Pose& { return c.T_object; },
                 "The object frame's pose (4, 4) [m].");
  array_property(ctx, "T_target", [](const C& c) -> const dqk::Pose& { return c.T_target; },
                 "The follower's target pose (4, 4) [m].");
  array_property(ctx, "T_f", [](const C& c) -> const dqk::Pose& { return c.T_f; },
                 "The follower's tool pose (4, 4) [m].");
  array_property(ctx, "J_tool", [](const C& c) -> const dqk::RowMat& { return c.J_tool; },
                 "The leader's tool Jacobian (6, n_l).");
  array_property(ctx, "J_object", [](const C& c) -> const dqk::RowMat& { return c.J_object; },
                 "The object frame's Jacobian (6, n_l + k), decision order.");
  array_property(ctx, "J_target", [](const C& c) -> const dqk::RowMat& { return c.J_target; },
                 "The follower's target's Jacobian (6, n_l + k), decision order.");
  array_property(ctx, "J_f", [](const C& c) -> const dqk::RowMat& { return c.J_f; },
                 "The follower's tool Jacobian (6, n_f).");
  array_property(ctx, "leader_error", [](const C& c) -> const dqk::Vec6& { return c.leader_error; },
                 "[dp; dw] from the object frame to D(t) [m, rad].");
  array_property(ctx, "closure_error",
                 [](const C& c) -> const dqk::Vec6& { return c.closure_error; },
                 "[dp; dw] from the follower's tool to its target [m, rad].");
  array_property(ctx, "twist", [](const C& c) -> const dqk::Vec6& { return c.twist; },
                 "D(t)'s twist [m/s, rad/s].");
  array_property(ctx, "positions", [](const C& c) -> const Vec& { return c.positions; },
                 "Joints [rad] and grasp coordinates [m], decision order.");
  array_property(ctx, "rate_lo", [](const C& c) -> const Vec& { return c.rate_lo; },
                 "Rates to the lower range ends in one sample.");
  array_property(ctx, "rate_hi", [](const C& c) -> const Vec& { return c.rate_hi; },
                 "Rates to the upper range ends in one sample.");
  array_property(ctx, "x_applied", [](const C& c) -> const Vec& { return c.x_applied; },
                 "The last command applied [rad/s, m/s].");
}

void bind_out(nb::module_& m) {
  auto out = nb::class_<dqk::StepOut>(
      m, "StepOut", "A step as Step.build makes it: its context, its problem's parts.");
  using O = dqk::StepOut;
  out.def(nb::init<>())
      .def_prop_ro(
          "context", [](O& o) -> dqk::Context& { return o.context; },
          nb::rv_policy::reference_internal, "What every part read (kinematics once).");
  array_property(out, "A", [](const O& o) -> const dqk::RowMat& { return o.A; },
                 "The equality tasks' rows (m, n).");
  array_property(out, "b", [](const O& o) -> const Vec& { return o.b; }, "(m)");
  out.def_prop_ro("eq_names", [](const O& o) { return names_tuple(o.eq_names); });
  out.def_prop_ro("weights", [](nb::handle self) {
    const auto& o = nb::cast<const O&>(self);
    return o.W.size() ? view(o.W, self) : view(o.w, self);
  }, "The cost's diagonal (n), or its whole matrix (n, n).");
  array_property(out, "center", [](const O& o) -> const Vec& { return o.center; }, "(n)");
  array_property(out, "lower", [](const O& o) -> const Vec& { return o.box.lower; }, "(n)");
  array_property(out, "upper", [](const O& o) -> const Vec& { return o.box.upper; }, "(n)");
  array_property(out, "lower_by", [](const O& o) -> const dqk::IndexVec& { return o.box.lower_by; },
                 "The limit that set each lower bound (-1: none).");
  array_property(out, "upper_by", [](const O& o) -> const dqk::IndexVec& { return o.box.upper_by; },
                 "The limit that set each upper bound (-1: none).");
  array_property(out, "G", [](const O& o) -> const dqk::RowMat& { return o.G; },
                 "The limits' rows (p, n).");
  array_property(out, "h", [](const O& o) -> const Vec& { return o.h; }, "(p)");
  // The limit that set each bound, by name ("" where none did).
  auto sources = [](const O& o, const dqk::IndexVec& by) {
    const Index n = by.size();
    nb::tuple names = nb::steal<nb::tuple>(PyTuple_New(n));
    for (Index i = 0; i < n; ++i) {
      const std::int64_t k = by(i);
      nb::str name("");
      if (k >= 0 && o.labels && size_t(k) < o.labels->size()) {
        const std::string& s = (*o.labels)[size_t(k)];
        name = nb::str(s.data(), s.size());
      }
      PyTuple_SET_ITEM(names.ptr(), i, name.release().ptr());
    }
    return names;
  };
  out.def_prop_ro("lower_names", [sources](const O& o) { return sources(o, o.box.lower_by); },
                  "The name of the limit that set each lower bound.")
      .def_prop_ro("upper_names", [sources](const O& o) { return sources(o, o.box.upper_by); },
                   "The name of the limit that set each upper bound.");
  out.def_prop_ro("row_names", [](const O& o) { return names_tuple(o.row_names); })
      .def_prop_ro("row_limit", [](const O& o) { return o.row_limit; },
                   "The limit of each row (indices).");
  array_property(out, "recovering", [](const O& o) -> const dqk::BoolVec& { return o.recovering; },
                 "Ranged variables outside their range.");
  out.def_ro("any_recovering", &O::any_recovering)
      .def_ro("failed_part", &O::failed_part, "The part that gave no piece (-1: none).")
      .def_ro("failed_kind", &O::failed_kind, "'task', 'cost' or 'limit'.")
      .def_ro("failure", &O::failure, "What it could not compute.")
      .def_ro("kinematics_seconds", &O::kinematics_seconds)
      .def_ro("seconds", &O::seconds)
      .def("sigma_min", &O::sigma_min,
           "The smallest singular values of the leader's tool Jacobian and the "
           "follower's (computed when first asked).");
}

// A compiled limit asked on its own: a piece it cannot compute (nonfinite) is raised as
// the library's NonFiniteError, as the step raises it.
template <typename T, typename Cls>
void bind_limit_method(Cls& cls) {
  cls.def(
      "constraint",
      [](const T& self, nb::handle py_ctx) {
        dqk::Constraint c = self.T::constraint(kernel_context(py_ctx));
        if (!c.nonfinite.empty()) {
          nb::object error =
              nb::module_::import_("dualarm_qp.errors").attr("NonFiniteError")(c.nonfinite);
          PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
          throw nb::python_error();
        }
        return c;
      },
      "ctx"_a, "The limit's boxes and rows at the step's context (a StepContext).");
}

void bind_parts(nb::module_& m) {
  nb::class_<dqk::Task, PyTask<dqk::Task>>(
      m, "Task", "A task of the step: equality(ctx) gives its rows A x = b.")
      .def(nb::init<>())
      .def_rw("weight", &dqk::Task::weight,
              "inf: equality rows; a finite weight: the cost term weight |A x - b|^2.");
  nb::class_<dqk::CostTerm, PyCost<dqk::CostTerm>>(
      m, "CostTerm", "A term of the step's cost: quadratic(ctx) gives its weights and centre.")
      .def(nb::init<>());
  nb::class_<dqk::Limit, PyLimit<dqk::Limit>>(
      m, "Limit", "A limit of the step: constraint(ctx) gives its boxes and rows.")
      .def(nb::init<>());

  auto object = nb::class_<dqk::ObjectPathTask, dqk::Task, PyTask<dqk::ObjectPathTask>>(
      m, "ObjectPathTask", "The object follows D(t): six rows (Eq. 14 differentiated).");
  object.def(nb::init<double>(), "gain"_a)
      .def_rw("gain", &dqk::ObjectPathTask::gain, "K_l [1/s].")
      .def(
          "equality",
          [](const dqk::ObjectPathTask& self, nb::handle py_ctx) {
            return self.dqk::ObjectPathTask::equality(kernel_context(py_ctx));
          },
          "ctx"_a);
  auto closure = nb::class_<dqk::GraspClosureTask, dqk::Task, PyTask<dqk::GraspClosureTask>>(
      m, "GraspClosureTask", "The follower's grasp stays closed: six rows (Eqs. 25-27).");
  closure.def(nb::init<double, bool>(), "gain"_a, "exact_orientation"_a)
      .def_rw("gain", &dqk::GraspClosureTask::gain, "K [1/s].")
      .def_rw("exact_orientation", &dqk::GraspClosureTask::exact_orientation)
      .def(
          "equality",
          [](const dqk::GraspClosureTask& self, nb::handle py_ctx) {
            return self.dqk::GraspClosureTask::equality(kernel_context(py_ctx));
          },
          "ctx"_a);

  nb::class_<dqk::CentringCost, dqk::CostTerm, PyCost<dqk::CentringCost>>(
      m, "CentringCost", "Eqs. 37-40: every variable pulled towards the middle of its range.")
      .def(nb::init<Vec, dqk::BoolVec, double>(), "weights"_a, "centred"_a, "shrink"_a)
      .def(
          "quadratic",
          [](const dqk::CentringCost& self, nb::handle py_ctx) {
            return self.dqk::CentringCost::quadratic(kernel_context(py_ctx));
          },
          "ctx"_a);

  auto range = nb::class_<dqk::RangeLimit, dqk::Limit, PyLimit<dqk::RangeLimit>>(
      m, "RangeLimit", "Rate boxes from the position ranges, with recovery (Eqs. 30-36).");
  range.def(nb::init<Vec, dqk::BoolVec>(), "recovery"_a, "off"_a)
      .def_prop_ro("size", [](const dqk::RangeLimit& l) { return l.recovery().size(); },
                   "The variables it is made for.");
  bind_limit_method<dqk::RangeLimit>(range);
  auto speed = nb::class_<dqk::SpeedLimit, dqk::Limit, PyLimit<dqk::SpeedLimit>>(
      m, "SpeedLimit", "The box [-v_max, v_max].");
  speed.def(nb::init<Vec>(), "v_max"_a)
      .def_prop_ro("size", [](const dqk::SpeedLimit& l) { return l.v_max().size(); },
                   "The variables it is made for.");
  bind_limit_method<dqk::SpeedLimit>(speed);
  auto accel = nb::class_<dqk::AccelerationLimit, dqk::Limit, PyLimit<dqk::AccelerationLimit>>(
      m, "AccelerationLimit", "|x - x_applied| <= a dt, cut by the braking bounds.");
  accel.def(nb::init<Vec>(), "delta"_a)
      .def_prop_ro("size", [](const dqk::AccelerationLimit& l) { return l.delta().size(); },
                   "The variables it is made for.");
  bind_limit_method<dqk::AccelerationLimit>(accel);
  auto collision = nb::class_<dqk::CollisionLimit, dqk::Limit, PyLimit<dqk::CollisionLimit>>(
      m, "CollisionLimit", "The velocity damper of a collision scene: one row per near pair.");
  collision.def(
      "__init__",
      [](dqk::CollisionLimit* self, const dqk::DamperScene& damper,
         std::vector<std::string> names, std::string nonfinite) {
        new (self) dqk::CollisionLimit(&damper, std::move(names), std::move(nonfinite));
      },
      "damper"_a, "names"_a, "nonfinite"_a, nb::keep_alive<1, 2>());
  bind_limit_method<dqk::CollisionLimit>(collision);

  nb::class_<dqk::SlidePath>(
      m, "SlidePath",
      "A sliding path as one joint: the hand's pose on the object H(sigma) = P M(rate sigma) C.")
      .def(
          "__init__",
          [](dqk::SlidePath* self, bool revolute, int axis, const dqk::Pose& placement,
             const dqk::Pose& child, double rate) {
            require((axis == 0 || axis == 1) && std::isfinite(rate) && placement.allFinite() &&
                        child.allFinite(),
                    "SlidePath: axis 0 (x) or 1 (y), finite placements and rate");
            new (self) dqk::SlidePath{revolute, axis, placement, child, rate};
          },
          "revolute"_a, "axis"_a, "placement"_a, "child"_a, "rate"_a,
          "revolute: a rotation (else a translation) about or along axis 0 (x) or 1 (y) of "
          "the joint frame; placement P and child C (4, 4) [m]; rate d theta / d sigma.")
      .def("at", &dqk::SlidePath::at, "sigma"_a, "H(sigma) (4, 4) [m], object coordinates.");

  auto torque = nb::class_<dqk::TorqueLimit, dqk::Limit, PyLimit<dqk::TorqueLimit>>(
      m, "TorqueLimit",
      "|tau + dt D x| <= tau_max: both arms' quasi-static torques from the step's context.");
  torque.def(nb::init<dqk::Chain*, int, dqk::Chain*, int, Vec, std::vector<std::string>,
                      std::optional<double>, const Eigen::Vector3d&, const Eigen::Vector3d&,
                      dqk::SlidePath, std::optional<dqk::SlidePath>, double, double, double>(),
             "leader"_a, "leader_tool"_a, "follower"_a, "follower_tool"_a, "tau_max"_a,
             "row_names"_a, "mass"_a.none(), "mass_centre"_a, "gravity"_a, "follower_path"_a,
             "leader_path"_a.none(), "grasp_step"_a, "fallback_length"_a, "rcond_min"_a,
             nb::keep_alive<1, 2>(), nb::keep_alive<1, 4>());
  torque.def_prop_rw("approach", &dqk::TorqueLimit::approach, &dqk::TorqueLimit::set_approach,
                     "time constant [s] with which a torque may approach its limit (each "
                     "sample closes at most dt / approach of a joint's margin; 0: all of it)");
  bind_limit_method<dqk::TorqueLimit>(torque);
}

void bind_loop(nb::module_& m) {
  nb::class_<dqk::Step>(m, "Step", "One step as one loop: the context, then every part in turn.")
      .def(nb::init<Index, Index, std::vector<int>, int, std::vector<int>, Vec, Vec, double,
                    dqk::BoolVec, double>(),
           "n_l"_a, "n_f"_a, "carry_frames"_a, "follower_tool"_a, "cols"_a, "q_min"_a,
           "q_max"_a, "dt"_a, "ranged"_a, "pin_rtol"_a)
      .def("add_task", &dqk::Step::add_task, "task"_a, nb::keep_alive<1, 2>())
      .def("add_cost", &dqk::Step::add_cost, "cost"_a, nb::keep_alive<1, 2>())
      .def("add_limit", &dqk::Step::add_limit, "limit"_a, nb::keep_alive<1, 2>())
      .def("set_labels", &dqk::Step::set_labels, "labels"_a,
           "The limits' names, in the order added (what the bounds' sources are called).")
      .def(
          "add_grasp_line",
          [](dqk::Step& self, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
             const Eigen::Vector3d& r_min, const Eigen::Vector3d& r_max, double sigma_min,
             double sigma_max) {
            self.add_grasp_line(dqk::GraspLine{origin, direction, r_min, r_max, sigma_min,
                                               sigma_max});
          },
          "origin"_a, "direction"_a, "r_min"_a, "r_max"_a, "sigma_min"_a, "sigma_max"_a)
      .def(
          "set_grasp_line",
          [](dqk::Step& self, Index g, const Eigen::Vector3d& origin,
             const Eigen::Vector3d& direction, const Eigen::Vector3d& r_min,
             const Eigen::Vector3d& r_max, double sigma_min, double sigma_max) {
            self.set_grasp_line(g, dqk::GraspLine{origin, direction, r_min, r_max, sigma_min,
                                                  sigma_max});
          },
          "grasp"_a, "origin"_a, "direction"_a, "r_min"_a, "r_max"_a, "sigma_min"_a,
          "sigma_max"_a, "Replace the line of grasp (an index in the grasps' order).")
      .def_prop_ro("n", &dqk::Step::n)
      .def_prop_ro("grasp_lines", &dqk::Step::grasp_lines)
      .def(
          "build",
          [](const dqk::Step& self, dqk::StepOut& out, dqk::Chain& carry,
             const Eigen::VectorXd& q_carry, const Vec& col_rate, dqk::Chain& follower,
             const Eigen::VectorXd& q_f, const dqk::Pose& T_D, const dqk::Vec6& twist,
             const Vec& sigmas, const Vec& grasp_lo, const Vec& grasp_hi, const Vec& x_applied,
             double t, double scale_max, nb::handle user) {
            self.build(out, carry, q_carry, col_rate, follower, q_f, T_D, twist, sigmas,
                       grasp_lo, grasp_hi, x_applied, t, scale_max,
                       user.is_none() ? nullptr : static_cast<void*>(user.ptr()));
          },
          "out"_a, "carry"_a, "q_carry"_a, "col_rate"_a, "follower"_a, "q_f"_a, "T_D"_a,
          "twist"_a, "sigmas"_a, "grasp_lo"_a, "grasp_hi"_a, "x_applied"_a, "t"_a,
          "scale_max"_a, "user"_a.none(),
          "The step at one state into out (a StepOut): the context, then every task, cost "
          "term and limit in the order added; user is what parts written in Python read "
          "(their context) or None.");
}

// A step problem's arrays as StepProblem holds them (float64, C-ordered; anything else is
// refused with a TypeError and converted by the caller first).
using Strict = nb::ndarray<const double, nb::c_contig, nb::device::cpu>;

// StepProblem's checks of its arrays in one pass (dualarm_qp/step/problem.py names the
// codes): 0 when they hold; 1 A is not 2-D; 2 to 7 the shape of b, center, lower, upper,
// weights, G; 8 the length of h; 10 + k a NaN or infinity in the k-th of A, b, weights,
// center, G (a NaN in lower, upper, h: 15 to 17); 20 a diagonal weight not > 0; 21 a
// full weighting matrix that is not symmetric (to 1e-12 relative).
int problem_check(const Strict& A, const Strict& b, const Strict& w, const Strict& c,
                  const Strict& lower, const Strict& upper, const Strict& G, const Strict& h) {
  if (A.ndim() != 2) return 1;
  const size_t m = A.shape(0), n = A.shape(1);
  auto vec = [](const Strict& a, size_t len) { return a.ndim() == 1 && a.shape(0) == len; };
  if (!vec(b, m)) return 2;
  if (!vec(c, n)) return 3;
  if (!vec(lower, n)) return 4;
  if (!vec(upper, n)) return 5;
  const bool diagonal = vec(w, n);
  if (!diagonal && !(w.ndim() == 2 && w.shape(0) == n && w.shape(1) == n)) return 6;
  if (G.ndim() != 2 || (G.size() > 0 && G.shape(1) != n)) return 7;  // no rows: any width
  if (G.size() == 0 && h.size() != 0) return 8;
  if (G.size() > 0 && !vec(h, G.shape(0))) return 8;
  auto finite = [](const Strict& a) {
    const double* d = a.data();
    for (size_t i = 0; i < a.size(); ++i)
      if (!std::isfinite(d[i])) return false;
    return true;
  };
  auto no_nan = [](const Strict& a) {
    const double* d = a.data();
    for (size_t i = 0; i < a.size(); ++i)
      if (std::isnan(d[i])) return false;
    return true;
  };
  const Strict* must_be_finite[] = {&A, &b, &w, &c, &G};
  for (int k = 0; k < 5; ++k)
    if (!finite(*must_be_finite[k])) return 10 + k;
  const Strict* not_nan[] = {&lower, &upper, &h};
  for (int k = 0; k < 3; ++k)
    if (!no_nan(*not_nan[k])) return 15 + k;
  const double* W = w.data();
  if (diagonal) {
    for (size_t i = 0; i < n; ++i)
      if (!(W[i] > 0.0)) return 20;
  } else {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < i; ++j)
        if (std::abs(W[i * n + j] - W[j * n + i]) >
            1e-12 * std::min(std::abs(W[i * n + j]), std::abs(W[j * n + i])))
          return 21;
  }
  return 0;
}

void bind_support(nb::module_& m) {
  auto line = nb::class_<dqk::SupportLine>(
      m, "SupportLine", "A Case 2 support line at one orientation (object coordinates).");
  using L = dqk::SupportLine;
  line.def_ro("held", &L::held, "False: no line with h > 0 inside the box here.")
      .def_ro("sigma_min", &L::sigma_min, "[m]")
      .def_ro("sigma_max", &L::sigma_max, "[m]")
      .def_ro("sigma_inf", &L::sigma_inf, "Where the push is infinite [m].")
      .def_ro("lever", &L::lever, "|a* x c| [N m]: the push is lever / (sigma - sigma_inf).")
      .def("push", &L::push, "sigma"_a, "The push h [N] at sigma [m] (inf at sigma_inf).");
  array_property(line, "gravity", [](const L& l) -> const Eigen::Vector3d& { return l.gravity; },
                 "Gravity in object coordinates [m/s^2].");
  array_property(line, "origin", [](const L& l) -> const Eigen::Vector3d& { return l.origin; },
                 "The line's point at sigma = 0 [m].");
  array_property(line, "direction",
                 [](const L& l) -> const Eigen::Vector3d& { return l.direction; },
                 "The sliding direction s* (unit).");
  array_property(line, "pose0", [](const L& l) -> const dqk::Pose& { return l.pose0; },
                 "The hand's pose at sigma = 0 (4, 4) [m].");
  nb::class_<dqk::SupportPlane>(
      m, "SupportPlane", "A Case 2 support on a plane: its line for any orientation.")
      .def(nb::init<double, const Eigen::Vector3d&, const Eigen::Vector3d&,
                    const Eigen::Vector3d&, const Eigen::Vector3d&, double,
                    const Eigen::Vector3d&, const Eigen::Vector3d&, double>(),
           "mass"_a, "mass_centre"_a, "gravity"_a, "r1"_a, "normal"_a, "offset"_a, "r_min"_a,
           "r_max"_a, "gravity_min"_a)
      .def("line", &dqk::SupportPlane::line, "R_world_object"_a,
           "The support line for the object's orientation (3, 3).")
      .def("__getstate__",
           [](const dqk::SupportPlane& plane) {
             const dqk::SupportPlaneArgs& a = plane.args();
             nb::dict d;
             d["mass"] = a.mass;
             d["mass_centre"] = nb::cast(Eigen::Vector3d(a.mass_centre));
             d["gravity"] = nb::cast(Eigen::Vector3d(a.gravity));
             d["r1"] = nb::cast(Eigen::Vector3d(a.r1));
             d["normal"] = nb::cast(Eigen::Vector3d(a.normal));
             d["offset"] = a.offset;
             d["r_min"] = nb::cast(Eigen::Vector3d(a.r_min));
             d["r_max"] = nb::cast(Eigen::Vector3d(a.r_max));
             d["gravity_min"] = a.gravity_min;
             return d;
           })
      .def("__setstate__", [](dqk::SupportPlane& plane, const nb::dict& d) {
        using V = Eigen::Vector3d;
        new (&plane) dqk::SupportPlane(
            nb::cast<double>(d["mass"]), nb::cast<V>(d["mass_centre"]),
            nb::cast<V>(d["gravity"]), nb::cast<V>(d["r1"]), nb::cast<V>(d["normal"]),
            nb::cast<double>(d["offset"]), nb::cast<V>(d["r_min"]), nb::cast<V>(d["r_max"]),
            nb::cast<double>(d["gravity_min"]));
      });
}

}  // namespace

void bind_step(nb::module_& m) {
  m.def("problem_check", &problem_check, "A"_a.noconvert(), "b"_a.noconvert(),
        "weights"_a.noconvert(), "center"_a.noconvert(), "lower"_a.noconvert(),
        "upper"_a.noconvert(), "G"_a.noconvert(), "h"_a.noconvert(),
        "StepProblem's checks of its arrays in one pass: 0 when they hold, else the code "
        "of the first that fails (src/kernel/bind_step.cpp); float64 C-ordered arrays only.");
  bind_values(m);
  bind_context(m);
  bind_out(m);
  bind_parts(m);
  bind_loop(m);
  bind_support(m);
}

}  // namespace dqk_binding

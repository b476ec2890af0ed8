"""The controller's step in one kernel call: the parts, the collision rows and the exact
solve with its certificate (``kernel.StepParts.prepare_solved``).

The one call must give what the calls one by one give, bit for bit: the build, the
answer, its certificate and every field the controller reports. A limit of Python's
(the torque limit, a user's own) keeps the calls one by one; a compiled row limit's rows
join the others in the limits' order.
"""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest
from test_controller_verify import stepped

from dualarm_qp import Constraint
from dualarm_qp._compiled import kernel
from dualarm_qp.control.controller import _inside
from dualarm_qp.control.lookahead import SKIP_SHARE
from dualarm_qp.errors import NonFiniteError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.solvers import Status, Tolerance, certified, solve_step
from dualarm_qp.solvers.base import DEFAULT_TOLERANCE
from dualarm_qp.solvers.nullspace import NullspaceSolver
from dualarm_qp.solvers.policy import solve_answered
from dualarm_qp.step.limits import CollisionLimit
from dualarm_qp.step.limits.row_form import RowForm, constraints_in_order
from dualarm_qp.step.state import DualArmState

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
#: Compiled limits only (boxes; collision rows with capsules and with boxes), and one
#: with a limit of Python's (the torque rows).
ONE_CALL = ("puma_beam_limits", "panda_pair_accel", "both_sliding_bar", "ur5_pair_collision",
            "puma_beam_pillar", "panda_pair_shelf")
PYTHON_LIMIT = ("ur5_pair_heavy_bar",)


def _experiment(name: str, solver: str = "nullspace"):
    path = CONFIGS / f"{name}.yaml"
    return build_experiment(load_config(path), str(path), solver=solver)


def _states(exp, n: int, seed: int) -> list[tuple[DualArmState, float]]:
    """States along the run (every fifth sample) moved a little, and the scale_max of
    each (some slowed)."""
    rng = np.random.default_rng(seed)
    ctrl = exp.controller()
    dt = ctrl.options.dt
    state = exp.initial
    out = []
    for k in range(5 * n):
        if k % 5 == 0:
            out.append((DualArmState(state.t, state.q_l + rng.normal(0.0, 0.002, state.q_l.shape),
                                     state.q_f + rng.normal(0.0, 0.002, state.q_f.shape),
                                     state.sigma, state.sigma_leader),
                        float(rng.choice([1.0, 0.5]))))
        state = state.advanced(ctrl.step(state), dt)
    return out


def _same(a: object, b: object, what: str) -> None:
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, what
        assert np.array_equal(a, b, equal_nan=True), what
        if a.dtype.kind == "f":
            assert np.array_equal(np.signbit(a), np.signbit(b)), f"{what}: a zero's sign"
    elif isinstance(a, float) and isinstance(b, float) and a != a:
        assert b != b, what
    else:
        assert a == b, what


def _same_solution(a, b) -> None:
    for field in ("x", "status", "objective", "eq_residual", "bound_violation",
                  "active_lower", "active_upper", "message", "scale", "solver",
                  "row_violation", "active_rows"):
        _same(getattr(a, field), getattr(b, field), field)
    assert {k: v for k, v in a.extras.items()} == {k: v for k, v in b.extras.items()}


@pytest.mark.parametrize("name", ONE_CALL + PYTHON_LIMIT)
def test_one_call_gives_what_the_calls_one_by_one_give(name: str) -> None:
    """The build and the certified answer of the one call equal those of the build and
    then the solve, bit for bit, at states near the start (full speed and slowed)."""
    exp = _experiment(name)
    ctrl = exp.controller()
    builder = ctrl.builder
    solver = certified(ctrl.solver, ctrl.tolerance)
    exact = solver.kernel_solve(builder.cost.weights)
    assert isinstance(exact, kernel.ExactSolve)
    for state, scale_max in _states(exp, 6, 5):
        x_applied = np.zeros(builder.n)
        one, solved = builder.build_solved(state, scale_max, None, x_applied, exact)
        apart = builder.build_checked(state, scale_max, None, x_applied)
        assert (solved is None) == (name in PYTHON_LIMIT)
        for field in ("A", "b", "weights", "center", "lower", "upper", "G", "h"):
            _same(getattr(one.problem, field), getattr(apart.problem, field), field)
        assert one.problem.names == apart.problem.names
        for field in ("recovering", "closure_error", "leader_error", "T_f", "J_f"):
            _same(getattr(one, field), getattr(apart, field), field)
        first = (solve_step(solver, one.problem, policy=ctrl.policy, tol=ctrl.tolerance)
                 if solved is None else
                 solve_answered(solver, one.problem, solved, policy=ctrl.policy,
                                tol=ctrl.tolerance))
        second = solve_step(solver, apart.problem, policy=ctrl.policy, tol=ctrl.tolerance)
        _same_solution(first, second)


@pytest.mark.parametrize("name", [*ONE_CALL[:4], "puma_beam_fast"])
def test_a_controller_steps_as_with_the_calls_one_by_one(name: str, monkeypatch) -> None:
    """A whole run of steps through the one call equals the same run with the calls one
    by one (the solver's kernel settings withheld), in every output the rollout records.
    On the fast beam the look-ahead's prediction slows some steps: the kernel's bound must
    skip it exactly where the Python bound does."""
    exp = _experiment(name)
    state = exp.initial
    one = stepped(exp.controller(), state, 60)
    monkeypatch.setattr(type(exp.controller().solver), "kernel_solve",
                        lambda self, weights: None)
    apart = stepped(exp.controller(), state, 60)
    for a, b in zip(one, apart, strict=True):
        for field in ("ql_dot", "qf_dot", "m", "m_leader", "scale", "status", "applied"):
            _same(getattr(a, field), getattr(b, field), field)
        _same_solution(a.solution, b.solution)
        _same(a.build.sigma_min, b.build.sigma_min, "sigma_min")


def test_the_one_call_is_used_when_every_limit_is_compiled() -> None:
    """The controller's build comes with the kernel's answer exactly when the solver
    solves in the kernel and no limit runs in Python; the times split the solve out."""
    exp = _experiment("ur5_pair_collision")
    ctrl = exp.controller()
    calls: list[bool] = []
    cls = type(ctrl.builder)
    real_solved, real_checked = cls.build_solved, cls.build_checked

    def solved_spy(self, *args):
        build, solved = real_solved(self, *args)
        calls.append(solved is not None)
        return build, solved

    def checked_spy(self, *args):
        calls.append(False)
        return real_checked(self, *args)

    cls.build_solved = solved_spy  # type: ignore[method-assign]
    cls.build_checked = checked_spy  # type: ignore[method-assign]
    try:
        out = ctrl.step(exp.initial)
        assert calls == [True]
        assert out.times.solve > 0.0 and out.times.assembly > 0.0
        qp = _experiment("ur5_pair_collision", "qp:daqp").controller()
        qp.step(exp.initial)
        assert calls == [True, False]  # a QP backend solves after the build
        heavy = _experiment("ur5_pair_heavy_bar").controller()
        heavy.step(_experiment("ur5_pair_heavy_bar").initial)
        assert calls == [True, False, False]  # the torque rows are Python's
    finally:
        cls.build_solved = real_solved  # type: ignore[method-assign]
        cls.build_checked = real_checked  # type: ignore[method-assign]


class Wall:
    """A user's own limit: the follower's tool stays below a height (one row)."""

    name = "wall"
    gives_rows = True

    def __init__(self, z: float) -> None:
        self.z = z

    def constraint(self, ctx):
        G = np.zeros((1, ctx.layout.n))
        G[0, ctx.layout.follower] = ctx.J_f[2]
        return Constraint(G=G, h=np.array([(self.z - ctx.T_f[2, 3]) / ctx.dt]),
                          row_names=("wall",))


class OwnCollision(CollisionLimit):
    """A collision limit whose constraint is its own: it runs in Python."""

    def constraint(self, ctx):
        return CollisionLimit.compiled_rows.fget(self).constraint(  # type: ignore[attr-defined]
            *self.compiled_rows.damper.rows(ctx.leader_arm.chain, ctx.follower_arm.chain,
                                            ctx.carry.J_object, ctx.carry.T_object))


def test_compiled_rows_keep_the_limits_order_with_python_limits() -> None:
    """The collision rows (the kernel's) and a user's rows (Python's) stack in the limits'
    order, as each limit's constraint(ctx) gives them, with compiled rows on both sides
    of a Python limit (a second collision limit of the user's, after a wall); a subclass
    that overrides ``constraint`` runs its own and gives the same rows."""
    exp = _experiment("ur5_pair_collision")
    base = exp.controller()
    collision = next(lim for lim in base.builder.limits if isinstance(lim, CollisionLimit))
    z = float(exp.controller().builder.build(exp.initial).T_f[2, 3]) + 0.01
    second = CollisionLimit(collision.scene, collision.layout, *collision._frames)
    ctrl = type(base)(exp.task, base.solver, base.options, limits=[Wall(z), second])
    builder = ctrl.builder
    assert [k for k, _ in builder._row_forms] == [
        k for k, lim in enumerate(builder.limits) if isinstance(lim, CollisionLimit)]
    assert [type(lim) for _, lim in builder._python_limits][-1] is Wall
    between = 0
    for state, scale_max in _states(exp, 5, 9):
        build = builder.build(state, scale_max=scale_max)
        ctx = build.context
        rows = [limit.constraint(ctx) for limit in builder.limits if limit.gives_rows]
        G = np.vstack([c.G for c in rows if c.G is not None and len(c.h)])
        h = np.concatenate([c.h for c in rows if c.h is not None and len(c.h)])
        names = [name for c in rows if c.h is not None and len(c.h) for name in c.row_names]
        _same(build.problem.G, G, "G")
        _same(build.problem.h, h, "h")
        assert list(build.problem.row_names) == names and "wall" in names
        between += names[-1] != "wall"  # the second collision limit's rows after the wall
    assert between  # the case that tells the order from "compiled rows first"
    own = OwnCollision(collision.scene, collision.layout, *collision._frames)
    assert own.compiled_rows is not None
    mixed = type(base)(exp.task, base.solver, base.options, limits=[own])
    assert any(lim is own for _, lim in mixed.builder._python_limits)
    for state, scale_max in _states(exp, 3, 4):
        a = base.builder.build(state, scale_max=scale_max).problem
        b = mixed.builder.build(state, scale_max=scale_max).problem
        # The scene's rows twice: the standard limit's (compiled), then the user's own.
        _same(b.G, np.vstack([a.G, a.G]) if len(a.h) else a.G, "G")


def test_non_finite_compiled_rows_are_refused() -> None:
    """A damper that found a frame or a Jacobian off the finite numbers is an error."""
    form = RowForm(None, ("clearance a-b",), "the collision rows (the test's)")
    with pytest.raises(NonFiniteError, match="the test's"):
        form.constraint(False, np.zeros(0, dtype=np.int64), np.zeros((0, 3)), np.zeros(0))
    c = form.constraint(True, np.array([0]), np.ones((1, 3)), np.array([2.0]))
    assert c.row_names == ("clearance a-b",) and c.h.tolist() == [2.0]
    assert form.constraint(True, np.zeros(0, dtype=np.int64), np.zeros((0, 3)),
                           np.zeros(0)).G is None


def test_the_kernel_settings_are_kept_while_nothing_changes() -> None:
    """``kernel_solve`` makes the kernel's settings once and again only when the weights,
    the tolerances, the claim or the solver's own settings change; a copy makes its own."""
    solver = NullspaceSolver()
    w = np.ones(13)
    first = solver.kernel_solve(w, DEFAULT_TOLERANCE)
    assert solver.kernel_solve(w, DEFAULT_TOLERANCE) is first
    assert solver.kernel_solve(w.copy(), DEFAULT_TOLERANCE) is not first
    changed = [solver.kernel_solve(w, Tolerance(equality=1e-6)),
               solver.kernel_solve(w, DEFAULT_TOLERANCE, claims_bounds=False)]
    solver.feasibility_tol = 1e-9
    changed.append(solver.kernel_solve(w, DEFAULT_TOLERANCE))
    solver.max_iter = 50
    changed.append(solver.kernel_solve(w, DEFAULT_TOLERANCE))
    assert len({id(e) for e in [*changed, first]}) == 5
    for clone in (pickle.loads(pickle.dumps(solver)), copy.deepcopy(solver)):
        assert clone.kernel_solve(w, DEFAULT_TOLERANCE).n == 13
    full = solver.kernel_solve(np.diag(np.arange(1.0, 14.0)), DEFAULT_TOLERANCE)
    assert full.n == 13


def test_the_one_call_refuses_settings_of_another_size() -> None:
    exp = _experiment("puma_beam_limits")
    builder = exp.controller().builder
    wrong = NullspaceSolver().kernel_solve(np.ones(builder.n + 1), DEFAULT_TOLERANCE)
    with pytest.raises(ValueError, match="another size"):
        builder.build_solved(exp.initial, 1.0, None, np.zeros(builder.n), wrong)
    with pytest.raises(ValueError, match="cost"):
        kernel.ExactSolve(np.ones(3), np.ones((2, 2)), np.zeros((0, 0)), 1e-10, -1, True,
                          1e-7, 1e-7)


def test_a_solver_that_does_not_solve_in_the_kernel_takes_no_kernel_answer() -> None:
    exp = _experiment("puma_beam_limits", "qp:daqp")
    ctrl = exp.controller()
    solver = certified(ctrl.solver, ctrl.tolerance)
    assert solver.kernel_solve(ctrl.builder.cost.weights) is None
    build = ctrl.builder.build(exp.initial)
    with pytest.raises(TypeError, match="does not solve in the kernel"):
        solver.read(build.problem, ("an answer", 0.0, None))
    assert solver.solve(build.problem).status is Status.OPTIMAL


@pytest.mark.parametrize("name", ["puma_beam_limits", "panda_pair", "ur5_pair_collision"])
def test_the_kernels_look_ahead_bound_is_the_bound(name: str) -> None:
    """The bound the one call asks for its answer is :meth:`Lookahead.negligible` of the
    answer clipped to the box, at states along the run and at states with a joint exactly
    at its range end (the clip's ties); it is asked only of an optimum."""
    exp = _experiment(name)
    ctrl = exp.controller()
    builder, la, dt = ctrl.builder, ctrl._lookahead, ctrl.options.dt
    exact = certified(ctrl.solver, ctrl.tolerance).kernel_solve(builder.cost.weights)
    bound = la.kernel_bound(dt)
    states = [s for s, _ in _states(exp, 8, 3)]
    lay = builder.layout
    for s in states[:4]:  # a joint of each arm at a range end
        q_l, q_f = s.q_l.copy(), s.q_f.copy()
        q_l[0] = exp.task.leader.q_max[0]
        q_f[1] = exp.task.follower.q_min[1]
        states.append(DualArmState(s.t, q_l, q_f, s.sigma, s.sigma_leader))
    asked = 0
    for s in states:
        for scale_max in (1.0, 0.5, 0.0):
            build, solved = builder.build_solved(s, scale_max, None, np.zeros(lay.n), exact,
                                                 bound)
            answer, _, skip = solved
            if answer[0] != 0:  # not an optimum: nothing asked
                assert skip is None
                continue
            asked += 1
            assert skip == la.negligible(build, _inside(answer[1], build.problem), dt)
            unbounded = builder.build_solved(s, scale_max, None, np.zeros(lay.n), exact)[1]
            assert unbounded[2] is None
    assert asked >= len(states)


def test_the_kernel_bound_follows_the_budget() -> None:
    """A look-ahead whose budget changed gives the kernel a bound of the new budget."""
    exp = _experiment("puma_beam_pillar")
    ctrl = exp.controller()
    la, dt = ctrl._lookahead, ctrl.options.dt
    first = la.kernel_bound(dt)
    assert la.kernel_bound(dt) is first
    builder = ctrl.builder
    exact = certified(ctrl.solver, ctrl.tolerance).kernel_solve(builder.cost.weights)
    state = exp.initial
    la.budget = (la.budget[0] / 1000.0, la.budget[1] / 1000.0)
    second = la.kernel_bound(dt)
    assert second is not first and la.kernel_bound(2 * dt) is not second
    build, (answer, _, skip) = builder.build_solved(state, 1.0, None, np.zeros(builder.n),
                                                    exact, la.kernel_bound(dt))
    assert skip == la.negligible(build, _inside(answer[1], build.problem), dt)
    assert SKIP_SHARE == 0.1


class _Box:
    """A Python limit that gives a box, and may raise."""

    gives_rows = False

    def __init__(self, name: str, fail: bool = False) -> None:
        self.name, self.fail, self.asked = name, fail, 0

    def constraint(self, ctx):
        self.asked += 1
        if self.fail:
            raise NonFiniteError(f"the bounds of {self.name}")
        return Constraint()


def test_constraints_come_in_the_limits_order_each_when_its_turn_comes() -> None:
    """Compiled rows between Python limits: yielded by the limits' index, each constraint
    made when its turn comes, so an error is raised after every constraint before it."""
    form = RowForm(None, ("clearance a-b", "clearance c-d"), "the rows (the test's)")
    good = (True, np.array([1]), np.ones((1, 2)), np.array([3.0]))
    bad = (False, np.zeros(0, dtype=np.int64), np.zeros((0, 2)), np.zeros(0))
    before, after = _Box("before"), _Box("after")
    order = [k for k, _ in constraints_in_order([(1, form), (3, form)], [good, good],
                                                [(0, before), (2, after)], None)]
    assert order == [0, 1, 2, 3] and before.asked == after.asked == 1
    names = [c.row_names for _, c in constraints_in_order([(1, form)], [good], [], None)]
    assert names == [("clearance c-d",)]
    # The compiled rows of index 1 are refused only after limit 0 was asked; limit 2 is
    # never asked.
    first, later = _Box("first"), _Box("later")
    with pytest.raises(NonFiniteError, match="the test's"):
        list(constraints_in_order([(1, form)], [bad], [(0, first), (2, later)], None))
    assert (first.asked, later.asked) == (1, 0)
    # A Python limit that fails before compiled rows stops them from being read.
    failing = _Box("failing", fail=True)
    with pytest.raises(NonFiniteError, match="failing"):
        list(constraints_in_order([(1, form)], [bad], [(0, failing)], None))


def test_the_parts_refuse_row_limits_out_of_order() -> None:
    exp = _experiment("ur5_pair_collision")
    builder = exp.controller().builder
    (k, form), = builder._row_forms
    parts = builder._make_parts()
    with pytest.raises(ValueError, match="increase"):
        parts.add_rows(form.damper, k)  # the same index again
    with pytest.raises(ValueError, match="increase"):
        builder._make_parts().add_rows(form.damper, -1)
    assert parts.row_forms == 1


def test_a_controller_whose_limit_refers_back_to_it_pickles() -> None:
    """The builder's kernel parts are made at their first use after unpickling: a
    collision limit reached first (it refers back to its controller) is remade by then."""
    exp = _experiment("ur5_pair_collision")
    ctrl = exp.controller()
    limit = next(lim for lim in ctrl.builder.limits if isinstance(lim, CollisionLimit))
    limit.owner = ctrl  # type: ignore[attr-defined]
    twin = pickle.loads(pickle.dumps(limit)).owner
    copied = copy.deepcopy(limit).owner
    state = exp.initial
    want = ctrl.step(state)
    for other in (twin, copied):
        got = other.step(state)
        _same_solution(got.solution, want.solution)
        (k, form), = other.builder._row_forms
        assert form.damper is other.builder.limits[k]._damper
        # The weights the kernel settings are kept for stay read-only in a copy.
        assert not other.builder.cost.weights.flags.writeable


class _CertifiesInKernel:
    """A user's solver registered with ``certifies_in_kernel=True`` as the registry
    documented it before the step became one call: ``solve_certified`` only."""

    name = "mine"

    def __init__(self) -> None:
        self._exact = NullspaceSolver()
        self.tol = self._exact.tol

    def solve(self, problem):
        return self._exact.solve(problem)

    def solve_certified(self, problem, tol, claims_bounds=True):
        return self._exact.solve_certified(problem, tol, claims_bounds)


def test_a_solver_that_certifies_in_the_kernel_without_kernel_settings_still_steps(
        monkeypatch) -> None:
    """It has no ``kernel_solve``: its steps take the calls one by one, and give the
    exact solver's answers."""
    import dualarm_qp.solvers.registry as registry_module
    from dualarm_qp.solvers import register

    monkeypatch.setattr(registry_module, "_REGISTRY", dict(registry_module._REGISTRY))
    register("mine", _CertifiesInKernel, description="mine", certifies_in_kernel=True,
             hard_bounds=True)
    mine = _experiment("puma_beam_limits", "mine").controller()
    assert certified(mine.solver, mine.tolerance).kernel_solve(
        mine.builder.cost.weights) is None
    exact = _experiment("puma_beam_limits").controller()
    state = _experiment("puma_beam_limits").initial
    for a, b in zip(stepped(mine, state, 10), stepped(exact, state, 10), strict=True):
        _same(a.solution.x, b.solution.x, "x")
        assert a.status == b.status

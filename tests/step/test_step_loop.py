"""The step's one loop: every part through the same door, in its place.

The kernel's loop (``kernel.Step.build``) asks the tasks, the cost terms and the limits in
turn. The library's own parts are compiled; a part of the user's (any object of the
protocols of ``dualarm_qp.step.parts``, or a Python subclass of a kernel part) is asked
by the same loop, in its place among the others.
"""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp import Constraint
from dualarm_qp._compiled import kernel
from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.solvers import get_solver, solve_step
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.limits import CollisionLimit
from dualarm_qp.step.parts import Equality, Quadratic
from dualarm_qp.step.state import DualArmState

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _experiment(name: str, solver: str = "nullspace"):
    path = CONFIGS / f"{name}.yaml"
    return build_experiment(load_config(path), str(path), solver=solver)


def _states(exp, n: int, seed: int) -> list[DualArmState]:
    """States along the run (every fifth sample), moved a little."""
    rng = np.random.default_rng(seed)
    ctrl = exp.controller()
    state, out = exp.initial, []
    for k in range(5 * n):
        if k % 5 == 0:
            out.append(DualArmState(state.t, state.q_l + rng.normal(0.0, 0.002, state.q_l.shape),
                                    state.q_f + rng.normal(0.0, 0.002, state.q_f.shape),
                                    state.sigma, state.sigma_leader))
        state = state.advanced(ctrl.step(state), ctrl.options.dt)
    return out


class HoldGrasp:
    """An equality task of the user's: the follower's grasp does not slide (m = 0)."""

    name = "hold the grasp"
    weight = None

    def equality(self, ctx):
        A = np.zeros((1, ctx.layout.n))
        A[0, ctx.layout.grasps.start] = 1.0
        return Equality(A, np.zeros(1), ("m = 0",))


class Posture:
    """A weighted task of the user's: the follower's joints move towards a posture."""

    name = "posture"

    def __init__(self, q_star: np.ndarray, gain: float, weight: float) -> None:
        self.q_star, self.gain, self.weight = q_star, gain, weight

    def equality(self, ctx):
        lay = ctx.layout
        A = np.zeros((lay.n_f, lay.n))
        A[:, lay.follower] = np.eye(lay.n_f)
        return Equality(A, self.gain * (self.q_star - ctx.state.q_f))


def test_an_equality_task_of_the_users_is_held_exactly() -> None:
    """m = 0 added to the paper's step: the fixed-grasp method's step (Eqs. 25-28 with
    the grasp held), which the fixed_grasp solver computes on its own."""
    exp = _experiment("puma_beam_limits", "fixed_grasp")
    fixed = exp.controller()
    builder = StepBuilder(exp.task, exp.options, leader_bounds=False, tasks=[HoldGrasp()])
    for state in _states(_experiment("puma_beam_limits"), 4, 2):
        problem = builder.build(state).problem
        assert problem.m == 13 and problem.eq_names[-1] == "m = 0"
        got = solve_step(get_solver("nullspace"), problem, policy="scale")
        want = fixed.step(state)
        assert got.status.usable and abs(got.x[builder.layout.grasps.start]) < 1e-12
        # The same 6 x 6 follower solve as the fixed-grasp method's, up to rounding.
        np.testing.assert_allclose(got.x[builder.layout.follower], want.qf_dot, atol=1e-9)


def test_a_weighted_task_joins_the_cost() -> None:
    """weight |A x - b|^2 summed with the centring: W = S + weight A^T A and the centre
    W^-1 (S c + weight A^T b), computed here independently."""
    exp = _experiment("panda_pair")
    base = StepBuilder(exp.task, exp.options)
    posture = Posture(exp.initial.q_f + 0.1, gain=2.0, weight=3.0)
    builder = StepBuilder(exp.task, exp.options, tasks=[posture])
    for state in _states(exp, 3, 5):
        a, b = base.build(state).problem, builder.build(state).problem
        assert b.m == a.m == 12  # no equality rows: a term of the cost
        lay = builder.layout
        A = np.zeros((lay.n_f, lay.n))
        A[:, lay.follower] = np.eye(lay.n_f)
        r = posture.gain * (posture.q_star - state.q_f)
        W = np.diag(a.weights) + posture.weight * A.T @ A
        c = np.linalg.solve(W, a.weights * a.center + posture.weight * A.T @ r)
        np.testing.assert_allclose(b.weights, W, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(b.center, c, rtol=1e-10, atol=1e-12)
        for name in ("A", "b", "lower", "upper"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_a_cost_term_of_the_users_is_summed_with_the_centring() -> None:
    exp = _experiment("puma_beam_limits")

    class Smallest:
        name = "smallest rates"

        def quadratic(self, ctx):
            return Quadratic(np.full(ctx.layout.n, 0.5), np.zeros(ctx.layout.n))

    base = StepBuilder(exp.task, exp.options)
    both = StepBuilder(exp.task, exp.options, costs=[Smallest()])
    a, b = base.build(exp.initial).problem, both.build(exp.initial).problem
    np.testing.assert_array_equal(b.weights, a.weights + 0.5)
    np.testing.assert_allclose(b.center, a.weights * a.center / (a.weights + 0.5), rtol=1e-15)


class Wall:
    """The follower's tool below a height (a user's rows, in Python)."""

    name = "wall"
    gives_rows = True

    def __init__(self, z: float) -> None:
        self.z = z

    def constraint(self, ctx):
        G = np.zeros((1, ctx.layout.n))
        G[0, ctx.layout.follower] = ctx.J_f[2]
        return Constraint(G=G, h=np.array([(self.z - ctx.T_f[2, 3]) / ctx.dt]),
                          row_names=("wall",))


def test_compiled_rows_and_a_users_rows_keep_the_limits_order() -> None:
    """The collision rows (compiled) and a user's rows (Python) stack in the limits'
    order, with compiled rows on both sides of the Python limit."""
    exp = _experiment("ur5_pair_collision")
    base = exp.controller()
    collision = next(lim for lim in base.builder.limits if isinstance(lim, CollisionLimit))
    z = float(base.builder.build(exp.initial).T_f[2, 3]) + 0.01
    second = CollisionLimit(collision.scene, collision.layout, *collision._frames)
    builder = StepBuilder(exp.task, exp.options, limits=[Wall(z), second])
    between = 0
    for state in _states(exp, 5, 9):
        build = builder.build(state)
        ctx = build.context
        rows = [limit.constraint(ctx) for limit in builder.limits if limit.gives_rows]
        G = np.vstack([c.G for c in rows if c.G is not None and len(c.h)])
        h = np.concatenate([c.h for c in rows if c.h is not None and len(c.h)])
        names = [name for c in rows if c.h is not None and len(c.h) for name in c.row_names]
        np.testing.assert_array_equal(build.problem.G, G)
        np.testing.assert_array_equal(build.problem.h, h)
        assert list(build.problem.row_names) == names and "wall" in names
        between += names[-1] != "wall"  # the second collision limit's rows after the wall
    assert between  # the case that tells the order from "compiled rows first"


class _Asked:
    """A box limit that counts how often it is asked, and fails if told to."""

    gives_rows = False

    def __init__(self, name: str, fail: bool = False) -> None:
        self.name, self.fail, self.asked = name, fail, 0

    def constraint(self, ctx):
        self.asked += 1
        if self.fail:
            raise NonFiniteError(f"the bounds of {self.name}")
        return Constraint()


def test_an_error_stops_the_loop_at_its_part() -> None:
    """The parts before it were asked; the ones after it never are."""
    exp = _experiment("puma_beam_limits")
    before, failing, after = _Asked("before"), _Asked("failing", fail=True), _Asked("after")
    builder = StepBuilder(exp.task, exp.options, limits=[before, failing, after])
    with pytest.raises(NonFiniteError, match="failing"):
        builder.build(exp.initial)
    assert (before.asked, failing.asked, after.asked) == (1, 1, 0)


def test_what_a_users_part_gives_is_checked_and_named() -> None:
    exp = _experiment("puma_beam_limits")
    n = StepBuilder(exp.task, exp.options).n

    class Bad:
        gives_rows = True

        def __init__(self, name, c):
            self.name, self.c = name, c

        def constraint(self, ctx):
            return self.c

    cases = [(Constraint(lower=np.zeros(3)), ShapeError, "lower bounds of the limit 'a'"),
             (Constraint(G=np.zeros((1, 3)), h=np.zeros(1)), ShapeError, "rows of the limit 'a'"),
             (Constraint(G=np.full((1, n), np.nan), h=np.zeros(1)), NonFiniteError,
              "rows of the limit 'a'"),
             (Constraint(lower=np.full(n, np.nan)), NonFiniteError, "bounds of the limit 'a'"),
             (Constraint(upper=["x"] * n), InvalidInputError, "upper bounds of the limit 'a'")]
    for c, error, match in cases:
        builder = StepBuilder(exp.task, exp.options, limits=[Bad("a", c)])
        with pytest.raises(error, match=match):
            builder.build(exp.initial)

    class BadTask:
        name = "t"
        weight = None

        def equality(self, ctx):
            return Equality(np.zeros((2, 3)), np.zeros(2))

    with pytest.raises(ShapeError, match="rows of the task 't'"):
        StepBuilder(exp.task, exp.options, tasks=[BadTask()]).build(exp.initial)
    BadTask.weight = -1.0
    with pytest.raises(InvalidInputError, match="weight"):
        StepBuilder(exp.task, exp.options, tasks=[BadTask()])
    for thing, kind in ((object(), "limits"), (object(), "tasks"), (object(), "costs")):
        with pytest.raises(InvalidInputError, match="is not a"):
            StepBuilder(exp.task, exp.options, **{kind: [thing]})


def test_a_python_subclass_of_the_kernels_limit_is_asked_by_the_loop() -> None:
    """The kernel's base, subclassed in Python: the loop calls its method (trampoline)."""
    exp = _experiment("puma_beam_limits")

    class Cap(kernel.Limit):
        name = "cap"
        gives_rows = False

        def __init__(self):
            super().__init__()
            self.asked = 0

        def constraint(self, ctx):
            self.asked += 1
            n = ctx.layout.n
            return Constraint(lower=np.full(n, -0.01), upper=np.full(n, 0.01))

    cap = Cap()
    problem = StepBuilder(exp.task, exp.options, limits=[cap]).build(exp.initial).problem
    assert cap.asked == 1 and np.all(problem.upper <= 0.01) and "cap" in problem.upper_by


def test_a_controller_whose_limit_refers_back_to_it_pickles() -> None:
    exp = _experiment("ur5_pair_collision")
    ctrl = exp.controller()
    limit = next(lim for lim in ctrl.builder.limits if isinstance(lim, CollisionLimit))
    limit.owner = ctrl  # type: ignore[attr-defined]
    state = exp.initial
    want = ctrl.step(state)
    for other in (pickle.loads(pickle.dumps(ctrl)), copy.deepcopy(ctrl)):
        got = other.step(state)
        np.testing.assert_array_equal(got.solution.x, want.solution.x)
        assert got.status == want.status
        assert not other.builder.cost.weights.flags.writeable

"""Build the one step problem of both arms and every sliding grasp by stacking its parts.

Each step the builder computes the kinematics once (both arms and the carried object,
:class:`~dualarm_qp.task.carry.CarryModel`, where every sliding grasp is a joint; a Case
2 support first places its line from the object's pose, then the step's kinematics
follow), puts them in the step's context (:class:`~dualarm_qp.step.context.StepContext`)
and stacks the step's parts (:mod:`dualarm_qp.step.parts`):

* the equality tasks, in this order: the object follows ``D(t)``, the grasp stays
  closed (:mod:`.tasks`, Eqs. 14 and 25-27);
* the cost: the paper's centring (:mod:`.cost`, Eqs. 37-40);
* the limits: joint and grasp ranges (Eqs. 30-36, with recovery), joint and grasp
  speeds, accelerations when asked for (:mod:`.limits`), then any limit of the user's.
  Their boxes are intersected (the largest lower, the smallest upper bound; each bound
  remembers the limit that set it, for messages) and their rows stacked.

The standard parts are computed by one kernel call per step (``kernel.StepParts``,
``src/kernel/step_parts.cpp``): the kinematics, the rates to the range ends (a straight
grasp's from its line, :attr:`~dualarm_qp.task.surfaces.GraspSurface.line`, without a
Case 2 support; another grasp's from its surface, through the same compiled Eqs.
30-31), the equality (what :meth:`.tasks.CarryTasks.equality` gives), the centres (what
:meth:`.cost.CentringCost.quadratic` gives), the boxes of the limits that declare a
compiled form (:mod:`.limits.box_form`: ranges, speeds, accelerations) and their
intersection, the rows of the limits that declare compiled rows
(:mod:`.limits.row_form`: the collision limit's damper), and the variables that recover.
The forms and the straight grasps' lines, boxes and ranges are read when the builder is
made, as the options are: a limit, a surface or a setting changed afterwards needs a new
builder. The other limits (the torque limit, a user's own) run their ``constraint(ctx)``
on the context each step. Given the exact solver's kernel settings and no such limit,
the same call also solves and certifies the step (:meth:`StepBuilder.build_solved`).
Both arms' smallest singular values are computed when first read
(:attr:`.context.StepContext.sigma_min`).

The decision vector's slices are the :class:`~dualarm_qp.step.layout.Layout`'s. ``s``
is the task scale of the infeasible-step policy (:func:`~dualarm_qp.solvers.solve_step`),
which multiplies the whole right-hand side.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .._frozen import made
from .._remade import KernelHolder
from .._validate import as_number
from ..errors import InvalidInputError, NonFiniteError, ShapeError, SupportLostError
from ..task.carry import CarryKinematics, CarryModel
from ..task.contact import SupportContact
from ..task.scene import DualArmTask
from ..task.support import SupportLine
from ..task.surfaces import GraspSurface
from .bounds import grasp_rates
from .built import StepBuild, smallest_singular_value
from .context import ArmKinematics, StepContext
from .cost import CentringCost
from .kinematics import both_arms
from .layout import Layout
from .limits import LimitSetup, standard_limits
from .limits.box_form import RANGE, compiled_form
from .limits.row_form import RowForm, compiled_rows, constraints_in_order
from .options import StepOptions
from .parts import Limit
from .problem import StepProblem
from .stacking import PIN_RTOL, LimitStack, checked_rates
from .state import DualArmState
from .tasks import CarryTasks

FloatArray = NDArray[np.float64]


class StepBuilder(KernelHolder):
    """Builds the step problems of one task under fixed options.

    What does not change from step to step (the layout, the weights, the limits, the
    carried-object model) is prepared once here; :meth:`build` does the per-step work:
    both arms' kinematics (once), the context, the stacking of the parts.

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surfaces and path.
    options : StepOptions
        Weights, limits and gains.
    leader_gain : float, optional
        Feedback gain ``K_l`` [1/s] of the object's tracking of ``D(t)``; default
        ``options.leader_gain``.
    leader_bounds : bool
        Impose the leader's joint ranges and speed and acceleration limits (hard-limit
        solvers); False leaves its box open (the paper's methods, which ignore limits by
        design).
    limits : sequence of Limit
        Limits of the user's, stacked after the standard ones (e.g. a wall the
        follower's tool may not cross, ``examples/custom_limit.py``).

    Raises
    ------
    InvalidInputError
        A weight vector of the wrong length, or a limit that is not a
        :class:`~dualarm_qp.step.parts.Limit`.
    ShapeError
        A limit's compiled box form does not hold one number per variable.
    """

    # The kernel's objects: made again when unpickled (a controller pickles whole).
    _kernel_attributes = ("_parts", "_leader_arm", "_follower_arm", "_row_forms")

    def __init__(self, task: DualArmTask, options: StepOptions, *,
                 leader_gain: float | None = None, leader_bounds: bool = True,
                 limits: Sequence[Limit] = ()) -> None:
        leader, follower = task.leader, task.follower
        n_l, n_f = leader.n, follower.n
        for w, n, who in ((options.joint_weights, n_f, "joint_weights (follower)"),
                          (options.leader_joint_weights, n_l, "leader_joint_weights")):
            if w is not None and w.shape[0] not in (1, n):
                raise InvalidInputError(f"{who} has {w.shape[0]} entries, the arm has {n}")
        for limit in limits:
            if not (isinstance(getattr(limit, "name", None), str)
                    and callable(getattr(limit, "constraint", None))
                    and isinstance(getattr(limit, "gives_rows", None), bool)):
                raise InvalidInputError(
                    f"{limit!r} is not a limit: a limit has a str 'name', a bool "
                    "'gives_rows' and a method 'constraint(ctx)' (dualarm_qp.step.parts)")
        self.task = task
        self.options = options
        self.carry = CarryModel(leader, task.surface, task.H1, task.leader_surface)
        self.layout = Layout(n_l, n_f, self.carry.n_grasp)
        self.carry_tasks = CarryTasks(
            float(options.leader_gain or 0.0) if leader_gain is None else leader_gain,
            float(options.correction_gain or 0.0), exact_orientation=options.exact_orientation)
        self.cost = CentringCost(self.layout, options, leader_ranges=leader_bounds)
        setup = LimitSetup(task, options, self.layout, leader_bounds)
        self.limits: tuple[Limit, ...] = (*standard_limits(setup), *limits)
        lay = self.layout
        ranged = np.ones(lay.n, dtype=bool)
        ranged[lay.leader] = leader_bounds
        self._ranged = ranged
        self._q_min = np.r_[leader.q_min, follower.q_min]
        self._q_max = np.r_[leader.q_max, follower.q_max]
        v = np.full(lay.n, np.inf)
        if options.velocity_limits:
            v[lay.follower] = follower.qd_max
            v[lay.grasps] = options.grasp_speed_max
            if leader_bounds:
                v[lay.leader] = leader.qd_max
        self._v_max = v
        self._surfaces: list[GraspSurface] = [task.surface] + (
            [] if task.leader_surface is None else [task.leader_surface])
        self._contact = task.contact
        self._zeros = np.zeros(lay.n)
        self._no_grasps = np.zeros(0)
        self._labels = tuple(limit.name for limit in self.limits)
        # The limits whose box (a compiled form, .limits.box_form) or rows (.limits.row_form)
        # the kernel computes with the standard parts, and the others, whose
        # constraint(ctx) runs here.
        forms = [compiled_form(limit) for limit in self.limits]
        row_forms = [None if form is not None else compiled_rows(limit)
                     for form, limit in zip(forms, self.limits, strict=True)]
        self._forms = [(k, form) for k, form in enumerate(forms) if form is not None]
        self._row_ids = [k for k, form in enumerate(row_forms) if form is not None]
        self._python_limits = tuple((k, limit) for k, limit in enumerate(self.limits)
                                    if forms[k] is None and row_forms[k] is None)
        self._stack = LimitStack(self._labels, lay.n, [k for k, _ in self._forms])
        self._remake()
        self._kernel_parts()  # made now: a bad compiled form is refused here

    def _remake(self) -> None:
        """Make both arms' views of the kernel's chains; the parts at their first use.

        The kernel's parts hold the compiled row limits' dampers, kernel objects of the
        limits: after unpickling, a limit may be remade after this builder (a limit that
        refers back to its controller), so the parts are made when a step first needs
        them (:meth:`_kernel_parts`).
        """
        follower = self.task.follower
        self._leader_arm = ArmKinematics(self.carry.model, self.carry.data, self.layout.n_l,
                                         self.carry.chain)
        self._follower_arm = ArmKinematics(follower.model, follower.data, self.layout.n_f,
                                           follower.chain)
        self._parts: kernel.StepParts | None = None
        self._row_forms: list[tuple[int, RowForm]] = []

    def _kernel_parts(self) -> kernel.StepParts:
        """Return the kernel's standard parts of this builder's steps (``step_parts.cpp``).

        Made at the first call (the constructor's) and after unpickling: the compiled row
        limits' forms are read from the limits then.

        Raises
        ------
        ShapeError
            A limit's compiled form does not hold one number per variable.
        """
        parts = self._parts
        if parts is None:
            self._row_forms = [(k, self.limits[k].compiled_rows)  # type: ignore[attr-defined]
                               for k in self._row_ids]
            parts = self._parts = self._make_parts()
        return parts

    def _make_parts(self) -> kernel.StepParts:
        """Return new kernel parts of this builder's steps (:meth:`_kernel_parts`'s).

        Raises
        ------
        ShapeError
            A limit's compiled form does not hold one number per variable.
        """
        lay, carry = self.layout, self.carry
        parts = kernel.StepParts(lay.n_l, lay.n_f, carry.frames, self.task.follower.tool_frame_id,
                                 carry.columns[0], self._q_min, self._q_max, self.options.dt,
                                 self.cost.centred, self.cost.shrink, self._ranged, PIN_RTOL)
        for k, form in self._forms:
            checked = (form.p, form.off) if form.kind == RANGE else (form.p,)
            for values in checked:
                if values.shape != (lay.n,):
                    raise ShapeError(f"the compiled box of the limit '{self._labels[k]}'",
                                     (lay.n,), values.shape)
            parts.add_form(form.kind, form.p, form.off, k)
        for k, row_form in self._row_forms:
            parts.add_rows(row_form.damper, k)
        # Straight grasps (and no Case 2 support, whose line moves): the kernel computes
        # their rates to the range ends from the grasp coordinates.
        lines = [line for line in (surf.line for surf in self._surfaces) if line is not None]
        if self._contact is None and len(lines) == len(self._surfaces):
            for surf, line in zip(self._surfaces, lines, strict=True):
                parts.add_grasp_line(*line, surf.r_min, surf.r_max, surf.sigma_min,
                                     surf.sigma_max)
        return parts

    # -- what the controller and the reports read -----------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        """Names of the decision variables (the layout's)."""
        return self.layout.names

    @property
    def n_l(self) -> int:
        """Leader joints."""
        return self.layout.n_l

    @property
    def n_f(self) -> int:
        """Follower joints."""
        return self.layout.n_f

    @property
    def n_grasp(self) -> int:
        """Sliding grasps."""
        return self.layout.n_grasp

    @property
    def n(self) -> int:
        """Length of the decision vector."""
        return self.layout.n

    @property
    def speed_limits(self) -> FloatArray:
        """Speed limit of every decision variable [rad/s, m/s] (``inf``: none imposed)."""
        return self._v_max

    @property
    def leader_gain(self) -> float:
        """Feedback gain ``K_l`` [1/s] of the object's tracking of ``D(t)``."""
        return self.carry_tasks.leader_gain

    @leader_gain.setter
    def leader_gain(self, value: float) -> None:
        self.carry_tasks.leader_gain = float(value)

    @property
    def solves_in_one_call(self) -> bool:
        """Whether a step can be built and solved in one kernel call (no limit of Python's)."""
        return not self._python_limits

    @property
    def row_limits(self) -> tuple[str, ...]:
        """Names of the limits that give general rows (what the pairing check reads)."""
        return tuple(limit.name for limit in self.limits if limit.gives_rows)

    # -- the step -----------------------------------------------------------------------
    def context(self, state: DualArmState, *, scale_max: float = 1.0,
                x_applied: FloatArray | None = None) -> tuple[StepContext, float]:
        """Return the step's context at ``state`` (the kinematics, once) and a support's push.

        Returns
        -------
        context : StepContext
        support_force : float
            Follower push ``h`` [N] of a Case 2 support (NaN for a grasp).
        """
        start = time.perf_counter()
        q_l, q_f, sigmas, x0 = self._checked(state, x_applied)
        parts, _, support_force, _ = self._prepared(state, q_l, q_f, sigmas, scale_max, x0,
                                                    start)
        positions = self.layout.join(q_l, q_f, state.sigma, state.sigma_leader)
        return self._context(state, scale_max, positions, tuple(self._surfaces), x0, parts,
                             None), support_force

    def _checked(self, state: DualArmState, x_applied: object
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Return the state's joints, grasp coordinates and ``x_applied`` checked.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a sliding grasp's coordinate
            that is not a finite number, ``x_applied`` not ``n`` finite numbers.
        """
        q_l = self.task.leader.check_q(state.q_l, "q_l")
        q_f = self.task.follower.check_q(state.q_f, "q_f")
        sigmas = self._sigmas(state.sigma, state.sigma_leader)
        x0 = self._zeros if x_applied is None else checked_rates(x_applied, "x_applied",
                                                                 self.layout.n)
        return q_l, q_f, sigmas, x0

    def _prepared(self, state: DualArmState, q_l: FloatArray, q_f: FloatArray,
                  sigmas: FloatArray, scale_max: float, x0: FloatArray, start: float,
                  exact: Any = None, bound: Any = None
                  ) -> tuple[tuple[Any, ...], float, float, Any]:
        """Return the kernel's parts at ``state``, their seconds, a support's push, a solve.

        One kernel call (``kernel.StepParts.prepare``): both arms' kinematics, the rates
        to the range ends, the equality, the centres, the compiled limits' boxes and rows. The
        seconds are those of the kinematics from ``start`` (the kernel's own, last in
        its tuple, and the Python before the call). With ``exact`` (the kernel's settings
        of the exact solve, ``kernel.ExactSolve``) and no limit of Python's, the same
        call also solves and certifies the step (``kernel.StepParts.prepare_solved``):
        its answer, seconds and the look-ahead ``bound``'s verdict on the answer clipped
        to the box, or None where the kernel did not solve.
        """
        sigma, sigma_l = state.sigma, state.sigma_leader
        follower, trajectory, carry = self.task.follower, self.task.trajectory, self.carry
        T_D = trajectory.pose(state.t)
        support_force = math.nan
        if self._contact is not None:
            # The support line follows the object's orientation at this state: placed
            # first, from the kinematics at the current placement.
            kin = both_arms(carry, follower, q_l, q_f, sigma, sigma_l, T_D).carry
            support_force = self._support(self._contact, kin, state)
        kernel_parts = self._parts
        if kernel_parts is None:  # after unpickling: made at the first step
            kernel_parts = self._kernel_parts()
        if kernel_parts.grasp_lines:  # the kernel computes the grasps' rates itself
            grasp_lo = grasp_hi = self._no_grasps
        else:
            grasp_lo, grasp_hi = self._grasp_rates(sigmas)
        tasks = self.carry_tasks
        q_carry, twist = carry.configuration(q_l, sigma, sigma_l), trajectory.twist(state.t)
        called = time.perf_counter()
        solved = None
        if exact is None or self._python_limits:
            parts = kernel_parts.prepare(
                carry.chain, q_carry, carry.columns[1], follower.chain, q_f, T_D, twist,
                sigmas, grasp_lo, grasp_hi, x0, scale_max, tasks.leader_gain,
                tasks.correction_gain, tasks.exact_orientation)
        else:
            parts, solved = kernel_parts.prepare_solved(
                carry.chain, q_carry, carry.columns[1], follower.chain, q_f, T_D, twist,
                sigmas, grasp_lo, grasp_hi, x0, scale_max, tasks.leader_gain,
                tasks.correction_gain, tasks.exact_orientation, exact, bound)
        return parts, called - start + parts[-1], support_force, solved

    def _context(self, state: DualArmState, scale_max: float, positions: FloatArray,
                 surfaces: tuple[GraspSurface, ...], x0: FloatArray, parts: tuple[Any, ...],
                 carry: CarryKinematics | None,
                 sigma_min: tuple[float, float] | None = None) -> StepContext:
        """Return the step's context from the kernel's parts (``carry``: made already).

        Everything it holds was taken at the step (the kernel's arrays are the step's
        own, the positions a copy, the surfaces those of the step: a Case 2 support's
        line moves), so a context made later reads the same.
        """
        T, J_tool, J_object, J_target, J_f, e, lo, hi = parts[:8]
        if carry is None:
            carry = CarryKinematics(T[0:4], J_tool, T[4:8], J_object, T[8:12], J_target)
        ctx = StepContext(state, self.task, self.layout, self.options.dt, scale_max, carry,
                          T[12:16], J_f, surfaces, positions, lo, hi, x0,
                          e[:6], e[6:], self._leader_arm, self._follower_arm)
        if sigma_min is not None:  # read from the build first: computed once
            object.__setattr__(ctx, "_sigma_min", sigma_min)
        return ctx

    def _sigmas(self, sigma: float, sigma_l: float) -> FloatArray:
        """Return the grasp coordinates, the follower's first [m], shape (n_grasp,).

        Raises
        ------
        InvalidInputError, NonFiniteError
            A sliding grasp's coordinate is not a finite number (what the grasp's
            surface refuses; a straight grasp's rates are the kernel's).
        """
        values = (sigma, sigma_l)[:self.layout.n_grasp]
        if all(type(v) is float for v in values) and math.isfinite(sum(values)):
            return np.array(values)  # the common case, checked cheaply
        return np.array([as_number(value, name) for value, name in
                         zip(values, ("sigma", "sigma_leader"), strict=False)])

    def _grasp_rates(self, sigmas: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Return the grasps' rates to the ends of their ranges (Eqs. 30-33) [m/s]."""
        n_grasp, dt = self.layout.n_grasp, self.options.dt
        lo = np.empty(n_grasp)
        hi = np.empty(n_grasp)
        for i, (surf, s) in enumerate(zip(self._surfaces, sigmas.tolist(), strict=True)):
            lo[i], hi[i] = grasp_rates(surf, s, dt)
        return lo, hi

    def build(self, state: DualArmState, *, scale_max: float = 1.0,
              x_prev: FloatArray | None = None,
              x_applied: FloatArray | None = None) -> StepBuild:
        """Build the step problem for ``state``.

        Parameters
        ----------
        state : DualArmState
            Joints [rad], grasp coordinates [m] and path time [s].
        scale_max : float
            Share in [0, 1] of the path's feed-forward twist (1: full speed).
        x_prev : ndarray, optional
            Previous step's solution (warm start only).
        x_applied : ndarray, optional
            The last command applied [rad/s, m/s] (acceleration limits); default zero
            (at rest).

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a sliding grasp's coordinate
            that is not a finite number, ``x_prev`` or ``x_applied`` not ``n`` numbers.
        NonFiniteError
            The problem would hold NaN or infinity.
        InvalidInputError
            A supporting follower (Case 2) would have to pull at this state.
        """
        start = time.perf_counter()
        q_l, q_f, sigmas, x0 = self._checked(state, x_applied)
        if x_prev is not None:
            x_prev = checked_rates(x_prev, "x_prev", self.layout.n, finite=False)
        return self._build(state, q_l, q_f, sigmas, scale_max, x_prev, x0, start)[0]

    def build_checked(self, state: DualArmState, scale_max: float,
                      x_prev: FloatArray | None, x_applied: FloatArray) -> StepBuild:
        """:meth:`build` for a caller that checked its inputs (the controller's step).

        Nothing is checked again: ``state.q_l`` and ``state.q_f`` are finite float64
        arrays of the arms' lengths, ``state.sigma`` and ``state.sigma_leader`` finite
        Python floats, ``x_prev`` None or a float64 array of ``n`` numbers and
        ``x_applied`` one of ``n`` finite numbers (the controller's own answers).
        """
        start = time.perf_counter()
        sigmas = np.array((state.sigma, state.sigma_leader)[:self.layout.n_grasp])
        return self._build(state, state.q_l, state.q_f, sigmas, scale_max, x_prev,
                           x_applied, start)[0]

    def build_solved(self, state: DualArmState, scale_max: float,
                     x_prev: FloatArray | None, x_applied: FloatArray, exact: Any,
                     bound: Any = None) -> tuple[StepBuild, Any]:
        """:meth:`build_checked` and the step solved in the same kernel call.

        ``exact`` is the exact solver's kernel settings
        (:meth:`~dualarm_qp.solvers.registry.CertifiedSolver.kernel_solve`); ``bound``
        the look-ahead's (:meth:`~dualarm_qp.control.lookahead.Lookahead.kernel_bound`)
        or None. Returns the build and the kernel's answer to it
        (:func:`~dualarm_qp.solvers.policy.solve_answered`'s ``answer``: the certified
        solve, its seconds, then with ``bound`` whether the look-ahead's prediction may
        be skipped for the answer clipped to the box), or None where the kernel did not
        solve: a limit runs in Python (:attr:`solves_in_one_call` is False), or the
        step is refused (the errors :meth:`build` raises).
        """
        start = time.perf_counter()
        sigmas = np.array((state.sigma, state.sigma_leader)[:self.layout.n_grasp])
        return self._build(state, state.q_l, state.q_f, sigmas, scale_max, x_prev,
                           x_applied, start, exact, bound)

    def _build(self, state: DualArmState, q_l: FloatArray, q_f: FloatArray,
               sigmas: FloatArray, scale_max: float, x_prev: FloatArray | None,
               x0: FloatArray, t0: float, exact: Any = None, bound: Any = None
               ) -> tuple[StepBuild, Any]:
        """Build the step from checked inputs (``t0``: when the build started).

        Returns the build and the kernel's answer to it when ``exact`` solved it in the
        same call (else None).
        """
        parts, kinematics_time, support_force, solved = self._prepared(
            state, q_l, q_f, sigmas, scale_max, x0, t0, exact, bound)
        (T, J_tool, J_object, J_target, J_f, e, _, _, A, b, finite, center, compiled_lo,
         compiled_hi, box, recovering, recovers, kernel_rows, _) = parts
        if not finite:
            raise NonFiniteError("the step's equality (D(t), its twist or the arms' poses)")
        carry = made(CarryKinematics, {  # the kernel's arrays: made unchecked
            "T_tool": T[0:4], "J_tool": J_tool, "T_object": T[4:8], "J_object": J_object,
            "T_target": T[8:12], "J_target": J_target})
        stack = self._stack
        lowers: list[FloatArray] = []
        lower_ids: list[int] = []
        uppers: list[FloatArray] = []
        upper_ids: list[int] = []
        G_parts: list[FloatArray] = []
        h_parts: list[FloatArray] = []
        row_ids: list[int] = []
        row_names: list[str] = []
        context: StepContext | Callable[[tuple[float, float] | None], StepContext]
        # Taken now: the caller may move its joints in place, and a support's line moves.
        positions = self.layout.join(q_l, q_f, state.sigma, state.sigma_leader)
        surfaces = tuple(self._surfaces)
        # The limits in the step's order: the compiled row limits' rows, which the kernel
        # computed with the parts, between the others' constraint(ctx).
        ctx: StepContext | None = None
        if self._python_limits:
            ctx = context = self._context(state, scale_max, positions, surfaces, x0, parts,
                                          carry)
        else:  # nothing read it: made if and when someone does
            context = partial(self._context, state, scale_max, positions, surfaces, x0, parts,
                              carry)
        constraints = (constraints_in_order(self._row_forms, kernel_rows, self._python_limits,
                                            ctx) if kernel_rows or ctx is not None else ())
        for k, c in constraints:
            if c.lower is not None:
                lowers.append(c.lower)
                lower_ids.append(k)
            if c.upper is not None:
                uppers.append(c.upper)
                upper_ids.append(k)
            if c.G is not None and c.h is not None and len(c.h):
                # The kernel's rows (a compiled row limit's) are float arrays of the right
                # shapes and finite (else refused above): only the others are checked.
                G_k, h_k = ((c.G, c.h) if k in self._row_ids
                            else stack.checked_rows(k, c.G, c.h, c.row_names))
                G_parts.append(G_k)
                h_parts.append(h_k)
                row_ids.append(k)
                row_names += list(c.row_names) or [f"{self._labels[k]} {i + 1}"
                                                   for i in range(len(h_k))]
        lower, upper, lower_by, upper_by = stack.box(compiled_lo, compiled_hi, box,
                                                     lowers, lower_ids, uppers, upper_ids)
        G, h = stack.rows(G_parts, h_parts, row_ids,
                          all_checked=not self._python_limits)
        # The build's seconds, less a solve made in the same call (the solve's own).
        t2 = time.perf_counter() - (0.0 if solved is None else solved[1])
        # Every part was checked where it was made (the limits' bounds and rows here):
        # the problem is assembled without a second check.
        problem = StepProblem.assembled(
            A=A, b=b, weights=self.cost.weights, center=center, lower=lower, upper=upper,
            G=G, h=h, n_grasp=self.layout.n_grasp, x_prev=x_prev, names=self.layout.names,
            row_names=tuple(row_names), eq_names=CarryTasks.row_names, lower_by=lower_by,
            upper_by=upper_by, build_time=t2 - t0)
        build = made(StepBuild, {
            "problem": problem, "recovering": recovering, "closure_error": e[6:],
            "leader_error": e[:6], "carry": carry, "T_f": T[12:16], "J_f": J_f,
            "kinematics_time": kinematics_time, "assembly_time": t2 - t0 - kinematics_time,
            "support_force": support_force, "_context": context})
        # The kernel's flag of this very array: not an init field, so that a build made
        # again with another array (dataclasses.replace) computes its own.
        object.__setattr__(build, "_recovers", recovers)
        return build, solved

    def _support(self, contact: SupportContact, kin: CarryKinematics, state: DualArmState
                 ) -> float:
        """Case 2: put the follower's path on the support line of this step; its push.

        The line is computed for the object's orientation at ``state`` and frozen for
        the step (as the paper freezes the grasp frame, Sec. 3.3). When it moved, the
        follower's grasp joint is re-placed (the step's kinematics come after); the
        target then jumps by the line's motion at ``sigma``, which the closure feedback
        removes. The grasp bounds of the step are the line's (``h > 0``).

        Returns
        -------
        float
            The follower's push ``h`` [N] at ``sigma``.

        Raises
        ------
        InvalidInputError
            No pushing support for this orientation, the line reversed (gravity's
            component along the push changed sign), or ``h <= 0`` at ``sigma``.
        """
        line = contact.line(kin.T_object[:3, :3])
        current = self._surfaces[0]
        if (isinstance(current, SupportLine)
                and float(line.tangent(0.0) @ current.tangent(0.0)) < 0.0):
            raise SupportLostError(
                "support lost: the support line reversed (gravity's component along the "
                "surface normal changed sign), so the follower would have to pull")
        if not np.allclose(line.pose(0.0), current.pose(0.0), rtol=0.0, atol=1e-12):
            self.carry.place_follower(line)
        self._surfaces[0] = line
        return contact.force(line, state.sigma)


__all__ = ["StepBuild", "StepBuilder", "smallest_singular_value"]

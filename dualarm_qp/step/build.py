"""Build the one step problem of both arms and every sliding grasp: one loop over its parts.

Each step the builder hands the state to the compiled kernel's loop (``kernel.Step``,
``src/kernel/step.cpp``), which

1. makes the step's context: both arms' kinematics and the carried object's
   (:class:`~dualarm_qp.task.carry.CarryModel`, where every sliding grasp is a joint),
   the two pose errors and every variable's rates to the ends of its range (a straight
   grasp's from its line, :attr:`~dualarm_qp.task.surfaces.GraspSurface.line`; another
   grasp's from its surface, through the same compiled Eqs. 30-31), once;
2. asks every part in turn (:mod:`dualarm_qp.step.parts`): the tasks (the object follows
   ``D(t)``, the grasp stays closed, :mod:`.tasks`, then any of the user's), the cost
   terms (the paper's centring, :mod:`.cost`, then any of the user's), the limits (joint
   and grasp ranges with recovery, joint and grasp speeds, accelerations, collisions,
   torques, :mod:`.limits`, then any of the user's);
3. stacks their pieces: the equality tasks' rows one under the other, the weighted
   tasks and the cost terms summed into one cost, the boxes intersected (the largest
   lower, the smallest upper bound; each bound remembers the limit that set it, for
   messages) and the rows stacked in the limits' order.

A part is a kernel object (the library's own are compiled) or any object of the
protocols of :mod:`.parts`, which the loop asks through the same door
(:mod:`.python_parts`). A Case 2 support first places its line from the object's pose
(:mod:`.support`), then the step's kinematics follow. The parts, the surfaces' lines,
boxes and ranges are read when the builder is made, as the options are: a part, a surface
or a setting changed afterwards needs a new builder (the tasks' gains may change:
:attr:`StepBuilder.leader_gain`).

The decision vector's slices are the :class:`~dualarm_qp.step.layout.Layout`'s. ``s``
is the task scale of the infeasible-step policy (:func:`~dualarm_qp.solvers.solve_step`),
which multiplies the whole right-hand side.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .._remade import KernelHolder
from .._validate import as_number
from ..errors import InvalidInputError, NonFiniteError, ShapeError
from ..task.carry import CarryModel
from ..task.scene import DualArmTask
from ..task.surfaces import GraspSurface
from .bounds import grasp_rates
from .built import StepBuild, smallest_singular_value
from .context import ArmKinematics, StepContext
from .cost import CentringCost
from .layout import Layout
from .limits import LimitSetup, standard_limits
from .options import StepOptions
from .parts import CostTerm, Limit, Task
from .problem import StepProblem
from .python_parts import cost_part, limit_part, task_part
from .stacking import PIN_RTOL, checked_rates
from .state import DualArmState
from .support import SupportPlacement
from .tasks import GraspClosureTask, ObjectPathTask

FloatArray = NDArray[np.float64]
Surfaces = tuple[GraspSurface, ...]

#: What a failed standard task names (its rows are not finite).
_EQUALITY = "the step's equality (D(t), its twist or the arms' poses)"


class StepBuilder(KernelHolder):
    """Builds the step problems of one task under fixed options: one loop over its parts.

    What does not change from step to step (the layout, the parts, the carried-object
    model) is prepared once here; :meth:`build` does the per-step work in one kernel
    call: the context (both arms' kinematics, once), then every part asked in turn.

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
        Limits of the user's, asked after the standard ones (e.g. a wall the follower's
        tool may not cross, ``examples/custom_limit.py``).
    tasks : sequence of Task
        Tasks of the user's, asked after the standard ones: equality rows, or with a
        ``weight`` a term of the cost (``examples/custom_task.py``). A grasp closure of
        the user's (a subclass of the kernel's ``GraspClosureTask``, e.g. the compliant
        follower of :mod:`dualarm_qp.physics.compliance`) takes the standard closure's
        place.
    costs : sequence of CostTerm
        Cost terms of the user's, summed with the paper's centring.

    Attributes
    ----------
    tasks : tuple
        Every task, in the order asked (the object's path and the grasp closure first).
    cost : CentringCost
        The paper's centring.
    costs : tuple
        Every cost term (the centring first).
    limits : tuple
        Every limit, in the order asked.

    Raises
    ------
    InvalidInputError
        A weight vector of the wrong length, or a part that is none (a limit without a
        ``name``, ``gives_rows`` and ``constraint``, a task without ``name`` and
        ``equality``, a cost term without ``name`` and ``quadratic``).
    """

    # The kernel's objects: made again when unpickled (a controller pickles whole).
    _kernel_attributes = ("_step", "_leader_arm", "_follower_arm", "_parts")

    def __init__(self, task: DualArmTask, options: StepOptions, *,
                 leader_gain: float | None = None, leader_bounds: bool = True,
                 limits: Sequence[Limit] = (), tasks: Sequence[Task] = (),
                 costs: Sequence[CostTerm] = ()) -> None:
        leader, follower = task.leader, task.follower
        n_l, n_f = leader.n, follower.n
        for w, n, who in ((options.joint_weights, n_f, "joint_weights (follower)"),
                          (options.leader_joint_weights, n_l, "leader_joint_weights")):
            if w is not None and w.shape[0] not in (1, n):
                raise InvalidInputError(f"{who} has {w.shape[0]} entries, the arm has {n}")
        self.task = task
        self.options = options
        self.carry = CarryModel(leader, task.surface, task.H1, task.leader_surface)
        self.layout = lay = Layout(n_l, n_f, self.carry.n_grasp)
        gain_l = float(options.leader_gain or 0.0) if leader_gain is None else leader_gain
        closures = [t for t in tasks if isinstance(t, kernel.GraspClosureTask)]
        if len(closures) > 1:
            raise InvalidInputError("a step has one grasp closure: "
                                    f"{', '.join(t.name for t in closures)} were given")
        closure = closures[0] if closures else GraspClosureTask(
            float(options.correction_gain or 0.0), exact_orientation=options.exact_orientation)
        self.tasks: tuple[Any, ...] = (
            ObjectPathTask(gain_l), closure,
            *(t for t in tasks if not isinstance(t, kernel.GraspClosureTask)))
        self.cost = CentringCost(lay, options, leader_ranges=leader_bounds)
        self.costs: tuple[Any, ...] = (self.cost, *costs)
        setup = LimitSetup(task, options, lay, leader_bounds)
        self.limits: tuple[Any, ...] = (*standard_limits(setup), *limits)
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
        self._support = (None if task.contact is None else
                         SupportPlacement(task.contact, self.carry, task.surface))
        self._zeros = np.zeros(lay.n)
        self._remake()
        self._labels = tuple(limit.name for limit in self.limits)

    def _remake(self) -> None:
        """Make the kernel's loop over the parts, and both arms' views of its chains."""
        lay, carry = self.layout, self.carry
        follower = self.task.follower
        # Every part as the kernel's loop asks it: the user's wrapped (python_parts).
        parts = ([task_part(t) for t in self.tasks], [cost_part(c) for c in self.costs],
                 [limit_part(limit) for limit in self.limits])
        for limit, part in zip(self.limits, parts[2], strict=True):
            size = getattr(part, "size", None)
            if size is not None and size != lay.n:
                raise ShapeError(f"the compiled box of the limit '{limit.name}'", (lay.n,),
                                 (size,))
        step = kernel.Step(lay.n_l, lay.n_f, carry.frames, follower.tool_frame_id,
                           carry.columns[0], self._q_min, self._q_max, self.options.dt,
                           self._ranged, PIN_RTOL)
        for t in parts[0]:
            step.add_task(t)
        for c in parts[1]:
            step.add_cost(c)
        for limit in parts[2]:
            step.add_limit(limit)
        step.set_labels([limit.name for limit in self.limits])
        # Straight grasps: the kernel computes their rates to the range ends from the grasp
        # coordinates (a Case 2 support's line is given again each step, build).
        lines = [line for line in (surf.line for surf in self._surfaces) if line is not None]
        if len(lines) == len(self._surfaces):
            for surf, line in zip(self._surfaces, lines, strict=True):
                step.add_grasp_line(*line, surf.r_min, surf.r_max, surf.sigma_min,
                                    surf.sigma_max)
        self._parts = parts
        self._step = step
        self._leader_arm = ArmKinematics(carry.model, carry.data, lay.n_l, carry.chain)
        self._follower_arm = ArmKinematics(follower.model, follower.data, lay.n_f,
                                           follower.chain)
        # The standard tasks' rows are named once: the kernel's names only when a task of
        # the user's adds rows.
        self._eq_names = (ObjectPathTask.row_names + GraspClosureTask.row_names
                          if len(self.tasks) == 2 else None)

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
        return float(self.tasks[0].gain)

    @leader_gain.setter
    def leader_gain(self, value: float) -> None:
        self.tasks[0].gain = float(value)

    @property
    def full_cost(self) -> bool:
        """Whether the step's cost is a full matrix (a weighted task of the user's).

        What the pairing check reads with :attr:`row_limits`: a solver that takes a
        diagonal cost only cannot take such a step. A cost term of the user's that
        gives a full matrix is refused by such a solver when the step is solved.
        """
        return any(getattr(task, "weight", None) is not None for task in self.tasks[2:])

    @property
    def row_limits(self) -> tuple[str, ...]:
        """Names of the limits that give general rows (what the pairing check reads)."""
        return tuple(limit.name for limit in self.limits if limit.gives_rows)

    # -- the step -----------------------------------------------------------------------
    def build(self, state: DualArmState, *, scale_max: float = 1.0,
              x_prev: FloatArray | None = None,
              x_applied: FloatArray | None = None,
              x_applied_prev: FloatArray | None = None) -> StepBuild:
        """Build the step problem for ``state``: the kernel's loop over every part.

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
        x_applied_prev : ndarray, optional
            The command applied before it [rad/s, m/s] (jerk limits); default
            ``x_applied`` (constant rates).

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a sliding grasp's coordinate
            that is not a finite number, ``x_prev`` or ``x_applied`` not ``n`` numbers.
        NonFiniteError
            A part's piece would hold NaN or infinity (the part is named).
        SupportLostError
            A supporting follower (Case 2) would have to pull at this state.
        """
        start = time.perf_counter()
        state, sigmas, x0 = self._checked(state, x_applied)
        q_l, q_f = state.q_l, state.q_f
        if x_prev is not None:
            x_prev = checked_rates(x_prev, "x_prev", self.layout.n, finite=False)
        carry, follower, trajectory = self.carry, self.task.follower, self.task.trajectory
        T_D = trajectory.pose(state.t)
        step = self._step
        support_force = math.nan
        surfaces: Surfaces | Callable[[], Surfaces] = tuple(self._surfaces)
        if self._support is not None:
            # The support line follows the object's orientation at this state: placed
            # first, then the step's kinematics follow.
            support_force, surfaces = self._supported(self._support, state)
        grasp_lo, grasp_hi = (self._zeros[:0], self._zeros[:0]) if step.grasp_lines else \
            self._grasp_rates(sigmas)
        out = kernel.StepOut()
        ctx = StepContext(out, state, self.task, self.layout, surfaces, self._leader_arm,
                          self._follower_arm)
        if x_applied_prev is not None:  # jerk limits read it (step/limits/jerk.py)
            ctx.x_applied_prev = checked_rates(x_applied_prev, "x_applied_prev", self.layout.n)
        q_carry = carry.configuration(q_l, state.sigma, state.sigma_leader)
        twist = trajectory.twist(state.t)
        called = time.perf_counter()
        step.build(out, carry.chain, q_carry, carry.columns[1], follower.chain, q_f, T_D,
                   twist, sigmas, grasp_lo, grasp_hi, x0, float(state.t), float(scale_max),
                   ctx)
        if out.failed_part != -1:
            raise self._failure(out)
        problem = self._problem(out, x_prev, time.perf_counter() - start)
        kinematics = called - start + out.kinematics_seconds
        return StepBuild(problem=problem, parts=out, context=ctx, support_force=support_force,
                         kinematics_time=kinematics,
                         assembly_time=problem.build_time - kinematics)

    def _problem(self, out: Any, x_prev: FloatArray | None, seconds: float) -> StepProblem:
        """Return the problem of the kernel's step ``out`` (named from the builder's parts)."""
        return StepProblem(
            A=out.A, b=out.b, weights=out.weights, center=out.center, lower=out.lower,
            upper=out.upper, G=out.G, h=out.h, n_grasp=self.layout.n_grasp, x_prev=x_prev,
            names=self.layout.names, row_names=out.row_names,
            eq_names=self._eq_names or out.eq_names, lower_by=out.lower_names,
            upper_by=out.upper_names, build_time=seconds)

    def _failure(self, out: Any) -> InvalidInputError:
        """Return the error of a part that gave no piece (``out.failed_part``)."""
        k, kind = out.failed_part, out.failed_kind
        if kind == "task":
            name = (_EQUALITY if k < 2 else
                    f"the rows of the task '{self.tasks[k].name}'")
        elif kind == "cost":
            if k < 0:  # the terms' sum
                return InvalidInputError(out.failure)
            name = f"the weights or centre of the cost term '{self.costs[k].name}'"
        else:
            name = out.failure or f"the bounds of the limit '{self._labels[k]}'"
        return NonFiniteError(name)

    def _checked(self, state: DualArmState, x_applied: object
                 ) -> tuple[DualArmState, FloatArray, FloatArray]:
        """Return the state, its grasp coordinates and ``x_applied``, checked.

        The state's joints become float arrays and its numbers floats: checked once, at
        the step's boundary.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a non-finite time or grasp
            coordinate, ``x_applied`` not ``n`` finite numbers.
        """
        q_l = self.task.leader.check_q(state.q_l, "leader joints q_l")
        q_f = self.task.follower.check_q(state.q_f, "follower joints q_f")
        t, sigma = as_number(state.t, "state t"), as_number(state.sigma, "sigma")
        sigma_l = as_number(state.sigma_leader, "sigma_leader")
        if not (q_l is state.q_l and q_f is state.q_f and t is state.t and sigma is state.sigma
                and sigma_l is state.sigma_leader):
            state = DualArmState(t, q_l, q_f, sigma, sigma_l)
        sigmas = np.array((sigma, sigma_l)[:self.layout.n_grasp])
        x0 = self._zeros if x_applied is None else checked_rates(x_applied, "x_applied",
                                                                 self.layout.n)
        return state, sigmas, x0

    def _grasp_rates(self, sigmas: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Return the grasps' rates to the ends of their ranges (Eqs. 30-33) [m/s]."""
        n_grasp, dt = self.layout.n_grasp, self.options.dt
        lo = np.empty(n_grasp)
        hi = np.empty(n_grasp)
        for i, (surf, s) in enumerate(zip(self._surfaces, sigmas.tolist(), strict=True)):
            lo[i], hi[i] = grasp_rates(surf, s, dt)
        return lo, hi

    def _supported(self, support: SupportPlacement, state: DualArmState
                   ) -> tuple[float, Callable[[], Surfaces]]:
        """Case 2: put the follower's path on the support line of this step; its push.

        The line is computed for the object's orientation at ``state`` and frozen for
        the step (as the paper freezes the grasp frame, Sec. 3.3;
        :class:`~dualarm_qp.step.support.SupportPlacement`). When it moved, the
        follower's grasp joint is re-placed (the step's kinematics come after); the
        target then jumps by the line's motion at ``sigma``, which the closure feedback
        removes. The grasp bounds of the step are the line's (``h > 0``).

        Returns
        -------
        h : float
            The follower's push [N] at ``sigma``.
        surfaces : callable
            The step's grasp paths (the support line of this orientation first), made
            when the step's context reads them.

        Raises
        ------
        SupportLostError
            No pushing support for this orientation, the line reversed (gravity's
            component along the push changed sign), or ``h <= 0`` at ``sigma``.
        """
        carry, contact = self.carry, support.contact
        line, h, R = support.place(
            carry.configuration(state.q_l, state.sigma, state.sigma_leader), state.sigma)
        rest = tuple(self._surfaces[1:])
        if self._step.grasp_lines:
            plane = contact.plane
            self._step.set_grasp_line(0, line.origin, line.direction, plane.r_min,
                                      plane.r_max, line.sigma_min, line.sigma_max)
        else:  # a path of the leader's that is not straight: the rates from the surfaces
            self._surfaces[0] = contact.line(R)
        return h, lambda: (contact.line(R), *rest)


__all__ = ["StepBuild", "StepBuilder", "smallest_singular_value"]

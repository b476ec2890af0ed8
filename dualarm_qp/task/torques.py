"""Quasi-static joint torques of both arms holding the carried object, and their derivatives.

Each arm holds itself and its hand's share of the load still (the plan's accelerations
are not counted). With ``w = [f; m]`` the wrench the hand applies to the object (world
frame, moment about the hand's grasp point ``c``, :mod:`dualarm_qp.task.loads`), the
object pushes back on the hand with ``-w``, and the joint torques that hold the arm are

    tau(q, w) = g(q) + J(q)^T [f; m + (c - p) x f],

``g`` the generalised gravity of the arm's links (their inertias are the arm's Pinocchio
model's: a URDF's ``inertial`` tags, the PUMA 560's published parameters) and ``J`` the
Jacobian of the tool point ``p``, world axes ``[v; omega]``: the moment is moved from the
grasp point, where the force acts, to the point whose Jacobian is used. The leader's
grasp point is its tool point; the follower's is its contact point on the object, which
is its tool point only up to the closure error (0.4 mm of it moves a heavy bar's torque
by 0.045 N m).

The wrench depends on where the object is and where the grasps are: the leader's joints
``q_l`` place the object, the grasp coordinates ``sigma`` (and ``sigma_l``) place the
follower's contact point (and the object in the leader's hand). So

    tau_l = tau(q_l, w_l(q_l, sigma, sigma_l)),   tau_f = tau(q_f, w_f(q_l, sigma, sigma_l)),

and the derivative of the torques over the decision vector's variables (both arms'
joints, the grasps) has three parts: the arm's own ``d tau / d q`` at a fixed world
wrench (Pinocchio's static torque derivatives, with fixed *world* forces instead of
Pinocchio's fixed *local* ones, see :meth:`ArmStatics.linearised`), and ``J^T d w / d y``
for ``y`` the leader's joints and the grasps (the leader's columns by a rotation
identity, the grasps' by forward differences of the split; for a support central
differences of the whole split). ``docs/derivation.md`` ("Joint torques") derives it;
the tests check every part against finite differences. With grasps the numeric work is
one call into the compiled kernel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._compiled import kernel
from ..errors import InvalidInputError
from ..kinematics.arm import SerialArm
from ..kinematics.compiled import compiled_chain
from .hands import hand_statics
from .loads import FALLBACK_LENGTH, GraspStatics, ObjectLoad, sliding_statics, split_load
from .scene import DualArmTask

FloatArray = NDArray[np.float64]

#: Step [rad or m] of the central differences of the whole load split (a support: its
#: push depends on the orientation); the split is smooth.
SPLIT_STEP = 1e-6

#: Step [m] of the forward differences of the split over a grasp coordinate (the
#: truncation error is this times the split's second derivative, below 1e-7 relative).
GRASP_STEP = 1e-7

#: Eigenvalues of the balance matrix ``M P M^T`` below this share of its largest are
#: treated as zero (:func:`split_operator`).
RCOND_MIN = 1e-10

__all__ = ["GRASP_STEP", "RCOND_MIN", "SPLIT_STEP", "ArmStatics", "LoadTorques", "TorqueState",
           "model_effort", "split_operator", "torque_limits_of"]

#: A model's effort limit at or above this [N m] means none (Pinocchio's default).
_NO_EFFORT = 1e30


def model_effort(arm: SerialArm) -> FloatArray:
    """Return an arm's joint torque limits from its model [N m] (a URDF's ``effort``).

    A joint whose model states none (zero, or Pinocchio's default: every joint of a DH
    arm) gets ``inf``.
    """
    effort = np.array(arm.model.effortLimit, dtype=np.float64)[:arm.n]
    if effort.shape != (arm.n,):
        return np.full(arm.n, np.inf)
    effort[~((effort > 0.0) & (effort < _NO_EFFORT))] = np.inf
    return effort


def torque_limits_of(arm: SerialArm, given: FloatArray | None, role: str) -> FloatArray:
    """Return an arm's joint torque limits [N m]: ``given``, else its model's ``effort``.

    A URDF's ``effort`` (``model.effortLimit``) is the default; a DH arm (the PUMA 560
    preset included) states none, so its limits must be given.

    Raises
    ------
    InvalidInputError
        No limit given and none in the model, a limit of the wrong length, or one that
        is not > 0 (``inf``: that joint is not limited).
    """
    if given is None:
        effort = model_effort(arm)
        if not np.isfinite(effort).all():
            raise InvalidInputError(
                f"{role}: torque limits are on but the arm's model states no joint torque "
                "limits (a URDF's effort); give tau_max [N m] for this arm")
        return effort
    tau = np.asarray(given, dtype=np.float64)
    if tau.shape != (arm.n,):
        raise InvalidInputError(f"{role}: tau_max needs {arm.n} values, got {tau.size}")
    bad = np.flatnonzero(~(tau > 0.0))
    if bad.size:
        j = int(bad[0])
        raise InvalidInputError(f"{role}: joint {j + 1}: tau_max must be > 0 N m "
                                f"(inf: no limit), got {tau[j]:g}")
    return tau


class ArmStatics:
    """One arm's quasi-static joint torques ``g(q) + J(q)^T w``, compiled.

    The kernel's copy of the arm's model (:func:`~dualarm_qp.kinematics.compiled.compiled_chain`)
    with the model's inertias and ``gravity``, its own: it never disturbs the arm's
    kinematics. Pinocchio's static torques and their derivatives run there
    (``src/kernel/statics.cpp``).

    Parameters
    ----------
    arm : SerialArm
        The arm (its model's inertias are the links').
    gravity : array_like, shape (3,)
        Gravity [m/s^2], world frame.
    """

    def __init__(self, arm: SerialArm, gravity: FloatArray) -> None:
        self.n = arm.n
        self.frame = arm.tool_frame_id
        self.gravity = np.array(gravity, dtype=np.float64)
        model = pin.Model(arm.model)  # a copy: later edits of the arm do not reach it
        self._chain = self._compiled(model)

    def _compiled(self, model: Any) -> kernel.Chain:
        """Return the kernel's chain of ``model``, with its inertias and this gravity.

        The chain pickles itself, bodies and gravity included.
        """
        chain = compiled_chain(model)
        for j in range(1, model.njoints):
            body = model.inertias[j]
            chain.set_inertia(j, float(body.mass), np.array(body.lever),
                              np.array(body.inertia))
        chain.set_gravity(self.gravity)
        return chain

    @property
    def chain(self) -> kernel.Chain:
        """The kernel's chain of the statics (the arm's model, its inertias and gravity).

        For the kernel's statics calls only: they leave its kinematics at their own
        joints (read the arm's kinematics from the arm or the step's context).
        """
        return self._chain


    def torque(self, q: FloatArray, wrench: FloatArray, point: FloatArray | None = None
               ) -> FloatArray:
        """Joint torques [N m] that hold the arm at ``q`` with the hand applying ``wrench``.

        Parameters
        ----------
        q : ndarray, shape (n,)
            Joints [rad].
        wrench : ndarray, shape (6,)
            ``[f; m]`` the hand applies to the object [N, N m], world frame, moment about
            ``point``.
        point : ndarray, shape (3,), optional
            Where the force acts [m], world frame (the grasp point); default the tool
            point. The moment is moved from it to the tool point, whose Jacobian is used.
        """
        tau = self._chain.static_torques(q, self.frame, wrench, point, False).tau
        return tau

    def linearised(self, q: FloatArray, wrench: FloatArray, point: FloatArray | None = None
                   ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Torques, their derivative over ``q`` at a fixed world wrench, and the Jacobian.

        Pinocchio's ``computeStaticTorqueDerivatives`` holds the external force fixed in
        the body; here it is fixed in the world (the load's wrench does not turn with
        the hand). With ``F = -w`` on the body, ``J^T F`` differs by the turn of ``F``
        with the body: column ``j`` gains ``-J^T [omega_j x f; omega_j x m_p]``
        (``omega_j`` the world axis of joint ``j``, ``m_p`` the moment about the tool
        point ``p``). A ``point`` stays in the world while ``p`` moves by ``v_j``: the
        moment about ``p``, ``m + (point - p) x f``, gains ``f x v_j``.

        Returns
        -------
        tau : ndarray, shape (n,)
            [N m].
        dtau_dq : ndarray, shape (n, n)
            [N m / rad].
        J : ndarray, shape (6, n)
            Tool-point Jacobian, world axes ``[v; omega]``.
        """
        st = self._chain.static_torques(q, self.frame, wrench, point, True)
        tau, dtau, J = st.tau, st.dtau, st.J
        return tau, dtau, J


@dataclass(frozen=True)
class TorqueState:
    """Both arms' torques at one state and their derivative over the decision variables.

    Attributes
    ----------
    tau : ndarray, shape (n_l + n_f,)
        The leader's joint torques, then the follower's [N m].
    D : ndarray, shape (n_l + n_f, n_l + n_f + n_grasp)
        ``d tau / d (q_l, q_f, sigma[, sigma_l])`` [N m / rad, N m / m], columns in the
        decision vector's order.
    wrenches : ndarray, shape (2, 6)
        The leader's and the follower's wrench on the object [N, N m].
    """

    tau: FloatArray
    D: FloatArray
    wrenches: FloatArray


class LoadTorques:
    """Joint torques of both arms of a task holding its load (none: their own weight only).

    Parameters
    ----------
    task : DualArmTask
        Arms (their inertias), object and load. Without a load the arms hold only
        themselves, under their models' gravity.
    """

    def __init__(self, task: DualArmTask) -> None:
        self.task = task
        load = task.load
        g_l = (np.array(task.leader.model.gravity.linear) if load is None else load.gravity)
        g_f = (np.array(task.follower.model.gravity.linear) if load is None
               else load.gravity)
        self.leader = ArmStatics(task.leader, g_l)
        self.follower = ArmStatics(task.follower, g_f)
        self.n_l = task.leader.n
        self.n_f = task.follower.n
        self.n_grasp = 1 if task.leader_surface is None else 2

    def wrenches(self, q_l: FloatArray, sigma: float, sigma_l: float = 0.0) -> FloatArray:
        """Return the leader's and the follower's wrench on the object (2, 6) [N, N m].

        Zero without a load.

        Raises
        ------
        UnbalancedLoadError, SupportLostError
            The grasps cannot hold the load here.
        """
        return self._split(q_l, sigma, sigma_l)[0]

    def _split(self, q_l: FloatArray, sigma: float, sigma_l: float
               ) -> tuple[FloatArray, FloatArray | None]:
        """Both hands' wrenches (2, 6) and their grasp points (2, 3) [m] (None: no load)."""
        if self.task.load is None:
            return np.zeros((2, 6)), None
        hands, T_obj = hand_statics(self.task, q_l, sigma, sigma_l)
        split = split_load(hands, self.task.load, T_obj)
        return split.wrenches, np.array([hand.point for hand in hands])

    def torques(self, q_l: FloatArray, q_f: FloatArray, sigma: float, sigma_l: float = 0.0
                ) -> FloatArray:
        """Both arms' joint torques, the leader's first (n_l + n_f,) [N m]."""
        w, c = self._split(q_l, sigma, sigma_l)
        return np.r_[self.leader.torque(q_l, w[0], None if c is None else c[0]),
                     self.follower.torque(q_f, w[1], None if c is None else c[1])]

    def linearised(self, q_l: FloatArray, q_f: FloatArray, sigma: float,
                   sigma_l: float = 0.0) -> TorqueState:
        """Both arms' torques and their derivative over the decision variables.

        With grasps (the split linear in gravity, :func:`split_operator`) the whole of it
        is one kernel call (``src/kernel/load_torques.cpp``): both arms' statics, the
        split, the leader's columns by the rotation identity and the grasps' by forward
        differences of the split over :data:`GRASP_STEP` (the hands' geometry at the
        moved grasps is computed here). A support (its push depends on the orientation):
        central differences of the whole split over :data:`SPLIT_STEP`. Without a load
        the arms hold only themselves.

        Raises
        ------
        UnbalancedLoadError, SupportLostError
            The grasps cannot hold the load here (or at a neighbouring state of the
            differences).
        """
        load = self.task.load
        if load is not None and self.task.contact is None:
            lt = self._with_split(load, q_l, q_f, sigma, sigma_l)
            return TorqueState(lt.tau, lt.D, lt.w)
        n_l, n_f, n_g = self.n_l, self.n_f, self.n_grasp
        w, c = self._split(q_l, sigma, sigma_l)
        tau_l, dl, J_l = self.leader.linearised(q_l, w[0], None if c is None else c[0])
        tau_f, df, J_f = self.follower.linearised(q_f, w[1], None if c is None else c[1])
        D = np.zeros((n_l + n_f, n_l + n_f + n_g))
        D[:n_l, :n_l] = dl
        D[n_l:, n_l:n_l + n_f] = df
        if load is not None:
            tools = np.array([self.task.leader.fk(q_l)[:3, 3], self.task.follower.fk(q_f)[:3, 3]])
            dw = self._support_derivative(q_l, sigma, sigma_l, tools)
            D[:n_l, :n_l] += J_l.T @ dw[0, :, :n_l]
            D[n_l:, :n_l] += J_f.T @ dw[1, :, :n_l]
            D[:n_l, n_l + n_f:] += J_l.T @ dw[0, :, n_l:]
            D[n_l:, n_l + n_f:] += J_f.T @ dw[1, :, n_l:]
        return TorqueState(np.r_[tau_l, tau_f], D, w)

    def _with_split(self, load: ObjectLoad, q_l: FloatArray, q_f: FloatArray, sigma: float,
                    sigma_l: float) -> kernel.LoadTorques:
        """``tau``, ``D`` and ``w`` of grasps: the hands at the state and at each moved grasp.

        The follower's grasp moved by :data:`GRASP_STEP` moves only the follower's hand
        (the rest of the set-up is kept); a sliding leader's moves the object.
        """
        task = self.task
        hands, T_obj = hand_statics(task, q_l, sigma, sigma_l)
        R, p = T_obj[:3, :3], T_obj[:3, 3]
        centre = R @ load.mass_centre + p
        surf = task.surface
        s1 = sigma + GRASP_STEP
        sets = [(hands, centre),
                ([hands[0], sliding_statics(R @ surf.point(s1) + p, R @ surf.tangent(s1),
                                            R @ surf.angular_rate(s1))], centre)]
        if self.n_grasp == 2:
            moved, T1 = hand_statics(task, q_l, sigma, sigma_l + GRASP_STEP)
            sets.append((moved, T1[:3, :3] @ load.mass_centre + T1[:3, 3]))
        leader, follower = self.leader, self.follower
        return kernel.load_torques(
            leader.chain, leader.frame, follower.chain, follower.frame, q_l, q_f,
            load.gravity, load.mass, [np.array([h.point for h in hs]) for hs, _ in sets],
            [[h.free for h in hs] for hs, _ in sets], [c for _, c in sets], GRASP_STEP,
            FALLBACK_LENGTH, RCOND_MIN)

    def _support_derivative(self, q_l: FloatArray, sigma: float, sigma_l: float,
                            tools: FloatArray) -> FloatArray:
        """``d w / d (q_l, grasps)`` of both hands with a support (2, 6, n_l + n_grasp).

        Central differences of the whole split over :data:`SPLIT_STEP`: a support's push
        depends on the object's orientation, so the split is not linear in gravity. Each
        wrench is moved from its grasp point (which moves with the state) to its arm's
        tool point at this state, ``tools`` (2, 3) [m], whose Jacobian carries it.
        """
        n_l, n_g = self.n_l, self.n_grasp
        h = SPLIT_STEP
        y = np.r_[q_l, sigma, sigma_l][:n_l + n_g]
        cols = []
        for k in range(n_l + n_g):
            up, down = y.copy(), y.copy()
            up[k] += h
            down[k] -= h
            cols.append((self._about_tools(up, tools) - self._about_tools(down, tools))
                        / (2.0 * h))
        return np.stack(cols, axis=-1)

    def _about_tools(self, y: FloatArray, tools: FloatArray) -> FloatArray:
        """Both hands' wrenches at ``y = (q_l, sigma[, sigma_l])``, moments about ``tools``."""
        n_l = self.n_l
        sigma_l = float(y[n_l + 1]) if self.n_grasp == 2 else 0.0
        w, c = self._split(y[:n_l], float(y[n_l]), sigma_l)
        if c is None:
            return w
        return w + np.c_[np.zeros((2, 3)), np.cross(c - tools, w[:, :3])]


def split_operator(hands: list[GraspStatics], centre: FloatArray, mass: float
                   ) -> FloatArray | None:
    """Return the minimum-norm split as a linear map of gravity, ``w = K g`` (6 n_hands, 3).

    Compiled (``src/kernel/load_split.cpp``).

    The rule of :func:`~dualarm_qp.task.loads.split_load`, written with projectors:
    in scaled coordinates ``u_i = U^-1 w_i`` (``U = diag(1, 1, 1, L, L, L)``) hand ``i``'s
    wrenches are those orthogonal to ``U T_i`` (``T_i`` its free twists), with projector
    ``P_i``; the balance is ``M u = b`` (``M_i = S A_i U``, ``A_i`` the transfer to the
    first hand's point, ``S = U^-1``), and the least ``|u|`` is
    ``u = P M^T (M P M^T)^-1 b``. ``b`` is linear in gravity. Where the hands span fewer
    than the 6 balance directions (two slides along one axis: ``M P M^T`` singular, its
    eigenvalues below :data:`RCOND_MIN` of the largest left out) the inverse is the
    pseudo-inverse: the same least-norm split wherever the load can be held (and the
    least-squares one next to it, which only differences read). Returns None when a hand
    has a prescribed wrench (a support: use the full split).

    Parameters
    ----------
    hands : list of GraspStatics
        The hands (world frame), the leader's first.
    centre : ndarray, shape (3,)
        The mass centre [m], world frame.
    mass : float
        [kg].
    """
    if any(hand.wrench is not None for hand in hands):
        return None
    points = np.array([hand.point for hand in hands], dtype=np.float64)
    return kernel.split_operator(points, [hand.free for hand in hands],
                                 np.asarray(centre, dtype=np.float64), float(mass),
                                 FALLBACK_LENGTH, RCOND_MIN)

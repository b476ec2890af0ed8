"""Closed-form inverse kinematics of the PUMA 560 (Table 1 geometry), every branch.

The arm has a spherical wrist: joints 4, 5 and 6 turn about axes through one point, the
wrist centre ``p_w``. Its position depends on joints 1-3 only, so the problem splits.

Derivation (standard DH, frames as in Fu, Gonzalez and Lee; ``theta_i = q_i + offset_i``)

1. Wrist centre. Frame 6 sits ``d6`` along the wrist axis, so ``p_w = p - d6 a`` with
   ``p`` and ``a`` (the z axis of frame 6) in the base frame.
2. Joint 1. Frame 1 has ``x1 = (c1, s1, 0)``, ``y1 = (0, 0, -1)`` and
   ``z1 = (-s1, c1, 0)``, and joints 2 and 3 keep the wrist centre in the plane
   ``z1 . p_w = d2``. Writing ``p_w = u x1 + v y1 + d2 z1`` gives ``v = -p_z`` and
   ``u = +-sqrt(px^2 + py^2 - d2^2)``, the signed reach along ``x1``;
   ``q1 = atan2(py, px) - atan2(d2, u)``.
3. Joint 3. In the ``(x1, y1)`` plane,
   ``(u, v) = Rz(theta2) [(a2, 0) + Rz(theta3) (a3, -d4)]``, so
   ``a3 c3 + d4 s3 = (u^2 + v^2 - a2^2 - a3^2 - d4^2) / (2 a2) = K`` and
   ``theta3 = beta +- acos(K / L)`` with ``L = sqrt(a3^2 + d4^2)``,
   ``beta = atan2(d4, a3)``.
4. Joint 2. ``theta2 = atan2(v, u) - atan2(w_y, w_x)`` with
   ``w = (a2 + a3 c3 + d4 s3, a3 s3 - d4 c3)``.
5. Wrist. ``W = R_3^6 = R_0^3(q1..q3)^T R_0^6 = Rz(theta4) Ry(theta5) Rz(theta6)``
   (ZYZ Euler angles), solved with ``theta5`` of either sign:
   ``theta4 = atan2(+-W12, +-W02)``, ``theta5 = atan2(+-sqrt(W02^2 + W12^2), W22)``.
   ``theta6`` comes from the sum ``theta4 + theta6 = atan2(W10 - W01, W00 + W11)``
   (or the difference when ``W22 < 0``), which stays accurate near the singularity
   ``s5 = 0`` where ``W20``, ``W21`` vanish.

Configuration indicators (in the spirit of Lee and Ziegler 1984 and Fu, Gonzalez and
Lee ch. 2, but defined here as explicit functions of the joint angles; each is +1 or -1
and ``sign(0) = +1``):

``arm = sign(-u)``, ``u = a2 c2 + a3 c23 + d4 s23``
    ``u`` is the signed reach of the wrist centre along ``x1 = (c1, s1, 0)``, and
    ``d(p_z)/d(theta2) = -u``: arm = +1 when a positive joint-2 rate raises the wrist
    centre (FGL's verbal definition of a RIGHT arm), -1 when it lowers it (LEFT).
``elbow = arm * sign(d4 c3 - a3 s3)``
    ``d4 c3 - a3 s3 = L sin(beta - theta3)`` tells the two solutions of step 3 apart.
    elbow = +1 when the elbow (origin of frame 2) lies above the line from the
    shoulder to the wrist centre, in the arm's vertical plane (ABOVE), -1 below it.
``wrist = sign(sin(theta5))``
    the two ZYZ solutions of step 5 (a wrist flip maps ``(theta4, theta5, theta6)``
    to ``(theta4 + pi, -theta5, theta6 + pi)``); +1 for ``theta5`` in ``(0, pi)``.

All three are invariant to 2 pi shifts of the joints. Away from the boundaries
(``u = 0``, ``K = +-L``, ``sin(theta5) = 0``) the eight triples name eight distinct
solutions; on a boundary two branches coincide and only one is returned.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from .._validate import as_array, as_pose
from ..errors import IKError, InvalidInputError
from .arm import FloatArray, SerialArm

#: Relative tolerance for the reach tests: a pose this far outside the workspace
#: boundary is treated as lying on it.
REACH_TOL = 1e-12
#: ``|sin(theta5)|`` below this counts as the wrist singularity (joints 4 and 6 align):
#: q4 is then taken from the reference.
WRIST_SINGULAR_TOL = 1e-12
#: Joint angles up to this far outside their limits [rad] are clipped onto them.
LIMIT_TOL = 1e-10

_PUMA_ALPHA = (-0.5 * math.pi, 0.0, 0.5 * math.pi, -0.5 * math.pi, 0.5 * math.pi, 0.0)


@dataclass(frozen=True)
class IKSolution:
    """One inverse-kinematics branch.

    Attributes
    ----------
    q : ndarray, shape (6,)
        Joint angles [rad], within the arm's limits.
    arm, elbow, wrist : int
        Configuration indicators (+1 or -1), see :func:`puma560_indicators`.
    """

    q: FloatArray
    arm: int
    elbow: int
    wrist: int

    @property
    def indicators(self) -> tuple[int, int, int]:
        """``(arm, elbow, wrist)``."""
        return (self.arm, self.elbow, self.wrist)


@dataclass(frozen=True)
class _Geometry:
    """The nonzero Table-1 parameters of a PUMA-like arm [m] and its joint offsets."""

    a2: float
    a3: float
    d2: float
    d4: float
    d6: float
    offset: tuple[float, ...]


def _geometry(arm: SerialArm) -> _Geometry:
    """Check that ``arm`` has the PUMA 560 structure and read its parameters."""
    if not isinstance(arm, SerialArm):
        raise InvalidInputError(f"arm must be a SerialArm, got {type(arm).__name__}")
    dh = arm.dh
    if dh is None:
        raise InvalidInputError(
            f"{arm.name}: closed-form PUMA 560 IK needs an arm built from a DH table "
            f"(this one is a {arm.model.name!r} model); use ik_dls for other arms")
    problems = []
    a, alpha, d = dh.a.tolist(), dh.alpha.tolist(), dh.d.tolist()
    if dh.n != 6 or dh.convention != "standard":
        problems.append(f"6 joints in standard DH (got {dh.n}, {dh.convention!r})")
    else:
        if any(abs(x - y) > 1e-12 for x, y in zip(alpha, _PUMA_ALPHA, strict=True)):
            problems.append("link twists (-90, 0, 90, -90, 90, 0) deg")
        if any(a[i] != 0.0 for i in (0, 3, 4, 5)) or any(d[i] != 0.0 for i in (0, 2, 4)):
            problems.append("a1 = a4 = a5 = a6 = 0 and d1 = d3 = d5 = 0")
        if a[1] == 0.0:
            problems.append("a2 != 0")
    if problems:
        raise InvalidInputError(
            f"{arm.name}: closed-form PUMA 560 IK needs " + "; ".join(problems)
            + " (use ik_dls for other arms)"
        )
    return _Geometry(a[1], a[2], d[1], d[3], d[5], tuple(dh.offset.tolist()))


def puma560_indicators(arm: SerialArm, q: Any) -> tuple[int, int, int]:
    """Return the configuration indicators ``(arm, elbow, wrist)`` of joints ``q``.

    Parameters
    ----------
    arm : SerialArm
        A PUMA-560-like arm (e.g. from :func:`~dualarm_qp.kinematics.puma560`).
    q : array_like, shape (6,)
        Joint angles [rad].

    Returns
    -------
    tuple of int
        ``(arm, elbow, wrist)``, each +1 or -1, defined in the module docstring:
        ``arm = sign(-(a2 c2 + a3 c23 + d4 s23))``,
        ``elbow = arm * sign(d4 c3 - a3 s3)``, ``wrist = sign(sin(theta5))``
        (sign(0) = +1).
    """
    g = _geometry(arm)
    th = [qi + oi for qi, oi in zip(arm.check_q(q).tolist(), g.offset, strict=True)]
    c2 = math.cos(th[1])
    c3, s3 = math.cos(th[2]), math.sin(th[2])
    c23, s23 = math.cos(th[1] + th[2]), math.sin(th[1] + th[2])
    arm_ind = _sign(-(g.a2 * c2 + g.a3 * c23 + g.d4 * s23))
    elbow = arm_ind * _sign(g.d4 * c3 - g.a3 * s3)
    return arm_ind, elbow, _sign(math.sin(th[4]))


def puma560_ik(arm: SerialArm, T_world_tool: Any, *, q_ref: Any = None) -> list[IKSolution]:
    """Return every joint solution reaching a tool pose, one per configuration branch.

    Parameters
    ----------
    arm : SerialArm
        A PUMA-560-like arm; its base and tool transforms are taken into account.
    T_world_tool : array_like, shape (4, 4)
        Desired tool pose in the world [m].
    q_ref : array_like, shape (6,), optional
        Reference joints [rad]: where a joint's range holds two representatives of an
        angle (joint 6 spans +-266 deg) the one closest to ``q_ref`` is taken (closest
        to 0 without ``q_ref``), and at the wrist singularity ``q4`` is kept at
        ``q_ref[3]`` (or 0).

    Returns
    -------
    list of IKSolution
        Up to 8 solutions within the joint limits, ordered by ``(arm, elbow, wrist)``
        from +1 to -1; empty when the pose is out of reach or every branch violates a
        limit.

    Raises
    ------
    InvalidInputError
        ``arm`` is not PUMA-like, or a malformed pose or ``q_ref``.
    """
    g = _geometry(arm)
    target = _flange_pose(arm, T_world_tool)
    ref = _reference(arm, q_ref)
    found: dict[tuple[int, int, int], IKSolution] = {}
    for arm_ind in (1, -1):
        for elbow in (1, -1):
            for wrist in (1, -1):
                theta = _branch_angles(g, target, arm_ind, elbow, wrist, ref)
                if theta is None:
                    continue
                q = _into_limits(arm, theta, g.offset, ref)
                if q is None:
                    continue
                sol = _solution(arm, q)
                found.setdefault(sol.indicators, sol)
    return list(found.values())


def ik_branch(arm: SerialArm, T_world_tool: Any, arm_ind: int, elbow: int, wrist: int,
              q_ref: Any = None) -> IKSolution:
    """Solve one configuration branch.

    Parameters
    ----------
    arm : SerialArm
        A PUMA-560-like arm (base and tool are taken into account).
    T_world_tool : array_like, shape (4, 4)
        Desired tool pose in the world [m].
    arm_ind, elbow, wrist : {+1, -1}
        The branch, see :func:`puma560_indicators`.
    q_ref : array_like, shape (6,), optional
        Reference joints [rad], as in :func:`puma560_ik`.

    Returns
    -------
    IKSolution
        Its indicators are recovered from its joints; they differ from the request
        only on a branch boundary, where the requested branch coincides with another
        (at the wrist singularity, for instance, both wrist values give one solution).

    Raises
    ------
    IKError
        The pose is out of reach, or this branch's solution violates a joint limit (then
        ``position_error`` and ``rotation_error`` are 0: the pose itself is reached).
    InvalidInputError
        Indicators other than +1 / -1, a non-PUMA arm or malformed inputs.
    """
    for name, value in (("arm_ind", arm_ind), ("elbow", elbow), ("wrist", wrist)):
        if value not in (1, -1):
            raise InvalidInputError(f"{name} must be +1 or -1, got {value!r}")
    g = _geometry(arm)
    target = _flange_pose(arm, T_world_tool)
    ref = _reference(arm, q_ref)
    theta = _branch_angles(g, target, arm_ind, elbow, wrist, ref)
    branch = f"(arm={arm_ind:+d}, elbow={elbow:+d}, wrist={wrist:+d})"
    if theta is None:
        raise IKError(f"{arm.name}: pose out of reach (wrist centre outside the workspace)")
    q = _into_limits(arm, theta, g.offset, ref)
    if q is None:
        raw = np.array(theta) - np.array(g.offset)
        raise IKError(f"{arm.name}: branch {branch} violates the joint limits "
                      f"(joints {np.round(np.rad2deg(raw), 3).tolist()} deg up to 2 pi shifts)",
                      position_error=0.0, rotation_error=0.0)
    return _solution(arm, q)


# --------------------------------------------------------------------------- helpers
def _sign(x: float) -> int:
    return 1 if x >= 0.0 else -1


def _flange_pose(arm: SerialArm, T_world_tool: Any) -> FloatArray:
    """``T_base_flange`` for a desired ``T_world_tool``."""
    T = as_pose(T_world_tool, "T_world_tool")
    return (pin.SE3(arm.base).inverse() * pin.SE3(T) * pin.SE3(arm.tool).inverse()).homogeneous


def _reference(arm: SerialArm, q_ref: Any) -> list[float]:
    """``q_ref`` (or zeros) clipped into the joint limits [rad]."""
    ref = np.zeros(arm.n) if q_ref is None else as_array(q_ref, "q_ref", (arm.n,))
    return np.clip(ref, arm.q_min, arm.q_max).tolist()


def _solution(arm: SerialArm, q: FloatArray) -> IKSolution:
    arm_ind, elbow, wrist = puma560_indicators(arm, q)
    q.flags.writeable = False
    return IKSolution(q, arm_ind, elbow, wrist)


def _branch_angles(g: _Geometry, T: FloatArray, arm_ind: int, elbow: int, wrist: int,
                   ref: list[float]) -> list[float] | None:
    """DH angles ``theta`` of one branch (not yet wrapped), or None when out of reach."""
    R = T[:3, :3]
    px, py, pz = (T[:3, 3] - g.d6 * R[:, 2]).tolist()  # wrist centre
    # Joint 1: the signed reach u along x1 and v = -pz in the plane of joints 2, 3.
    r2 = px * px + py * py
    u2 = r2 - g.d2 * g.d2
    if u2 < -REACH_TOL * max(r2, g.d2 * g.d2, 1.0):
        return None
    u = -arm_ind * math.sqrt(max(u2, 0.0))
    if r2 == 0.0:  # wrist centre on the z0 axis (only possible with d2 = 0)
        t1 = ref[0] + g.offset[0]
    else:
        t1 = math.atan2(py, px) - math.atan2(g.d2, u)
    v = -pz
    # Joint 3: a3 c3 + d4 s3 = K = L cos(theta3 - beta).
    L = math.hypot(g.a3, g.d4)
    K = (u * u + v * v - g.a2 * g.a2 - L * L) / (2.0 * g.a2)
    if abs(K) > L * (1.0 + REACH_TOL):
        return None
    beta = math.atan2(g.d4, g.a3)
    # sign(d4 c3 - a3 s3) = sign(sin(beta - theta3)) = arm * elbow.
    t3 = beta - arm_ind * elbow * math.acos(max(-1.0, min(1.0, K / L)))
    c3, s3 = math.cos(t3), math.sin(t3)
    t2 = math.atan2(v, u) - math.atan2(g.a3 * s3 - g.d4 * c3, g.a2 + g.a3 * c3 + g.d4 * s3)
    # Wrist: R36 = R03^T R06 = Rz(theta4) Ry(theta5) Rz(theta6).
    c1, s1 = math.cos(t1), math.sin(t1)
    c23, s23 = math.cos(t2 + t3), math.sin(t2 + t3)
    R03 = np.array([[c1 * c23, -s1, c1 * s23],
                    [s1 * c23, c1, s1 * s23],
                    [-s23, 0.0, c23]])
    W = (R03.T @ R).tolist()
    s5 = math.hypot(W[0][2], W[1][2])
    if s5 < WRIST_SINGULAR_TOL:  # joints 4 and 6 aligned: keep q4 from the reference
        t4 = ref[3] + g.offset[3]
        # theta5 for this theta4: Rz(-theta4) W = Ry(theta5) Rz(theta6) up to O(s5).
        t5 = math.atan2(math.cos(t4) * W[0][2] + math.sin(t4) * W[1][2], W[2][2])
    else:
        t4 = math.atan2(wrist * W[1][2], wrist * W[0][2])
        t5 = math.atan2(wrist * s5, W[2][2])
    # theta6 from the well-conditioned 2x2 block rather than from W20, W21 (which are
    # O(s5) and would give errors of eps / s5 near the singularity):
    # W00 + W11 = (1 + c5) cos(t4 + t6), W10 - W01 = (1 + c5) sin(t4 + t6),
    # W11 - W00 = (1 - c5) cos(t4 - t6), W10 + W01 = -(1 - c5) sin(t4 - t6).
    if W[2][2] >= 0.0:
        t6 = math.atan2(W[1][0] - W[0][1], W[0][0] + W[1][1]) - t4
    else:
        t6 = t4 - math.atan2(-(W[1][0] + W[0][1]), W[1][1] - W[0][0])
    return [t1, t2, t3, t4, t5, t6]


def _into_limits(arm: SerialArm, theta: list[float], offset: tuple[float, ...],
                 ref: list[float]) -> FloatArray | None:
    """Joint angles ``theta - offset`` shifted by multiples of 2 pi into the limits.

    Where several shifts fit, the one closest to ``ref`` wins. None if a joint fits
    nowhere.
    """
    two_pi = 2.0 * math.pi
    q = np.empty(len(theta))
    for i, (t, lo, hi) in enumerate(
            zip(theta, arm.q_min.tolist(), arm.q_max.tolist(), strict=True)):
        angle = t - offset[i]
        # Representative closest to the reference, then step towards the range.
        best = angle + two_pi * round((ref[i] - angle) / two_pi)
        if best > hi + LIMIT_TOL:
            best -= two_pi * math.ceil((best - hi - LIMIT_TOL) / two_pi)
        elif best < lo - LIMIT_TOL:
            best += two_pi * math.ceil((lo - LIMIT_TOL - best) / two_pi)
        if not lo - LIMIT_TOL <= best <= hi + LIMIT_TOL:
            return None
        q[i] = min(max(best, lo), hi)
    return q

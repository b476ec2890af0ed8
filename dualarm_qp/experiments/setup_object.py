"""The carried object of an experiment file: its surfaces, grasps, load and support.

The follower's grasp surface (or, for a Case 2 support, its support line), the leader's
hand on the object (``H1``, or a sliding leader grasp), the grasp coordinates at the
start, and the object's load, each checked with errors naming the key to change.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ConfigError, DualArmError
from ..task.contact import GRAVITY_ALONG_PUSH_MIN, SupportContact
from ..task.hands import hand_wrenches
from ..task.loads import ObjectLoad, UnbalancedLoadError
from ..task.scene import DualArmTask
from ..task.surfaces import CurvedBar, CylinderSurface, GraspSurface, PlaneBar
from ..task.trajectory import Trajectory
from .config import ExperimentConfig, SurfaceSpec
from .setup_values import Scales, at_key, file_pose, required

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Grasps:
    """How the hands hold the object at the start.

    Attributes
    ----------
    surface : GraspSurface
        The follower's grasp surface (its support line for a support).
    H1 : ndarray, shape (4, 4)
        ``T_leader_object`` (m).
    sigma0 : float
        The follower's grasp coordinate at the start [m].
    contact : SupportContact or None
        The Case 2 support, if the follower supports the object.
    leader_surface : GraspSurface or None
        The leader's sliding grasp surface, if its grasp slides.
    sigma_l0 : float
        The leader's grasp coordinate at the start [m] (0 for a rigid grasp).
    """

    surface: GraspSurface
    H1: FloatArray
    sigma0: float
    contact: SupportContact | None
    leader_surface: GraspSurface | None
    sigma_l0: float


def grasps_of(cfg: ExperimentConfig, sc: Scales, surface: GraspSurface,
              trajectory: Trajectory, path: str, notes: dict[str, Any]) -> Grasps:
    """Return the grasps at the start on the follower's ``surface`` (checked; notes a support)."""
    with at_key("object.H1", path):
        H1 = np.eye(4) if cfg.object.H1 is None else file_pose(cfg.object.H1, sc)
    sigma0 = cfg.object.grasp_initial * sc.length
    contact: SupportContact | None = None
    if cfg.object.contact == "support":
        contact, surface = support_of(cfg, sc, surface, H1, trajectory, sigma0, path, notes)
    with at_key("object.grasp_initial", path):
        surface.pose(sigma0)
    leader_surface: GraspSurface | None = None
    sigma_l0 = 0.0
    if cfg.object.leader_surface is not None and cfg.object.leader_grasp_initial is not None:
        with at_key("object.leader_surface", path):
            leader_surface = surface_of(cfg.object.leader_surface, sc, "object.leader_surface")
        sigma_l0 = cfg.object.leader_grasp_initial * sc.length
        with at_key("object.leader_grasp_initial", path):
            leader_surface.pose(sigma_l0)
    return Grasps(surface, H1, sigma0, contact, leader_surface, sigma_l0)


def surface_of(s: SurfaceSpec, sc: Scales, key: str) -> GraspSurface:
    """Return the grasp surface the file gives at ``key``, in SI."""
    if s.type == "plane_bar":
        r_min = np.zeros(3) if s.r_min is None else np.asarray(s.r_min, dtype=float) * sc.length
        r_max = (np.array([0.0, 0.0, 0.4]) if s.r_max is None
                 else np.asarray(s.r_max, dtype=float) * sc.length)
        return PlaneBar(r_min=r_min, r_max=r_max)
    radius = required(s.radius, f"{key}.radius") * sc.length
    lo, hi = (v * sc.length for v in required(s.grasp_range, f"{key}.grasp_range"))
    if s.type == "cylinder":
        azimuth = 0.0 if s.azimuth is None else s.azimuth * sc.angle
        return CylinderSurface(radius, azimuth=azimuth, sigma_min=lo, sigma_max=hi)
    return CurvedBar(radius, side=s.side or "outer", sigma_min=lo, sigma_max=hi)


#: Gravity when the file gives none: world z up [m/s^2].
STANDARD_GRAVITY = (0.0, 0.0, -9.81)


def load_of(cfg: ExperimentConfig, sc: Scales, path: str) -> ObjectLoad:
    """Return the object's load in SI (``object.mass`` must be given)."""
    o = cfg.object
    mass = required(o.mass, "object.mass", path)
    centre = np.zeros(3) if o.mass_centre is None else np.asarray(o.mass_centre) * sc.length
    gravity = (np.asarray(STANDARD_GRAVITY) if o.gravity is None
               else np.asarray(o.gravity, dtype=float) * sc.length / sc.time**2)
    with at_key("object.mass", path):
        return ObjectLoad(mass, centre, gravity)


def check_load(task: DualArmTask, q_l0: FloatArray, sigma0: float, sigma_l0: float,
                path: str) -> None:
    """Refuse a load the grasps cannot hold at the start, naming the key to change.

    ``object.gravity`` when the force cannot be balanced (gravity along a direction no
    grasp carries), ``object.mass_centre`` when only its moment cannot (the mass centre
    off an axis both grasps turn about).
    """
    if task.load is None or task.contact is not None:  # a support is checked by support_of
        return
    try:
        hand_wrenches(task, q_l0, sigma0, sigma_l0)
    except UnbalancedLoadError as err:
        T_obj = task.object_pose(q_l0, sigma_l0)
        centre = T_obj[:3, :3].T @ (task.leader.fk(q_l0)[:3, 3] - T_obj[:3, 3])
        at_grasp = dataclasses.replace(task.load, mass_centre=centre)
        try:
            hand_wrenches(dataclasses.replace(task, load=at_grasp), q_l0, sigma0, sigma_l0)
            key = "object.mass_centre"
        except UnbalancedLoadError:
            key = "object.gravity"
        raise ConfigError(f"at the start {err}", path=path, key=key) from None


def support_of(cfg: ExperimentConfig, sc: Scales, plane: GraspSurface, H1: FloatArray,
             trajectory: Trajectory, sigma0: float, path: str, notes: dict[str, Any]
             ) -> tuple[SupportContact, GraspSurface]:
    """Return the Case 2 contact and its support line at t0 (the follower's first path).

    Errors name the key to change: ``object.gravity`` when gravity has no component
    along the push at the start, ``object.mass_centre`` when no point of the box holds
    the object with a push, ``object.grasp_initial`` when the start needs a pull.
    """
    load = load_of(cfg, sc, path)
    mass, centre, gravity = load.mass, load.mass_centre, load.gravity
    if not isinstance(plane, PlaneBar):  # the schema allows only a plane_bar
        raise ConfigError("a support needs a plane_bar surface", path=path,
                          key="object.surface.type")
    with at_key("object", path):
        contact = SupportContact(mass=mass, mass_centre=centre, gravity=gravity, plane=plane,
                                 H1=H1)
    R0 = trajectory.pose(trajectory.t0)[:3, :3]
    g0 = contact.gravity_in_object(R0)
    if abs(float(g0[0])) <= GRAVITY_ALONG_PUSH_MIN * float(np.linalg.norm(g0)):
        raise ConfigError(
            f"at the start gravity in object coordinates is {np.round(g0, 6).tolist()} m/s^2: "
            "it has no component along the object's x axis (the supporting face's normal), "
            "so the follower's push carries none of the weight; turn the object or gravity",
            path=path, key="object.gravity")
    try:
        line = contact.line(R0)
    except DualArmError as err:
        raise ConfigError(
            "no support at the start: the follower pushes on the support line from the "
            "leader's hand through the mass centre (both projected on the face), on the "
            "side where the push h is > 0, and that part must lie in the box of "
            f"object.surface (r_min, r_max); here: {err}", path=path,
            key="object.mass_centre") from None
    with at_key("object.grasp_initial", path):
        h0 = contact.force(line, sigma0)
    notes["support"] = {
        "mass_kg": mass, "mass_centre_m": centre.tolist(), "gravity_world_m_s2":
        gravity.tolist(), "gravity_object_t0_m_s2": g0.tolist(),
        "line_origin_m": line.origin.tolist(), "line_direction": line.tangent(0.0).tolist(),
        "grasp_range_m": [line.sigma_min, line.sigma_max], "force_t0_N": h0}
    return contact, line


__all__ = ["STANDARD_GRAVITY", "Grasps", "check_load", "grasps_of", "load_of", "support_of",
           "surface_of"]

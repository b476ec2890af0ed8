"""What the MuJoCo plant reads at the end of a sample: the hands' wrenches and the object.

:class:`Readout` holds the compiled model's names (the object body, the grasp points,
the welds, the sensors) and reads, at the current state:

* each hand's wrench on the object from its **force/torque sensor**
  (:mod:`.sensors`), what the plant measures and hands on, and from its **weld's
  constraint force** (:func:`.measure.weld_wrench`), the simulator's own account of
  the same force (a test compares the two);
* what each grasp can transmit (its wrench space, world frame) and the push direction
  (up against gravity; a support's normal), and from them the internal (squeeze) part
  of the pair (:func:`.measure.internal_force`) and the follower's share of the load;
* each weld's position error.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..control.measured import HandReading, load_share
from ..task.loads import rigid_grasp, sliding_grasp, support_push
from ..task.scene import DualArmTask
from .measure import internal_force, space_of, weld_wrench
from .mjcf import CHAIN_MASS, PhysicsModel
from .sensors import sensed_wrench

FloatArray = NDArray[np.float64]

#: MuJoCo's constraint type of an equality (``mjCNSTR_EQUALITY``).
_EQUALITY = 0


class Readout:
    """The hands' wrenches and the object's pose in one compiled model (module docstring).

    Parameters
    ----------
    model, data
        MuJoCo's compiled model and its data.
    physics : PhysicsModel
        The names the model was built with (:func:`~.mjcf.build_mjcf`).
    task : DualArmTask
        The task (its grasps' surfaces and support).
    """

    def __init__(self, model: Any, data: Any, physics: PhysicsModel, task: DualArmTask
                 ) -> None:
        self.model, self.data, self.physics, self.task = model, data, physics, task
        self.obj = model.body("object").id
        self.obj_dof = model.jnt_dofadr[model.joint("object_free").id]
        self.points = {r: model.body(b).id for r, b in physics.points.items()}
        g = np.asarray(physics.gravity, dtype=float)
        self.gravity = g
        self.up = -g / np.linalg.norm(g)

    def point(self, role: str) -> FloatArray:
        """Return the grasp point of ``role`` [m], world."""
        return np.asarray(self.data.xpos[self.points[role]], dtype=float).copy()

    def welds(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Return the hands' wrenches on the object from the welds, and the grasp points."""
        m, d = self.model, self.data
        p_l, p_f = self.point("leader"), self.point("follower")
        w_l = weld_wrench(m, d, self.physics.welds["leader"], self.obj, self.obj_dof, p_l)
        w_f = weld_wrench(m, d, self.physics.welds["follower"], self.obj, self.obj_dof, p_f)
        return w_l, w_f, p_l, p_f

    def sensed(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Return the hands' wrenches on the object from the sensors, and the grasp points."""
        p_l, p_f = self.point("leader"), self.point("follower")
        w_l = sensed_wrench(self.model, self.data, "leader", p_l, CHAIN_MASS, self.gravity)
        w_f = sensed_wrench(self.model, self.data, "follower", p_f, CHAIN_MASS, self.gravity)
        return w_l, w_f, p_l, p_f

    def spaces(self, sigma: float, sigma_leader: float
               ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Return each hand's wrench space (world) and the follower's push direction."""
        task, d = self.task, self.data
        R = d.xmat[self.obj].reshape(3, 3)
        spaces = []
        for role, surface in (("leader", task.leader_surface), ("follower", task.surface)):
            p = d.xpos[self.points[role]]
            if surface is None:
                spaces.append(space_of(rigid_grasp(p).free))
                continue
            s = sigma if role == "follower" else sigma_leader
            if role == "follower" and task.contact is not None:
                spaces.append(space_of(support_push(p, R @ surface.normal(s), 1.0).free))
                continue
            g = sliding_grasp(p, R @ surface.tangent(s), R @ surface.angular_rate(s))
            spaces.append(space_of(g.free))
        push = R @ task.surface.normal(sigma) if task.contact is not None else self.up
        return spaces[0], spaces[1], push

    def reading(self, sigma: float, sigma_leader: float) -> HandReading:
        """Return what the sensors measure now (:class:`HandReading`)."""
        w_l, w_f, p_l, p_f = self.sensed()
        s_l, s_f, push = self.spaces(sigma, sigma_leader)
        size, pair = internal_force((p_l, p_f), (s_l, s_f), (w_l, w_f))
        d = self.data
        quat = np.asarray(d.xquat[self.obj], dtype=float).copy()  # w x y z
        pose = np.r_[d.xpos[self.obj], quat]
        return HandReading(w_l, w_f, size, pair[1], load_share(w_l, w_f, push), pose)

    def deviation(self, D: FloatArray) -> tuple[float, float]:
        """Return the object's distance [m] and turn [rad] from the pose ``D`` (4, 4)."""
        d = self.data
        R = d.xmat[self.obj].reshape(3, 3)
        return (float(np.linalg.norm(d.xpos[self.obj] - D[:3, 3])),
                float(np.linalg.norm(pin.log3(D[:3, :3].T @ R))))

    def weld_error(self, eq: int) -> float:
        """Return weld ``eq``'s position error [m]."""
        d = self.data
        nefc = int(d.nefc)
        rows = np.flatnonzero((d.efc_type[:nefc] == _EQUALITY) & (d.efc_id[:nefc] == eq))
        return float(np.linalg.norm(d.efc_pos[rows[:3]])) if rows.size else 0.0


__all__ = ["Readout"]

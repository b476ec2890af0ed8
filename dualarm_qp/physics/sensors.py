"""The force/torque sensors at both hands: what each hand applies to the object.

Each arm's tool body carries a six-axis sensor (MuJoCo's ``force`` and ``torque``
sensors at the site ``<role>_ft``, :func:`~dualarm_qp.physics.mjcf.build_mjcf`): the
force and moment the arm's last link applies to its tool body, in the site's frame, as
a wrist sensor between a robot's flange and its hand measures them. The tool body
(:data:`~dualarm_qp.physics.mjcf.CHAIN_MASS`) hangs between the sensor and the grasp,
so its weight is taken off, as a real cell compensates its hand's weight:

    w = [R f_s + m_tool g;  R t_s + (p_tool - p) x (R f_s + m_tool g)],

``R`` the site's orientation, ``p_tool`` the sensor's point and ``p`` the grasp point
about which the moment is taken (the leader's tool point, the follower's contact
point: the welds keep them within a fraction of a millimetre). The tool's inertia
(0.1 kg times its acceleration) is not taken off. The wrench is that of
:mod:`dualarm_qp.task.loads`: ``[f; m]`` the hand applies to the object, world frame.

A test compares it with the welds' own constraint forces
(:func:`~dualarm_qp.physics.measure.weld_wrench`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: The six-axis sensors' names in the model, by role: (force, torque, site).
SENSORS = {role: (f"{role}_force", f"{role}_torque", f"{role}_ft")
           for role in ("leader", "follower")}


def sensed_wrench(model: Any, data: Any, role: str, point: FloatArray, tool_mass: float,
                  gravity: FloatArray) -> FloatArray:
    """Return the wrench ``[f; m]`` the ``role`` hand applies to the object (world frame).

    Parameters
    ----------
    model, data
        MuJoCo's model and data after a step (the sensors computed).
    role : {"leader", "follower"}
    point : ndarray, shape (3,)
        The grasp point the moment is taken about [m], world.
    tool_mass : float
        The tool body's mass [kg] between the sensor and the grasp.
    gravity : ndarray, shape (3,)
        [m/s^2], world.
    """
    force, torque, site = SENSORS[role]
    sid = model.site(site).id
    R = data.site_xmat[sid].reshape(3, 3)
    f = R @ data.sensor(force).data + tool_mass * np.asarray(gravity, dtype=float)
    m = R @ data.sensor(torque).data + np.cross(data.site_xpos[sid] - point, f)
    return np.r_[f, m]


__all__ = ["SENSORS", "sensed_wrench"]

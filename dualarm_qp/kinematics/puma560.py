"""The PUMA 560 of the paper's Table 1 (Fu, Gonzalez and Lee; standard DH).

Table 1 gives, in mm and degrees (converted here to SI):

====== ======== ========= ======== ================
joint  alpha    a [mm]    d [mm]   range [deg]
====== ======== ========= ======== ================
1      -90      0         0        -160 .. +160
2      0        431.8     149.09   -225 .. 45
3      90       -20.32    0        -45 .. 225
4      -90      0         433.07   -110 .. 170
5      90       0         0        -100 .. 100
6      0        0         56.25    -266 .. 266
====== ======== ========= ======== ================

No joint offsets, no base or tool transform beyond ``d6`` (the flange is frame 6).

Joint speed limits are not given by the paper. :data:`PUMA560_QD_MAX` is our
documented choice (see ``docs/kinematics.md``): 2 rad/s (115 deg/s) for the three
arm joints and 4 rad/s (229 deg/s) for the wrist, which keeps the flange speed of the
fully stretched arm below about 2 m/s. Override them with ``qd_max=`` for a real arm.

Joint acceleration limits are not given either. :data:`PUMA560_QDD_MAX` is our
documented choice too: each joint may reach its speed limit from rest in 0.2 s, i.e.
10 rad/s^2 for the arm joints and 20 rad/s^2 for the wrist. They are used only when a
run asks for acceleration limits; override them with ``qdd_max=``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .arm import DHTable, SerialArm

#: Table 1 link twists [rad].
PUMA560_ALPHA = np.deg2rad([-90.0, 0.0, 90.0, -90.0, 90.0, 0.0])
#: Table 1 link lengths [m].
PUMA560_A = np.array([0.0, 431.8, -20.32, 0.0, 0.0, 0.0]) * 1e-3
#: Table 1 link offsets [m].
PUMA560_D = np.array([0.0, 149.09, 0.0, 433.07, 0.0, 56.25]) * 1e-3
#: Table 1 joint ranges [rad].
PUMA560_Q_MIN = np.deg2rad([-160.0, -225.0, -45.0, -110.0, -100.0, -266.0])
PUMA560_Q_MAX = np.deg2rad([160.0, 45.0, 225.0, 170.0, 100.0, 266.0])
#: Joint speed limits [rad/s] (our choice, see the module docstring).
PUMA560_QD_MAX = np.array([2.0, 2.0, 2.0, 4.0, 4.0, 4.0])
#: Joint acceleration limits [rad/s^2]: the speed limits reached from rest in 0.2 s.
PUMA560_QDD_MAX = PUMA560_QD_MAX / 0.2


def puma560(base: Any = None, *, tool: Any = None, qd_max: Any = None,
            qdd_max: Any = None, name: str = "puma560") -> SerialArm:
    """Build the paper's Table 1 PUMA 560 in SI units (m, rad).

    Parameters
    ----------
    base : array_like, shape (4, 4), optional
        ``T_world_base`` [m]; identity by default.
    tool : array_like, shape (4, 4), optional
        ``T_flange_tool`` [m]; identity by default (the paper's frame 6).
    qd_max : array_like, shape (6,), optional
        Joint speed limits [rad/s]; default :data:`PUMA560_QD_MAX`.
    qdd_max : array_like, shape (6,), optional
        Joint acceleration limits [rad/s^2]; default :data:`PUMA560_QDD_MAX`.
    name : str
        Label used in messages.

    Returns
    -------
    SerialArm
        A 6-joint standard-DH arm with Table 1 joint ranges.
    """
    dh = DHTable(PUMA560_A, PUMA560_ALPHA, PUMA560_D, np.zeros(6), "standard")
    arm = SerialArm(
        dh,
        q_min=PUMA560_Q_MIN,
        q_max=PUMA560_Q_MAX,
        qd_max=PUMA560_QD_MAX if qd_max is None else qd_max,
        qdd_max=PUMA560_QDD_MAX if qdd_max is None else qdd_max,
        base=base,
        tool=tool,
        name=name,
    )
    arm.source = "preset:puma560"
    return arm

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

**Link inertias.** The paper gives none. The model carries the published parameters of
B. Armstrong, O. Khatib and J. Burdick, "The explicit dynamic model and inertial
parameters of the PUMA 560 arm", Proc. IEEE ICRA 1986, pp. 510-518 (as transcribed in
P. Corke's Robotics Toolbox, model ``puma560akb``): masses [kg], centres [m] and
inertias about the centre [kg m^2], each in that paper's link frame, which follows the
*modified* DH convention (:data:`PUMA560_AKB_MASS` .. :data:`PUMA560_AKB_INERTIA`).
Link 1's mass was not identified (it moves about a vertical axis: no gravity torque),
only its inertia about joint 1. Their twists and link lengths are Table 1's, so each of
their link frames ``i`` has the axes of our joint frame ``i`` (DH frame ``i - 1`` turned
by ``q_i``) and sits on joint axis ``i`` at :data:`PUMA560_AKB_SHIFT` along it: 243.5 mm
for link 2 (their ``d2``, from the shoulder centre), Table 1's ``d4`` for link 4 (the
wrist centre), 0 otherwise. Each centre is moved by that shift; inertias about the
centre keep their axes. (The two sources' offsets differ by at most 1 mm: their
``d2 + d3`` is 150.1 mm against Table 1's 149.09 mm, ``d4`` 433.1 against 433.07 mm;
the kinematics stay Table 1's.) ``docs/kinematics.md`` states the conversion and how it
is tested.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

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

#: Link masses [kg] (Armstrong, Khatib and Burdick 1986; link 1 not identified).
PUMA560_AKB_MASS = np.array([0.0, 17.4, 4.8, 0.82, 0.34, 0.09])
#: Link mass centres [m], each in that paper's (modified DH) link frame.
PUMA560_AKB_CENTRE = np.array([[0.0, 0.0, 0.0], [0.068, 0.006, -0.016],
                               [0.0, -0.070, 0.014], [0.0, 0.0, -0.019],
                               [0.0, 0.0, 0.0], [0.0, 0.0, 0.032]])
#: Principal inertias ``(Ixx, Iyy, Izz)`` about each centre [kg m^2], same frames (link 1:
#: about joint 1's axis).
PUMA560_AKB_INERTIA = np.array([[0.0, 0.0, 0.35], [0.13, 0.524, 0.539],
                                [0.066, 0.0125, 0.066], [1.8e-3, 1.8e-3, 1.3e-3],
                                [0.3e-3, 0.3e-3, 0.4e-3], [0.15e-3, 0.15e-3, 0.04e-3]])
#: Where each of that paper's link frames sits on its joint axis, from our joint frame
#: (the z-offset of frame ``i`` along axis ``i``) [m].
PUMA560_AKB_SHIFT = np.array([0.0, 0.2435, 0.0, 433.07e-3, 0.0, 0.0])


def puma560_inertias() -> list[pin.Inertia]:
    """Return the links' inertias in our joint frames (see the module docstring).

    Link ``i``'s centre moves by :data:`PUMA560_AKB_SHIFT` ``[i]`` along z; its inertia
    about the centre keeps its axes (the frames differ by that shift only).
    """
    out = []
    for m, c, inertia, dz in zip(PUMA560_AKB_MASS, PUMA560_AKB_CENTRE, PUMA560_AKB_INERTIA,
                                 PUMA560_AKB_SHIFT, strict=True):
        out.append(pin.Inertia(float(m), c + np.array([0.0, 0.0, dz]), np.diag(inertia)))
    return out


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
        A 6-joint standard-DH arm with Table 1 joint ranges, its model carrying the
        links' inertias (:func:`puma560_inertias`).
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
    arm.set_link_inertias(puma560_inertias())
    arm.source = "preset:puma560"
    return arm

"""The kernel's chain, waypoint path and support plane pickle themselves.

A pickle (and ``copy.deepcopy``) of a ``kernel.Chain`` holds the chain as it is now: its
joints and frames with the placements set since it was made, each joint's body and
gravity. The copy computes bit for bit what the original computes.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from dualarm_qp._compiled import kernel
from dualarm_qp.kinematics import SerialArm, puma560
from dualarm_qp.kinematics.compiled import compiled_chain
from dualarm_qp.task.torques import ArmStatics


def _puma() -> SerialArm:
    return puma560()


def _moved_chain() -> kernel.Chain:
    """A PUMA chain with a joint moved, the universe's frame moved, bodies and gravity."""
    arm = _puma()
    chain = compiled_chain(arm.model)
    T = np.eye(4)
    T[:3, 3] = [0.01, -0.02, 0.03]
    chain.set_joint_placement(2, arm.model.jointPlacements[2].homogeneous @ T)
    chain.set_frame_placement(0, T)
    rng = np.random.default_rng(7)
    for j in range(1, chain.njoints):
        A = rng.normal(size=(3, 3))
        chain.set_inertia(j, 1.0 + j, rng.normal(size=3) * 0.1, A @ A.T)
    chain.set_gravity(np.array([0.3, -0.2, -9.81]))
    return chain


def _outputs(chain: kernel.Chain, q: np.ndarray) -> list[np.ndarray]:
    frames = list(range(chain.nframes))
    T = np.empty((4 * len(frames), 4))
    J = np.empty((6 * len(frames), chain.nq))
    chain.compute(q, frames, frames, T, J)
    wrench = np.array([1.0, -2.0, 3.0, 0.1, 0.2, -0.3])
    st = chain.static_torques(q, chain.nframes - 1, wrench, None, True)
    return [T, J, st.tau, st.dtau, st.J]


@pytest.mark.parametrize("copier", [lambda c: pickle.loads(pickle.dumps(c)), copy.deepcopy],
                         ids=["pickle", "deepcopy"])
def test_a_chain_copies_itself_as_it_is_now(copier) -> None:
    chain = _moved_chain()
    twin = copier(chain)
    assert twin is not chain and twin.nq == chain.nq and twin.nframes == chain.nframes
    q = np.linspace(-0.7, 0.9, chain.nq)
    for a, b in zip(_outputs(chain, q), _outputs(twin, q), strict=True):
        np.testing.assert_array_equal(a, b)
    # The moved joint and frame, the bodies and the gravity are in the copy: a chain made
    # afresh from the arm's model computes something else.
    fresh = compiled_chain(_puma().model)
    fresh_T = _outputs(fresh, q)[0]
    assert not np.array_equal(fresh_T, _outputs(twin, q)[0])


def test_the_state_names_its_parts() -> None:
    state = _moved_chain().__getstate__()
    assert set(state) == {"parents", "kinds", "axes", "placements", "frame_parents",
                          "frame_placements", "universe", "masses", "levers", "inertias",
                          "gravity"}
    np.testing.assert_array_equal(state["gravity"], [0.3, -0.2, -9.81])
    assert state["universe"][0, 3] == 0.01


def test_arm_statics_pickle_with_their_chain() -> None:
    arm = _puma()
    statics = ArmStatics(arm, np.array([0.0, 0.0, -9.81]))
    twin = pickle.loads(pickle.dumps(statics))
    q = np.linspace(-0.5, 0.5, arm.n)
    w = np.array([0.0, 0.0, -20.0, 0.0, 0.5, 0.0])
    np.testing.assert_array_equal(twin.torque(q, w), statics.torque(q, w))
    np.testing.assert_array_equal(twin.chain.__getstate__()["masses"],
                                  statics.chain.__getstate__()["masses"])


def test_a_waypoint_path_copies_itself() -> None:
    Ts = [np.eye(4) for _ in range(3)]
    Ts[1][:3, 3] = [0.1, 0.2, 0.3]
    c, s = np.cos(0.4), np.sin(0.4)
    Ts[2][:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    Ts[2][:3, 3] = [0.4, 0.0, -0.1]
    poses = np.concatenate(Ts)
    path = kernel.WaypointPath([0.0, 1.0, 2.5], poses)
    twin = pickle.loads(pickle.dumps(path))
    np.testing.assert_array_equal(twin.__getstate__()["poses"], poses)
    for t in (0.0, 0.3, 1.7, 2.5):
        a, b = np.empty((4, 4)), np.empty((4, 4))
        path.pose(t, a)
        twin.pose(t, b)
        np.testing.assert_array_equal(a, b)
        da, db = np.empty(6), np.empty(6)
        path.derivative(t, 1, da)
        twin.derivative(t, 1, db)
        np.testing.assert_array_equal(da, db)


def test_a_support_plane_copies_itself_as_given() -> None:
    args = dict(mass=4.0, mass_centre=np.array([0.2, 0.0, 0.0]),
                gravity=np.array([0.0, 0.0, -9.81]), r1=np.array([0.0, 0.0, 0.0]),
                normal=np.array([0.0, 0.0, 3.0]), offset=0.01,
                r_min=np.array([0.1, -0.05, -np.inf]), r_max=np.array([0.5, 0.05, np.inf]),
                gravity_min=0.01)
    plane = kernel.SupportPlane(**args)
    twin = pickle.loads(pickle.dumps(plane))
    state = twin.__getstate__()
    np.testing.assert_array_equal(state["normal"], [0.0, 0.0, 3.0])  # as given, not unit
    R = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    a, b = plane.line(R), twin.line(R)
    assert a.held == b.held
    np.testing.assert_array_equal(a.direction, b.direction)

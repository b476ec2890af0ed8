"""Markers of the 3D view a person must find: the grasp."""

from __future__ import annotations

from dualarm_qp.task.surfaces import CylinderSurface, PlaneBar
from dualarm_qp.viz.scene import BAR_WIDTH, object_parts


def test_the_grasp_marker_is_scaled_to_the_object() -> None:
    short = object_parts(PlaneBar())["grasp_radius"]  # 0.4 m: the paper's bar
    long = object_parts(PlaneBar(r_max=(0.0, 0.0, 3.0)))["grasp_radius"]
    assert short > BAR_WIDTH / 2  # wider than the bar: seen beside the gripper
    assert long > 2.0 * short  # and grows with the object
    thick = CylinderSurface(0.08, sigma_min=0.0, sigma_max=0.4)
    assert object_parts(thick)["grasp_radius"] > 0.08  # wider than the cylinder

"""Markers of the 3D view a person must find: the grasp, and the joint axes (explained in
the legend, all of them or only those near a limit, on a toggle)."""

from __future__ import annotations

import re

import pytest

from dualarm_qp.task.surfaces import CylinderSurface, PlaneBar
from dualarm_qp.viz.page import render_page
from dualarm_qp.viz.scene import BAR_WIDTH, describe_scene, object_parts


def test_the_grasp_marker_is_scaled_to_the_object() -> None:
    short = object_parts(PlaneBar())["grasp_radius"]  # 0.4 m: the paper's bar
    long = object_parts(PlaneBar(r_max=(0.0, 0.0, 3.0)))["grasp_radius"]
    assert short > BAR_WIDTH / 2  # wider than the bar: seen beside the gripper
    assert long > 2.0 * short  # and grows with the object
    thick = CylinderSurface(0.08, sigma_min=0.0, sigma_max=0.4)
    assert object_parts(thick)["grasp_radius"] > 0.08  # wider than the cylinder


def test_capsule_arms_show_every_joint_axis(beam) -> None:
    scene = describe_scene(beam.task, t_start=0.0, t_end=1.0)
    assert scene["all_joint_axes"] is True


@pytest.mark.slow
def test_mesh_arms_show_only_the_axes_of_joints_near_a_limit(ur5_pair) -> None:
    scene = describe_scene(ur5_pair.task, t_start=0.0, t_end=1.0)
    assert scene["all_joint_axes"] is False  # rods out of every joint hid the meshes


def test_the_legend_explains_the_joint_axes_and_the_page_can_show_them_all(beam) -> None:
    pytest.importorskip("meshcat")
    page = render_page({"scene": describe_scene(beam.task, t_start=0.0, t_end=1.0),
                        "frames": None}, title="beam")
    panel = page[page.index('class="legend"'):page.index('id="notes"')]
    legend = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", panel))
    assert "joint axis: near a limit outside its range" in legend
    assert '<input type="checkbox" id="all-axes">' in page
    assert "every joint axis" in legend

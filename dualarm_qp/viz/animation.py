"""A run's 3D animation: one HTML file that opens offline, with no server.

:func:`write_animation` draws a task and a recorded ``trajectory.csv``. Rebuilding the
task of a finished run folder is the experiments layer's job
(:func:`dualarm_qp.experiments.animate.animate_run`, ``dualarm-qp animate RUN_DIR``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._io import write_text
from ..errors import InvalidInputError
from ..task.scene import DualArmTask
from .frames import Timeline, frame_payload, read_timeline
from .page import render_page
from .scene import describe_scene

#: The file name of a run's animation.
ANIMATION_FILE = "animation.html"


def animation_html(task: DualArmTask, timeline: Timeline, *, title: str = "") -> str:
    """Return the animation page of a recorded motion.

    Parameters
    ----------
    task : DualArmTask
        The task the motion was recorded on (arms, object, path).
    timeline : Timeline
        The recorded samples (:func:`~dualarm_qp.viz.frames.read_timeline`).
    title : str
        Shown on the page.
    """
    if len(timeline) == 0:
        raise InvalidInputError("no samples to animate")
    scene = describe_scene(task, t_start=float(np.min(timeline.path_t)),
                           t_end=float(np.max(timeline.path_t)), grasps=timeline.grasp,
                           title=title)
    return render_page({"scene": scene, "frames": frame_payload(task, timeline)},
                       title=title or "dualarm_qp animation")


def write_animation(path: str | Path, task: DualArmTask, trajectory_csv: str | Path, *,
                    title: str = "") -> Path:
    """Write the animation of a recorded ``trajectory.csv`` to ``path``, atomically.

    Returns
    -------
    Path
        ``path``.
    """
    out = Path(path)
    write_text(out, animation_html(task, read_timeline(trajectory_csv), title=title))
    return out

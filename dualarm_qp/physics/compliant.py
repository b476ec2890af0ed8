"""The closed loop's compliant follower: the experiment's step with it, fed by the plant.

With ``physics.compliance`` (:class:`~dualarm_qp.physics.settings.PhysicsSettings`), the
closed loop's step takes the compliant grasp closure of
:mod:`dualarm_qp.physics.compliance` in place of the standard one, and the MuJoCo
plant updates its wrench measurement with each state it hands the controller.
"""

from __future__ import annotations

import dataclasses
from typing import cast

from ..experiments.setup import Experiment
from ..step.parts import Task
from .compliance import ComplianceTask
from .plant import MujocoPlant


def compliant_experiment(exp: Experiment, plant: MujocoPlant) -> Experiment:
    """Return ``exp`` with the compliant follower of ``plant.settings.compliance``.

    The task's measurement is the plant's (:attr:`MujocoPlant.measurement`). Without
    ``compliance`` in the settings, ``exp`` as it is.
    """
    gains = plant.settings.compliance
    if gains is None:
        return exp
    task = ComplianceTask(float(exp.options.correction_gain or 0.0), plant.load, gains,
                          exact_orientation=exp.options.exact_orientation)
    plant.measurement = task.measurement
    # A kernel task (its weight a float, infinite for equality rows) is a step's Task.
    return dataclasses.replace(exp, tasks_extra=(*exp.tasks_extra, cast("Task", task)))


__all__ = ["compliant_experiment"]

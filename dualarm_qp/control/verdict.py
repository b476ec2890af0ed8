"""After the loop: the run's verdict, from what the loop left and what the trace records.

In order, the first that applies fails the run: the loop's own failure (a sample's
criterion, :mod:`.sample_checks`), an interrupt (``"interrupted"``), a path not executed
to its end (``"path_incomplete"``), for a solver that claims hard limits the realised
motion (``"range"``, ``"speed"``, ``"acceleration"``), the recorded clearance with
collision avoidance on (``"collision"``) and the recorded torques with torque limits on
(``"torque"``); a breach measured with a plant is a warning instead (the state was
measured, not commanded). Then a failure that a collision pair or a joint's torque
caused is relabelled, and one whose cause can be named says it (:mod:`.diagnosis`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..collision.clearance import ClearanceReport
from ..errors import DualArmError
from .collisions import blocked_by_pair, record_clearance
from .controller import DualArmController
from .failure import EXPLAINED, Failure
from .loads import LoadReport, record_loads
from .plant import Plant
from .realised import LimitReport
from .realised_checks import (
    clearance_failure,
    realised_failure,
    realised_reports,
    torque_failure,
)
from .run_loop import LoopOutcome, end_tolerance
from .torques import TorqueReport, blocked_by_torque, record_torques
from .trace import Trace, record_margins

FloatArray = NDArray[np.float64]


@dataclass
class Verdict:
    """How the run ended, and the records that decided it.

    Attributes
    ----------
    failure : Failure or None
        Why the run failed; None when it completed.
    warnings : list of str
        What a person should know although the run may have completed.
    realised : dict of str to LimitReport
        The realised motion against the limits (:func:`.realised_checks.realised_reports`).
    clearance : ClearanceReport or None
        The recorded clearance (a task with a collision scene).
    torque : TorqueReport or None
        The recorded joint torques (a task with a load, or torque limits).
    loads : LoadReport or None
        The wrench each hand applied (a task with a load).
    """

    failure: Failure | None
    warnings: list[str]
    realised: dict[str, LimitReport]
    clearance: ClearanceReport | None
    torque: TorqueReport | None
    loads: LoadReport | None


def judge(controller: DualArmController, loop: LoopOutcome, *, v_start: FloatArray,
          path_start: float, duration: float, cap: float, plant: Plant | None) -> Verdict:
    """Return the verdict of the run the loop left (see the module docstring).

    Parameters
    ----------
    controller : DualArmController
        The controller that ran.
    loop : LoopOutcome
        What the loop left (its trace gets the margins to the ranges written here).
    v_start : ndarray
        The rates the run started with (decision order).
    path_start : float
        Path time at the start [s].
    duration : float
        Length of the path [s].
    cap : float
        Longest run [s].
    plant : Plant, optional
        What the commands drove (then a realised breach is a warning).
    """
    task, dt, trace = controller.task, controller.options.dt, loop.trace
    warnings = loop.warnings
    record_margins(trace, task)
    realised = realised_reports(controller, trace, dt, v_start)
    failure = _end_failure(loop, path_start, duration, cap)
    if failure is None and controller.hard_bounds:
        failure = realised_failure(realised, trace, dt)
        if failure is not None and plant is not None:  # measured, not commanded: tell
            warnings.append(f"the measured motion left a limit: {failure.message}")
            failure = None
    clearance = record_clearance(task, trace)
    loads = record_loads(task, trace)  # the wrench each hand applies (a task with a load)
    torque = record_torques(controller, trace)  # each joint's torque (a load or limits)
    if loads is not None and loads.warning():
        warnings.append(str(loads.warning()))
    if task.scene is not None:
        overlapping = task.scene.overlapping_at_start()
        if overlapping:
            warnings.append("collision pairs left out because their shapes overlap at the "
                            f"start (not checked during the run): {', '.join(overlapping)}; "
                            "move the arms apart or add the pairs to collision.exclude")
    failure = _recorded_failure(failure, clearance, torque, trace, warnings, plant)
    failure = _relabelled(controller, trace, failure, plant, loop.plant_lag)
    return Verdict(failure, warnings, realised, clearance, torque, loads)


def _end_failure(loop: LoopOutcome, path_start: float, duration: float, cap: float
                 ) -> Failure | None:
    """Return the loop's failure, or else an interrupt's, or a path not executed to its end."""
    trace, rows, failure = loop.trace, len(loop.trace), loop.failure
    if loop.interrupted is not None:
        t_last = float(trace.t[-1]) if rows else path_start
        failure = Failure("interrupted", max(rows - 1, 0), t_last, math.nan, math.nan,
                          f"interrupted ({str(loop.interrupted) or 'KeyboardInterrupt'}) "
                          f"after {rows} samples, at t = {t_last:.4f} s")
    path_end = path_start + duration
    if failure is None and len(trace) and trace.tau[-1] < path_end - end_tolerance(path_end):
        done = (trace.tau[-1] - path_start) / duration
        failure = Failure(
            "path_incomplete", len(trace) - 1, float(trace.t[-1]), done, 1.0,
            f"path not completed: {100 * done:.1f}% of the path in {cap:g} s "
            f"(the duration cap; the task was slowed)")
    return failure


def _recorded_failure(failure: Failure | None, clearance: ClearanceReport | None,
                      torque: TorqueReport | None, trace: Trace, warnings: list[str],
                      plant: Plant | None) -> Failure | None:
    """Return ``failure``, or else the recorded clearance's or torques' (appends warnings)."""
    if clearance is not None:
        if failure is None and clearance.enforced and not clearance.kept:
            failure = clearance_failure(clearance, trace)
        elif clearance.minimum < 0.0 and not clearance.enforced:
            warnings.append(f"the recorded motion penetrates: {clearance.pair} at "
                            f"{clearance.minimum * 1e3:.1f} mm (sample {clearance.sample}; "
                            "collision avoidance is off)")
    if torque is not None and failure is None and torque.enforced and not torque.kept:
        if plant is None:
            failure = torque_failure(torque, trace)
        else:  # quasi-static torques at measured states, not commanded ones: tell
            warnings.append("the measured motion left a limit: "
                            f"{torque_failure(torque, trace).message}")
    return failure


def _relabelled(controller: DualArmController, trace: Trace, failure: Failure | None,
                plant: Plant | None, plant_lag: bool) -> Failure | None:
    """Return ``failure`` relabelled by the pair or torque that caused it, and explained."""
    if failure is not None and failure.criterion in (*EXPLAINED, "solver") and len(trace):
        failure = blocked_by_pair(controller, trace, failure)
    if (failure is not None and plant is None
            and failure.criterion in (*EXPLAINED, "solver") and len(trace)):
        # With a plant, a failure at a measured state may be the plant's own (a diverged
        # simulation): it is not relabelled.
        failure = blocked_by_torque(controller, trace, failure)
    if failure is not None and failure.criterion in EXPLAINED and len(trace) and not plant_lag:
        failure = _explained(controller, trace, failure)
    return failure


def _explained(controller: DualArmController, trace: Trace, failure: Failure) -> Failure:
    """``failure`` with its cause appended (:func:`.diagnosis.explain` at its sample)."""
    k = min(failure.sample, len(trace) - 1)
    state = trace.state(k)
    try:
        why = controller.explain(state)
    except DualArmError:  # the state itself cannot be posed: say nothing more
        return failure
    return dataclasses.replace(failure, message=f"{failure.message}; {why}")


__all__ = ["Verdict", "judge"]

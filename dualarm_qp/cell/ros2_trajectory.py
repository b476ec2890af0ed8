"""A verified run sent whole to ros2_control: ``drive --cell ros2 --send-run [RUN_DIR]``.

Instead of streaming a command every sample, the whole motion of a run that completed
(the file's run folder, or a fresh rollout of the file when no folder is given) goes to
each arm's ``joint_trajectory_controller`` as one ``trajectory_msgs/JointTrajectory``
on ``<trajectory_controller>/joint_trajectory``: one point per recorded sample (the
recorded joints [rad] and the rates commanded there [rad/s], ``time_from_start`` from
the run's first sample). Both messages carry **one header stamp**, a moment just ahead
on the node's ROS clock (:data:`LEAD` or ten samples, the longer), so that both
controllers start the motion at the same instant.

The node then watches both arms' joint states on the same clock until the motion's end
(and a few samples more), each sample comparing the measured joints with the run's at
that time. The robots must be at the run's start (``start_tolerance``) before it is
sent; a state older than the watchdog, or Ctrl-C / SIGTERM, sends both controllers an
empty trajectory (a ``joint_trajectory_controller`` then holds the joints where they
are) and ends the watch. The folder written holds ``sent.json`` (what was sent, when,
and how the arms followed: the largest and the final distance from the run's joints)
and ``measured.csv`` (per sample of the watch: the time from the start, the state's
age, the measured and the run's joints).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_open, write_json
from .._signals import SignalHold
from ..errors import InvalidInputError
from ..experiments.setup import Experiment
from .base import CellError, Reading
from .ros2 import Ros2Cell
from .settings import DriveSettings

FloatArray = NDArray[np.float64]

#: How far ahead of the node's clock the motion starts at least [s].
LEAD = 0.5
#: The files the watch writes.
OUTPUT_FILES = ("sent.json", "measured.csv")


@dataclass(frozen=True)
class Plan:
    """The motion to send: a completed run's recorded joints and rates.

    Attributes
    ----------
    t : ndarray, shape (rows,)
        Time from the run's first sample [s].
    q_l, q_f : ndarray
        The recorded joints [rad], one row per sample.
    ql_dot, qf_dot : ndarray
        The rates commanded at each sample [rad/s] (zero at the last).
    source : str
        Where it came from (a folder, or ``"rollout"``).
    """

    t: FloatArray
    q_l: FloatArray
    q_f: FloatArray
    ql_dot: FloatArray
    qf_dot: FloatArray
    source: str

    @property
    def duration(self) -> float:
        """Length of the motion [s]."""
        return float(self.t[-1]) if len(self.t) else 0.0

    def at(self, tau: float) -> tuple[FloatArray, FloatArray]:
        """Return both arms' joints at ``tau`` [s] from the start (linear between samples)."""
        q_l = np.array([np.interp(tau, self.t, col) for col in self.q_l.T])
        q_f = np.array([np.interp(tau, self.t, col) for col in self.q_f.T])
        return q_l, q_f


def _plan(t: FloatArray, q_l: FloatArray, q_f: FloatArray, ql_dot: FloatArray,
          qf_dot: FloatArray, source: str) -> Plan:
    ql_dot, qf_dot = ql_dot.copy(), qf_dot.copy()
    ql_dot[-1] = 0.0  # at rest at the end, as the run's last sample
    qf_dot[-1] = 0.0
    return Plan(t - t[0], q_l, q_f, np.nan_to_num(ql_dot), np.nan_to_num(qf_dot), source)


def plan_from_run(run_dir: str | Path, exp: Experiment) -> Plan:
    """Return the motion of a completed run folder of the same arms.

    Raises
    ------
    InvalidInputError
        Not a run folder, a run that did not complete, or arms of other sizes.
    """
    from ..experiments.animate import read_run_summary
    from ..experiments.figures.rundata import RunData

    run = Path(run_dir)
    summary = read_run_summary(run)
    if summary.get("status") != "completed":
        raise InvalidInputError(f"{run}: the run did not complete (status "
                                f"{summary.get('status')!r}); only a verified run is sent")
    data = RunData.read(run / "trajectory.csv")
    n_l, n_f = exp.task.leader.n, exp.task.follower.n
    if (data.n_joints("l"), data.n_joints("f")) != (n_l, n_f) or len(data) < 2:
        raise InvalidInputError(f"{run}: its arms have {data.n_joints('l')} and "
                                f"{data.n_joints('f')} joints over {len(data)} samples; the "
                                f"file's have {n_l} and {n_f}")
    keep = np.array([s != "stopping" for s in data.columns["status"]])
    return _plan(data.col("t")[keep], data.joints("l")[keep], data.joints("f")[keep],
                 data.commanded_rates("l")[keep], data.commanded_rates("f")[keep], str(run))


def plan_from_rollout(exp: Experiment) -> Plan:
    """Roll the file out (nothing written) and return its motion.

    Raises
    ------
    InvalidInputError
        The rollout did not complete.
    """
    from ..experiments.run import run_experiment

    outcome = run_experiment(exp, None, progress=False, plots=False)
    if not outcome.ok:
        raise InvalidInputError(f"the file's run did not complete ({outcome.result.message}); "
                                "only a verified run is sent")
    tr = outcome.result.trace
    return _plan(tr.t, tr.q_l, tr.q_f, tr.ql_dot, tr.qf_dot, "rollout")


def trajectory_message(types: Any, joints: tuple[str, ...], stamp: Any, plan: Plan,
                       arm: int) -> Any:
    """Return one arm's ``JointTrajectory`` of ``plan`` (``arm`` 0: leader, 1: follower)."""
    q, v = (plan.q_l, plan.ql_dot) if arm == 0 else (plan.q_f, plan.qf_dot)
    msg = types.JointTrajectory(joint_names=list(joints))
    msg.header.stamp = stamp
    for k, tau in enumerate(plan.t):
        ns = round(float(tau) * 1e9)
        msg.points.append(types.JointTrajectoryPoint(
            positions=[float(x) for x in q[k]], velocities=[float(x) for x in v[k]],
            time_from_start=types.Duration(sec=ns // 1_000_000_000,
                                           nanosec=ns % 1_000_000_000)))
    return msg


@dataclass
class Watch:
    """What the arms did while the motion ran (one row per sample of the watch)."""

    tau: list[float]
    age: list[float]
    measured: list[FloatArray]
    planned: list[FloatArray]

    def deviation(self) -> FloatArray:
        """Return the largest joint distance from the run's joints per row [rad]."""
        return np.array([float(np.max(np.abs(m - p))) for m, p in
                         zip(self.measured, self.planned, strict=True)])


def _hold(cell: Ros2Cell) -> None:
    """Send both controllers an empty trajectory: hold the joints where they are."""
    assert cell.node is not None
    t = cell.node.types
    for pub, arm in zip(cell.publishers, cell.settings.arms, strict=True):
        pub.publish(t.JointTrajectory(joint_names=list(arm.joints)))


def _watch(cell: Ros2Cell, plan: Plan, start: float, watchdog: float, dt: float,
           watch: Watch) -> str:
    """Follow the motion until its end; return why the watch ended."""
    k = 0
    end = start + plan.duration + 10 * dt
    while True:
        t_k = start + k * dt
        if t_k > end:
            return "end"
        cell.wait_until(t_k)
        r: Reading = cell.read()
        age = cell.now() - r.t
        tau = r.t - start
        q_l, q_f = plan.at(max(tau, 0.0))
        watch.tau.append(tau)
        watch.age.append(age)
        watch.measured.append(np.r_[r.q_l, r.q_f])
        watch.planned.append(np.r_[q_l, q_f])
        if age > watchdog:
            return "watchdog"
        k += 1


def send_run(cell: Ros2Cell, plan: Plan, *, watchdog: float, start_tolerance: float,
             dt: float) -> tuple[dict[str, Any], Watch]:
    """Send ``plan`` to both arms' trajectory controllers and watch it run (see the module).

    Returns
    -------
    summary : dict
        What ``sent.json`` holds; ``status`` is ``completed``, ``failed`` or
        ``interrupted``.
    watch : Watch
        The samples of the watch.
    """
    watch = Watch([], [], [], [])
    summary: dict[str, Any] = {"source": plan.source, "points": len(plan.t),
                               "duration_s": plan.duration, "watchdog_s": watchdog,
                               "topics": [a.trajectory_topic for a in cell.settings.arms]}
    try:
        first = cell.open()
        off = float(np.max(np.abs(np.r_[first.q_l - plan.q_l[0], first.q_f - plan.q_f[0]])))
        summary["start_offset_rad"] = off
        if off > start_tolerance:
            return dict(summary, status="failed", reason="start",
                        message=f"the robots are not at the run's start: a joint is {off:.4g} "
                                f"rad from it (start_tolerance {start_tolerance:g} rad)"), watch
        assert cell.node is not None
        start = cell.now() + max(LEAD, 10 * dt)
        stamp = _stamp(cell, start)
        for i, (pub, arm) in enumerate(zip(cell.publishers, cell.settings.arms, strict=True)):
            pub.publish(trajectory_message(cell.node.types, arm.joints, stamp, plan, i))
        summary["start_s"] = start
        reason = _watch(cell, plan, start, watchdog, dt, watch)
    except KeyboardInterrupt:
        reason = "interrupted"
    except CellError as err:
        reason = "cell"
        summary["message"] = str(err)
    if reason != "end":
        with SignalHold():
            try:
                if cell.node is not None and cell.publishers:
                    _hold(cell)
            except CellError:
                pass
    cell.close()
    dev = watch.deviation()
    summary.update(reason=reason, samples=len(watch.tau),
                   deviation_max_rad=float(np.max(dev, initial=0.0)),
                   deviation_end_rad=float(dev[-1]) if len(dev) else math.nan)
    ok = reason == "end" and summary["deviation_end_rad"] <= start_tolerance
    summary["status"] = ("completed" if ok else
                         "interrupted" if reason == "interrupted" else "failed")
    summary.setdefault("message", f"watch ended ({reason}); the arms ended "
                       f"{summary['deviation_end_rad']:.4g} rad from the run's end")
    return summary, watch


def _stamp(cell: Ros2Cell, t: float) -> Any:
    assert cell.node is not None
    ns = round(t * 1e9)
    return cell.node.types.Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def write_watch(out: Path, summary: dict[str, Any], watch: Watch, n_l: int) -> None:
    """Write ``sent.json`` and ``measured.csv`` into ``out`` (each whole or not at all)."""
    buf = io.StringIO()
    w = csv.writer(buf)
    n = len(watch.measured[0]) if watch.measured else n_l
    w.writerow(["tau", "state_age"]
               + [f"ql{j + 1}" for j in range(n_l)] + [f"qf{j + 1}" for j in range(n - n_l)]
               + [f"ql{j + 1}_run" for j in range(n_l)]
               + [f"qf{j + 1}_run" for j in range(n - n_l)])
    for tau, age, m, p in zip(watch.tau, watch.age, watch.measured, watch.planned,
                              strict=True):
        w.writerow([repr(tau), repr(age), *(repr(float(x)) for x in m),
                    *(repr(float(x)) for x in p)])
    with SignalHold():
        with atomic_open(out / "measured.csv") as fh:
            fh.write(buf.getvalue())
        write_json(out / "sent.json", summary)


__all__ = ["LEAD", "OUTPUT_FILES", "Plan", "Watch", "plan_from_rollout", "plan_from_run",
           "send_run", "trajectory_message", "write_watch"]


def cmd_send_run(args: Any, cfg: Any, exp: Experiment, path: str, guards: DriveSettings
                 ) -> int:
    """``drive --cell ros2 --send-run [RUN_DIR]``: exit 0 followed, 1 not, 130 interrupted.

    ``guards``: the file's watchdog and start tolerance (:func:`.command.drive_settings`).
    """
    from ..cli_commands import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, output_folder, print_error
    from ..experiments.config import safe_name
    from ..experiments.outputs import check_unused_folder
    from .ros2 import ros2_settings
    from .ros2_node import ros_types

    if args.dry_run:
        raise InvalidInputError("--send-run sends the run: it has no dry run")
    settings = ros2_settings(cfg, exp, path, need="trajectory_controller")
    plan = None if args.send_run == "rollout" else plan_from_run(args.send_run, exp)
    ros_types()  # before a rollout: say at once when rclpy is missing
    plan = plan_from_rollout(exp) if plan is None else plan
    out = Path(args.out if args.out else Path("runs") / safe_name(exp.name)
               / "cell_ros2_trajectory")
    check_unused_folder(out, force=args.force, what="a sent run", names=OUTPUT_FILES)
    out = output_folder(out)
    from ..bag.stream import StreamNames

    names = StreamNames.of(exp.task, cfg.cell.leader.joints, cfg.cell.follower.joints,
                           path=path)
    cell = Ros2Cell(settings, exp.task, names, trajectories=True)
    summary, watch = send_run(cell, plan, watchdog=guards.watchdog,
                              start_tolerance=guards.start_tolerance, dt=exp.options.dt)
    write_watch(out, summary, watch, exp.task.leader.n)
    print(f"{exp.name}: sent {plan.source} ({summary['points']} points, "
          f"{summary['duration_s']:.3g} s) to {', '.join(map(str, summary['topics']))}: "
          f"{summary['status']}; largest distance from the run's joints "
          f"{summary['deviation_max_rad']:.3g} rad, at the end {summary['deviation_end_rad']:.3g}")
    print(f"  outputs: {out}/")
    if summary["status"] == "interrupted":
        print_error("interrupted; both controllers were told to hold the joints")
        return EXIT_INTERRUPTED
    if summary["status"] != "completed":
        print_error(summary["message"])
        return EXIT_FAILED
    return EXIT_OK

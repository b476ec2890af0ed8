"""The closed loop against lag and against a base calibration error, with and without
the compliant follower (docs/physics.md, "Lag" and "A base off its calibration").

For each experiment file, the closed loop runs in MuJoCo with the file's ``physics:``
settings, the compliant follower on (``physics.compliance``, the file's gains or the
defaults) and off, and

* ``lag``: the measurement 0 to 3 samples late (``physics.delay``);
* ``base``: the simulated follower's base moved by 1 to 10 mm along ``(1, -1, 1)/sqrt 3``
  of its own frame, or turned by 0.1 to 1 deg about the same axis
  (``physics.base_error``); the controller keeps the model's base.

``stiffness`` prints instead, at the start, the chain's stiffness ``k_c`` (the two arms'
servo stiffnesses in series, ``(J_l Kp_l^-1 J_l^T + J_f Kp_f^-1 J_f^T)^-1``, its least and
largest eigenvalue for forces and for moments, in the directions the follower's grasp
holds) and the compliant follower's loop gain per sample ``g = K k_c dt`` in the
stiffest held direction, against its bound
``2 sin(pi / (2 (2 d + 1)))`` at the file's delay ``d`` (docs/physics.md, "Stability").

Prints one Markdown row per run: the verdict, the largest internal force (over the run
and over its second half), the largest share of a joint torque limit, the largest split
error and the object's largest deviation from D(t).

    .venv/bin/python benchmarks/physics_closed_loop.py lag [CONFIG ...]
    .venv/bin/python benchmarks/physics_closed_loop.py base [CONFIG ...]
    .venv/bin/python benchmarks/physics_closed_loop.py stiffness [CONFIG ...]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.physics.check import closed_loop, diagnose
from dualarm_qp.physics.command import settings_of
from dualarm_qp.physics.compliance import ComplianceGains
from dualarm_qp.physics.plant import DivergedError, MujocoPlant
from dualarm_qp.physics.settings import PhysicsSettings
from dualarm_qp.task.hands import hand_statics

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ("puma_beam_limits", "ur5_pair_heavy_bar")
AXIS = np.array([1.0, -1.0, 1.0]) / math.sqrt(3.0)


def _lag(settings: PhysicsSettings) -> Iterator[tuple[str, PhysicsSettings]]:
    for delay in range(4):
        yield f"{delay}", dataclasses.replace(settings, delay=delay)


def _base(settings: PhysicsSettings) -> Iterator[tuple[str, PhysicsSettings]]:
    yield "none", settings
    for mm in (1.0, 3.0, 10.0):
        yield f"{mm:g} mm", dataclasses.replace(settings, base_error=np.r_[mm * 1e-3 * AXIS,
                                                                           np.zeros(3)])
    for deg in (0.1, 0.3, 1.0):
        yield f"{deg:g} deg", dataclasses.replace(settings, base_error=np.r_[
            np.zeros(3), math.radians(deg) * AXIS])


def _row(exp, settings: PhysicsSettings) -> str:
    try:
        run = closed_loop(exp, settings)
    except DivergedError as e:
        return f"diverged | {str(e)[:60]} | | | | |"
    s = run.summary()
    verdict = diagnose(run, None, settings)
    c = verdict.cause
    cause = "" if c is None else f" ({c.kind} at {c.t:.2f} s)"
    t, internal = run.log["t"], np.asarray(run.log["internal"], dtype=float)
    late = internal[t >= 0.5 * t[-1]] if t.size else internal
    settled = f"{np.nanmax(late):.3g}" if late.size else "n/a"
    return (f"{verdict.status}{cause} | {s['internal_force_max_N']:.3g} | {settled} | "
            f"{s['torque_ratio_max']:.3g} | {s['split_error_max']:.3g} | "
            f"{s['deviation_pos_max_m'] * 1e3:.3g}")


def _held_stiffness(compliance: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Return the stiffness eigenvalues in the directions ``free`` (3, k) leaves held."""
    basis = np.linalg.svd(free)[0] if free.size else np.eye(3)
    rank = int(np.sum(np.linalg.svd(free, compute_uv=False) > 1e-9)) if free.size else 0
    held = basis[:, rank:]
    if held.shape[1] == 0:
        return np.array([np.nan])
    return 1.0 / np.linalg.eigvalsh(held.T @ compliance @ held)


def _stiffness(exp, settings: PhysicsSettings) -> str:
    """Return the row of ``stiffness`` (module docstring) for one experiment."""
    plant = MujocoPlant(exp.task, settings)
    plant.reset(exp.initial, exp.options.dt)
    assert plant.gains is not None
    n_l = exp.task.leader.n
    s0 = exp.initial
    hands, _ = hand_statics(exp.task, s0.q_l, s0.sigma, s0.sigma_leader)
    free = hands[1].free
    compliance = np.zeros((6, 6))
    for arm, q, kp in ((exp.task.leader, exp.initial.q_l, plant.gains.kp[:n_l]),
                       (exp.task.follower, exp.initial.q_f, plant.gains.kp[n_l:])):
        _, J = arm.fk_jacobian(q)
        compliance += J @ np.diag(1.0 / kp) @ J.T
    force = _held_stiffness(compliance[:3, :3], free[:3])
    moment = _held_stiffness(compliance[3:, 3:], free[3:])
    gains = settings.compliance or ComplianceGains()
    dt, d = exp.options.dt, settings.delay
    bound = 2.0 * math.sin(math.pi / (2.0 * (2 * d + 1)))
    return (f"{force.min():.3g} .. {force.max():.3g} | {moment.min():.3g} .. "
            f"{moment.max():.3g} | {dt * 1e3:.3g} | {d} | "
            f"{gains.force_gain * force.max() * dt:.3g} | "
            f"{gains.moment_gain * moment.max() * dt:.3g} | {bound:.3g}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", choices=("lag", "base", "stiffness"))
    parser.add_argument("configs", nargs="*", type=Path)
    args = parser.parse_args()
    configs = args.configs or [ROOT / "configs" / f"{n}.yaml" for n in DEFAULT]
    if args.study == "stiffness":
        print("| config | k_c force [N/m] | k_c moment [N m/rad] | dt [ms] | delay | g force "
              "| g moment | bound on g |")
        print("|---|---|---|---|---|---|---|---|")
        for path in configs:
            cfg = load_config(path)
            row = _stiffness(build_experiment(cfg, str(path)), settings_of(cfg))
            print(f"| {path.stem} | {row} |", flush=True)
        return
    cases = _lag if args.study == "lag" else _base
    head = "delay [samples]" if args.study == "lag" else "follower's base error"
    print(f"| config | {head} | compliance | status | internal force [N] | in the second "
          "half [N] | torque share | split error | off D(t) [mm] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for path in configs:
        cfg = load_config(path)
        exp = build_experiment(cfg, str(path))
        base = settings_of(cfg)
        gains = base.compliance or ComplianceGains()
        for compliance in (None, gains):
            for label, settings in cases(dataclasses.replace(base, compliance=compliance)):
                print(f"| {path.stem} | {label} | {'on' if compliance else 'off'} | "
                      f"{_row(exp, settings)} |", flush=True)


if __name__ == "__main__":
    main()

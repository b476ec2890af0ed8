"""The physics check on shipped configurations: verdicts, peaks and wall times.

For each experiment file: the run is recorded (the rollout, in this process), then the
rigid replay and the closed loop run in MuJoCo with the file's ``physics:`` settings
(docs/physics.md). Prints one Markdown row per file: the verdict and its cause (what
the simulation saw first, and when), the closed loop's largest deviation from D(t), its
internal force and the replay's, the largest share of a torque limit, and the wall time
of the replay and of the closed loop.

    .venv/bin/python benchmarks/physics_check.py [CONFIG ...]    # default: configs/*.yaml
"""

from __future__ import annotations

import argparse
from pathlib import Path

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.physics.check import closed_loop, physics_summary, replay
from dualarm_qp.physics.command import settings_of

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", type=Path)
    args = parser.parse_args()
    configs = args.configs or sorted((ROOT / "configs").glob("*.yaml"))
    print("| config | status | cause | off D(t) [mm] | internal (replay) [N] | torque share | "
          "replay [s] | closed loop [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for path in configs:
        cfg = load_config(path)
        exp = build_experiment(cfg, str(path))
        settings = settings_of(cfg)
        run = rollout(exp.controller(), exp.initial, duration=exp.duration,
                      limits=exp.limits, project=exp.project,
                      initial_rates=exp.start_rates())
        tr = run.trace
        base = None
        if len(tr) >= 2:
            base = replay(exp, settings, tr.t, tr.q_l, tr.q_f, tr.tau, tr.grasp,
                          tr.grasp_leader if exp.task.leader_surface is not None else None)
        loop = closed_loop(exp, settings)
        p = physics_summary(loop, base, settings)
        c, r = p["closed_loop"], p["replay"]
        base_int = "n/a" if r is None else f"{r['internal_force_max_N']:.3g}"
        base_wall = "n/a" if r is None else f"{r['wall_time_s']:.2f}"
        cause = ("" if p["cause"] is None
                 else f"{p['cause']} at {p['cause_t_s']:.3g} s")
        if p["status"] == "ok" and p["oscillation"] is not None:
            cause = f"(an oscillation at {p['oscillation']['t_s']:.3g} s)"
        print(f"| {path.stem} | {p['status']} | {cause} | {c['deviation_pos_max_m'] * 1e3:.3g} | "
              f"{c['internal_force_max_N']:.3g} ({base_int}) | {c['torque_ratio_max']:.3g} | "
              f"{base_wall} | {c['wall_time_s']:.2f} |", flush=True)


if __name__ == "__main__":
    main()

"""Outside references for the step timings, measured in one process on one machine.

* our kinematics alone: ``SerialArm.fk_jacobian`` of one PUMA 560 (the controller step
  does it for both arms);
* Pinocchio's forward kinematics + frame Jacobian of the same PUMA 560 (built from the
  same DH table; checked to agree with ours to 1e-12);
* pink's differential-IK step on that 6-dof arm: ``Configuration.update`` + ``solve_ik``
  with one frame task and pink's default configuration and velocity limits, per QP
  backend;
* our whole controller step (nullspace solver) on the paper's beam case, for scale.

pink and Pinocchio are benchmark-only dependencies: ``pip install "dualarm-qp[bench]"``
(or ``pip install pin-pink``). Without them only our numbers are printed.

    python benchmarks/outside_refs.py [--samples 2000] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dualarm_qp import puma560
from dualarm_qp.bench.runner import machine_info

ROOT = Path(__file__).resolve().parent.parent


def timeit(fn: Callable[[int], Any], samples: int) -> dict[str, float]:
    for i in range(min(200, samples)):  # warm-up
        fn(i)
    t = np.empty(samples)
    for i in range(samples):
        t0 = time.perf_counter()
        fn(i)
        t[i] = time.perf_counter() - t0
    return {"median_us": float(np.median(t) * 1e6), "p99_us": float(np.percentile(t, 99) * 1e6)}


def pin_model(arm: Any) -> tuple[Any, Any, int]:
    """Pinocchio model of a standard-DH arm: joint i rotates about z, then Tz(d) Tx(a) Rx(alpha)."""
    import pinocchio as pin

    dh = arm.dh
    if dh.convention != "standard":
        raise ValueError("only standard DH here")
    model = pin.Model()
    parent = 0
    placement = pin.SE3(arm.base[:3, :3].copy(), arm.base[:3, 3].copy())
    for i in range(dh.n):
        jid = model.addJoint(parent, pin.JointModelRZ(), placement, f"j{i + 1}")
        model.appendBodyToJoint(jid, pin.Inertia.Random(), pin.SE3.Identity())
        c, s = np.cos(dh.alpha[i]), np.sin(dh.alpha[i])
        T = np.eye(4)
        T[:3, :3] = [[1, 0, 0], [0, c, -s], [0, s, c]]
        T[:3, 3] = [dh.a[i], 0.0, dh.d[i]]
        if i + 1 < dh.n:
            T = T @ _rz(dh.offset[i + 1])
        placement = pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())
        parent = jid
    tool = placement.homogeneous @ arm.tool
    fid = model.addFrame(pin.Frame("tool", parent, 0, pin.SE3(tool[:3, :3].copy(),
                                                              tool[:3, 3].copy()),
                                   pin.FrameType.OP_FRAME))
    model.lowerPositionLimit = np.asarray(arm.q_min, dtype=float) + _first_offset(arm)
    model.upperPositionLimit = np.asarray(arm.q_max, dtype=float) + _first_offset(arm)
    model.velocityLimit = np.asarray(arm.qd_max, dtype=float)
    return model, model.createData(), fid


def _rz(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")  # qpsolvers' sparse-conversion notices for osqp
    n = args.samples
    arm = puma560()
    rng = np.random.default_rng(0)
    mid = 0.5 * (arm.q_min + arm.q_max)
    half = 0.4 * (arm.q_max - arm.q_min)
    qs = mid + half * rng.uniform(-1, 1, (n, arm.n))
    out: dict[str, Any] = {"machine": machine_info(), "samples": n}
    out["dualarm_qp fk_jacobian (1 arm)"] = timeit(lambda i: arm.fk_jacobian(qs[i]), n)

    try:
        import pinocchio as pin
    except ImportError:
        out["pinocchio"] = "not installed: pip install 'dualarm-qp[bench]'"
    else:
        model, data, fid = pin_model(arm)
        err = 0.0
        for q in qs[:50]:
            pin.framesForwardKinematics(model, data, q + _first_offset(arm))
            err = max(err, float(np.abs(data.oMf[fid].homogeneous - arm.fk(q)).max()))
        out["pinocchio vs dualarm_qp fk max abs diff"] = float(err)

        def pin_fk_jac(i: int) -> None:
            q = qs[i] + _first_offset(arm)
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)

        out["pinocchio fk + frame jacobian (1 arm)"] = timeit(pin_fk_jac, n)
        out["pinocchio version"] = pin.__version__
        try:
            import pink
            from pink.tasks import FrameTask
        except ImportError:
            out["pink"] = "not installed: pip install 'dualarm-qp[bench]'"
        else:
            import qpsolvers

            out["pink version"] = pink.__version__
            for backend in ("daqp", "quadprog", "proxqp", "osqp"):
                if backend not in qpsolvers.available_solvers:
                    out[f"pink solve_ik ({backend})"] = "backend not installed"
                    continue
                q_pin = qs + _first_offset(arm)
                conf = pink.Configuration(model, data, q_pin[0].copy())
                task = FrameTask("tool", position_cost=1.0, orientation_cost=1.0)
                target = conf.get_transform_frame_to_world("tool").copy()
                target.translation += np.array([0.01, 0.0, 0.0])
                task.set_target(target)

                def step(i: int, conf: Any = conf, task: Any = task,
                         backend: str = backend, q_pin: Any = q_pin) -> None:
                    conf.update(q_pin[i])
                    pink.solve_ik(conf, [task], 0.01, solver=backend, safety_break=False)

                out[f"pink update + solve_ik ({backend})"] = timeit(step, min(n, 1000))

    # Our whole controller step on the paper's case (b), for scale.
    from dualarm_qp.experiments import build_experiment, load_config

    exp = build_experiment(load_config(ROOT / "configs" / "puma_beam_sliding_s7_100.yaml"),
                           solver="nullspace")
    ctrl = exp.controller()
    out["dualarm_qp controller step (nullspace, both arms)"] = timeit(
        lambda i: ctrl.step(exp.initial), n)

    width = max(len(k) for k in out)
    for k, v in out.items():
        if k == "machine":
            continue
        if isinstance(v, dict):
            v = f"median {v['median_us']:8.1f} us   p99 {v['p99_us']:8.1f} us"
        print(f"{k:<{width}}  {v}")
    print(f"machine: {out['machine']['cpu']}, {out['machine']['cpus']} cpus, load "
          f"{out['machine']['load_average']}")
    if args.json:
        args.json.write_text(json.dumps(out, indent=2) + "\n")
    return 0


def _first_offset(arm: Any) -> np.ndarray:
    """Pinocchio's joint 1 has no offset placement before it: add DH offset 1 to q1."""
    off = np.zeros(arm.n)
    off[0] = arm.dh.offset[0]
    return off


if __name__ == "__main__":
    sys.exit(main())

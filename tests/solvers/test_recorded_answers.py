"""The compiled exact solver reproduces the Python-era answers and certificates.

``tests/solvers/data/exact_answers.npz`` (written by ``benchmarks/record_exact.py``
before the solver moved to C++) holds the ``nullspace`` solver's answers on every step
of the instance suite and on steps of rollouts of seven shipped configurations (boxes,
general rows, null-space dimensions 1 to 3, infeasible steps), with the certificate's
verdict on each.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dualarm_qp.solvers.certify import certify
from dualarm_qp.solvers.nullspace import NullspaceSolver
from dualarm_qp.step.problem import StepProblem

DATA = Path(__file__).parent / "data" / "exact_answers.npz"
ARRAYS = ("A", "b", "weights", "center", "lower", "upper", "G", "h")

#: Agreement of x with the Python-era answer, relative to max(1, |x|_inf): both are
#: rounding-exact, from two SVDs (LAPACK's and Eigen's) with different null bases.
X_RTOL = 1e-12


def recorded() -> list[dict[str, Any]]:
    """One dict per instance: the problem and the recorded answers."""
    with np.load(DATA, allow_pickle=False) as z:
        d = {k: z[k] for k in z.files}
    meta = json.loads(str(d["meta"]))
    offsets = dict.fromkeys(ARRAYS, 0)
    x_off = 0
    cases = []
    for i, m in enumerate(meta):
        fields: dict[str, Any] = {}
        for k in ARRAYS:
            shape = tuple(int(s) for s in d[k + "_shape"][i][:int(d[k + "_ndim"][i])])
            size = int(np.prod(shape))
            fields[k] = d[k][offsets[k]:offsets[k] + size].reshape(shape)
            offsets[k] += size
        n = fields["A"].shape[1]
        problem = StepProblem(**fields, n_grasp=m["n_grasp"],
                              **{k: tuple(v) for k, v in m["strings"].items()})
        cases.append({"problem": problem, "x": d["x"][x_off:x_off + n],
                      "status": str(d["status"][i]), "verdict": str(d["verdict"][i]),
                      "nullity": int(d["nullity"][i]), "source": str(d["source"][i]),
                      "conflicts": tuple(m["conflicts"])})
        x_off += n
    return cases


CASES = recorded()
SOURCES = sorted({c["source"] for c in CASES})


@pytest.mark.parametrize("source", SOURCES)
def test_kernel_reproduces_the_recorded_answers(source: str) -> None:
    solver = NullspaceSolver()
    cases = [c for c in CASES if c["source"] == source]
    worst = 0.0
    for c in cases:
        problem = c["problem"]
        sol = solver.solve(problem)
        assert sol.status.value == c["status"], (source, sol.message)
        assert sol.extras.get("nullity", -1) == c["nullity"]
        # The same rows; the order of a d = 1 pair followed the sign LAPACK gave the null
        # vector, it is ascending now.
        assert sorted(sol.extras.get("conflicts", ())) == sorted(c["conflicts"])
        if c["status"] == "optimal":
            err = float(np.abs(sol.x - c["x"]).max()) / max(1.0, float(np.abs(c["x"]).max()))
            worst = max(worst, err)
        assert certify(problem, sol, solver.tol).status.value == c["verdict"]
    assert worst <= X_RTOL


def test_the_record_covers_the_solver_s_branches() -> None:
    statuses = {(c["status"], c["nullity"]) for c in CASES}
    assert {("optimal", 1), ("optimal", 2), ("optimal", 3), ("infeasible", 1),
            ("infeasible", -1)} <= statuses
    assert any(c["problem"].p for c in CASES)  # general rows

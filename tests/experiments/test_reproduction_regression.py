"""The paper's three cases give the same motion as before the one-vector step (to 1e-9).

``data/paper_cases_reference.json`` holds samples of cases (a), (b), (c) (path time,
both arms' joints [rad], grasp [m]) computed by the code before the step solved both
arms in one problem, when the leader had its own square step and the follower's grasp
column was assembled by hand (Eqs. 25-27). The one-vector step on the carried-object
model must reproduce them.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config

HERE = Path(__file__).resolve().parent
CONFIGS = HERE.parents[1] / "configs"
REFERENCE = json.loads((HERE / "data" / "paper_cases_reference.json").read_text())


@pytest.mark.parametrize("case", sorted(REFERENCE))
def test_paper_case_matches_the_former_step(case):
    ref = REFERENCE[case]
    path = CONFIGS / ref["config"]
    exp = build_experiment(load_config(path), str(path))
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, project=exp.project,
                  limits=exp.limits)
    tr = res.trace
    assert len(tr) == ref["samples"]
    rows = ref["rows"]
    np.testing.assert_allclose(tr.tau[rows], ref["path_t"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.q_l[rows], ref["q_l"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.q_f[rows], ref["q_f"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.grasp[rows], ref["grasp"], rtol=0, atol=1e-9)

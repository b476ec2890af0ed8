"""The independent FK oracle agrees with the library's forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from executed_runs import VARIANTS, build
from oracle import is_puma, puma_fk

from dualarm_qp.kinematics.puma560 import puma560


def test_oracle_matches_library_fk_plain() -> None:
    arm = puma560()
    assert is_puma(arm)
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, 6)
        assert np.abs(puma_fk(q) - arm.fk(q)).max() < 1e-12


def test_oracle_zero_pose_by_hand() -> None:
    """At q = 0 the flange sits at x = a2 + a3, y = d2, z = d4 + d6 (a hand check)."""
    T = puma_fk(np.zeros(6))
    assert np.allclose(T[:3, 3], [0.4318 - 0.02032, 0.14909, 0.43307 + 0.05625], atol=1e-15)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_oracle_matches_library_fk_with_bases(variant: str) -> None:
    """Every variant of the executed-run tests builds, and with its bases and tools both
    arms agree with the oracle: random joints, to 1e-12."""
    exp = build(variant, "nullspace")
    rng = np.random.default_rng(7)
    for arm in (exp.task.leader, exp.task.follower):
        assert is_puma(arm)
        for _ in range(10):
            q = rng.uniform(arm.q_min, arm.q_max)
            T = puma_fk(q, arm.base, arm.tool)
            assert np.abs(T - arm.fk(q)).max() < 1e-12

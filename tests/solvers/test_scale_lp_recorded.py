"""The compiled task-scale LP against the Python simplex it replaced (recorded answers).

tests/solvers/data/scale_lp_answers.npz holds 2401 LPs (the instance suite's and those
asked in rollouts where the scale policy slows steps) and the answers of the Python
revised simplex (``benchmarks/record_scale_lp.py``, written before the simplex moved to
``src/kernel/scale_lp.cpp``). The kernel must give the same verdict and the same rows,
and ``t``, ``s`` to 1e-12 relative to ``max(1, |.|)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.solvers._scale import _lp

DATA = Path(__file__).parent / "data" / "scale_lp_answers.npz"


def _cases() -> list[tuple[object, ...]]:
    with np.load(DATA) as f:  # each item of an NpzFile decompresses again: read once
        d = {k: f[k] for k in f.files}
    out, m_at, v_at, t_at = [], 0, 0, 0
    for i, (k, n) in enumerate(d["M_shape"]):
        M = d["M"][m_at:m_at + k * n].reshape(k, n)
        a, g = d["a"][v_at:v_at + k], d["g"][v_at:v_at + k]
        t = d["t"][t_at:t_at + n]
        m_at, v_at, t_at = m_at + k * n, v_at + k, t_at + n
        rows = [int(j) for j in str(d["rows"][i]).split(",") if j]
        out.append((M, a, g, *d["s_range"][i], bool(d["done"][i]), bool(d["ok"][i]), t,
                    float(d["s"][i]), rows, str(d["source"][i])))
    return out


CASES = _cases()


def test_the_record_covers_feasible_infeasible_and_rollout_lps() -> None:
    assert len(CASES) == 2401
    assert sum(c[6] for c in CASES) > 2000 and sum(not c[6] for c in CASES) > 100
    assert {c[10] for c in CASES} >= {"step_suite", "panda_pair", "puma_beam_tight_limits"}
    assert {c[0].shape[1] for c in CASES} >= {1, 3}


def test_the_kernel_gives_the_recorded_answers() -> None:
    worst = 0.0
    for M, a, g, s_lo, s_hi, done, ok, t, s, rows, source in CASES:
        got = _lp(M, a, g, float(s_lo), float(s_hi))
        assert (got is not None) == done, source
        if got is None:
            continue
        ok_now, t_now, s_now, rows_now = got
        assert ok_now == ok and rows_now == rows, source
        if ok:
            worst = max(worst, abs(s_now - s) / max(1.0, abs(s)),
                        float(np.max(np.abs(t_now - t) / np.maximum(1.0, np.abs(t)))))
    assert worst <= 1e-12, worst


@pytest.mark.parametrize("seed", range(20))
def test_the_largest_scale_is_feasible_and_cannot_grow(seed: int) -> None:
    """An independent check: at the kernel's s some t meets every row, and an LP solver
    of scipy finds no larger s."""
    from scipy.optimize import linprog

    rng = np.random.default_rng(seed)
    k, d = int(rng.integers(2, 12)), int(rng.integers(1, 4))
    M = rng.normal(size=(k, d))
    a = rng.normal(size=k)
    g = rng.uniform(0.1, 1.0, size=k)  # t = 0, s = 0 is feasible
    got = _lp(M, a, g, 0.0, 1.0)
    assert got is not None
    ok, t, s, _ = got
    assert ok and 0.0 <= s <= 1.0
    assert np.all(M @ t + a * s <= g + 1e-9)
    ref = linprog(np.r_[np.zeros(d), -1.0], A_ub=np.c_[M, a], b_ub=g,
                  bounds=[(None, None)] * d + [(0.0, 1.0)], method="highs")
    assert ref.status == 0 and s == pytest.approx(-ref.fun, abs=1e-9)


def test_an_infeasible_lp_names_the_rows_of_its_ray() -> None:
    # t <= -1 and -t <= -1 (t >= 1): no t, whatever s.
    got = _lp(np.array([[1.0], [-1.0]]), np.zeros(2), np.array([-1.0, -1.0]), 0.0, 1.0)
    assert got is not None and not got[0] and sorted(got[3]) == [0, 1]

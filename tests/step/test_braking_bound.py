"""The exact discrete braking bound keeps every step feasible up to the end of the range."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp._compiled import kernel
from dualarm_qp.step.limits import AccelerationLimit, braking_bound
from dualarm_qp.step.stacking import pin_rounding


def run_to_the_limit(rule, trials: int = 20_000, steps: int = 300, seed: int = 0):
    """Drive ``trials`` variables as hard as the box allows towards the end of their
    range; return how many reached an empty box and the largest overshoot [units of q].

    Each sample the box is ``[x_prev - delta, min(v_max, rule, D / dt)]``, ``rule`` being
    the upper end of the acceleration box cut by a braking rule at the distance ``D``
    left, ``D / dt`` the range limit's; the rate taken is its upper end (the variable
    rushes to the wall).
    """
    rng = np.random.default_rng(seed)
    dt = rng.uniform(0.001, 0.05, trials)
    a = rng.uniform(0.5, 50.0, trials)
    v_max = rng.uniform(0.1, 5.0, trials)
    D = rng.uniform(0.0, 2.0, trials)  # distance to the upper end of the range
    delta = a * dt
    x = np.minimum(rng.uniform(-1.0, 1.0, trials) * v_max, braking_bound(D, delta, dt))
    empty = np.zeros(trials, dtype=bool)
    overshoot = 0.0
    for _ in range(steps):
        # The range limit (Eqs. 34-36, with recovery: outside, never further out).
        in_range = np.where(D >= 0.0, D / dt, 0.0)
        upper = np.minimum(np.minimum(v_max, rule(D, delta, dt, x)), in_range)
        lower = x - delta
        upper = pin_rounding(lower, upper)  # as the builder intersects the boxes
        empty |= upper < lower - 1e-12 * np.maximum(1.0, np.abs(lower))
        x = np.where(empty, x, np.maximum(upper, lower))
        D = D - x * dt
        overshoot = max(overshoot, float(-D.min()))
    return int(empty.sum()), overshoot


def exact(D, delta, dt, x):
    """The upper end of the acceleration limit's box, with a dt per trial.

    The limit's rule with the library's braking bound (the kernel's);
    ``test_the_limit_object_gives_that_box`` checks the limit object against it.
    """
    return np.minimum(x + delta, np.where(D >= 0.0, braking_bound(D, delta, dt), np.inf))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_limit_object_gives_that_box(seed):
    rng = np.random.default_rng(seed)
    n, dt = 9, float(rng.uniform(0.001, 0.05))
    a = rng.uniform(0.5, 50.0, n)
    a[0] = np.inf  # no acceleration limit on this variable
    x = rng.uniform(-1.0, 1.0, n)
    hi = rng.uniform(-0.5, 2.0, n) / dt  # some past the upper end (D < 0)
    lo = -rng.uniform(-0.5, 2.0, n) / dt
    hi[1], lo[2] = np.inf, -np.inf  # no range end
    ctx = kernel.Context(lo, hi, x, dt=dt)
    box = AccelerationLimit(a, dt).constraint(ctx)
    delta = a * dt
    with np.errstate(invalid="ignore"):
        up = np.minimum(x + delta, np.where(hi * dt >= 0.0, braking_bound(hi * dt, delta, dt),
                                            np.inf))
        down = np.maximum(x - delta, -np.where(-lo * dt >= 0.0,
                                               braking_bound(-lo * dt, delta, dt), np.inf))
    assert np.array_equal(box.upper, up) and np.array_equal(box.lower, down)


def continuous(D, delta, dt, x):
    """The continuous rule ``sqrt(2 a D)`` (``a = delta / dt``), as in pink's limit."""
    return np.minimum(x + delta, np.sqrt(2.0 * (delta / dt) * np.maximum(D, 0.0)))


def test_the_exact_bound_never_empties_the_box_nor_crosses_the_end() -> None:
    empty, overshoot = run_to_the_limit(exact)
    assert empty == 0
    assert overshoot <= 1e-12


def test_the_continuous_rule_does_empty_the_box() -> None:
    """The rule a discrete controller must not use: ``sqrt(2 a D)`` lets a variable
    arrive too fast to stop within one sample's change of rate."""
    empty, _ = run_to_the_limit(continuous)
    assert empty > 0


@settings(max_examples=200, deadline=None)
@given(D=st.floats(0.0, 10.0), a=st.floats(0.01, 100.0), dt=st.floats(1e-4, 0.1))
def test_braking_from_the_bound_stops_exactly_within_the_distance(D, a, dt) -> None:
    """From ``V(D)`` the rates ``V, V - delta, ...`` (down to 0) cover at most ``D``, and
    a rate a little higher does not stop in time."""
    delta = a * dt
    V = float(braking_bound(np.array([D]), np.array([delta]), dt)[0])
    rates = np.arange(V, 0.0, -delta)
    covered = dt * rates.sum()
    assert covered <= D * (1 + 1e-9) + 1e-12
    faster = V * (1 + 1e-6) + 1e-9
    assert dt * np.arange(faster, 0.0, -delta).sum() > D - 1e-12 or D == 0.0


def test_the_bound_is_the_position_bound_near_the_end_and_infinite_without_one() -> None:
    dt, delta = 0.01, 0.1
    assert braking_bound(np.array([0.0]), np.array([delta]), dt)[0] == 0.0
    small = 0.5 * delta * dt  # less than one braking sample: the range itself binds
    assert braking_bound(np.array([small]), np.array([delta]), dt)[0] == pytest.approx(
        small / dt)
    assert np.isinf(braking_bound(np.array([np.inf]), np.array([delta]), dt)[0])
    assert np.isinf(braking_bound(np.array([1.0]), np.array([np.inf]), dt)[0])


def numpy_braking_bound(D, delta, dt):
    """The Python-era numpy implementation, kept as the reference of the kernel's."""
    D = np.asarray(D, dtype=np.float64)
    delta = np.asarray(delta, dtype=np.float64)
    finite = np.isfinite(D) & np.isfinite(delta)
    Dd = np.where(finite, np.maximum(D, 0.0), 0.0)
    dd = np.where(finite, delta, 1.0)
    n = np.floor(0.5 * (-1.0 + np.sqrt(1.0 + 8.0 * Dd / (dd * dt))))
    V = (Dd / dt + dd * n * (n + 1.0) / 2.0) / (n + 1.0)
    return np.where(finite, V, np.inf)


@settings(max_examples=100, deadline=None)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_the_kernel_bound_equals_the_python_era_bound(seed):
    rng = np.random.default_rng(seed)
    k = 64
    D = rng.choice([0.0, 1e-9, 1.0, 3.0], k) * rng.uniform(0.0, 2.0, k)
    D[rng.random(k) < 0.1] = np.inf
    D[rng.random(k) < 0.1] *= -1.0
    delta = rng.uniform(1e-4, 2.0, k)
    delta[rng.random(k) < 0.1] = np.inf
    dt = float(rng.uniform(1e-3, 0.05))
    assert np.array_equal(braking_bound(D, delta, dt), numpy_braking_bound(D, delta, dt))

"""The detector of a growing servo oscillation, on signals whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from dualarm_qp.physics.oscillation import FLOOR, growing_oscillation, half_cycles

H = 1e-3  # the simulator's substep [s]
T = np.arange(0.0, 1.0, H)
F = 80.0  # Hz: a stiff servo's rhythm, 12.5 substeps a cycle


def _sine(amplitude: np.ndarray) -> np.ndarray:
    return amplitude * np.sin(2.0 * np.pi * F * T)


def test_a_growing_sine_is_found_with_its_frequency_and_start():
    x = _sine(0.01 * np.exp(5.0 * T))  # x1.65 a tenth of a second, to 1.5 rad/s
    found = growing_oscillation(x, H)
    assert found is not None
    assert found.frequency_hz == pytest.approx(F, rel=0.02)
    assert found.growth >= 4.0
    assert found.start * H < 0.02  # it grows from the first cycle
    assert found.peak_index * H > 0.98 and found.peak == pytest.approx(1.48, rel=0.02)


def test_an_oscillation_that_starts_late_is_dated_where_it_starts():
    onset = 0.4
    x = _sine(np.where(T < onset, 0.0, 0.01 * np.exp(15.0 * (T - onset))))
    x = x + 0.005  # on a steady offset of the velocity error: no sign change before
    found = growing_oscillation(x, H)
    assert found is not None
    assert onset <= found.start * H < onset + 0.03
    assert found.frequency_hz == pytest.approx(F, rel=0.05)


@pytest.mark.parametrize(("name", "x"), [
    ("decaying", _sine(0.5 * np.exp(-5.0 * T))),
    ("steady amplitude", _sine(np.full(T.size, 0.5))),
    ("steady offset", np.full(T.size, 0.3)),
    ("slow drift through zero", 0.2 * np.sin(2.0 * np.pi * 1.5 * T) * np.exp(3.0 * T)),
    ("growing, but far below the floor", _sine(1e-6 * np.exp(5.0 * T))),
])
def test_what_does_not_grow_at_a_servos_rhythm_is_not_an_oscillation(name, x):
    assert growing_oscillation(x, H) is None, name


@pytest.mark.parametrize("seed", range(5))
def test_growing_noise_is_not_an_oscillation(seed):
    """Noise changes sign at random intervals: not a rhythm, however it grows."""
    rng = np.random.default_rng(seed)
    assert growing_oscillation(np.exp(8.0 * T) * 1e-2 * rng.standard_normal(T.size), H) is None


def test_the_floor_is_a_position_amplitude():
    """A growth that ends just above FLOOR [rad] of amplitude counts, just below does not."""
    omega = 2.0 * np.pi * F
    # x5 over the last 8 cycles (0.1 s): exp(16 t), ending at FLOOR * omega * factor.
    for factor, counts in ((1.5, True), (0.5, False)):
        amplitude = factor * FLOOR * omega * np.exp(16.0 * (T - T[-1]))
        assert (growing_oscillation(_sine(amplitude), H) is not None) is counts, factor


def test_half_cycles_cut_at_sign_changes_and_leave_out_the_partial_ends():
    x = np.array([0.5, 1.0, -2.0, -1.0, 0.0, -3.0, 4.0, 1.0, -0.5])
    starts, lengths, peaks = half_cycles(x)
    np.testing.assert_array_equal(starts, [2, 6])  # the zero keeps the sign before it
    np.testing.assert_array_equal(lengths, [4, 2])
    np.testing.assert_array_equal(peaks, [3.0, 4.0])
    assert half_cycles(np.ones(5))[0].size == 0

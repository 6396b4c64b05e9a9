"""The locked error of a partly dithered quantiser (diagnosis/dither.py, review 44 failure 4): m(y) against a
quadrature of the converter's mean and against its Fourier series, L against m's mean square over a step, and
the dither sd read back from records quantised here (a Gaussian dither added before ``q round(. / q)``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bouc_wen_id.diagnosis import dither

Q = 0.02


def _quadrature_mean(y: float, q: float, sigma: float) -> float:
    """``E[q round((y + n) / q)] - y`` for n ~ N(0, sigma^2): the trapezoid rule on a fine grid of n."""
    n = np.linspace(-9.0 * sigma, 9.0 * sigma, 400_001)
    w = np.exp(-0.5 * (n / sigma) ** 2)
    rec = q * np.round((y + n) / q)
    return float(np.trapezoid(rec * w, n) / np.trapezoid(w, n)) - y


def _series_mean(y: float, q: float, sigma: float, terms: int = 400) -> float:
    """CAUSES section 2's Fourier series of m(y)."""
    k = np.arange(1, terms + 1, dtype=np.float64)
    g = np.exp(-2.0 * math.pi**2 * k * k * sigma * sigma / (q * q))
    return float(q / math.pi * np.sum((-1.0) ** k * g * np.sin(2.0 * math.pi * k * y / q) / k))


@pytest.mark.parametrize("ratio", [0.1, 0.25, 0.35])
def test_the_mean_error_is_the_quadrature_and_the_series(ratio: float) -> None:
    rng = np.random.default_rng(7)
    ys = rng.uniform(-0.5, 0.5, 12)
    got = dither.mean_error(ys, Q, ratio * Q)
    quad = np.array([_quadrature_mean(float(y), Q, ratio * Q) for y in ys])
    series = np.array([_series_mean(float(y), Q, ratio * Q) for y in ys])
    assert np.max(np.abs(got - quad)) < 2e-5 * Q
    assert np.max(np.abs(got - series)) < 1e-9 * Q
    assert np.max(np.abs(got)) > 1e-4 * Q  # something is locked at these dithers


def test_no_dither_locks_the_whole_rounding_error_and_the_grid_offset_moves_it() -> None:
    ys = np.linspace(-0.3, 0.3, 101)
    np.testing.assert_allclose(dither.mean_error(ys, Q, 0.0), Q * np.round(ys / Q) - ys, atol=1e-15)
    shifted = dither.mean_error(ys + 0.3 * Q, Q, 0.25 * Q, offset=0.3 * Q)
    np.testing.assert_allclose(shifted, dither.mean_error(ys, Q, 0.25 * Q), atol=1e-12)


@pytest.mark.parametrize("ratio", [0.0, 0.1, 0.25, 0.35, 0.5])
def test_the_locked_power_is_the_mean_square_of_m_over_a_step(ratio: float) -> None:
    y = (np.arange(20_000) + 0.5) / 20_000 * Q
    mean_square = float(np.mean(dither.mean_error(y, Q, ratio * Q) ** 2))
    assert dither.locked_power(Q, ratio * Q) == pytest.approx(mean_square, rel=5e-3, abs=1e-9 * Q * Q)


def test_the_locked_power_falls_from_a_whole_step_to_nothing_at_half_a_step() -> None:
    ls = [dither.locked_power(Q, r * Q) / (Q * Q / 12.0) for r in (0.0, 0.1, 0.25, 0.35, 0.5)]
    assert ls[0] > 0.99 and ls[-1] < 1e-4
    assert all(a > b for a, b in zip(ls, ls[1:]))


@pytest.mark.parametrize("ratio", [0.1, 0.25, 0.35])
def test_the_dither_sd_is_read_back_from_the_level_counts(ratio: float) -> None:
    rng = np.random.default_rng([45, int(100 * ratio)])
    t = np.arange(200) / 200.0
    rows = []
    for amp in (0.3, 0.5, 1.0):  # a loop-like output, dwelling near its peaks
        y = amp * np.sin(2 * math.pi * t) + 0.1 * amp * np.sign(np.sin(2 * math.pi * t))
        rows.append(Q * np.round((y[None, :] + rng.normal(0.0, ratio * Q, (20, 200))) / Q))
    assert dither.fit_sigma_counts(rows, Q) == pytest.approx(ratio * Q, abs=0.012 * Q)


def test_periods_that_repeat_one_level_read_no_dither() -> None:
    y = np.sin(2 * math.pi * np.arange(100) / 100.0)
    rows = [np.tile(Q * np.round(y / Q), (10, 1))]
    assert dither.fit_sigma_counts(rows, Q) == 0.0

"""The adequacy test of the feedback fits (issue #20): it passes on the true structure and fails on a
misspecified one, on data made by integrators independent of the library's (solve_ivp for the sine steady
states, a plain-Python RK4 for the records), with an unmodelled cubic spring as the misspecification."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.timedomain import TimeRecord, fit_feedback, fit_feedback_sines
from bouc_wen_id.timedomain._feedback_adequacy import FeedbackAdequacy

BENCH = np.array([2.0, 10.0, 5e4, 5e4, 800.0, -1100.0, 1.0])
FS = 750.0
NOISE = 8e-6
#: The unmodelled cubic spring of the misspecified data (N/m^3): k3 y^2 / k = 2-80 % at the sines' peaks.
CUBIC = 2e10


def _rhs(u: float, x: np.ndarray, cubic: float) -> np.ndarray:
    m, c, k, alpha, bg, bd, nu = BENCH
    az = abs(x[2]) ** nu
    return np.array(
        [
            x[1],
            (u - c * x[1] - k * x[0] - cubic * x[0] ** 3 - x[2]) / m,
            alpha * x[1] - bg * abs(x[1]) * math.copysign(az, x[2]) - bd * x[1] * az,
        ]
    )


@functools.lru_cache(maxsize=32)
def _steady_periods(amp: float, freq: float, n: int, periods: int, cubic: float) -> np.ndarray:
    """``(periods, n)``: periods of the steady displacement under ``amp cos(2 pi freq t)``, solve_ivp."""
    from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

    settle = math.ceil(4.0 * freq) / freq
    t = settle + np.arange(periods * n) / (freq * n)
    sol = solve_ivp(
        lambda tt, x: _rhs(amp * math.cos(2 * math.pi * freq * tt), x, cubic),
        (0.0, t[-1]),
        np.zeros(3),
        t_eval=t,
        method="DOP853",
        rtol=1e-10,
        atol=1e-14,
    )
    return np.asarray(sol.y[0].reshape(periods, n))


DESIGN = [
    (20.0, 15.0),
    (40.0, 15.0),
    (20.0, 30.0),
    (40.0, 30.0),
    (60.0, 30.0),
    (40.0, 38.0),
    (30.0, 50.0),
    (60.0, 50.0),
]


def _sine_data(
    cubic: float, seed: int
) -> tuple[list[tuple[float, float, np.ndarray]], list[tuple[float, int]]]:
    """Averaged periods with the noise of the period-to-period spread (variance of the mean, its dof)."""
    rng = np.random.default_rng(seed)
    n, periods = 64, 4
    exps, noise = [], []
    for amp, freq in DESIGN:
        y = _steady_periods(amp, freq, n, periods, cubic) + NOISE * rng.standard_normal((periods, n))
        ybar = y.mean(axis=0)
        spread = float(np.sum((y - ybar) ** 2)) / (n * (periods - 1))
        exps.append((amp, freq, ybar))
        noise.append((spread / periods, n * (periods - 1)))
    return exps, noise


@pytest.mark.parametrize("seed", [1, 2])
def test_sine_adequacy_passes_on_the_true_structure_and_fails_on_a_cubic_spring(seed: int) -> None:
    exps, noise = _sine_data(0.0, seed)
    fit = fit_feedback_sines(exps, beta=1e3, theta0=BENCH * 1.05, starts=1, noise=noise)
    a = fit.adequacy
    assert isinstance(a, FeedbackAdequacy) and a.noise_dof == sum(d for _, d in noise)
    assert a.dof == 8 * 64 - 7 and a.passed and not a.rejects(0.01), a
    assert "adequacy" in fit.summary() and "pass" in fit.summary()
    known = fit_feedback_sines(exps, beta=1e3, theta0=BENCH * 1.05, starts=1, noise_variance=NOISE**2 / 4)
    assert known.adequacy is not None and not known.adequacy.rejects(0.01)
    exps, noise = _sine_data(CUBIC, seed)
    bad = fit_feedback_sines(exps, beta=1e3, theta0=BENCH * 1.05, starts=1, noise=noise)
    assert bad.adequacy is not None and bad.adequacy.rejects(0.01) and not bad.adequacy.passed
    assert "FAIL" in bad.summary()
    assert bad.adequacy.to_dict()["passed"] is False


def test_sine_adequacy_needs_a_noise_level_and_names_a_bad_one() -> None:
    exps, noise = _sine_data(0.0, 1)
    fit = fit_feedback_sines(exps[:3], beta=1e3, theta0=BENCH, starts=1, max_iter=2)
    assert fit.adequacy is None and "not run" in fit.summary()
    for bad in ([(1e-12, 10)], [(-1.0, 10)] * 3, [(1e-12, 0)] * 3, [(math.nan, 5)] * 3, "x"):
        with pytest.raises(InvalidParameterError, match="noise"):
            fit_feedback_sines(exps[:3], beta=1e3, theta0=BENCH, starts=1, noise=bad)  # type: ignore[arg-type]


def _record(cubic: float, seed: int, n: int = 1536, sub: int = 8) -> TimeRecord:
    """A random-phase multisine 5-150 Hz at 50 N RMS, plain-Python RK4 at 8 x 750 Hz, white noise."""
    rng = np.random.default_rng(seed)
    spec = np.zeros(n // 2 + 1, dtype=complex)
    f = np.arange(n // 2 + 1) * FS / n
    band = (f >= 5) & (f <= 150)
    spec[band] = np.exp(2j * np.pi * rng.uniform(size=int(band.sum())))
    fine = np.fft.irfft(spec, n * 2 * sub) * 2 * sub
    fine *= 50.0 / np.sqrt(np.mean(fine**2))
    h = 1 / (FS * sub)
    x = np.zeros(3)
    y = [0.0]
    for i in range(n * sub - 1):
        k1 = _rhs(fine[2 * i], x, cubic)
        k2 = _rhs(fine[2 * i + 1], x + 0.5 * h * k1, cubic)
        k3 = _rhs(fine[2 * i + 1], x + 0.5 * h * k2, cubic)
        k4 = _rhs(fine[(2 * i + 2) % fine.size], x + h * k3, cubic)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (i + 1) % sub == 0:
            y.append(x[0])
    yy = np.array(y) + NOISE * rng.standard_normal(n)
    return TimeRecord(np.arange(n) / FS, fine[:: 2 * sub], yy)


def test_record_adequacy_passes_on_the_true_structure_and_fails_on_a_cubic_spring() -> None:
    opts = dict(beta=1e3, theta0=BENCH * 1.05, starts=1, upsample=4, periodic=True, substeps=8)
    good = fit_feedback(_record(0.0, 6), **opts)  # type: ignore[arg-type]
    a = good.adequacy
    assert a is not None and a.test.startswith("residual whiteness") and a.dof == 20
    assert not a.rejects(0.01), a
    assert "adequacy" in good.summary()
    bad = fit_feedback(_record(CUBIC, 6), **opts)  # type: ignore[arg-type]
    assert bad.adequacy is not None and bad.adequacy.rejects(0.01), bad.adequacy

"""Standard errors of the time-domain fit under coloured noise (timedomain/_coloured.py; review 36, problem 9:
AR(1) noise, c 2.1 white-noise standard errors off while the fit's own whiteness test said p = 0).

The sandwich is checked against a Monte-Carlo spread on a linear regression with AR(1) errors (the exact
answer known by simulation, no library code in it), and the fit on a record made by the bench's own
simulator (``solve_ivp`` on G's state space, benches/timedomain.py) with AR(1) noise: the standard errors
widen and say so; with white noise they are the Cramer-Rao ones, unchanged.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.timedomain import _coloured

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
bench: Any = importlib.import_module("timedomain")


def _ar1(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    e = np.empty(n)
    e[0] = rng.normal()
    shocks = rng.normal(size=n) * np.sqrt(1.0 - rho**2)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + shocks[i]
    return e


def test_the_sandwich_matches_the_monte_carlo_spread_of_a_regression_with_ar1_errors() -> None:
    rng = np.random.default_rng(36)
    n, rho = 800, 0.8
    t = np.linspace(0.0, 1.0, n)
    x = np.column_stack((np.ones(n), np.sin(2 * np.pi * 3 * t), np.cos(2 * np.pi * 1.3 * t)))
    est, se_hac, se_white = [], [], []
    for _ in range(300):
        e = _ar1(rng, n, rho)
        b, *_ = np.linalg.lstsq(x, e, rcond=None)
        r = e - x @ b
        est.append(b)
        lags = _coloured.bandwidth([r])
        se_hac.append(np.sqrt(np.diag(_coloured.hac_covariance([x], [r], lags))))
        se_white.append(np.sqrt(np.diag(float(r @ r) / (n - 3) * np.linalg.inv(x.T @ x))))
    spread = np.std(np.array(est), axis=0, ddof=1)
    hac = np.mean(np.array(se_hac), axis=0)
    white = np.mean(np.array(se_white), axis=0)
    # 300 draws: the spread is known to ~4 %; the sandwich's small-sample bias is ~10 % at these lags
    np.testing.assert_allclose(hac / spread, 1.0, atol=0.2)
    assert np.all(white / spread < 0.55)  # the white-noise formula is far too small


def test_the_fit_widens_its_standard_errors_under_coloured_noise_and_says_so() -> None:
    case = replace(bench.CASES[1], duration=4.0)
    t, u, y, w = bench.independent_record(case, 3)
    sd = case.noise * np.std(w)
    yc = w + sd * _ar1(np.random.default_rng(5), t.size, 0.8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        white = bw.fit_time_domain((t, u, y), start=bench.perturbed_start(case), delay=True)
        col = bw.fit_time_domain((t, u, yc), start=bench.perturbed_start(case), delay=True)
    assert not white.adequacy.rejects(0.05) and not any("Newey-West" in x for x in white.warnings)
    assert col.adequacy.rejects(0.05)
    ratio = np.array([col.standard_errors[n] / white.standard_errors[n] for n in col.parameter_names])
    assert np.all(ratio > 1.8), dict(zip(col.parameter_names, ratio))
    assert "Newey-West" in col.summary() and "not white" in col.summary()
    np.testing.assert_allclose(np.diag(col.correlation), 1.0)


def test_widened_keeps_the_larger_standard_error_and_a_valid_covariance() -> None:
    cov = np.array([[4.0, 1.0], [1.0, 1.0]])
    hac = np.array([[1.0, -0.5], [-0.5, 9.0]])
    out = _coloured.widened(cov, hac)
    np.testing.assert_allclose(np.sqrt(np.diag(out)), [2.0, 3.0])
    assert np.all(np.linalg.eigvalsh(out) >= -1e-12)
    assert out[0, 1] < 0  # the sandwich's correlation
    nan = np.array([[np.nan, 0.0], [0.0, 1.0]])
    np.testing.assert_array_equal(_coloured.widened(cov, nan), cov)

"""``signal._harmonic_ls.harmonic_series`` (Horner's rule in exp(i theta)) against the direct sum of
complex exponentials it replaced in diagnosis/zero_drift.py and lab_settle.py (docs/diagnosis-speed.md,
session 38), and against an extended-precision reference."""

from __future__ import annotations

import numpy as np
import pytest
from bouc_wen_id.diagnosis.lab_settle import _upper_harmonics
from bouc_wen_id.signal._harmonic_ls import harmonic_series


def _direct(th: np.ndarray, c: np.ndarray) -> np.ndarray:
    out: np.ndarray = (np.exp(1j * np.outer(th, np.arange(c.size))) @ c).real
    return out


def _period(seed: int, p: int) -> tuple[np.ndarray, np.ndarray]:
    """A random averaged period's harmonics (rfft / P, doubled above DC) and phases of a long record."""
    rng = np.random.default_rng(seed)
    yb = np.cumsum(rng.standard_normal(p))  # a loop-like period: most power in the low harmonics
    c = np.fft.rfft(yb) / p
    c[1:] *= 2.0
    th = rng.uniform(0.0, 400.0) + np.sort(rng.uniform(0.0, 60.0, 3000))
    return th, c


@pytest.mark.parametrize("seed,p", [(1, 401), (2, 100), (3, 37), (4, 402)])
def test_matches_the_direct_sum(seed: int, p: int) -> None:
    th, c = _period(seed, p)
    scale = float(np.sum(np.abs(c)))
    assert np.max(np.abs(harmonic_series(th, c) - _direct(th, c))) < 1e-11 * scale


def test_no_less_accurate_than_the_direct_sum() -> None:
    th, c = _period(5, 401)
    tl, cl = th.astype(np.longdouble), c.astype(np.clongdouble)
    ref = np.zeros(th.shape, dtype=np.longdouble)
    for h in range(c.size):  # each harmonic's phase in 80-bit arithmetic
        ref += (cl[h] * np.exp(1j * (tl * h))).real
    err_new = float(np.max(np.abs(harmonic_series(th, c) - ref)))
    err_old = float(np.max(np.abs(_direct(th, c) - ref)))
    assert err_new <= err_old


def test_upper_harmonics_is_the_old_loop() -> None:
    class _Ap:
        ybar = np.cumsum(np.random.default_rng(6).standard_normal(101))

    th = 100.0 + np.linspace(0.0, 50.0, 2001)
    c = np.fft.rfft(_Ap.ybar) / _Ap.ybar.size
    old = np.zeros(th.shape)
    for h in range(2, (_Ap.ybar.size - 1) // 2 + 1):
        old += 2.0 * (c[h].real * np.cos(h * th) - c[h].imag * np.sin(h * th))
    new = _upper_harmonics(_Ap(), th)
    assert np.max(np.abs(new - old)) < 1e-11 * float(np.sum(np.abs(c)))
    assert np.max(np.abs(new)) > 0.1 * np.max(np.abs(old))  # the harmonics 2..K, not nothing


def test_empty_and_constant() -> None:
    th = np.linspace(0.0, 10.0, 7)
    assert np.array_equal(harmonic_series(th, np.zeros(0, dtype=np.complex128)), np.zeros(7))
    assert np.allclose(harmonic_series(th, np.array([2.5 + 1.0j])), 2.5)

"""A smooth wander of the zero taken out as a curve, not as steps (session 47, wander47).

``baseline.removed`` takes each period's mean out and leaves a random walk's leak on the harmonics (the walk's
step variance read from the differences of neighbouring period means, ``baseline.step_variance``). A zero
that wanders smoothly (``dc_wander.py``: a fraction of a cycle over the record) is no walk: the differences
of its period means are its slope, and read as steps they put the noise floor at 1.1-3.1 times the true
noise variance on review 45's design C (studies/wander46), a loss of power. Its within-period ramp does leak
into the harmonics (a few averaged-noise sd at the fundamental there), so it cannot be ignored either.

Here, per recording (the periods after settling), a polynomial in time (Legendre, degree 0 to
:data:`MAX_DEGREE` and at most a third of the ``n`` periods: a smooth curve spends few of them) is fitted
to the period means, each column of the basis averaged over the period as the means are; the degree is the
one of least AIC (the chi-square against the white noise, whose variance over ``P`` is each mean's, plus
twice the parameters). On 16 periods of a random walk (tests/test_diagnosis_baseline.py) the best curve
of degree 5 or less misses the means at p < 1e-3 in 60 of 60 recordings (``studies/wander47/probe47.py``).
When the means sit on that curve within the noise (its chi-square p at least :data:`CURVE_ALPHA`),
:func:`removed` takes the curve out sample by sample (its ramp within each period too) and then what is left
of each period's mean, and leaves no walk level. When they do not (a random walk's means are rough at every
scale), the recording is taken out period by period with the walk's leak, as before (:func:`degree` is
None).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from .data import BASELINE_MARK

#: Level of the period means' chi-square about the chosen curve below which they are not smooth (steps).
CURVE_ALPHA = 1e-3
#: Highest degree of the curve (a wander of up to a cycle or so over the record needs 5-9 on 30 periods).
MAX_DEGREE = 12


def _rows(rec: Any) -> tuple[np.ndarray, int, int]:
    """The periods after settling (n, P), P and the settling periods."""
    p, s = int(rec.samples_per_period), int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    return np.asarray(rec.y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p), p, s


def _basis(n: int, p: int, d: int) -> np.ndarray:
    """Legendre polynomials 0..d over the ``n * p`` samples' times mapped onto [-1, 1]."""
    x = (np.arange(n * p, dtype=np.float64) + 0.5) / (n * p) * 2.0 - 1.0
    return np.asarray(np.polynomial.legendre.legvander(x, d))


def fit(rows: np.ndarray) -> Optional[tuple[int, float, int, float]]:
    """The chosen curve through the period means of ``rows`` (n, P): its degree, chi-square, dof and p;
    None when the periods are too few (under 4) or the white noise cannot be read."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    n, p = rows.shape
    if n < 4 or p < 2:
        return None
    dc = rows.mean(axis=1)
    white = float(np.mean(np.diff(rows - dc[:, None], axis=0) ** 2)) / 2.0 * p / (p - 1)
    if not (white > 0 and math.isfinite(white)):
        return None
    top = min(MAX_DEGREE, n // 3)
    means = _basis(n, p, top).reshape(n, p, top + 1).mean(axis=1)
    best: Optional[tuple[float, int, float]] = None
    for d in range(top + 1):
        a = means[:, : d + 1]
        res = dc - a @ np.linalg.lstsq(a, dc, rcond=None)[0]
        chi2 = float(res @ res) * p / white
        if best is None or chi2 + 2.0 * (d + 1) < best[0]:
            best = (chi2 + 2.0 * (d + 1), d, chi2)
    assert best is not None
    _, d, chi2 = best
    return d, chi2, n - d - 1, float(chdtrc(n - d - 1, chi2))


def degree(rec: Any) -> Optional[int]:
    """The curve's degree for Recording ``rec`` (:func:`fit`) when its period means sit on it within the
    noise (p at least :data:`CURVE_ALPHA`), else None (taken out period by period, with a walk's leak)."""
    try:
        rows, _, _ = _rows(rec)
    except Exception:  # no whole-period grid: prepare() names the problem
        return None
    got = fit(rows)
    return got[0] if got is not None and got[3] >= CURVE_ALPHA else None


def removed(rec: Any, d: int, centre: float) -> Any:
    """``rec`` with the degree-``d`` curve through its period means after settling taken out sample by
    sample, then each period's remaining mean (the settling periods' and the tail's means as
    ``baseline.removed`` takes them), ``centre`` put back; marked with no walk."""
    rows, p, s = _rows(rec)
    n = rows.shape[0]
    y = np.array(rec.y, dtype=np.float64)
    basis = _basis(n, p, d)
    means = basis.reshape(n, p, d + 1).mean(axis=1)
    beta = np.linalg.lstsq(means, rows.mean(axis=1), rcond=None)[0]
    y[s * p : (s + n) * p] -= basis @ beta
    whole = int(rec.whole_periods)
    dc = y[: whole * p].reshape(whole, p).mean(axis=1)
    shift = np.concatenate([np.repeat(dc, p), np.full(y.size - whole * p, dc[-1] if whole else 0.0)])
    meta = {**dict(rec.metadata), BASELINE_MARK: repr(0.0)}
    return replace(rec, y=y - shift + centre, metadata=meta)


__all__ = ["fit", "degree", "removed", "CURVE_ALPHA", "MAX_DEGREE"]

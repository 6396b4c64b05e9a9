"""One candidate order fitted: the Sanathanan-Koerner start, then the weighted nonlinear refinement."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ._model import _Model, _stabilise
from ._points import _Points, _whiten

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Sanathanan-Koerner re-weighting iterations: the weights converge in a handful on clean data, and the
#: start only has to land in the refinement's basin.
SK_ITERATIONS = 12
#: Trial delays of the start, as fractions of the delay the high-frequency phase slope suggests: the slope
#: also holds the poles' phase lag, so the true delay is somewhere below it.
DELAY_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: Evaluations of the refinement: a model of the right order converges in a few tens; an over-sized one
#: (redundant poles and zeros) creeps along a flat valley, and its criterion is not helped by creeping on.
MAX_NFEV = 100


@dataclass
class _Fit:
    m: int
    n: int
    delay: bool
    theta: FloatArray
    chi2: float
    jac: FloatArray  # whitened (2k, p)
    reflected: int


def _sk_start(
    points: _Points, s: ComplexArray, m: int, n: int, tau: float
) -> tuple[FloatArray, ComplexArray]:
    """Sanathanan-Koerner fit of ``G exp(tau s)`` by ``N/D``; returns (num, den) in s', den monic."""
    g = points.g * np.exp(tau * s)
    prev: Any = np.ones_like(s)
    num: Any = np.zeros(m + 1)
    den: Any = np.ones(1)
    for _ in range(SK_ITERATIONS):
        cols = [s ** (m - k) / prev for k in range(m + 1)] + [
            -g * s ** (n - k) / prev for k in range(1, n + 1)
        ]
        a = np.stack(cols, axis=1) if cols else np.zeros((s.size, 0), dtype=np.complex128)
        y = g * s**n / prev
        aw = _whiten(points, a).reshape(2 * s.size, -1)
        yw = _whiten(points, y).reshape(-1)
        x, *_ = np.linalg.lstsq(aw, yw, rcond=None)
        num = x[: m + 1]
        den = np.concatenate([[1.0], x[m + 1 :]])
        new = np.polyval(den, s)
        if np.any(new == 0.0):
            break
        prev = new
    return num, den


def _numerator_for(points: _Points, s: ComplexArray, m: int, den: FloatArray, tau: float) -> FloatArray:
    """The weighted least-squares numerator for a fixed denominator and delay (linear in b)."""
    base = np.exp(-tau * s) / np.polyval(den, s)
    a = np.stack([s ** (m - k) * base for k in range(m + 1)], axis=1)
    aw = _whiten(points, a).reshape(2 * s.size, -1)
    yw = _whiten(points, points.g).reshape(-1)
    x, *_ = np.linalg.lstsq(aw, yw, rcond=None)
    out: FloatArray = np.asarray(x, dtype=np.float64)
    return out


def _phase_slope_delay(points: _Points, s: ComplexArray) -> float:
    """Delay (scaled) suggested by the slope of the unwrapped phase over the upper half of the points."""
    w = s.imag
    phi = -np.unwrap(np.angle(points.g))
    half = max(2, w.size // 2)
    ww, pp = w[-half:], phi[-half:]
    if ww.size < 2 or np.ptp(ww) == 0.0:
        return 0.0
    slope = float(np.polyfit(ww, pp, 1)[0])
    return max(slope, 0.0)


def _fit_one(points: _Points, s: ComplexArray, m: int, n: int, delay: bool, fixed_tau: float) -> _Fit:
    from scipy.optimize import least_squares  # type: ignore[import-untyped]

    model = _Model(m, n, delay, fixed_tau)
    taus = [fixed_tau] if not delay else [f * _phase_slope_delay(points, s) for f in DELAY_FRACTIONS]
    best: Optional[tuple[float, FloatArray, int]] = None
    poles: Any
    den: Any
    for tau in taus:
        if n > 0:
            _, den = _sk_start(points, s, m, n, tau)
            poles, reflected = _stabilise(np.roots(den).astype(np.complex128))
            den = np.real(np.poly(poles))
        else:
            poles, reflected, den = np.zeros(0, dtype=np.complex128), 0, np.ones(1)
        num = _numerator_for(points, s, m, den, tau)
        theta0 = model.theta_from(num, poles, tau)
        cost = float(np.sum(_whiten(points, model.response(theta0, s) - points.g) ** 2))
        if best is None or cost < best[0]:
            best = (cost, theta0, reflected)
    assert best is not None
    theta0, reflected = best[1], best[2]

    def fun(theta: FloatArray) -> FloatArray:
        out: FloatArray = _whiten(points, model.response(theta, s) - points.g).reshape(-1)
        return out

    def jac(theta: FloatArray) -> FloatArray:
        _, dg = model.response(theta, s, jacobian=True)
        out: FloatArray = _whiten(points, dg).reshape(2 * s.size, -1)
        return out

    sol = least_squares(
        # MINPACK's LM is the fastest here but needs at least as many residuals as parameters; an
        # over-parameterised fit (forced by the user, warned about) takes the trust-region solver.
        fun,
        theta0,
        jac=jac,
        method="lm" if 2 * s.size >= model.size else "trf",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=MAX_NFEV,
    )
    theta = np.asarray(sol.x, dtype=np.float64)
    return _Fit(m, n, delay, theta, float(np.sum(sol.fun**2)), jac(theta), reflected)


def _criteria(chi2: float, k: int, eqs: int, weighted: bool) -> tuple[float, float]:
    """(AICc, BIC) of a fit with ``k`` parameters on ``eqs`` real equations."""
    if weighted:
        fit = chi2  # -2 log L up to a constant, the variances known
    else:
        fit = eqs * math.log(max(chi2, 1e-300) / eqs)  # variance estimated from the residuals
    aic = fit + 2.0 * k
    aicc = aic + 2.0 * k * (k + 1) / (eqs - k - 1) if eqs - k - 1 > 0 else math.inf
    bic = fit + k * math.log(eqs)
    return aicc, bic

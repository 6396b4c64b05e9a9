"""NumPy reference of ``rust/series_loop.rs``: the steady loop behind Spencer's series dashpot.

Written from ``docs/diagnosis.md`` ("Series dashpot"), step for step as the core so that the parity tests
hold the two to rounding. With alpha = 1, ``x = A cos(theta - phi)`` and ``r = rho / omega``::

    dw/dtheta = v [1 - |w|^mu (beta sgn(v w) + gamma + delta sgn(w))],   v = -A sin(theta - phi) - r w

integrated by classical RK4 in theta with the forward sensitivities to ``(w0, beta, gamma, mu, A, phi,
delta, r)`` carried as a vector beside the value; the steady loop is the root of ``W(w0) - w0`` on
``[-w_b, w_b]`` (Newton safeguarded by bisection, from ``w0 = 0``), and each sample's row is
``dw_j/dp + dw_j/dw0 (dW/dp) / (1 - dW/dw0)``.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import InsufficientDataError, InvalidParameterError, NotConvergedError, ZeroAmplitudeError
from ..validation import finite_scalar

__all__ = ["series_loop", "N_SD"]

FloatArray = NDArray[np.float64]

#: Columns of a row: d w / d(beta, gamma, mu, A, phi, delta, r).
N_SD = 7
#: Carried derivatives: w0, then the seven parameters.
_ND = 8
_MAX_ITER = 80
_RTOL = 1e-12
#: Most RK4 steps per sample interval (beyond: too stiff, a named error).
MAX_STEPS_PER_SAMPLE = 256


def _sign(v: float) -> float:
    return 1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0


def _rhs(prm: tuple[float, ...], theta: float, w: float, dw: FloatArray) -> tuple[float, FloatArray]:
    a, beta, gamma, mu, delta, phi, r = prm
    s, c = math.sin(theta - phi), math.cos(theta - phi)
    v = -a * s - r * w
    dv = -r * dw
    dv[4] += -s
    dv[5] += a * c
    dv[7] += -w
    sw, svw = _sign(w), _sign(v * w)
    aw = abs(w)
    m = aw**mu
    dm_dw, dm_dmu = (mu * m / aw * sw, m * math.log(aw)) if aw > 0.0 else (0.0, 0.0)
    bracket = beta * svw + gamma + delta * sw
    h = 1.0 - m * bracket
    dh = -dm_dw * dw * bracket
    dh[1] -= m * svw
    dh[2] -= m
    dh[3] -= dm_dmu * bracket
    dh[6] -= m * sw
    return v * h, dv * h + v * dh


def _pass(
    prm: tuple[float, ...], w0: float, n: int, m: int, record: Optional[list[tuple[float, FloatArray]]] = None
) -> tuple[float, FloatArray]:
    w, dw = w0, np.zeros(_ND)
    dw[0] = 1.0
    h = 2.0 * math.pi / (n * m)
    for j in range(n):
        if record is not None:
            record.append((w, dw.copy()))
        for s in range(m):
            t = h * (j * m + s)
            k1, d1 = _rhs(prm, t, w, dw)
            k2, d2 = _rhs(prm, t + 0.5 * h, w + 0.5 * h * k1, dw + 0.5 * h * d1)
            k3, d3 = _rhs(prm, t + 0.5 * h, w + 0.5 * h * k2, dw + 0.5 * h * d2)
            k4, d4 = _rhs(prm, t + h, w + h * k3, dw + h * d3)
            w = w + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            dw = dw + h / 6.0 * (d1 + 2.0 * d2 + 2.0 * d3 + d4)
    return w, dw


def _steps_per_sample(prm: tuple[float, ...], bound: float, n: int, substeps: int) -> int:
    a, beta, gamma, mu, delta, _, r = prm
    bg = abs(beta) + abs(gamma) + abs(delta)
    vmax = abs(a) + r * bound
    stiff = vmax * mu * bg * bound ** (mu - 1.0) + r * (1.0 + bg * bound**mu)
    need = stiff * 2.0 * math.pi / n
    if not math.isfinite(need) or need > MAX_STEPS_PER_SAMPLE:
        return MAX_STEPS_PER_SAMPLE + 1
    return int(math.ceil(need)) if need > substeps else substeps


def series_loop(
    amplitude: float,
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    phi: float,
    r: float,
    p: int,
    substeps: int,
) -> tuple[FloatArray, FloatArray, int]:
    """``(w (P,), jac (P, 7), passes)``: the steady loop behind the series dashpot (module docstring).

    ``amplitude`` is the signed A of x, ``r = rho / omega >= 0``; the columns are
    ``d/d(beta, gamma, mu, A, phi, delta, r)``.
    """
    for name, v in (
        ("amplitude", amplitude),
        ("beta", beta),
        ("gamma", gamma),
        ("mu", mu),
        ("delta", delta),
        ("phi", phi),
        ("series_dashpot r", r),
    ):
        finite_scalar(name, v)
    if mu <= 1.0:
        raise InvalidParameterError(f"mu = {mu} must be > 1 in the identification model")
    margin = beta + gamma - abs(delta)
    if margin <= 0.0:
        raise InvalidParameterError(f"beta + gamma - |delta| = {margin} must be > 0")
    if r < 0.0:
        raise InvalidParameterError(f"series_dashpot r = rho/omega = {r} must be >= 0")
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the amplitude of x is 0: the loop is a point")
    if p < 4:
        raise InsufficientDataError(f"P = {p} samples per period; the steady loop needs at least 4")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    bound = (1.0 / margin) ** (1.0 / mu)
    prm = (float(amplitude), float(beta), float(gamma), float(mu), float(delta), float(phi), float(r))
    m = _steps_per_sample(prm, bound, p, substeps)
    if m > max(MAX_STEPS_PER_SAMPLE, substeps):
        raise NotConvergedError(
            f"the series-dashpot loop is too stiff for its explicit RK4 (more than {MAX_STEPS_PER_SAMPLE} "
            f"steps per sample) at r = rho/omega = {r}"
        )
    lo, hi, w0, passes = -bound, bound, 0.0, 0
    while True:
        if passes == _MAX_ITER:
            raise NotConvergedError(
                f"the series-dashpot loop found no periodic solution in {_MAX_ITER} passes"
            )
        passes += 1
        wn, dwn = _pass(prm, w0, p, m)
        if not math.isfinite(wn):
            raise NotConvergedError(f"the series-dashpot loop diverged (w = {wn} after one period)")
        g = wn - w0
        if abs(g) <= _RTOL * bound:
            break
        if g > 0.0:
            lo = w0
        else:
            hi = w0
        slope = dwn[0] - 1.0
        newton = w0 - g / slope
        w0 = newton if slope < 0.0 and lo < newton < hi else 0.5 * (lo + hi)
    record: list[tuple[float, FloatArray]] = []
    _pass(prm, w0, p, m, record)
    dw0 = dwn[1:] / (1.0 - dwn[0])
    w = np.array([v for v, _ in record])
    jac = np.array([d[1:] + d[0] * dw0 for _, d in record])
    return w, jac, passes

"""NumPy reference of ``rust/timedomain.rs``: the time-domain Wiener cascade and its exact Jacobian.

Written from the module documentation of the Rust file, independently of its code: every quantity of the
RK4 step is a NumPy vector ``[value, d/dtheta_0, ..., d/dtheta_(p-1)]`` (forward-mode differentiation, the
derivative of the discrete map), with the chain rule written out per operation below.  Plain Python loops:
slow, for the parity tests only.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, InvalidParameterError, NonFiniteError

__all__ = ["timedomain_sensitivities", "MAX_ORDER"]

FloatArray = NDArray[np.float64]

#: Largest denominator degree (as rust/timedomain.rs).
MAX_ORDER = 4


def _mul(a: FloatArray, b: FloatArray) -> FloatArray:
    out: FloatArray = a[0] * b
    out[1:] += b[0] * a[1:]
    return out


def _pow_abs(w: FloatArray, mu: FloatArray) -> FloatArray:
    """``|w|^mu`` with its derivatives (0 at w = 0)."""
    aw = abs(float(w[0]))
    out = np.zeros_like(w)
    if aw == 0.0:
        return out
    val = aw ** float(mu[0])
    out[0] = val
    out[1:] = val * (float(mu[0]) * math.copysign(1.0, float(w[0])) / aw * w[1:] + math.log(aw) * mu[1:])
    return out


def _sgn(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


def _check(m: int, n: int, theta: FloatArray, u: FloatArray, dt: float, substeps: int) -> None:
    if not (0 <= m <= n <= MAX_ORDER):
        raise InvalidParameterError(f"the degrees must satisfy m <= n <= {MAX_ORDER}, got m = {m}, n = {n}")
    if theta.size != m + n + 6:
        raise InvalidParameterError(f"theta must hold m + n + 6 = {m + n + 6} values, got {theta.size}")
    if not np.all(np.isfinite(theta)):
        raise NonFiniteError("theta holds a non-finite value")
    if not np.all(np.isfinite(u)):
        raise NonFiniteError("u holds a non-finite value")
    if u.size < 2:
        raise InsufficientDataError(f"a sampled input needs at least 2 samples, got {u.size}")
    if not math.isfinite(dt):
        raise NonFiniteError(f"dt = {dt} is not finite")
    if dt <= 0.0:
        raise InvalidParameterError(f"dt = {dt} s must be > 0")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    if theta[m + 1 + n] < 0.0:
        raise InvalidParameterError(f"the delay = {theta[m + 1 + n]} s must be >= 0")
    if theta[m + n + 4] < 1.0:
        raise InvalidParameterError(f"mu = {theta[m + n + 4]} must be >= 1")


def _hermite(u: FloatArray, slopes: FloatArray, dt: float, tau: float) -> tuple[float, float, float]:
    """The Catmull-Rom cubic of ``rust/simulate.rs`` at ``tau >= 0``: value, first and second derivative."""
    last = u.size - 1
    q = tau / dt
    k = math.floor(q)
    if k >= last:
        return float(u[last]), 0.0, 0.0
    s = q - k
    u0, u1, m0, m1 = float(u[k]), float(u[k + 1]), float(slopes[k]), float(slopes[k + 1])
    val = (2 * s**3 - 3 * s**2 + 1) * u0 + (s**3 - 2 * s**2 + s) * dt * m0
    val += (-2 * s**3 + 3 * s**2) * u1 + (s**3 - s**2) * dt * m1
    der = ((6 * s**2 - 6 * s) * u0 + (-6 * s**2 + 6 * s) * u1) / dt
    der += (3 * s**2 - 4 * s + 1) * m0 + (3 * s**2 - 2 * s) * m1
    der2 = ((12 * s - 6) * u0 + (-12 * s + 6) * u1) / dt**2 + ((6 * s - 4) * m0 + (6 * s - 2) * m1) / dt
    return val, der, der2


def timedomain_sensitivities(
    m: int, n: int, theta: ArrayLike, u: ArrayLike, dt: float, substeps: int
) -> tuple[FloatArray, FloatArray]:
    """``(y, J)`` of ``rust/timedomain.rs`` ``simulate_sensitivities`` (same layout and errors)."""
    th = np.asarray(theta, dtype=np.float64).reshape(-1)
    uu = np.asarray(u, dtype=np.float64).reshape(-1)
    _check(int(m), int(n), th, uu, float(dt), int(substeps))
    p = th.size
    eye = np.eye(p)

    def var(i: int) -> FloatArray:
        return np.concatenate([[th[i]], eye[i]])

    def const(v: float) -> FloatArray:
        out = np.zeros(p + 1)
        out[0] = v
        return out

    b = [const(0.0) for _ in range(n - m)] + [var(k) for k in range(m + 1)]
    a = [var(m + 1 + j) for j in range(n)]
    d = b[0]
    c = [b[j + 1] - _mul(d, a[j]) for j in range(n)]
    i_tau = m + 1 + n
    tau = float(th[i_tau])
    beta, gamma, mu = var(i_tau + 1), var(i_tau + 2), var(i_tau + 3)
    slopes = np.empty_like(uu)
    slopes[1:-1] = (uu[2:] - uu[:-2]) / (2.0 * dt)
    slopes[0] = (uu[1] - uu[0]) / dt
    slopes[-1] = (uu[-1] - uu[-2]) / dt

    def source(t: float) -> tuple[FloatArray, FloatArray]:
        s = t - tau
        if s < 0.0:
            return const(0.0), const(0.0)
        val, der, der2 = _hermite(uu, slopes, float(dt), s)
        v, vd = const(val), const(der)
        v[1 + i_tau] = -der
        vd[1 + i_tau] = -der2
        return v, vd

    def rhs(
        xs: list[FloatArray], w: FloatArray, vin: tuple[FloatArray, FloatArray]
    ) -> tuple[list[FloatArray], FloatArray]:
        v, vdot = vin
        dxs: list[FloatArray] = []
        xdot = _mul(d, vdot)
        if n:
            first = v.copy()
            for j in range(n):
                first = first - _mul(a[j], xs[j])
            dxs = [first] + xs[: n - 1]
            for j in range(n):
                xdot = xdot + _mul(c[j], dxs[j])
        wmu = _pow_abs(w, mu)
        k = beta * (_sgn(float(xdot[0])) * _sgn(float(w[0]))) + gamma
        return dxs, xdot - _mul(xdot, _mul(k, wmu))

    h = dt / substeps
    xs = [const(0.0) for _ in range(n)]
    w = var(i_tau + 4)
    y = np.empty(uu.size)
    jac = np.empty((uu.size, p))
    for k in range(uu.size):
        y[k] = w[0]
        jac[k] = w[1:]
        if k == uu.size - 1:
            break
        t = k * dt
        for s in range(substeps):
            ts = t + s * h
            start, mid, end = source(ts), source(ts + 0.5 * h), source(ts + h)
            k1, kw1 = rhs(xs, w, start)
            k2, kw2 = rhs([x + 0.5 * h * q for x, q in zip(xs, k1)], w + 0.5 * h * kw1, mid)
            k3, kw3 = rhs([x + 0.5 * h * q for x, q in zip(xs, k2)], w + 0.5 * h * kw2, mid)
            k4, kw4 = rhs([x + h * q for x, q in zip(xs, k3)], w + h * kw3, end)
            xs = [x + h / 6.0 * (q1 + 2 * q2 + 2 * q3 + q4) for x, q1, q2, q3, q4 in zip(xs, k1, k2, k3, k4)]
            w = w + h / 6.0 * (kw1 + 2 * kw2 + 2 * kw3 + kw4)
    return y, jac

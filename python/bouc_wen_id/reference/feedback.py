"""NumPy reference of ``rust/feedback.rs``: Bouc-Wen in feedback (the Noel-Schoukens benchmark structure),

``m ydd + c yd + k y + z = u``, ``zdot = alpha yd - bg |yd| |z|^(nu-1) z - bd yd |z|^nu``,

simulated by RK4 with the forward sensitivities of the discrete map w.r.t. ``[m, c, k, alpha, bg, bd, nu]``
and the initial state ``[y0, yd0, z0]``.  The input is given on the grid ``dt / upsample`` and interpolated
by Catmull-Rom cubics, as ``reference/simulate.py`` does.  Plain Python loops: slow, for the parity tests.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, InvalidParameterError, NonFiniteError, NotConvergedError
from ..validation import finite_array as _finite_array
from ..validation import finite_scalar as _finite_scalar

__all__ = ["feedback_periodic", "feedback_simulate"]

FloatArray = NDArray[np.float64]

N_PARAMS = 7
N_COLS = 10
_NAMES = ("m", "c", "k", "alpha", "beta*gamma", "beta*delta", "nu")


def _sgn(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


def _check(
    theta: ArrayLike, x0: ArrayLike, u: ArrayLike, dt: float, upsample: int, substeps: int
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    th = np.asarray(theta, dtype=np.float64).ravel()
    if th.size != N_PARAMS:
        raise InvalidParameterError(
            f"theta must hold the {N_PARAMS} parameters [m, c, k, alpha, beta*gamma, beta*delta, nu], "
            f"got {th.size}"
        )
    for name, v in zip(_NAMES, th):
        _finite_scalar(name, float(v))
    if th[0] <= 0.0:
        raise InvalidParameterError(f"m = {th[0]} must be > 0 (the mass divides the force balance)")
    if th[6] <= 0.0:
        raise InvalidParameterError(f"nu = {th[6]} must be > 0 (the exponent of |z|)")
    uu = _finite_array("u", u)
    xx = _finite_array("x0", x0)
    if xx.size != 3:
        raise InvalidParameterError(f"x0 must hold [y0, yd0, z0], got {xx.size} values")
    dt_f = _finite_scalar("dt", dt)
    if dt_f <= 0.0:
        raise InvalidParameterError(f"dt = {dt_f} s must be > 0")
    if upsample < 1 or substeps < 1:
        raise InvalidParameterError(f"upsample = {upsample} and substeps = {substeps} must be >= 1")
    if uu.size < 2:
        raise InsufficientDataError(f"a sampled input needs at least 2 samples, got {uu.size}")
    return th, xx, uu, dt_f


def _hermite(uu: FloatArray, du: float) -> tuple[FloatArray, float]:
    m = np.empty_like(uu)
    m[1:-1] = (uu[2:] - uu[:-2]) / (2.0 * du)
    m[0] = (uu[1] - uu[0]) / du
    m[-1] = (uu[-1] - uu[-2]) / du
    return m, du


def _interp(uu: FloatArray, m: FloatArray, du: float, tau: float) -> float:
    if tau <= 0.0:
        return float(uu[0])
    last = uu.size - 1
    q = tau / du
    kf = math.floor(q)
    if kf >= last:
        return float(uu[last])
    k = int(kf)
    s = q - kf
    s2, s3 = s * s, s * s * s
    h00 = 2.0 * s3 - 3.0 * s2 + 1.0
    h10 = s3 - 2.0 * s2 + s
    h01 = -2.0 * s3 + 3.0 * s2
    h11 = s3 - s2
    return float(h00 * uu[k] + h10 * du * m[k] + h01 * uu[k + 1] + h11 * du * m[k + 1])


def _eval(th: FloatArray, x: FloatArray, u: float) -> tuple[FloatArray, FloatArray]:
    """``f(x)`` and the stage's ``[f_x | f_p]`` pieces as a 3 x (3 + 7) matrix."""
    m, c, k, alpha, bg, bd, nu = (float(v) for v in th)
    y, v, z = (float(e) for e in x)
    az, sz, av = abs(z), _sgn(z), abs(v)
    wmu = az**nu
    vdot = (u - c * v - k * y - z) / m
    zdot = alpha * v - bg * av * sz * wmu - bd * v * wmu
    pz = wmu / az if az > 0.0 else (1.0 if nu == 1.0 else 0.0)
    lz = math.log(az) if az > 0.0 else 0.0
    d = np.zeros((3, 3 + N_PARAMS))
    d[0, 1] = 1.0
    d[1, :3] = [-k / m, -c / m, -1.0 / m]
    d[2, 1] = alpha - bg * _sgn(v) * sz * wmu - bd * wmu
    d[2, 2] = -nu * pz * (bg * av + bd * v * sz)
    d[1, 3:6] = [-vdot / m, -v / m, -y / m]
    d[2, 6:10] = [v, -av * sz * wmu, -v * wmu, -(bg * av * sz + bd * v) * wmu * lz]
    return np.array([v, vdot, zdot]), d


def _sens_rate(d: FloatArray, s: FloatArray) -> FloatArray:
    out = d[:, :3] @ s
    out[:, :N_PARAMS] += d[:, 3:]
    return out


def _integrate(
    th: FloatArray,
    x0: FloatArray,
    source: Callable[[float], float],
    dt: float,
    n: int,
    substeps: int,
    sensitivities: bool,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """RK4 over ``n`` output samples: ``(y, jacobian, final state, final state sensitivity 3 x 10)``."""
    h = dt / substeps
    x = np.array(x0, dtype=np.float64)
    s = np.zeros((3, N_COLS))
    s[:, N_PARAMS:] = np.eye(3)
    y = np.empty(n)
    jac = np.empty((n, N_COLS if sensitivities else 0))
    with np.errstate(all="ignore"):
        for kk in range(n):
            y[kk] = x[0]
            if sensitivities:
                jac[kk] = s[0]
            if kk == n - 1:
                break
            t = kk * dt
            for step in range(substeps):
                ts = t + step * h
                u0, um, u1 = (source(tt) for tt in (ts, ts + 0.5 * h, ts + h))
                f1, d1 = _eval(th, x, u0)
                f2, d2 = _eval(th, x + 0.5 * h * f1, um)
                f3, d3 = _eval(th, x + 0.5 * h * f2, um)
                f4, d4 = _eval(th, x + h * f3, u1)
                if sensitivities:
                    k1 = _sens_rate(d1, s)
                    k2 = _sens_rate(d2, s + 0.5 * h * k1)
                    k3 = _sens_rate(d3, s + 0.5 * h * k2)
                    k4 = _sens_rate(d4, s + h * k3)
                    s = s + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
                x = x + (h / 6.0) * (f1 + 2.0 * f2 + 2.0 * f3 + f4)
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(x))):
        bad = int(np.argmax(~np.isfinite(y))) if not np.all(np.isfinite(y)) else n - 1
        raise NonFiniteError(
            f"the feedback simulation blew up at sample {bad} (t = {bad * dt:.6e} s); the parameters "
            f"[m, c, k, alpha, beta*gamma, beta*delta, nu] = {th.tolist()} make the state overflow at this "
            "input level; use parameters of moderate size or more substeps"
        )
    return y, jac, x, s


def feedback_simulate(
    theta: Sequence[float] | FloatArray,
    x0: Sequence[float] | FloatArray,
    u: FloatArray,
    dt: float,
    upsample: int,
    substeps: int,
    sensitivities: bool = True,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(y, jacobian, state)``: ``y`` on the output grid (``(u.size - 1) // upsample + 1`` samples), the
    Jacobian ``d y / d [theta, x0]`` (``n x 10``; ``n x 0`` without ``sensitivities``) and the final state."""
    th, xx, uu, dt_f = _check(theta, x0, u, dt, upsample, substeps)
    n = (uu.size - 1) // upsample + 1
    slopes, du = _hermite(uu, dt_f / upsample)
    y, jac, x, _ = _integrate(th, xx, lambda t: _interp(uu, slopes, du, t), dt_f, n, substeps, sensitivities)
    return y, jac, x


def feedback_periodic(
    theta: Sequence[float] | FloatArray,
    amplitude: float,
    omega: float,
    samples: int,
    substeps: int,
    settle_periods: int = 2,
    max_iter: int = 50,
    tol: float = 1e-10,
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """One period of the periodic steady state under ``amplitude cos(omega t)`` by Newton shooting with the
    monodromy matrix: ``(y, d y / d theta (samples x 7), x0*, iterations)``
    (``rust/feedback/periodic.rs``)."""
    th, _, _, _ = _check(theta, np.zeros(3), np.zeros(2), 1.0, 1, max(substeps, 1))
    amp = _finite_scalar("amplitude", amplitude)
    om = _finite_scalar("omega", omega)
    tol = _finite_scalar("tol", tol)
    if om <= 0.0 or samples < 4 or substeps < 1 or tol <= 0.0:
        raise InvalidParameterError(
            f"omega = {om} rad/s and tol = {tol} must be > 0, samples = {samples} >= 4, "
            f"substeps = {substeps} >= 1"
        )

    def source(t: float) -> float:
        return amp * math.cos(om * t)

    dt = 2.0 * math.pi / om / samples
    x0 = np.zeros(3)
    if settle_periods > 0:
        x0 = _integrate(th, x0, source, dt, samples * settle_periods + 1, substeps, False)[2]
    for iteration in range(1, max_iter + 1):
        y, jac, x_end, s_end = _integrate(th, x0, source, dt, samples + 1, substeps, True)
        big_y = float(np.max(np.abs(y)))
        scale = np.array([big_y, om * big_y, abs(amp) + abs(th[3]) * big_y])
        f = x_end - x0
        try:
            inv = np.linalg.inv(s_end[:, N_PARAMS:] - np.eye(3))
        except np.linalg.LinAlgError:
            raise NotConvergedError(
                f"the monodromy matrix minus the identity is singular at iteration {iteration}"
            ) from None
        if np.all(np.abs(f) <= tol * np.maximum(scale, np.finfo(float).tiny)):
            dx0 = -inv @ s_end[:, :N_PARAMS]
            total = jac[:samples, :N_PARAMS] + jac[:samples, N_PARAMS:] @ dx0
            return y[:samples], total, x0, iteration
        x0 = x0 - inv @ f
    raise NotConvergedError(
        f"the Newton shooting did not find the periodic state in {max_iter} iterations (amplitude = {amp}, "
        f"omega = {om} rad/s); settle more periods first or raise max_iter"
    )

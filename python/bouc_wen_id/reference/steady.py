"""NumPy reference of ``rust/steady.rs``: the steady hysteresis loop under a sine, by half-cycle RK4 and
Newton shooting on w(0), with forward sensitivities.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
    NotConvergedError,
    ZeroAmplitudeError,
)
from ..validation import MIN_AVERAGE_SAMPLES
from ..validation import finite_scalar as _finite_scalar

__all__ = ["steady_loop"]

FloatArray = NDArray[np.float64]


#: Newton iterations allowed for the shooting on w(0) of the steady loop.
SHOOT_MAX_ITER = 60
#: Relative tolerance of the periodicity condition |w(pi) + w(0)| <= tol * w_bound.
SHOOT_RTOL = 1e-13
#: Relative tolerance and iteration cap of the coarse shooting that starts the fine one (rust/steady.rs).
COARSE_RTOL = 1e-9
COARSE_MAX_ITER = 20
#: The shootings' first bracket is |w(0)| < BRACKET_SLACK w_bound: a saturated loop's w(0) is the bound
#: itself, where the first Newton step lands (rust/steady.rs).
BRACKET_SLACK = 1.0 + 1e-9


def _loop_rhs(a: float, beta: float, gamma: float, mu: float, theta: float, y: FloatArray) -> FloatArray:
    """Rate of [w, Phi, S_beta, S_gamma, S_mu, S_A] along theta for x = A cos(theta) (alpha = 1)."""
    sin_t = np.sin(theta)
    xt = -a * sin_t
    w = y[0]
    aw = abs(w)
    sw = np.sign(w)
    sx = np.sign(xt)
    if aw > 0.0:
        lnw = np.log(aw)
        wmu = np.exp(mu * lnw)
        wmu1 = wmu / aw
    else:
        lnw = wmu = wmu1 = 0.0
    bracket = 1.0 - beta * sx * sw * wmu - gamma * wmu
    fw = xt * (-beta * sx * mu * wmu1 - gamma * mu * wmu1 * sw)
    return np.array(
        [
            xt * bracket,
            fw * y[1],
            fw * y[2] - xt * sx * sw * wmu,
            fw * y[3] - xt * wmu,
            fw * y[4] + xt * (-beta * sx * sw - gamma) * wmu * lnw,
            fw * y[5] - sin_t * bracket,
        ]
    )


def _check_loop(
    amplitude: float, beta: float, gamma: float, mu: float, phi: float, samples_per_period: int, substeps: int
) -> int:
    """The arguments of :func:`steady_loop` checked as the core does; the samples per period."""
    for name, v in (("amplitude", amplitude), ("beta", beta), ("gamma", gamma), ("mu", mu), ("phi", phi)):
        _finite_scalar(name, v)
    if mu <= 1.0:
        raise InvalidParameterError(f"mu = {mu} must be > 1 in the identification model")
    if beta + gamma <= 0.0:
        raise InvalidParameterError(f"beta + gamma = {beta + gamma} must be > 0: the loop is unbounded")
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the amplitude of x is 0: the loop is a point")
    p = int(samples_per_period)
    if p < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(f"samples_per_period = {p}: at least {MIN_AVERAGE_SAMPLES} are needed")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    return p


def next_iteration(iterations: int, max_iter: int, failure: str, resid: float) -> int:
    """``iterations + 1``, or :class:`NotConvergedError` (``"{failure} iterations (residual ...)"``) past
    ``max_iter``: the count the shootings keep, as the cores do."""
    iterations += 1
    if iterations > max_iter:
        raise NotConvergedError(f"{failure} iterations (residual {resid:.3e})")
    return iterations


def bracketed_newton(
    x: float, resid: float, slope: float, lo: float, hi: float
) -> tuple[float, float, float]:
    """One safeguarded Newton step on a residual increasing in ``x`` (as the cores' shootings):
    ``(x_next, lo, hi)``, ``x`` narrowing the bracket on the side its residual's sign says, and the
    bisection of the bracket where the Newton step ``x - resid / slope`` leaves it or is not finite."""
    if resid > 0.0:
        hi = x
    else:
        lo = x
    newton = x - resid / slope
    return (newton if lo < newton < hi and np.isfinite(newton) else 0.5 * (lo + hi)), lo, hi


def steady_loop(
    amplitude: float, beta: float, gamma: float, mu: float, phi: float, samples_per_period: int, substeps: int
) -> tuple[FloatArray, FloatArray, float, int]:
    """Steady loop of (2b) under ``x = amplitude cos(omega t - phi)`` on P samples per period.

    Half a cycle of ``dw/dtheta`` by RK4 and Newton shooting on ``w(0)`` so that ``w(pi) = -w(0)``,
    with forward sensitivities.  Returns ``(w, jac, w_top, iterations)``, ``jac`` of shape (P, 5):
    ``d w / d(beta, gamma, mu, amplitude, phi)``.
    """
    p = _check_loop(amplitude, beta, gamma, mu, phi, samples_per_period, substeps)
    phi = float(np.mod(phi, 2.0 * np.pi))
    # The sample phases theta_j = 2 pi j/P - phi fold, modulo pi, onto a lattice offset + k L.
    c, n_lat = (1, p // 2) if p % 2 == 0 else (2, p)
    spacing = np.pi / n_lat
    q = phi / spacing
    qf = np.floor(q)
    r = q - qf
    offset, shift = ((1.0 - r) * spacing, int(qf) + 1) if r > 0.0 else (0.0, int(qf))
    idx = c * np.arange(p) - shift
    half = np.floor_divide(idx, n_lat)
    lat = np.mod(idx, n_lat)
    sign = np.where(half % 2 == 0, 1.0, -1.0)

    def rk4(theta: float, y: FloatArray, h: float) -> FloatArray:
        k1 = _loop_rhs(amplitude, beta, gamma, mu, theta, y)
        k2 = _loop_rhs(amplitude, beta, gamma, mu, theta + 0.5 * h, y + 0.5 * h * k1)
        k3 = _loop_rhs(amplitude, beta, gamma, mu, theta + 0.5 * h, y + 0.5 * h * k2)
        k4 = _loop_rhs(amplitude, beta, gamma, mu, theta + h, y + h * k3)
        return y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)

    rec = np.zeros((n_lat, 6))

    def half_cycle(w_top: float, sub: int = substeps) -> FloatArray:
        y = np.array([w_top, 1.0, 0.0, 0.0, 0.0, 0.0])
        if offset > 0.0:
            h = offset / sub
            for s in range(sub):
                y = rk4(s * h, y, h)
        for k in range(n_lat):
            rec[k] = y
            start = offset + k * spacing
            length = np.pi - start if k + 1 == n_lat else spacing
            h = length / sub
            for s in range(sub):
                y = rk4(start + s * h, y, h)
        return y

    def coarse_top() -> Optional[float]:
        # Coarse to fine (as rust/steady.rs): the shooting with one RK4 step per lattice interval
        # proposes the fine shooting's start.
        c_lo, c_hi, top = -bound * BRACKET_SLACK, bound * BRACKET_SLACK, 0.0
        for _ in range(COARSE_MAX_ITER):
            end = half_cycle(top, 1)
            resid = float(end[0] + top)
            if not np.isfinite(resid):
                return None
            if abs(resid) <= COARSE_RTOL * bound:
                return top
            top, c_lo, c_hi = bracketed_newton(top, resid, end[1] + 1.0, c_lo, c_hi)
        return None

    bound = (1.0 / (beta + gamma)) ** (1.0 / mu)
    lo, hi = -bound * BRACKET_SLACK, bound * BRACKET_SLACK
    w_top = (coarse_top() or 0.0) if substeps > 1 else 0.0
    iterations = 0
    while True:
        end = half_cycle(w_top)
        resid = end[0] + w_top
        if abs(resid) <= SHOOT_RTOL * bound:
            break
        iterations = next_iteration(
            iterations,
            SHOOT_MAX_ITER,
            f"the steady-loop shooting did not converge in {SHOOT_MAX_ITER}",
            resid,
        )
        w_top, lo, hi = bracketed_newton(w_top, resid, end[1] + 1.0, lo, hi)
    dtop = -end[2:6] / (1.0 + end[1])
    y = rec[lat]
    theta = offset + lat * spacing
    slope = np.array([_loop_rhs(amplitude, beta, gamma, mu, th, yy)[0] for th, yy in zip(theta, y)])
    w = sign * y[:, 0]
    jac = np.empty((p, 5))
    jac[:, :4] = sign[:, None] * (y[:, 2:6] + y[:, 1:2] * dtop[None, :])
    jac[:, 4] = -sign * slope
    return w, jac, float(w_top), iterations

"""NumPy reference of ``rust/simulate.rs``: the RK4 simulation of the Wiener-Bouc-Wen system under a sine or a
sampled input (Catmull-Rom cubics); with ``terms`` it runs :mod:`.with_terms`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Callable, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
)
from ..validation import check_bouc_wen as _check_bouc_wen
from ..validation import finite_array as _finite_array
from ..validation import finite_scalar as _finite_scalar
from . import on_x, with_terms
from .linear import realize

__all__ = ["simulate_sine", "simulate_sampled"]

FloatArray = NDArray[np.float64]


def _bw_rate(xdot: float, w: float, alpha: float, beta: float, gamma: float, mu: float) -> float:
    """Bouc-Wen (2a): alpha xdot - beta |xdot| |w|^(mu-1) w - gamma xdot |w|^mu."""
    try:
        wmu = abs(w) ** mu
    except OverflowError:  # a blow-up: let it run to inf/NaN as the core does, and be reported at the end
        wmu = float("inf")
    return float(alpha * xdot - beta * abs(xdot) * np.sign(w) * wmu - gamma * xdot * wmu)


def _checked(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    bw: tuple[float, float, float, float, float],
    dt: float,
    n_samples: int,
    substeps: int,
) -> tuple[tuple[FloatArray, FloatArray, float, float], float]:
    """A run's arguments checked as the core does: the realisation ``(a, c, d, delay)`` and ``dt``."""
    realization = realize(num, den, delay)
    _check_bouc_wen(*bw)
    dt = _finite_scalar("dt", dt)
    if dt <= 0.0:
        raise InvalidParameterError(f"dt = {dt} must be > 0")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    if n_samples < 1:
        raise InvalidParameterError(f"n_samples = {n_samples} must be >= 1")
    return realization, dt


def _simulate(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    bw: tuple[float, float, float, float, float],
    source: Callable[[float], tuple[float, float]],
    dt: float,
    n_samples: int,
    substeps: int,
) -> tuple[FloatArray, FloatArray]:
    (a, c, d, delay), dt = _checked(num, den, delay, bw, dt, n_samples, substeps)
    alpha, beta, gamma, mu, w0 = bw
    n = a.size

    def delayed(t: float) -> tuple[float, float]:
        if t - delay < 0.0:
            return 0.0, 0.0
        return source(t - delay)

    def rhs(t: float, z: FloatArray) -> FloatArray:
        v, vdot = delayed(t)
        xs = z[:n]
        dz = np.empty(n + 1)
        if n:
            dz[0] = -np.dot(a, xs) + v
            dz[1:n] = xs[: n - 1]
        xdot = float(np.dot(c, dz[:n])) + d * vdot
        dz[n] = _bw_rate(xdot, float(z[n]), alpha, beta, gamma, mu)
        return dz

    h = dt / substeps
    z = np.zeros(n + 1)
    z[n] = w0
    x_out = np.empty(n_samples)
    w_out = np.empty(n_samples)
    # A blow-up runs on to inf/NaN silently here and is reported, with the parameters, just below.
    with np.errstate(all="ignore"):
        for k in range(n_samples):
            t = k * dt
            x_out[k] = float(np.dot(c, z[:n])) + d * delayed(t)[0]
            w_out[k] = z[n]
            if k == n_samples - 1:
                break
            for s in range(substeps):
                ts = t + s * h
                k1 = rhs(ts, z)
                k2 = rhs(ts + 0.5 * h, z + 0.5 * h * k1)
                k3 = rhs(ts + 0.5 * h, z + 0.5 * h * k2)
                k4 = rhs(ts + h, z + h * k3)
                z = z + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    bad = [int(np.argmax(~np.isfinite(v))) if not np.all(np.isfinite(v)) else None for v in (x_out, w_out)]
    if bad != [None, None]:
        # The model's blow-up, not the caller's data (rust/simulate.rs check_blow_up).
        name, k = min(((nm, kk) for nm, kk in zip(("x", "w"), bad) if kk is not None), key=lambda p: p[1])
        raise NonFiniteError(
            f"the simulation blew up: {name} is not finite from sample {k} (t = {k * dt:.6e} s) on; the "
            f"model parameters (alpha = {alpha:e}, beta = {beta:e}, gamma = {gamma:e}, mu = {mu}, "
            f"w0 = {w0:e}) or the input level make the Bouc-Wen state overflow; use parameters of "
            "moderate size, a smaller amplitude or a finer step (substeps)"
        )
    return x_out, w_out


def _with_terms(
    num: FloatArray,
    den: FloatArray,
    delay: float,
    bw: tuple[float, float, float, float, float],
    inp: with_terms.Input,
    dt: float,
    n_samples: int,
    substeps: int,
    terms: Mapping[str, float],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(x, w, y)`` with physical terms: the plain RK4 plus the output terms when no term has a state."""
    (a, c, d, delay_in), dt = _checked(num, den, delay, bw, dt, n_samples, substeps)
    checked = with_terms.check_terms(terms, bw[1], bw[2])
    steady = None
    if inp.sine is not None:  # the sine's steady |xdot| peak |U| |G(j omega)| omega
        amplitude, omega = inp.sine
        gain = abs(np.polyval(num, 1j * omega)) / abs(np.polyval(den, 1j * omega))
        steady = abs(amplitude) * float(gain) * omega
    onx = on_x.make((a, c, d), checked, with_terms.delayed3(inp, delay_in), steady, (dt, n_samples, substeps))
    model = with_terms.Model(a, c, d, delay_in, bw, checked, onx)
    if with_terms.has_state(model):
        with np.errstate(all="ignore"):  # a blow-up runs on to inf/NaN and is reported just below
            out = with_terms.integrate(model, inp, dt, n_samples, substeps)
    else:
        x_out, w_out = _simulate(num, den, delay, bw, inp.source, dt, n_samples, substeps)
        out = x_out, w_out, with_terms.outputs(model, w_out, inp, dt, substeps)
    _check_blow_up_terms(out, bw, checked, dt)
    return out


def _check_blow_up_terms(
    out: tuple[FloatArray, FloatArray, FloatArray],
    bw: tuple[float, float, float, float, float],
    terms: Mapping[str, float],
    dt: float,
) -> None:
    """A non-finite x, w or y is the model's blow-up: name the parameters and the terms (as the core)."""
    bad = [
        (int(np.argmax(~np.isfinite(v))), name) for name, v in zip("xwy", out) if not np.all(np.isfinite(v))
    ]
    if not bad:
        return
    k, name = min(bad)
    present = ", ".join(f"{n} = {v:e}" for n, v in terms.items() if v != 0.0 and not n.endswith("_smoothing"))
    alpha, beta, gamma, mu, w0 = bw
    raise NonFiniteError(
        f"the simulation blew up: {name} is not finite from sample {k} (t = {k * dt:.6e} s) on; the model "
        f"parameters (alpha = {alpha:e}, beta = {beta:e}, gamma = {gamma:e}, mu = {mu}, w0 = {w0:e}) with "
        f"the terms ({present or 'none'}) or the input level make the state overflow; use term values and "
        "parameters of moderate size, a smaller amplitude or a finer step (substeps)"
    )


def simulate_sine(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    alpha: float,
    beta: float,
    gamma: float,
    mu: float,
    w0: float,
    amplitude: float,
    omega: float,
    dt: float,
    n_samples: int,
    substeps: int,
    *,
    terms: Optional[Mapping[str, float]] = None,
) -> Any:
    """RK4 simulation of the Wiener system driven by ``u(t) = amplitude cos(omega t)``, t >= 0.

    Returns ``(x, w)`` at the ``n_samples`` grid times ``k dt`` (s); ``omega`` in rad/s.  With ``terms``
    (design.md 9.4, ``{code name: value}``) returns ``(x, w, y)`` (:mod:`.with_terms`).
    """
    amplitude = _finite_scalar("amplitude", amplitude)
    omega = _finite_scalar("omega", omega)
    if omega <= 0.0:
        raise InvalidParameterError(f"omega = {omega} rad/s must be > 0")
    if terms is not None:
        bw = (alpha, beta, gamma, mu, w0)
        inp = with_terms.sine_input(amplitude, omega)
        return _with_terms(np.asarray(num), np.asarray(den), delay, bw, inp, dt, n_samples, substeps, terms)

    def source(tau: float) -> tuple[float, float]:
        return amplitude * np.cos(omega * tau), -amplitude * omega * np.sin(omega * tau)

    return _simulate(num, den, delay, (alpha, beta, gamma, mu, w0), source, dt, n_samples, substeps)


def simulate_sampled(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    alpha: float,
    beta: float,
    gamma: float,
    mu: float,
    w0: float,
    u: ArrayLike,
    dt: float,
    substeps: int,
    *,
    terms: Optional[Mapping[str, float]] = None,
) -> Any:
    """RK4 simulation driven by samples ``u`` on the grid ``k dt``, interpolated by Catmull-Rom cubics.

    With ``terms`` (design.md 9.4) returns ``(x, w, y)`` (:mod:`.with_terms`).
    """
    uu = _finite_array("u", u)
    if uu.size < 2:
        raise InsufficientDataError("a sampled input needs at least 2 samples")
    dt_f = _finite_scalar("dt", dt)
    if dt_f <= 0.0:
        raise InvalidParameterError(f"dt = {dt_f} must be > 0")
    m = np.empty_like(uu)
    m[1:-1] = (uu[2:] - uu[:-2]) / (2.0 * dt_f)
    m[0] = (uu[1] - uu[0]) / dt_f
    m[-1] = (uu[-1] - uu[-2]) / dt_f
    if terms is not None:
        bw = (alpha, beta, gamma, mu, w0)
        inp = with_terms.sampled_input(uu, m, dt_f)
        return _with_terms(np.asarray(num), np.asarray(den), delay, bw, inp, dt_f, uu.size, substeps, terms)
    last = uu.size - 1

    def source(tau: float) -> tuple[float, float]:
        k = int(np.floor(tau / dt_f))
        if k >= last:
            return float(uu[last]), 0.0
        s = tau / dt_f - k
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        val = h00 * uu[k] + h10 * dt_f * m[k] + h01 * uu[k + 1] + h11 * dt_f * m[k + 1]
        d00 = 6 * s**2 - 6 * s
        d10 = 3 * s**2 - 4 * s + 1
        d01 = -6 * s**2 + 6 * s
        d11 = 3 * s**2 - 2 * s
        der = (d00 * uu[k] + d01 * uu[k + 1]) / dt_f + d10 * m[k] + d11 * m[k + 1]
        return float(val), float(der)

    return _simulate(num, den, delay, (alpha, beta, gamma, mu, w0), source, dt_f, uu.size, substeps)

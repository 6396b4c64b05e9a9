"""NumPy reference of ``rust/simulate/on_x.rs``: the mechanical terms across the hysteretic element, on its
input ``x = G u`` (design.md 9.1 place x, 9.4), in the time-domain simulation.

``k_x x + c_x xdot + m_x xddot + f_x tanh(xdot / (eps_x Vx))`` with x and its derivatives from the linear
part's controllable canonical state: ``xsdot = A xs + B v``, ``xdot = C xsdot + D vdot``,
``xsddot = A xsdot + B vdot``, ``xddot = C xsddot + D vddot`` (``v`` the delayed input, its derivatives
those the terms on u use).  ``Vx``: ``|U| |G(j omega)| omega`` for a sine, the largest ``|xdot|`` at the
output samples of a pass of the linear part alone for samples.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Callable, NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..validation import finite_scalar
from .terms import (
    COULOMB,
    COULOMB_SMOOTHING,
    COULOMB_SMOOTHING_MAX,
    INERTIA,
    ON_X_TERMS,
    PLACE_X,
    STIFFNESS,
    VISCOUS,
)

__all__ = ["ON_X_KEYS", "SMOOTHING_KEY", "OnX", "check_on_x", "kinematics", "linear_pass", "placed"]

FloatArray = NDArray[np.float64]
Input3 = Callable[[float], tuple[float, float, float]]


def placed(name: str) -> str:
    """``"<code name>@x"``: the term acting on x (composed, never spelled)."""
    return f"{name}@{PLACE_X}"


#: The on-x friction's smoothing key (``rust/simulate/on_x.rs`` ``smoothing_key``).
SMOOTHING_KEY = placed(COULOMB) + "_smoothing"
#: The keys of the on-x terms in a simulation's ``terms`` mapping.
ON_X_KEYS: tuple[str, ...] = (*(placed(k) for k in ON_X_TERMS), SMOOTHING_KEY)


def check_on_x(values: Mapping[str, float]) -> dict[str, float]:
    """The on-x values (absent ones 0, the smoothing its default) after the core's checks."""
    out = {placed(k): float(values.get(placed(k), 0.0)) for k in ON_X_TERMS}
    out[SMOOTHING_KEY] = float(values.get(SMOOTHING_KEY, COULOMB_SMOOTHING))
    for name, v in out.items():
        finite_scalar(name, v)
    eps = out[SMOOTHING_KEY]
    if not 0.0 < eps <= COULOMB_SMOOTHING_MAX:
        raise InvalidParameterError(f"{SMOOTHING_KEY} eps = {eps} must be in (0, {COULOMB_SMOOTHING_MAX}]")
    return out


def _state_derivative(a: FloatArray, xs: FloatArray, v: float) -> FloatArray:
    """``A xs + B v`` of the companion form (``rust/linear.rs``)."""
    out = np.empty(a.size)
    if a.size:
        out[0] = -float(np.dot(a, xs)) + v
        out[1:] = xs[: a.size - 1]
    return out


def kinematics(
    a: FloatArray, c: FloatArray, d: float, xs: FloatArray, inp: tuple[float, float, float]
) -> tuple[float, float, float]:
    """``(x, xdot, xddot)`` at state ``xs`` and delayed input ``(v, vdot, vddot)``."""
    v, vdot, vddot = inp
    xsdot = _state_derivative(a, xs, v)
    xsddot = _state_derivative(a, xsdot, vdot)
    return (
        float(np.dot(c, xs)) + d * v,
        float(np.dot(c, xsdot)) + d * vdot,
        float(np.dot(c, xsddot)) + d * vddot,
    )


class OnX(NamedTuple):
    """The on-x terms of a run: realisation, values and the friction's scale ``eps_x Vx``."""

    a: FloatArray
    c: FloatArray
    d: float
    values: dict[str, float]
    velocity_scale: float

    @property
    def active(self) -> bool:
        return any(self.values[placed(k)] != 0.0 for k in ON_X_TERMS)

    def at(self, xs: FloatArray, inp: tuple[float, float, float]) -> float:
        x, xdot, xddot = kinematics(self.a, self.c, self.d, xs, inp)
        p = self.values
        scale = self.velocity_scale
        friction = p[placed(COULOMB)] * math.tanh(xdot / scale) if scale > 0.0 else 0.0
        return p[placed(STIFFNESS)] * x + p[placed(VISCOUS)] * xdot + p[placed(INERTIA)] * xddot + friction


def linear_pass(
    a: FloatArray, inp: Input3, dt: float, n_samples: int, substeps: int
) -> list[tuple[float, FloatArray]]:
    """``(t_k, xs(t_k))`` of the linear part stepped alone from rest by the integrators' RK4."""
    h = dt / substeps
    xs = np.zeros(a.size)
    out = []
    for k in range(n_samples):
        t = k * dt
        out.append((t, xs.copy()))
        if k == n_samples - 1:
            break
        for s in range(substeps):
            ts = t + s * h
            k1 = _state_derivative(a, xs, inp(ts)[0])
            k2 = _state_derivative(a, xs + 0.5 * h * k1, inp(ts + 0.5 * h)[0])
            k3 = _state_derivative(a, xs + 0.5 * h * k2, inp(ts + 0.5 * h)[0])
            k4 = _state_derivative(a, xs + h * k3, inp(ts + h)[0])
            xs = xs + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return out


def make(
    realization: tuple[FloatArray, FloatArray, float],
    values: dict[str, float],
    inp: Input3,
    steady_peak: Optional[float],
    grid: tuple[float, int, int],
) -> Optional[OnX]:
    """The run's :class:`OnX` (``None`` without on-x terms); ``steady_peak`` is a sine's ``|U| |G| omega``,
    ``None`` for samples (then the pass's largest ``|xdot|`` at the samples)."""
    a, c, d = realization
    probe = OnX(a, c, d, values, 0.0)
    if not probe.active:
        return None
    if values[placed(COULOMB)] == 0.0:
        peak = 0.0
    elif steady_peak is not None:
        peak = steady_peak
    else:
        dt, n_samples, substeps = grid
        peak = 0.0
        for t, xs in linear_pass(a, inp, dt, n_samples, substeps):
            peak = max(peak, abs(kinematics(a, c, d, xs, inp(t))[1]))
    return probe._replace(velocity_scale=values[SMOOTHING_KEY] * peak)

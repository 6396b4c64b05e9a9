"""The simulator's right-hand side in Python, operation for operation (docs/design.md sections 1 and 9.4):
shared by the continuous (:mod:`._nlsys`) and the discrete-time (:mod:`._discrete`) python-control systems.

The transcription follows ``rust/simulate/with_terms.rs`` (the rate, the terms on u, the play's frozen mode,
its path map, the series dashpot's element travel, the lag's exponential weights) and
``rust/simulate/on_x.rs`` (x's derivatives from the linear part's state, the terms on x, the peak ``|xdot|``
from one pass of the linear part alone) and ``rust/simulate/with_terms/dahl.rs`` (Dahl friction's force, one
more state per place, stepped with the rates of the four RK4 stages).
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..validation import count, real_number
from ._input import SampledInput
from ._model import PINCHING_CENTRE, PINCHING_WIDTH, PLAY_ENGAGE_RTOL, Flat, flatten

__all__ = [
    "sgn",
    "dot",
    "rate",
    "mechanical",
    "linear",
    "kinematics",
    "on_x",
    "engage_mode",
    "played",
    "element",
    "path",
    "lag_weights",
    "dahl_rate",
    "dahl_step",
    "with_dahl",
    "optional_states",
    "delayed",
    "peak_xrate",
    "peak_speeds",
    "check_speed",
    "initial_state",
]

FloatArray = NDArray[np.float64]

#: Below this ``r = h / tau`` the lag's phi functions are summed as Taylor series (the simulator's rule).
PHI_SERIES_BELOW = 1.0
PHI_TERMS = 20


def sgn(v: float) -> float:
    return 1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0


def dot(p: FloatArray, q: Any) -> float:
    """``sum p_i q_i`` from the first term on (the simulator's order)."""
    acc = 0.0
    for pi, qi in zip(p, q):
        acc += float(pi) * float(qi)
    return acc


def rate(flat: Flat, xpdot: float, w: float, e: float) -> float:
    """The generalised Bouc-Wen rate with degradation and pinching (docs/design.md 9.4), in the simulator's
    operation order."""
    wmu = float(abs(w) ** flat.mu)
    sw = sgn(w)
    nu = 1.0 + flat.delta_nu * e
    r = (
        flat.alpha * xpdot
        - nu * (flat.beta * abs(xpdot) * sw * wmu)
        - nu * (flat.gamma * xpdot * wmu)
        - nu * (flat.delta * xpdot * sw * wmu)
    )
    if flat.delta_eta != 0.0:
        r /= 1.0 + flat.delta_eta * e
    if flat.zeta1 != 0.0:
        w_u = flat.w_u
        z = (w * sgn(xpdot) - PINCHING_CENTRE * w_u) / (PINCHING_WIDTH * w_u)
        r *= 1.0 - flat.zeta1 * math.exp(-z * z)
    return r


def mechanical(flat: Flat, u: float, udot: float, uddot: float, vmax: float) -> float:
    """``k u + c udot + m uddot + f tanh(udot / (eps Vmax))`` (0 friction when ``Vmax = 0``)."""
    scale = flat.smoothing * vmax
    friction = flat.f * math.tanh(udot / scale) if scale > 0.0 else 0.0
    return flat.k * u + flat.c * udot + flat.m * uddot + friction


def linear(flat: Flat, xs: Any, v: float, vdot: float) -> tuple[list[float], float]:
    """``(xsdot, xdot)``: ``xsdot = A xs + B v``, ``xdot = C xsdot + D vdot``."""
    n = flat.order
    dxs = [0.0] * n
    if n:
        dxs[0] = -dot(flat.a, xs) + v
        dxs[1:] = [float(q) for q in xs[: n - 1]]
    return dxs, dot(flat.crow, dxs) + flat.dfeed * vdot


def kinematics(flat: Flat, xs: Any, v: float, vdot: float, vddot: float) -> tuple[float, float, float]:
    """``(x, xdot, xddot)`` of the linear part from its state (on_x.rs: the state derivative twice)."""
    x = dot(flat.crow, xs) + flat.dfeed * v
    d1, xdot = linear(flat, xs, v, vdot)
    _, xddot = linear(flat, d1, vdot, vddot)
    return x, xdot, xddot


def on_x(flat: Flat, xs: Any, v: float, vdot: float, vddot: float, vx: float) -> float:
    """``k_x x + c_x xdot + m_x xddot + f_x tanh(xdot / (eps_x Vx))`` (0 when no term acts on x)."""
    if not flat.has_on_x:
        return 0.0
    x, xdot, xddot = kinematics(flat, xs, v, vdot, vddot)
    scale = flat.smoothing_x * vx
    friction = flat.f_x * math.tanh(xdot / scale) if scale > 0.0 else 0.0
    return flat.k_x * x + flat.c_x * xdot + flat.m_x * xddot + friction


def engage_mode(flat: Flat, x: float, xp: float, xdot: float) -> int:
    """The play's mode from a step's start: +1 up, -1 down, 0 dwell (with_terms.rs)."""
    e = x - xp
    b = flat.b
    slack = PLAY_ENGAGE_RTOL * (b + abs(x))
    if xdot > 0.0 and e >= b - slack:
        return 1
    if xdot < 0.0 and e <= -b + slack:
        return -1
    return 0


def played(flat: Flat, mode: int, xdot: float) -> float:
    """``xpdot`` in the frozen ``mode`` (``xdot`` itself without play)."""
    if not flat.has_play:
        return xdot
    if mode == 1:
        return max(xdot, 0.0)
    if mode == -1:
        return min(xdot, 0.0)
    return 0.0


def element(flat: Flat, p: float, w: float) -> float:
    """The hysteretic element's travel rate behind the series dashpot: ``p - rho w`` for the (played)
    x-rate ``p`` (with_terms.rs, at every RK4 stage; ``rho = 0``: ``p``). The play's ``xp`` still
    integrates ``p``, and its path map after the clamp uses the travel without the dashpot."""
    return p - flat.rho * w


def path(flat: Flat, w: float, e: float, dxp: float) -> tuple[float, float]:
    """``(w, e)`` moved along the hysteresis path by the play's clamped travel ``dxp`` (one RK4 step in
    xp)."""
    k1 = rate(flat, dxp, w, e)
    w2, e2 = w + 0.5 * k1, e + 0.5 * w * dxp
    k2 = rate(flat, dxp, w2, e2)
    w3, e3 = w + 0.5 * k2, e + 0.5 * w2 * dxp
    k3 = rate(flat, dxp, w3, e3)
    w4, e4 = w + k3, e + w3 * dxp
    k4 = rate(flat, dxp, w4, e4)
    return w + (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0, e + (w + 2.0 * w2 + 2.0 * w3 + w4) * dxp / 6.0


def dahl_rate(fc: float, sigma: float, vdot: float, f: float) -> float:
    """Dahl friction's ``F' = sigma vdot (1 - sgn(vdot) F / Fc)``; 0 unless ``Fc > 0`` and ``sigma > 0``
    (dahl.rs ``rate``, same operation order)."""
    if not (fc > 0.0 and sigma > 0.0):
        return 0.0
    return sigma * vdot * (1.0 - sgn(vdot) * f / fc)


def dahl_step(fc: float, sigma: float, f: float, h: float, vdots: tuple[float, ...]) -> tuple[float, float]:
    """One RK4 step of the Dahl force ``f`` over ``h`` with the stage rates ``vdots = (v1, v2, v3, v4)``:
    the new force and its third-order continuous extension at the step's middle (dahl.rs ``step``)."""
    half_h = 0.5 * h
    k1 = dahl_rate(fc, sigma, vdots[0], f)
    k2 = dahl_rate(fc, sigma, vdots[1], f + half_h * k1)
    k3 = dahl_rate(fc, sigma, vdots[2], f + half_h * k2)
    k4 = dahl_rate(fc, sigma, vdots[3], f + h * k3)
    return (
        f + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4),
        f + h * (5.0 * k1 + 4.0 * (k2 + k3) - k4) / 24.0,
    )


def with_dahl(flat: Flat, f: float, fu: float, fx: float) -> float:
    """``f + (F_u + F_x)`` when Dahl friction moves at either place, ``f`` itself otherwise (the simulator's
    order: a plant without it rounds as before)."""
    return f + (fu + fx) if flat.has_dahl else f


def optional_states(flat: Flat) -> tuple[str, ...]:
    """The states a plant's terms add after ``xs0.., w``, in order: ``e`` (a degradation's dissipated
    energy), ``xp`` (the play's output), ``ys`` (the lagged sensor output), ``fu`` and ``fx`` (Dahl
    friction's forces on u and on x)."""
    flags = (
        (flat.has_energy, "e"),
        (flat.has_play, "xp"),
        (flat.has_lag, "ys"),
        (flat.has_dahl_u, "fu"),
        (flat.has_dahl_x, "fx"),
    )
    return tuple(name for flag, name in flags if flag)


def lag_weights(r: float) -> tuple[float, float, float, float]:
    """``(e^-r, r c_0, r c_m, r c_1)`` of the exponential lag step over ``r = h / tau`` (with_terms.rs)."""
    if not math.isfinite(r):
        return 0.0, 0.0, 0.0, 1.0
    z = -r
    if r < PHI_SERIES_BELOW:
        fact = [float(math.factorial(i)) for i in range(PHI_TERMS + 4)]

        def phi(k: int) -> float:
            acc = 0.0
            for j in range(PHI_TERMS - 1, -1, -1):
                acc = acc * z + 1.0 / fact[j + k]
            return acc

        p1, p2, p3 = phi(1), phi(2), phi(3)
    else:
        p1 = math.expm1(z) / z
        p2 = (p1 - 1.0) / z
        p3 = (p2 - 0.5) / z
    return math.exp(z), r * (p1 - 3.0 * p2 + 4.0 * p3), r * (4.0 * p2 - 8.0 * p3), r * (4.0 * p3 - p2)


def delayed(src: SampledInput, delay: float, t: float) -> tuple[float, float, float]:
    """``(v, vdot, vddot)``: the input at ``t - delay``, 0 before the delay has elapsed."""
    tau = t - delay
    return src.at(tau) if tau >= 0.0 else (0.0, 0.0, 0.0)


def peak_xrate(flat: Flat, src: SampledInput, substeps: int) -> float:
    """``Vx``, the peak ``|xdot|`` at the samples: the linear part stepped alone from rest with the run's
    RK4 (on_x.rs ``linear_pass``); 0 without friction on x (the simulator does not use it then)."""
    if flat.f_x == 0.0:
        return 0.0
    n, dt = src.u.size, src.dt
    h = dt / substeps
    half_h, h_sixth = 0.5 * h, h / 6.0
    xs = np.zeros(flat.order)
    peak = 0.0
    for k in range(n):
        t = k * dt
        peak = max(peak, abs(kinematics(flat, xs, *delayed(src, flat.delay, t))[1]))
        if k == n - 1:
            break
        for s in range(substeps):
            ts = t + s * h
            k1 = np.array(linear(flat, xs, delayed(src, flat.delay, ts)[0], 0.0)[0])
            k2 = np.array(linear(flat, xs + half_h * k1, delayed(src, flat.delay, ts + half_h)[0], 0.0)[0])
            k3 = np.array(linear(flat, xs + half_h * k2, delayed(src, flat.delay, ts + half_h)[0], 0.0)[0])
            k4 = np.array(linear(flat, xs + h * k3, delayed(src, flat.delay, ts + h)[0], 0.0)[0])
            xs = xs + h_sixth * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return peak


def peak_speeds(plant: WienerPlant, t: ArrayLike, u: ArrayLike, substeps: int = 4) -> tuple[float, float]:
    """``(Vmax, Vx)`` of the simulator for samples ``u(t)``: the interpolant's exact peak ``|udot|`` and the
    peak ``|xdot|`` at the samples (one pass of the linear part alone; 0 without friction on x)."""
    flat = flatten(plant, "peak_speeds")
    src = SampledInput(t, u)
    return src.peak_rate(), peak_xrate(flat, src, count("substeps", substeps, 1, 2**20))


def check_speed(name: str, value: Optional[float], needed: bool, what: str) -> float:
    """A peak speed parameter (``vmax``, ``vx``): required when a friction uses it, finite and >= 0."""
    if value is None:
        if needed:
            raise InvalidParameterError(
                f"the plant has Coulomb friction {what}, whose smoothed sign needs its peak speed: pass "
                f"{name}= (for a sampled input, export.peak_speeds(plant, t, u, substeps) gives both)"
            )
        return 0.0
    v = real_number(name, value)
    if v < 0.0:
        raise InvalidParameterError(f"{name} = {v} must be >= 0 (a peak speed)")
    return v


def initial_state(sys: Any, first_input: ArrayLike) -> FloatArray:
    """The simulator's state at rest: ``xs = 0``, ``w = w0``, ``e = 0``, ``ys = 0``,
    ``xp = clamp(0, x(0) - b, x(0) + b)``; ``first_input`` is the input vector at ``t = 0``."""
    lay_states = list(sys.state_labels)
    w0 = float(sys.params.get("w0", 0.0))
    z = np.zeros(len(lay_states))
    z[lay_states.index("w")] = w0
    if "xp" in lay_states:
        x0 = float(sys.output(0.0, z, np.asarray(first_input, dtype=np.float64))[1])
        b = float(sys.params["b"])
        z[lay_states.index("xp")] = min(max(0.0, x0 - b), x0 + b)
    return z

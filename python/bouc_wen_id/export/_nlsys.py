"""The whole model as a python-control nonlinear I/O system (``control.nlsys``), in physical units.

State ``[xs_0 .. xs_{n-1}, w]`` (the controllable canonical form of G and the Bouc-Wen output, docs/design.md
section 1), then, when the plant's terms need them (section 9.4), ``e`` (the dissipated energy of a
degradation), ``xp`` (the play's output) and ``ys`` (the sensor's lagged output).  Inputs ``u, udot, uddot``:
the measured input and its first two derivatives (the viscous and inertia terms and a biproper G need them);
with a delay also ``v, vdot``, the input delayed by it (a nonlinear I/O system cannot hold a delay:
:func:`input_signals` makes both from samples).  Outputs ``y, x, w``.  Parameter ``vmax``: the peak input
velocity that scales the Coulomb friction's smoothed sign (the simulator takes it from the whole input).

The right-hand side is the simulator's, operation for operation, so that classical RK4 on it with the
simulator's step and stage times (:func:`rk4_response`) reproduces :func:`bouc_wen_id.simulate_input`
to rounding, for every term but two whose simulator scheme is not an RK4 step of an ODE: the play (the
simulator freezes its mode per step and clamps ``xp`` after it) and the sensor lag (integrated
exponentially); there the system is the exact ODE and agrees to the integration error of either scheme.
``control.input_output_response`` integrates the same system with SciPy's adaptive solvers.

Reference: R. M. Murray et al., *python-control*, ``NonlinearIOSystem``.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _optional
from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..validation import count, real_number
from ._input import SampledInput
from ._model import PINCHING_CENTRE, PINCHING_WIDTH, PLAY_ENGAGE_RTOL, Flat, flatten

__all__ = ["to_nlsys", "input_signals", "initial_state", "rk4_response"]

FloatArray = NDArray[np.float64]


def _sgn(v: float) -> float:
    return 1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0


def _dot(p: FloatArray, q: Any) -> float:
    """``sum p_i q_i`` from the first term on (the simulator's order)."""
    acc = 0.0
    for pi, qi in zip(p, q):
        acc += float(pi) * float(qi)
    return acc


def rate(flat: Flat, xpdot: float, w: float, e: float) -> float:
    """The generalised Bouc-Wen rate with degradation and pinching (docs/design.md 9.4), in the simulator's
    operation order."""
    wmu = float(abs(w) ** flat.mu)
    sw = _sgn(w)
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
        z = (w * _sgn(xpdot) - PINCHING_CENTRE * w_u) / (PINCHING_WIDTH * w_u)
        r *= 1.0 - flat.zeta1 * math.exp(-z * z)
    return r


def mechanical(flat: Flat, u: float, udot: float, uddot: float, vmax: float) -> float:
    """``k u + c udot + m uddot + f tanh(udot / (eps Vmax))`` (0 friction when ``Vmax = 0``)."""
    scale = flat.smoothing * vmax
    friction = flat.f * math.tanh(udot / scale) if scale > 0.0 else 0.0
    return flat.k * u + flat.c * udot + flat.m * uddot + friction


class _Layout:
    """Where each state and input sits."""

    def __init__(self, flat: Flat) -> None:
        n = flat.order
        self.states = [f"xs{i}" for i in range(n)] + ["w"]
        self.w = n
        self.e = self.xp = self.ys = -1
        for flag, name in ((flat.has_energy, "e"), (flat.has_play, "xp"), (flat.has_lag, "ys")):
            if flag:
                setattr(self, name, len(self.states))
                self.states.append(name)
        self.inputs = ["u", "udot", "uddot"] + (["v", "vdot"] if flat.delay > 0.0 else [])
        #: (v, vdot) columns of the input vector: the delayed pair, or u, udot themselves without a delay.
        self.v = (3, 4) if flat.delay > 0.0 else (0, 1)


def _vmax(params: Optional[dict[str, Any]], default: float) -> float:
    if params and "vmax" in params:
        return float(params["vmax"])
    return default


def _system_functions(flat: Flat, lay: _Layout, vmax_default: float) -> tuple[Any, Any]:
    n = flat.order

    def linear(xs: Any, v: float, vdot: float) -> tuple[list[float], float]:
        dxs = [0.0] * n
        if n:
            dxs[0] = -_dot(flat.a, xs) + v
            dxs[1:] = [float(q) for q in xs[: n - 1]]
        return dxs, _dot(flat.crow, dxs) + flat.dfeed * vdot

    def played(z: Any, x: float, xdot: float) -> float:
        if not flat.has_play:
            return xdot
        e = x - float(z[lay.xp])
        b = flat.b
        slack = PLAY_ENGAGE_RTOL * (b + abs(x))
        if xdot > 0.0 and e >= b - slack:
            return max(xdot, 0.0)
        if xdot < 0.0 and e <= -b + slack:
            return min(xdot, 0.0)
        return 0.0

    def dynamics(t: float, z: Any, inp: Any, params: Optional[dict[str, Any]] = None) -> FloatArray:
        xs = z[:n]
        w = float(z[lay.w])
        v, vdot = float(inp[lay.v[0]]), float(inp[lay.v[1]])
        dxs, xdot = linear(xs, v, vdot)
        x = _dot(flat.crow, xs) + flat.dfeed * v
        p = played(z, x, xdot)
        e = float(z[lay.e]) if lay.e >= 0 else 0.0
        out = np.empty(len(lay.states))
        out[:n] = dxs
        out[lay.w] = rate(flat, p, w, e)
        if lay.e >= 0:
            out[lay.e] = w * p
        if lay.xp >= 0:
            out[lay.xp] = p
        if lay.ys >= 0:
            big_f = w + mechanical(
                flat, float(inp[0]), float(inp[1]), float(inp[2]), _vmax(params, vmax_default)
            )
            out[lay.ys] = (big_f - float(z[lay.ys])) / flat.tau
        return out

    def output(t: float, z: Any, inp: Any, params: Optional[dict[str, Any]] = None) -> FloatArray:
        w = float(z[lay.w])
        x = _dot(flat.crow, z[:n]) + flat.dfeed * float(inp[lay.v[0]])
        if lay.ys >= 0:
            y = flat.y0 + float(z[lay.ys])
        else:
            mech = mechanical(flat, float(inp[0]), float(inp[1]), float(inp[2]), _vmax(params, vmax_default))
            y = flat.y0 + (w + mech)
        return np.array([y, x, w])

    return dynamics, output


def to_nlsys(plant: WienerPlant, *, vmax: Optional[float] = None, name: Optional[str] = None) -> Any:
    """``plant`` (plain or with terms) as a continuous-time ``control.NonlinearIOSystem``.

    Parameters
    ----------
    plant : WienerPlant
        In physical units, as identified or built (alpha need not be 1).
    vmax : float, optional
        Peak input velocity ``Vmax`` (units of u per s) of the Coulomb friction's smoothing
        ``tanh(udot / (eps Vmax))``; needed when the plant has Coulomb friction (for a sampled input,
        ``SampledInput(t, u).peak_rate()``, which :func:`rk4_response` passes itself). It is the system's
        parameter ``vmax`` (``params={"vmax": ...}`` overrides it in a simulation).
    name : str, optional
        The system's name.

    Returns
    -------
    control.NonlinearIOSystem
        Inputs ``u, udot, uddot`` (and ``v, vdot``, the input delayed by G's delay, when it has one),
        outputs ``y, x, w``, states ``xs0.., w`` (and ``e``, ``xp``, ``ys``; module docstring); its
        ``params`` hold ``vmax`` and, for reading only, ``delay``, ``w0`` and ``b`` (the play's
        half-width). Start it from :func:`initial_state`.

    Raises
    ------
    InvalidParameterError
        A term the time-domain simulator does not simulate (a term on x, the distortion), a Coulomb
        friction without ``vmax``, a negative or non-finite ``vmax``.
    ImportError
        python-control is not installed (``pip install 'bouc_wen_id[control]'``).
    """
    control = _optional.require("control", "exporting the model to python-control")
    flat = flatten(plant, "to_nlsys")
    if vmax is None:
        if flat.f != 0.0:
            raise InvalidParameterError(
                "the plant has Coulomb friction, whose smoothed sign tanh(udot / (eps Vmax)) needs the peak "
                "input velocity: pass vmax= (SampledInput(t, u).peak_rate() for a sampled input)"
            )
        vmax = 0.0
    vmax = real_number("vmax", vmax)
    if vmax < 0.0:
        raise InvalidParameterError(f"vmax = {vmax} must be >= 0 (a peak speed)")
    lay = _Layout(flat)
    dynamics, output = _system_functions(flat, lay, vmax)
    return control.nlsys(
        dynamics,
        output,
        inputs=lay.inputs,
        outputs=["y", "x", "w"],
        states=lay.states,
        params={"vmax": vmax, "delay": flat.delay, "w0": flat.w0, "b": flat.b},
        name=name,
    )


def input_signals(sys: Any, t: ArrayLike, u: Union[ArrayLike, SampledInput], times: ArrayLike) -> FloatArray:
    """The input vector of ``sys`` (from :func:`to_nlsys`) at ``times``: shape ``(ninputs, len(times))``.

    ``u`` sampled on the uniform grid ``t`` is interpolated as the simulator does (Catmull-Rom, held after
    the last sample, 0 before ``t[0]``); times count from ``t[0]``. With a delay the rows ``v, vdot`` are the
    same interpolant at ``times - delay``.
    """
    src = u if isinstance(u, SampledInput) else SampledInput(t, u)
    tt = np.atleast_1d(np.asarray(times, dtype=np.float64))
    delay = float(sys.params.get("delay", 0.0))
    rows = np.empty((sys.ninputs, tt.size))
    for j, tj in enumerate(tt):
        rows[:3, j] = src.at(float(tj))
        if sys.ninputs == 5:
            tau = float(tj) - delay
            rows[3:, j] = src.at(tau)[:2] if tau >= 0.0 else (0.0, 0.0)
    return rows


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


def rk4_response(
    sys: Any, t: ArrayLike, u: ArrayLike, *, substeps: int = 4
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(x, w, y)`` of ``sys`` driven by samples ``u(t)``: classical RK4 on its right-hand side with the
    simulator's step ``h = dt / substeps`` and stage times ``t + s h, + h/2, + h`` (design.md section 1).

    The input is :func:`input_signals`'s interpolant; ``vmax`` is the interpolant's peak slope. For a plant
    without play or sensor lag this is :func:`bouc_wen_id.simulate_input` to rounding.
    """
    src = SampledInput(t, u)
    steps = count("substeps", substeps, 1, 2**20)
    params = dict(sys.params)
    params["vmax"] = src.peak_rate()
    n = src.u.size
    dt = src.dt
    h = dt / steps
    half_h, h_sixth = 0.5 * h, h / 6.0
    z = initial_state(sys, input_signals(sys, t, src, [0.0])[:, 0])
    out = np.empty((3, n))
    for k in range(n):
        tk = k * dt
        out[:, k] = sys.output(tk, z, input_signals(sys, t, src, [tk])[:, 0], params)
        if k == n - 1:
            break
        for s in range(steps):
            ts = tk + s * h
            ins = input_signals(sys, t, src, [ts, ts + half_h, ts + h])
            k1 = sys.dynamics(ts, z, ins[:, 0], params)
            k2 = sys.dynamics(ts + half_h, z + half_h * k1, ins[:, 1], params)
            k3 = sys.dynamics(ts + half_h, z + half_h * k2, ins[:, 1], params)
            k4 = sys.dynamics(ts + h, z + h * k3, ins[:, 2], params)
            z = z + h_sixth * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return out[1], out[2], out[0]

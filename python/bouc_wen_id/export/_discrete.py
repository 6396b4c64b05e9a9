"""The whole model as a discrete-time python-control system whose update is one step of the simulator.

A continuous ``nlsys`` cannot reproduce the simulator's scheme for two elements under RK4 of the same step:
the play (the simulator freezes its mode over each step and clamps ``xp`` after it, with the clamped travel
fed through the path map) and the sensor lag (stepped exponentially, exact for the decay and stable at any
``h / tau``). A control engineer who wants the model that was identified and validated, not a nearby ODE,
gets it here: ``control.nlsys(update, output, dt=h)`` with ``h = dt / substeps`` whose update is exactly one
RK4 step of ``rust/simulate/with_terms.rs`` (+ ``on_x.rs``, ``with_terms/dahl.rs``), every term included,
operation for operation.

Inputs: the input's values at the step's three stage times ``t, t + h/2, t + h`` (the simulator's stage
times; RK4 needs the input between samples), each ``u, udot, uddot`` of the Catmull-Rom interpolant and,
with a delay, ``v, vdot, vddot`` of the delayed one: labels ``u_0, udot_0, .., u_m, .., vddot_1``.
:func:`stage_inputs` builds them from samples; :func:`discrete_response` runs
``control.input_output_response`` on them and returns the samples. States and outputs as the continuous
system's (``xs0.., w, e, xp, ys, fu, fx``; ``y, x, w``); ``e``, ``xp``, ``ys`` and the Dahl forces ``fu``,
``fx`` only when a term needs them.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _optional
from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..validation import count, real_number
from ._input import SampledInput
from ._model import Flat
from ._rhs import (
    dahl_step,
    delayed,
    dot,
    element,
    engage_mode,
    initial_state,
    lag_weights,
    linear,
    mechanical,
    on_x,
    optional_states,
    path,
    peak_speeds,
    played,
    rate,
    with_dahl,
)

__all__ = ["to_discrete", "stage_inputs", "discrete_response", "STAGES"]

FloatArray = NDArray[np.float64]

#: The stage times of one RK4 step: its start, its middle, its end.
STAGES = ("0", "m", "1")


class _Layout:
    def __init__(self, flat: Flat) -> None:
        n = flat.order
        self.n = n
        self.states = [f"xs{i}" for i in range(n)] + ["w"]
        self.e = self.xp = self.ys = self.fu = self.fx = -1
        for name in optional_states(flat):
            setattr(self, name, len(self.states))
            self.states.append(name)
        per = ["u", "udot", "uddot"] + (["v", "vdot", "vddot"] if flat.delay > 0.0 else [])
        self.width = len(per)
        self.inputs = [f"{q}_{s}" for s in STAGES for q in per]
        #: Offset of (v, vdot, vddot) within one stage's block.
        self.v = 3 if flat.delay > 0.0 else 0

    def stage(self, inp: Any, j: int) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """``((u, udot, uddot), (v, vdot, vddot))`` of stage ``j``."""
        b = j * self.width
        u3 = (float(inp[b]), float(inp[b + 1]), float(inp[b + 2]))
        c = b + self.v
        return u3, (float(inp[c]), float(inp[c + 1]), float(inp[c + 2]))


def _functions(flat: Flat, lay: _Layout, h: float, defaults: tuple[float, float]) -> tuple[Any, Any]:
    half_h, h_sixth = 0.5 * h, h / 6.0
    decay, l0, lm, l1 = lag_weights(h / flat.tau) if flat.has_lag else (0.0, 0.0, 0.0, 0.0)

    def speeds(params: Optional[dict[str, Any]]) -> tuple[float, float]:
        p = params or {}
        return float(p.get("vmax", defaults[0])), float(p.get("vx", defaults[1]))

    def forcing(w: float, st: Any, xs: Any, vmax: float, vx: float, fu: float, fx: float) -> float:
        """``w`` + the terms on u and on x (+ the Dahl forces): the lag's input, the output before the
        offset."""
        (u, udot, uddot), (v, vdot, vddot) = st
        f = w + mechanical(flat, u, udot, uddot, vmax)
        f = f + on_x(flat, xs, v, vdot, vddot, vx) if flat.has_on_x else f
        return with_dahl(flat, f, fu, fx)

    def update(t: float, z: Any, inp: Any, params: Optional[dict[str, Any]] = None) -> FloatArray:
        vmax, vx = speeds(params)
        z = np.asarray(z, dtype=np.float64)
        xs, w = z[: lay.n], float(z[lay.n])
        en = float(z[lay.e]) if lay.e >= 0 else 0.0
        xp = float(z[lay.xp]) if lay.xp >= 0 else 0.0
        fu = float(z[lay.fu]) if lay.fu >= 0 else 0.0
        fx = float(z[lay.fx]) if lay.fx >= 0 else 0.0
        s0, sm, s1 = (lay.stage(inp, j) for j in range(3))
        k1, xdot1 = linear(flat, xs, *s0[1][:2])
        mode = (
            engage_mode(flat, dot(flat.crow, xs) + flat.dfeed * s0[1][0], xp, xdot1) if flat.has_play else 1
        )
        p1 = played(flat, mode, xdot1)
        d1 = element(flat, p1, w)
        kw1, ke1 = rate(flat, d1, w, en), w * d1
        w2, e2 = w + half_h * kw1, en + half_h * ke1
        k2, xdot2 = linear(flat, xs + half_h * np.asarray(k1), *sm[1][:2])
        p2 = played(flat, mode, xdot2)
        d2 = element(flat, p2, w2)
        kw2, ke2 = rate(flat, d2, w2, e2), w2 * d2
        w3, e3 = w + half_h * kw2, en + half_h * ke2
        k3, xdot3 = linear(flat, xs + half_h * np.asarray(k2), *sm[1][:2])
        p3 = played(flat, mode, xdot3)
        d3 = element(flat, p3, w3)
        kw3, ke3 = rate(flat, d3, w3, e3), w3 * d3
        w4, e4 = w + h * kw3, en + h * ke3
        k4, xdot4 = linear(flat, xs + h * np.asarray(k3), *s1[1][:2])
        p4 = played(flat, mode, xdot4)
        d4 = element(flat, p4, w4)
        kw4, ke4 = rate(flat, d4, w4, e4), w4 * d4
        ka, kb, kc, kd = (np.asarray(k) for k in (k1, k2, k3, k4))
        w_mid = w + h * (5.0 * kw1 + 4.0 * (kw2 + kw3) - kw4) / 24.0
        xs_mid = xs + h * (5.0 * ka + 4.0 * (kb + kc) - kd) / 24.0
        f0 = forcing(w, s0, xs, vmax, vx, fu, fx) if flat.has_lag else 0.0
        xs_new = xs + h_sixth * (ka + 2.0 * kb + 2.0 * kc + kd)
        w = w + h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4)
        out = np.empty(len(lay.states))
        # Dahl friction (dahl.rs): on u with the undelayed input's rate at the stage times, on x with x's.
        fu_mid, fx_mid = fu, fx
        if flat.has_dahl_u:
            um = sm[0][1]
            fu, fu_mid = dahl_step(flat.fc, flat.sigma, fu, h, (s0[0][1], um, um, s1[0][1]))
            out[lay.fu] = fu
        if flat.has_dahl_x:
            fx, fx_mid = dahl_step(flat.fc_x, flat.sigma_x, fx, h, (xdot1, xdot2, xdot3, xdot4))
            out[lay.fx] = fx
        en = en + h_sixth * (ke1 + 2.0 * ke2 + 2.0 * ke3 + ke4)
        if flat.has_play:
            xp += h_sixth * (p1 + 2.0 * p2 + 2.0 * p3 + p4)
            x_end = dot(flat.crow, xs_new) + flat.dfeed * s1[1][0]
            clamped = min(max(xp, x_end - flat.b), x_end + flat.b)
            if clamped - xp != 0.0:
                w, en = path(flat, w, en, clamped - xp)
            out[lay.xp] = clamped
        if flat.has_lag:
            fm = forcing(w_mid, sm, xs_mid, vmax, vx, fu_mid, fx_mid)
            f1 = forcing(w, s1, xs_new, vmax, vx, fu, fx)
            out[lay.ys] = decay * float(z[lay.ys]) + (l0 * f0 + lm * fm + l1 * f1)
        out[: lay.n] = xs_new
        out[lay.n] = w
        if lay.e >= 0:
            out[lay.e] = en
        return out

    def output(t: float, z: Any, inp: Any, params: Optional[dict[str, Any]] = None) -> FloatArray:
        vmax, vx = speeds(params)
        s0 = lay.stage(inp, 0)
        xs, w = z[: lay.n], float(z[lay.n])
        x = dot(flat.crow, xs) + flat.dfeed * s0[1][0]
        fu = float(z[lay.fu]) if lay.fu >= 0 else 0.0
        fx = float(z[lay.fx]) if lay.fx >= 0 else 0.0
        y = flat.y0 + (float(z[lay.ys]) if flat.has_lag else forcing(w, s0, xs, vmax, vx, fu, fx))
        return np.array([y, x, w])

    return update, output


def to_discrete(
    control: Any, flat: Flat, vmax: float, vx: float, name: Optional[str], dt: float, substeps: int
) -> Any:
    """The discrete-time system of ``flat`` (module docstring), ``sys.dt = dt / substeps``; ``params`` hold
    ``vmax``, ``vx``, ``substeps`` and, for reading, ``delay``, ``w0``, ``b``."""
    step = real_number("dt", dt)
    if not step > 0.0:
        raise InvalidParameterError(f"dt = {step} must be > 0 (the sample step)")
    steps = count("substeps", substeps, 1, 2**20)
    h = step / steps
    lay = _Layout(flat)
    update, output = _functions(flat, lay, h, (vmax, vx))
    return control.nlsys(
        update,
        output,
        inputs=lay.inputs,
        outputs=["y", "x", "w"],
        states=lay.states,
        dt=h,
        params={"vmax": vmax, "vx": vx, "substeps": steps, "delay": flat.delay, "w0": flat.w0, "b": flat.b},
        name=name,
    )


def stage_inputs(sys: Any, t: ArrayLike, u: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``(T, U)`` driving the discrete ``sys`` over samples ``u(t)``: ``T`` the RK4 step times
    ``k dt + s h`` (``(n - 1) substeps + 1`` of them, the last the last sample's), ``U`` the interpolant
    at each step's stage times, as the simulator computes them (``ts = k dt + s h``, ``ts + h/2``,
    ``ts + h``: the inertia's second derivative jumps at the knots, so the same doubles matter).

    Raises
    ------
    InvalidParameterError
        ``sys`` built for another sample step (its ``dt`` is not this grid's step over its ``substeps``).
    """
    src = SampledInput(t, u)
    steps = int(sys.params["substeps"])
    dt = src.dt
    h = dt / steps
    if abs(h - float(sys.dt)) > 1e-9 * h:
        raise InvalidParameterError(
            f"the system steps h = {float(sys.dt)!r} s, this grid's step over substeps = {steps} is {h!r} s: "
            "build it with to_nlsys(plant, dt=<this grid's step>)"
        )
    delay = float(sys.params["delay"])
    width = sys.ninputs // 3
    n = src.u.size
    total = (n - 1) * steps + 1
    big_u = np.empty((sys.ninputs, total))
    half_h = 0.5 * h
    for j in range(total):
        k, s = divmod(j, steps)
        ts = k * dt + s * h
        for q, tq in enumerate((ts, ts + half_h, ts + h)):
            block = src.at(tq) + (delayed(src, delay, tq) if width == 6 else ())
            big_u[q * width : (q + 1) * width, j] = block
    return np.arange(total) * float(sys.dt), big_u


def discrete_response(
    sys: Any, t: ArrayLike, u: ArrayLike, plant: Optional[WienerPlant] = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(x, w, y)`` at the samples: ``control.input_output_response`` of the discrete ``sys`` on
    :func:`stage_inputs`, from :func:`initial_state`; ``vmax`` the interpolant's peak slope and, when the
    ``plant`` is given, ``vx`` the peak ``|xdot|`` (:func:`peak_speeds`). Equal to
    :func:`bouc_wen_id.simulate_input` with the same ``substeps``, to rounding."""
    control = _optional.require("control", "simulating the exported model")
    big_t, big_u = stage_inputs(sys, t, u)
    params = dict(sys.params)
    steps = int(params["substeps"])
    params["vmax"] = SampledInput(t, u).peak_rate()
    if plant is not None:
        params["vx"] = peak_speeds(plant, t, u, steps)[1]
    z0 = initial_state(sys, big_u[:, 0])
    resp = control.input_output_response(sys, big_t, big_u, X0=z0, params=params, t_eval=big_t)
    out = np.asarray(resp.outputs)[:, ::steps]
    return out[1], out[2], out[0]

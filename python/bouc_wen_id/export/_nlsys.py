"""The whole model as a continuous-time python-control system (``control.nlsys``), in physical units.

State ``[xs_0 .. xs_{n-1}, w]`` (the controllable canonical form of G and the Bouc-Wen output, docs/design.md
section 1), then, when the plant's terms need them (section 9.4), ``e`` (the dissipated energy of a
degradation), ``xp`` (the play's output), ``ys`` (the sensor's lagged output), ``fu`` and ``fx`` (Dahl
friction's forces on u and on x, ``F' = sigma v' (1 - sgn(v') F / Fc)``, docs/dahl-time-domain.md). Inputs
``u, udot, uddot``: the measured input and its first two derivatives (the terms on u, the terms on x and a
biproper G need them); with a delay also ``v, vdot, vddot``, the input delayed by it (a nonlinear I/O system
cannot hold a delay: :func:`input_signals` makes them from samples). Outputs ``y, x, w``. Parameters ``vmax``
and ``vx``: the peak input velocity and the peak ``|xdot|`` that scale the Coulomb frictions' smoothed signs
on u and on x (the simulator takes them from the whole input: :func:`._rhs.peak_speeds`).

The right-hand side is the simulator's (:mod:`._rhs`), so that classical RK4 on it with the simulator's step
and stage times (:func:`rk4_response`) reproduces :func:`bouc_wen_id.simulate_input` to rounding, for every
term but two whose simulator scheme is not an RK4 step of an ODE: the play (the simulator freezes its mode
per step and clamps ``xp`` after it) and the sensor lag (integrated exponentially); there the system is the
exact ODE and agrees to the integration error of either scheme. ``to_nlsys(plant, dt=...)`` gives instead
the discrete-time system whose update is the simulator's own step (:mod:`._discrete`), exact for every term.
``control.input_output_response`` integrates the continuous system with SciPy's adaptive solvers.

Reference: R. M. Murray et al., *python-control*, ``NonlinearIOSystem``.
"""

from __future__ import annotations

from typing import Any, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _optional
from ..model import WienerPlant
from ..validation import count
from ._discrete import to_discrete
from ._input import SampledInput
from ._model import PLAY_ENGAGE_RTOL, Flat, flatten
from ._rhs import (
    check_speed,
    dahl_rate,
    dot,
    element,
    initial_state,
    linear,
    mechanical,
    on_x,
    optional_states,
    peak_speeds,
    rate,
    with_dahl,
)

__all__ = ["to_nlsys", "input_signals", "rk4_response"]

FloatArray = NDArray[np.float64]


class _Layout:
    """Where each state and input sits."""

    def __init__(self, flat: Flat) -> None:
        n = flat.order
        self.states = [f"xs{i}" for i in range(n)] + ["w"]
        self.w = n
        self.e = self.xp = self.ys = self.fu = self.fx = -1
        for name in optional_states(flat):
            setattr(self, name, len(self.states))
            self.states.append(name)
        self.inputs = ["u", "udot", "uddot"] + (["v", "vdot", "vddot"] if flat.delay > 0.0 else [])
        #: (v, vdot, vddot) columns of the input vector: the delayed ones, or u's own without a delay.
        self.v = (3, 4, 5) if flat.delay > 0.0 else (0, 1, 2)


def _param(params: Optional[dict[str, Any]], name: str, default: float) -> float:
    if params and name in params:
        return float(params[name])
    return default


def _system_functions(flat: Flat, lay: _Layout, vmax_default: float, vx_default: float) -> tuple[Any, Any]:
    n = flat.order

    def forcing(z: Any, w: float, inp: Any, params: Optional[dict[str, Any]]) -> float:
        """``w`` + the terms on u + the terms on x (+ the Dahl forces): the lag's input, the output before
        the offset."""
        mech = mechanical(
            flat, float(inp[0]), float(inp[1]), float(inp[2]), _param(params, "vmax", vmax_default)
        )
        f = w + mech
        if flat.has_on_x:
            v3 = (float(inp[lay.v[0]]), float(inp[lay.v[1]]), float(inp[lay.v[2]]))
            f += on_x(flat, z[:n], *v3, _param(params, "vx", vx_default))
        fu = float(z[lay.fu]) if lay.fu >= 0 else 0.0
        fx = float(z[lay.fx]) if lay.fx >= 0 else 0.0
        return with_dahl(flat, f, fu, fx)

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
        dxs, xdot = linear(flat, xs, v, vdot)
        x = dot(flat.crow, xs) + flat.dfeed * v
        p = played(z, x, xdot)
        e = float(z[lay.e]) if lay.e >= 0 else 0.0
        d = element(flat, p, w)  # behind the series dashpot; xp still moves at p
        out = np.empty(len(lay.states))
        out[:n] = dxs
        out[lay.w] = rate(flat, d, w, e)
        if lay.e >= 0:
            out[lay.e] = w * d
        if lay.xp >= 0:
            out[lay.xp] = p
        if lay.ys >= 0:
            out[lay.ys] = (forcing(z, w, inp, params) - float(z[lay.ys])) / flat.tau
        if lay.fu >= 0:  # Dahl friction on u moves with the undelayed input's rate, on x with x's
            out[lay.fu] = dahl_rate(flat.fc, flat.sigma, float(inp[1]), float(z[lay.fu]))
        if lay.fx >= 0:
            out[lay.fx] = dahl_rate(flat.fc_x, flat.sigma_x, xdot, float(z[lay.fx]))
        return out

    def output(t: float, z: Any, inp: Any, params: Optional[dict[str, Any]] = None) -> FloatArray:
        w = float(z[lay.w])
        x = dot(flat.crow, z[:n]) + flat.dfeed * float(inp[lay.v[0]])
        if lay.ys >= 0:
            y = flat.y0 + float(z[lay.ys])
        else:
            y = flat.y0 + forcing(z, w, inp, params)
        return np.array([y, x, w])

    return dynamics, output


def to_nlsys(
    plant: WienerPlant,
    *,
    vmax: Optional[float] = None,
    vx: Optional[float] = None,
    name: Optional[str] = None,
    dt: Optional[float] = None,
    substeps: int = 4,
) -> Any:
    """``plant`` (plain or with any terms at any place) as a ``control.NonlinearIOSystem``.

    Two forms (docs/export.md says when to use which):

    * ``dt=None`` (default): the continuous-time system, the model's ODE (the play as its exact
      rate, the sensor lag as its ODE). Under RK4 with the simulator's step (:func:`rk4_response`) it
      reproduces :func:`bouc_wen_id.simulate_input` to rounding for every term but play and sensor lag,
      whose simulator schemes are not RK4 steps of an ODE (there: to the integration error).
    * ``dt`` = the sample step: the discrete-time system (``sys.dt = dt / substeps``, one RK4 step of the
      simulator's own scheme per update, the play's frozen mode and clamp and the lag's exponential step
      included; :mod:`._discrete`): driven by :func:`stage_inputs`, it reproduces ``simulate_input`` to
      rounding for every term. This is the form to use when the exact discrete map matters.

    Parameters
    ----------
    plant : WienerPlant
        In physical units, as identified or built (alpha need not be 1).
    vmax : float, optional
        Peak input velocity ``Vmax`` (units of u per s) of the Coulomb friction's smoothing
        ``tanh(udot / (eps Vmax))`` on u; needed when the plant has it (:func:`peak_speeds`, which
        :func:`rk4_response` and :func:`discrete_response` call themselves). The system's parameter
        ``vmax`` (``params={"vmax": ...}`` overrides it).
    vx : float, optional
        Peak ``|xdot|`` at the samples for the Coulomb friction on x (``tanh(xdot / (eps_x Vx))``); needed
        when the plant has it. The system's parameter ``vx``.
    name : str, optional
        The system's name.
    dt, substeps : float, int
        The discrete form's sample step and RK4 steps per sample (above).

    Returns
    -------
    control.NonlinearIOSystem
        Continuous: inputs ``u, udot, uddot`` (and ``v, vdot, vddot``, the input delayed by G's delay, when
        it has one), outputs ``y, x, w``, states ``xs0.., w`` (and ``e``, ``xp``, ``ys``, ``fu``, ``fx``;
        module docstring); ``params`` hold ``vmax``, ``vx`` and, for reading only, ``delay``, ``w0``,
        ``b``.
        Start it from :func:`initial_state`. Discrete: :func:`._discrete.to_discrete`'s.

    Raises
    ------
    InvalidParameterError
        A Coulomb friction without its peak speed, a negative or non-finite speed, a bad ``dt`` or
        ``substeps``.
    UnsupportedTermError
        The measured-input distortion (``simulate_input`` refuses it too), a term with no exporter.
    ImportError
        python-control is not installed (``pip install 'bouc_wen_id[control]'``).
    """
    control = _optional.require("control", "exporting the model to python-control")
    flat = flatten(plant, "to_nlsys")
    vmax = check_speed("vmax", vmax, flat.f != 0.0, "on u")
    vx = check_speed("vx", vx, flat.f_x != 0.0, "on x")
    if dt is not None:
        return to_discrete(control, flat, vmax, vx, name, dt, substeps)
    lay = _Layout(flat)
    dynamics, output = _system_functions(flat, lay, vmax, vx)
    return control.nlsys(
        dynamics,
        output,
        inputs=lay.inputs,
        outputs=["y", "x", "w"],
        states=lay.states,
        params={"vmax": vmax, "vx": vx, "delay": flat.delay, "w0": flat.w0, "b": flat.b},
        name=name,
    )


def input_signals(sys: Any, t: ArrayLike, u: Union[ArrayLike, SampledInput], times: ArrayLike) -> FloatArray:
    """The input vector of ``sys`` (from :func:`to_nlsys`) at ``times``: shape ``(ninputs, len(times))``.

    ``u`` sampled on the uniform grid ``t`` is interpolated as the simulator does (Catmull-Rom, held after
    the last sample, 0 before ``t[0]``); times count from ``t[0]``. With a delay the rows ``v, vdot, vddot``
    are the same interpolant at ``times - delay``.
    """
    src = u if isinstance(u, SampledInput) else SampledInput(t, u)
    tt = np.atleast_1d(np.asarray(times, dtype=np.float64))
    delay = float(sys.params.get("delay", 0.0))
    rows = np.empty((sys.ninputs, tt.size))
    for j, tj in enumerate(tt):
        rows[:3, j] = src.at(float(tj))
        if sys.ninputs == 6:
            tau = float(tj) - delay
            rows[3:, j] = src.at(tau) if tau >= 0.0 else (0.0, 0.0, 0.0)
    return rows


def rk4_response(
    sys: Any, t: ArrayLike, u: ArrayLike, *, substeps: int = 4, plant: Optional[WienerPlant] = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(x, w, y)`` of the continuous ``sys`` driven by samples ``u(t)``: classical RK4 on its right-hand
    side with the simulator's step ``h = dt / substeps`` and stage times ``t + s h, + h/2, + h`` (design.md
    section 1).

    The input is :func:`input_signals`'s interpolant; ``vmax`` is the interpolant's peak slope and ``vx``
    (friction on x: pass the ``plant``) :func:`peak_speeds`'s. For a plant without play or sensor lag this
    is :func:`bouc_wen_id.simulate_input` to rounding.
    """
    src = SampledInput(t, u)
    steps = count("substeps", substeps, 1, 2**20)
    params = dict(sys.params)
    params["vmax"] = src.peak_rate()
    if plant is not None:
        params["vx"] = peak_speeds(plant, t, u, steps)[1]
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

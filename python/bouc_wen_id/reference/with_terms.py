"""NumPy reference of ``rust/simulate/with_terms.rs``: the simulation with physical terms (design.md 9.4).

Step by step the same scheme as the Rust core, so that the parity tests hold the two to rounding:

- the plain Wiener-Bouc-Wen RK4 of section 1 on ``[xs, w, xp]``, with the generalised rate
  ``wdot = alpha xpdot - beta |xpdot| |w|^(mu-1) w - gamma xpdot |w|^mu - delta xpdot |w|^(mu-1) w``;
- the play's mode frozen per step (up: ``xpdot = max(xdot, 0)``, down: ``min(xdot, 0)``, dwell: 0),
  then ``xp`` clamped into ``[x - b, x + b]`` and ``w`` moved along the path by the clamped travel;
- the sensor lag integrated exponentially over each step with the quadratic through ``F`` at the step's
  start, middle (RK4 continuous extension of ``w``) and end;
- degradation (Baber-Noori): the dissipated energy ``e = int w dxp`` as one more RK4 state, and
  ``nu = 1 + delta_nu e`` multiplying the beta, gamma and delta terms of the rate;
- stiffness degradation (Baber-Noori ``eta = 1 + delta_eta e``, the same energy state) dividing the whole
  rate, and pinching (Foliente's ``h = 1 - zeta1 exp(-((w sgn(xpdot) - q w_u)/(zeta2 w_u))^2)``, the shape
  fixed, ``w_u = (alpha/(beta + gamma))^(1/mu)``) multiplying it, each applied only when present;
- output terms ``k u + c udot + m uddot + f tanh(udot/(eps Vmax))`` on the undelayed input, and the
  mechanical terms on x from the linear part's state (:mod:`.on_x`), added after them;
- the series dashpot (Spencer's MR-damper model with ``c0 = k0 = 0``): the element driven by its own
  travel, ``ddot = xpdot - rho w`` at every stage, its energy ``e = int w dd``;
- Dahl friction on u and on x (``rust/simulate/with_terms/dahl.rs``): its force ``F`` one more RK4 state each,
  ``F' = sigma v' (1 - sgn(v') F / Fc)``, ``F(0) = 0``, with the stage rates of u (undelayed) or x; added to
  the output only when active.

Without asymmetry, play, lag or degradation the plain RK4 of :mod:`.simulate` gives ``x, w`` and the
terms are added at the samples (:func:`outputs`).  Called through ``reference.simulate_sine(..., terms=...)``
and ``reference.simulate_sampled(..., terms=...)`` (:mod:`.simulate`), which choose between the two.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Callable, NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ..validation import finite_scalar
from . import on_x as _on_x
from .terms import (
    ASYMMETRY,
    COULOMB,
    COULOMB_SMOOTHING,
    COULOMB_SMOOTHING_KEY,
    COULOMB_SMOOTHING_MAX,
    DAHL,
    DAHL_SIGMA,
    DEGRADATION,
    INERTIA,
    OFFSET,
    PINCHING,
    PINCHING_CENTRE,
    PINCHING_WIDTH,
    PLACE_X,
    PLAY,
    SENSOR_LAG,
    SERIES_DASHPOT,
    SIMULATION_KEYS,
    STIFFNESS,
    STIFFNESS_DEGRADATION,
    VISCOUS,
)

__all__ = [
    "TERM_NAMES",
    "Input",
    "Model",
    "check_terms",
    "has_state",
    "integrate",
    "lag_weights",
    "outputs",
    "sampled_input",
    "sine_input",
]

FloatArray = NDArray[np.float64]

TERM_NAMES = SIMULATION_KEYS
#: Dahl friction's keys, on u and on x: ``(Fc, sigma)`` at each place.
DAHL_KEYS: tuple[str, ...] = (DAHL, DAHL_SIGMA, f"{DAHL}@{PLACE_X}", f"{DAHL_SIGMA}@{PLACE_X}")
#: Relative slack of the play's engagement test (after a clamp ``x - xp`` is ``b`` only to rounding).
PLAY_ENGAGE_RTOL = 1e-12
#: Below this ``r = h/tau`` the phi functions are Taylor series of PHI_TERMS terms.
PHI_SERIES_BELOW = 1.0
PHI_TERMS = 20


def check_terms(terms: Mapping[str, float], beta: float, gamma: float) -> dict[str, float]:
    """The full set of term parameters (absent ones 0) after the Rust core's checks, in its order."""
    out = {name: 0.0 for name in TERM_NAMES}
    out[COULOMB_SMOOTHING_KEY] = COULOMB_SMOOTHING
    out.update({name: 0.0 for name in DAHL_KEYS})
    for name, value in terms.items():
        if name not in out and name not in _on_x.ON_X_KEYS:
            raise InvalidParameterError(f"unknown term {name!r}; the terms are {', '.join(TERM_NAMES)}")
        if name not in _on_x.ON_X_KEYS:
            out[name] = float(value)
    for name in (*TERM_NAMES, *DAHL_KEYS):
        finite_scalar(name, out[name])
    for name in DAHL_KEYS:
        if out[name] < 0.0:
            raise InvalidParameterError(f"Dahl friction's {name} = {out[name]} must be >= 0")
    if out[SENSOR_LAG] < 0.0:
        raise InvalidParameterError(f"sensor_lag tau = {out[SENSOR_LAG]} s must be >= 0")
    if out[PLAY] < 0.0:
        raise InvalidParameterError(f"play b = {out[PLAY]} must be >= 0 (it is a half-width)")
    if not 0.0 < out[COULOMB_SMOOTHING_KEY] <= COULOMB_SMOOTHING_MAX:
        raise InvalidParameterError(
            f"coulomb_smoothing eps = {out[COULOMB_SMOOTHING_KEY]} must be in (0, {COULOMB_SMOOTHING_MAX}]"
        )
    if out[DEGRADATION] < 0.0:
        raise InvalidParameterError(
            f"degradation delta_nu = {out[DEGRADATION]} must be >= 0 (the strength falls with dissipated "
            "energy)"
        )
    if out[STIFFNESS_DEGRADATION] < 0.0:
        raise InvalidParameterError(
            f"stiffness_degradation delta_eta = {out[STIFFNESS_DEGRADATION]} must be >= 0 (the stiffness "
            "falls with dissipated energy)"
        )
    if not 0.0 <= out[PINCHING] < 1.0:
        raise InvalidParameterError(
            f"pinching zeta1 = {out[PINCHING]} must be in [0, 1) (the share of the rate taken out at the "
            "pinching band's centre)"
        )
    if out[SERIES_DASHPOT] < 0.0:
        raise InvalidParameterError(
            f"series_dashpot rho = {out[SERIES_DASHPOT]} must be >= 0 (the inverse of the series dashpot's "
            "coefficient; 0: no dashpot)"
        )
    out.update(_on_x.check_on_x(terms))
    if abs(out[ASYMMETRY]) >= beta + gamma:
        raise InvalidParameterError(
            f"asymmetry |delta| = {abs(out[ASYMMETRY])} must be < beta + gamma = {beta + gamma}"
        )
    return out


def lag_weights(r: float) -> tuple[float, float, float, float]:
    """``(e^-r, r c_0, r c_m, r c_1)`` of the exponential lag step over ``r = h/tau``."""
    if not math.isfinite(r):
        return 0.0, 0.0, 0.0, 1.0
    z = -r
    if r < PHI_SERIES_BELOW:
        fact = [1.0] * (PHI_TERMS + 4)
        for i in range(1, len(fact)):
            fact[i] = fact[i - 1] * i

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
    return (
        math.exp(z),
        r * (p1 - 3.0 * p2 + 4.0 * p3),
        r * (4.0 * p2 - 8.0 * p3),
        r * (4.0 * p3 - p2),
    )


Source = Callable[[float], tuple[float, float]]


class Input(NamedTuple):
    """The input as the terms see it: ``source(t) -> (u, udot)``, ``second(t) -> uddot`` and the peak
    ``max |udot|`` that scales the Coulomb smoothing."""

    source: Source
    second: Callable[[float], float]
    peak_rate: float
    #: ``(U, omega)`` of a sine (its steady ``|xdot|`` peak scales the friction on x); ``None`` for samples.
    sine: Optional[tuple[float, float]] = None


class Model(NamedTuple):
    """The checked model: realisation ``(a, c, d, delay)`` and Bouc-Wen ``bw`` (checked by :mod:`.simulate`,
    as the plain run's), and the full set of term parameters (:func:`check_terms`)."""

    a: FloatArray
    c: FloatArray
    d: float
    delay: float
    bw: tuple[float, float, float, float, float]
    terms: dict[str, float]
    #: The mechanical terms on x of the run (:func:`.on_x.make`), ``None`` without them.
    on_x: Optional[_on_x.OnX] = None


def has_state(model: Model) -> bool:
    """Whether a term changes the states (asymmetry, play, lag, degradation); if not, the plain RK4 of
    :mod:`.simulate` gives ``x, w`` and :func:`outputs` adds the output terms at the samples."""
    p = model.terms
    return (
        p[ASYMMETRY] != 0.0
        or p[PLAY] > 0.0
        or p[SENSOR_LAG] > 0.0
        or p[DEGRADATION] > 0.0
        or p[STIFFNESS_DEGRADATION] > 0.0
        or p[PINCHING] > 0.0
        or p[SERIES_DASHPOT] > 0.0
        or _dahl_on(_dahl(p))
    )


def _dahl_on(dahl: tuple[tuple[float, float], ...]) -> bool:
    """Whether Dahl friction moves at some place (level and stiffness both > 0)."""
    return any(fc > 0.0 and sigma > 0.0 for fc, sigma in dahl)


def _with_dahl(on: bool, f: float, fu: float, fx: float) -> float:
    """``F`` plus the two Dahl forces when active (only then, so that other runs round as before)."""
    return f + (fu + fx) if on else f


def _dahl_steps(
    dahl: tuple[tuple[float, float], ...],
    fs: tuple[float, float],
    h: float,
    inp: Input,
    ts: float,
    xdots: tuple[float, ...],
) -> tuple[float, float, float, float]:
    """``(fu, fu_mid, fx, fx_mid)`` after one RK4 step from ``ts``: on u with the undelayed input's rates, on
    x with the stage rates ``xdots`` (unchanged when no friction is ``on``)."""
    if not _dahl_on(dahl):
        return fs[0], fs[0], fs[1], fs[1]
    um = inp.source(ts + 0.5 * h)[1]
    fu, fu_mid = _dahl_step(*dahl[0], fs[0], h, (inp.source(ts)[1], um, um, inp.source(ts + h)[1]))
    fx, fx_mid = _dahl_step(*dahl[1], fs[1], h, xdots)
    return fu, fu_mid, fx, fx_mid


def _dahl(p: Mapping[str, float]) -> tuple[tuple[float, float], tuple[float, float]]:
    """Dahl friction's ``(Fc, sigma)`` on u and on x."""
    k = DAHL_KEYS
    return (p[k[0]], p[k[1]]), (p[k[2]], p[k[3]])


def _dahl_step(fc: float, sigma: float, f: float, h: float, vdot: tuple[float, ...]) -> tuple[float, float]:
    """One RK4 step of Dahl's ``F`` with the stage rates ``vdot``: the new ``F`` and its continuous extension
    at the step's middle (as the core's ``Dahl::step``)."""
    if not (fc > 0.0 and sigma > 0.0):
        return f, f

    def rate(v: float, f: float) -> float:
        s = 1.0 if v > 0.0 else -1.0 if v < 0.0 else 0.0
        return sigma * v * (1.0 - s * f / fc)

    half_h = 0.5 * h
    k1 = rate(vdot[0], f)
    k2 = rate(vdot[1], f + half_h * k1)
    k3 = rate(vdot[2], f + half_h * k2)
    k4 = rate(vdot[3], f + h * k3)
    return f + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4), f + h * (5.0 * k1 + 4.0 * (k2 + k3) - k4) / 24.0


def _mech(p: Mapping[str, float], inp: Input) -> Callable[[float], float]:
    """``k u + c udot + m uddot + f tanh(udot/(eps Vmax))`` at time t (the undelayed input)."""
    stiff, visc, iner, coul = p[STIFFNESS], p[VISCOUS], p[INERTIA], p[COULOMB]
    scale = p[COULOMB_SMOOTHING_KEY] * inp.peak_rate

    def mech(t: float) -> float:
        u, udot = inp.source(t)
        uddot = inp.second(t)
        friction = coul * math.tanh(udot / scale) if scale > 0.0 else 0.0
        return stiff * u + visc * udot + iner * uddot + friction

    return mech


def delayed3(inp: Input, delay: float) -> Callable[[float], tuple[float, float, float]]:
    """The delayed input ``(v, vdot, vddot)`` at time t (0 before the delay has elapsed)."""

    def at(t: float) -> tuple[float, float, float]:
        if t - delay < 0.0:
            return 0.0, 0.0, 0.0
        v, vdot = inp.source(t - delay)
        return v, vdot, inp.second(t - delay)

    return at


def outputs(model: Model, w_out: FloatArray, inp: Input, dt: float, substeps: int = 1) -> FloatArray:
    """``y`` at the samples from the plain ``w`` (no state term); the terms on x from the states of a pass
    of the linear part alone."""
    mech = _mech(model.terms, inp)
    f = [float(w_out[k]) + mech(k * dt) for k in range(w_out.size)]
    if model.on_x is not None:
        at = delayed3(inp, model.delay)
        for k, (t, xs) in enumerate(_on_x.linear_pass(model.a, at, dt, w_out.size, substeps)):
            f[k] += model.on_x.at(xs, at(t))
    return np.array([model.terms[OFFSET] + fk for fk in f])


def _forcing(
    mech: Callable[[float], float],
    onx: Optional[_on_x.OnX],
    at: Callable[[float], tuple[float, float, float]],
) -> Callable[[float, float, FloatArray], float]:
    """``F(w, t, xs) = w + mech(t)`` (+ the terms on x at state xs when present): the core's ``forcing``."""

    def forcing(w: float, t: float, xs: FloatArray) -> float:
        f = w + mech(t)
        return f + onx.at(xs, at(t)) if onx is not None else f

    return forcing


class _Rates(NamedTuple):
    """The generalised Bouc-Wen rate with degradation, and the RK4 along the play's path."""

    alpha: float
    beta: float
    gamma: float
    mu: float
    delta: float
    dnu: float
    deta: float = 0.0
    #: Pinching: zeta1, and the band's centre and width in units of w.
    pinch: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def rate(self, xpdot: float, w: float, e: float) -> float:
        try:
            wmu = float(abs(w) ** self.mu)
        except OverflowError:  # a blow-up: run on to inf/NaN as the core does; reported after the run
            wmu = math.inf
        sw = float(np.sign(w))
        nu = 1.0 + self.dnu * e  # Baber-Noori strength degradation; each term times nu, as the core
        r = (
            self.alpha * xpdot
            - nu * (self.beta * abs(xpdot) * sw * wmu)
            - nu * (self.gamma * xpdot * wmu)
            - nu * (self.delta * xpdot * sw * wmu)
        )
        if self.deta != 0.0:  # stiffness degradation: the whole rate over eta
            r /= 1.0 + self.deta * e
        zeta1, centre, width = self.pinch
        if zeta1 != 0.0:  # pinching: Foliente's h(w, sgn xpdot)
            z = (w * float(np.sign(xpdot)) - centre) / width
            r *= 1.0 - zeta1 * math.exp(-z * z)
        return r

    def path(self, w: float, e: float, dxp: float) -> tuple[float, float]:
        rate = self.rate
        k1 = rate(dxp, w, e)
        w2, e2 = w + 0.5 * k1, e + 0.5 * w * dxp
        k2 = rate(dxp, w2, e2)
        w3, e3 = w + 0.5 * k2, e + 0.5 * w2 * dxp
        k3 = rate(dxp, w3, e3)
        w4, e4 = w + k3, e + w3 * dxp
        k4 = rate(dxp, w4, e4)
        return w + (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0, e + (w + 2.0 * w2 + 2.0 * w3 + w4) * dxp / 6.0


def _delayed(inp: Input, delay: float) -> Source:
    """The delayed input ``(v, vdot)`` at time t (0 before the delay has elapsed)."""

    def at(t: float) -> tuple[float, float]:
        if t - delay < 0.0:
            return 0.0, 0.0
        return inp.source(t - delay)

    return at


def _play_mode(x: float, xp: float, b: float, xdot: float) -> int:
    """+1 when the play is engaged going up, -1 going down, 0 in its dwell."""
    e = x - xp
    slack = PLAY_ENGAGE_RTOL * (b + abs(x))
    if xdot > 0.0 and e >= b - slack:
        return 1
    if xdot < 0.0 and e <= -b + slack:
        return -1
    return 0


def integrate(
    model: Model, inp: Input, dt: float, n_samples: int, substeps: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(x, w, y)`` by the RK4 on ``[xs, w, e]`` with the play's mode frozen per step and the lag's
    exponential step (module docstring)."""
    a, c, d, delay, (alpha, beta, gamma, mu, w0), p, onx = model
    forcing = _forcing(_mech(p, inp), onx, delayed3(inp, delay))
    b, tau = p[PLAY], p[SENSOR_LAG]
    w_u = (alpha / (beta + gamma)) ** (1.0 / mu)  # pinching's band in units of the saturation level
    pinch = (p[PINCHING], PINCHING_CENTRE * w_u, PINCHING_WIDTH * w_u)
    rates = _Rates(alpha, beta, gamma, mu, p[ASYMMETRY], p[DEGRADATION], p[STIFFNESS_DEGRADATION], pinch)
    rate = rates.rate
    n = a.size

    delayed = _delayed(inp, delay)

    def linear(xs: FloatArray, vin: tuple[float, float]) -> tuple[FloatArray, float]:
        v, vdot = vin
        dxs = np.empty(n)
        if n:
            dxs[0] = -float(np.dot(a, xs)) + v
            dxs[1:] = xs[: n - 1]
        return dxs, float(np.dot(c, dxs)) + d * vdot

    h = dt / substeps
    half_h, h_sixth = 0.5 * h, h / 6.0
    has_play, has_lag, rho = b > 0.0, tau > 0.0, p[SERIES_DASHPOT]  # the element's travel: xpdot - rho w
    decay, l0, lm, l1 = lag_weights(h / tau) if has_lag else (0.0, 0.0, 0.0, 0.0)

    xs = np.zeros(n)
    w = w0
    en = 0.0  # dissipated energy int w dxp (the degradation's state)
    x0 = float(np.dot(c, xs)) + d * delayed(0.0)[0]
    xp = min(max(0.0, x0 - b), x0 + b)
    ys = 0.0
    dahl, fu, fx = _dahl(p), 0.0, 0.0  # Dahl friction's forces on u and on x
    has_dahl = _dahl_on(dahl)
    x_out, w_out, y_out = np.empty(n_samples), np.empty(n_samples), np.empty(n_samples)
    for k in range(n_samples):
        t = k * dt
        x_out[k] = float(np.dot(c, xs)) + d * delayed(t)[0]
        w_out[k] = w
        y_out[k] = p[OFFSET] + (ys if has_lag else _with_dahl(has_dahl, forcing(w, t, xs), fu, fx))
        if k == n_samples - 1:
            break
        for s in range(substeps):
            ts = t + s * h
            tm, te = ts + half_h, ts + h
            in1, inm, in4 = delayed(ts), delayed(tm), delayed(te)
            k1, xdot1 = linear(xs, in1)
            mode = _play_mode(float(np.dot(c, xs)) + d * in1[0], xp, b, xdot1) if has_play else 0

            def played(xdot: float, mode: int = mode) -> float:
                if not has_play:
                    return xdot
                return max(xdot, 0.0) if mode == 1 else min(xdot, 0.0) if mode == -1 else 0.0

            p1 = played(xdot1)
            d1 = p1 - rho * w
            kw1 = rate(d1, w, en)
            ke1 = w * d1
            w2, e2 = w + half_h * kw1, en + half_h * ke1
            k2, xdot2 = linear(xs + half_h * k1, inm)
            p2 = played(xdot2)
            d2 = p2 - rho * w2
            kw2 = rate(d2, w2, e2)
            ke2 = w2 * d2
            w3, e3 = w + half_h * kw2, en + half_h * ke2
            k3, xdot3 = linear(xs + half_h * k2, inm)
            p3 = played(xdot3)
            d3 = p3 - rho * w3
            kw3 = rate(d3, w3, e3)
            ke3 = w3 * d3
            w4, e4 = w + h * kw3, en + h * ke3
            k4, xdot4 = linear(xs + h * k3, in4)
            p4 = played(xdot4)
            d4 = p4 - rho * w4
            kw4 = rate(d4, w4, e4)
            ke4 = w4 * d4

            w_mid = w + h * (5.0 * kw1 + 4.0 * (kw2 + kw3) - kw4) / 24.0
            xs_mid = xs + h * (5.0 * k1 + 4.0 * (k2 + k3) - k4) / 24.0
            f0 = _with_dahl(has_dahl, forcing(w, ts, xs), fu, fx)
            xs = xs + h_sixth * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            w = w + h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4)
            en = en + h_sixth * (ke1 + 2.0 * ke2 + 2.0 * ke3 + ke4)
            fu, fu_mid, fx, fx_mid = _dahl_steps(dahl, (fu, fx), h, inp, ts, (xdot1, xdot2, xdot3, xdot4))
            if has_play:
                xp = xp + h_sixth * (p1 + 2.0 * p2 + 2.0 * p3 + p4)
                x_end = float(np.dot(c, xs)) + d * in4[0]
                clamped = min(max(xp, x_end - b), x_end + b)
                travel = clamped - xp
                if travel != 0.0:
                    w, en = rates.path(w, en, travel)
                xp = clamped
            if has_lag:
                fm = _with_dahl(has_dahl, forcing(w_mid, tm, xs_mid), fu_mid, fx_mid)
                f1 = _with_dahl(has_dahl, forcing(w, te, xs), fu, fx)
                ys = decay * ys + (l0 * f0 + lm * fm + l1 * f1)
    return x_out, w_out, y_out


def sine_input(amplitude: float, omega: float) -> Input:
    """``u = amplitude cos(omega t)`` (already checked by the caller)."""
    neg_amplitude_omega = -amplitude * omega

    def source(tau: float) -> tuple[float, float]:
        arg = omega * tau
        return amplitude * math.cos(arg), neg_amplitude_omega * math.sin(arg)

    def second(tau: float) -> float:
        return neg_amplitude_omega * omega * math.cos(omega * tau)

    return Input(source, second, abs(amplitude) * omega, (amplitude, omega))


def hermite_peak_rate(u: FloatArray, m: FloatArray, dt: float) -> float:
    """Exact ``max |udot|`` of the Catmull-Rom interpolant: knot slopes and interior vertices."""
    peak = 0.0
    for k in range(u.size - 1):
        m0, m1 = float(m[k]), float(m[k + 1])
        slope = (float(u[k + 1]) - float(u[k])) / dt
        qa = 3.0 * (m0 + m1) - 6.0 * slope
        qb = 6.0 * slope - 4.0 * m0 - 2.0 * m1
        peak = max(peak, abs(m0), abs(m1))
        if qa != 0.0:
            s = -qb / (2.0 * qa)
            if 0.0 < s < 1.0:
                peak = max(peak, abs(m0 + s * (qb + s * qa)))
    return peak


def sampled_input(u: FloatArray, m: FloatArray, dt: float) -> Input:
    """Samples ``u`` with Catmull-Rom slopes ``m`` (already checked by the caller)."""
    last = u.size - 1

    def locate(tau: float) -> tuple[int, float]:
        q = tau / dt
        kf = math.floor(q)
        return int(kf), q - kf

    def source(tau: float) -> tuple[float, float]:
        k, s = locate(tau)
        if k >= last:
            return float(u[last]), 0.0
        s2, s3 = s * s, s * s * s
        u0, u1, m0, m1 = float(u[k]), float(u[k + 1]), float(m[k]), float(m[k + 1])
        h00, h10 = 2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s
        h01, h11 = -2.0 * s3 + 3.0 * s2, s3 - s2
        val = h00 * u0 + h10 * dt * m0 + h01 * u1 + h11 * dt * m1
        d00, d10 = 6.0 * s2 - 6.0 * s, 3.0 * s2 - 4.0 * s + 1.0
        d01, d11 = -6.0 * s2 + 6.0 * s, 3.0 * s2 - 2.0 * s
        der = (d00 * u0 + d01 * u1) / dt + d10 * m0 + d11 * m1
        return val, der

    def second(tau: float) -> float:
        k, s = locate(tau)
        if k >= last:
            return 0.0
        u0, u1, m0, m1 = float(u[k]), float(u[k + 1]), float(m[k]), float(m[k + 1])
        return ((12.0 * s - 6.0) * u0 + (6.0 - 12.0 * s) * u1) / (dt * dt) + (
            (6.0 * s - 4.0) * m0 + (6.0 * s - 2.0) * m1
        ) / dt

    return Input(source, second, hermite_peak_rate(u, m, dt))

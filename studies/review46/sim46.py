"""An independent simulator for review 46: a first-order system integrated by VODE's Adams method.

Nothing from bouc_wen_id but ``bw.Recording`` (in :func:`recordings`). It differs from review 44 (RK4, closed
form G) and review 45 (solve_ivp DOP853, tf2ss, a cosine input) on purpose:

* the input is ``u = U sin(w t)`` from rest, so a delayed input ``U sin(w (t - d))`` (zero before d) is
  continuous and nothing is split;
* G is written by hand in observable canonical form (``_canon``), not by scipy.signal;
* the states are integrated by ``scipy.integrate.ode``'s VODE, variable-order Adams (up to order 12), rtol
  1e-9, atol 1e-12, max step 1/64 period, sampled on the record's grid by VODE's own interpolation (LSODA,
  tried first, stalls at a play's or a stop's engagement: its BDF Newton iteration chatters on the switch);
* :func:`rk4` integrates the same right-hand side by a fixed-step RK4 as a check.

States: [G (n), z, e (dissipated energy, e' = z v), p (play), ym (sensor lag), PI stops (8)].
Bouc-Wen (alpha = 1): ``z' = (v - nuf ratef (beta |v| |z|^mu sgn z + gamma v |z|^mu + delta v |z|^mu sgn z))
pinch / etaf`` with ``nuf = 1 + nu e``, ``etaf = 1 + eta e``, ``ratef = 1 + rate |v| / vref`` and Foliente
pinching ``1 - pinch exp(-((z sgn v - 0.1 w_u) / (0.2 w_u))^2)``; v is x' through a slack gap and a play.
y = z (or ym) + k u + c u' + m u'' + f sgn(u') + the same on x + y0 + PI(u) + noise; Coulomb is a true sign.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np
from scipy.integrate import ode
from scipy.signal import lfilter

NSTOP = 8
RTOL = 1e-9
ATOL = 1e-12
#: A play or stop counts as engaged within TOL of its edge: the integrator's drift must not release it.
TOL = 1e-7


@dataclass(frozen=True)
class Gs:
    """G(s) = num(s)/den(s) exp(-delay s), coefficients highest power first; ``den == ()`` is a pure gain."""

    num: tuple[float, ...] = ()
    den: tuple[float, ...] = ()
    delay: float = 0.0
    gain: float = 1.0

    def at(self, w: float) -> complex:
        s = 1j * w
        g = self.gain if not self.den else np.polyval(self.num, s) / np.polyval(self.den, s)
        return complex(g * np.exp(-s * self.delay))


def isolator(wn: float, zeta: float, delay: float) -> Gs:
    """A lightly damped mode (base-isolator-like): wn^2 / (s^2 + 2 zeta wn s + wn^2), with a delay."""
    return Gs((wn * wn,), (1.0, 2.0 * zeta * wn, wn * wn), delay)


def actuator(tau: float, delay: float) -> Gs:
    return Gs((1.0 / tau,), (1.0, 1.0 / tau), delay)


def _canon(g: Gs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Observable canonical form of a strictly proper num/den (den monic after scaling)."""
    if not g.den:
        return np.zeros((0, 0)), np.zeros(0), np.zeros(0)
    den = np.asarray(g.den, float) / g.den[0]
    n = den.size - 1
    num = np.zeros(n)
    raw = np.asarray(g.num, float) / g.den[0]
    num[n - raw.size :] = raw
    a = np.zeros((n, n))
    a[:, 0] = -den[1:]
    a[: n - 1, 1:] = np.eye(n - 1)
    c = np.zeros(n)
    c[0] = 1.0
    return a, num.copy(), c


#: The element's further parameters, in the order of ``_f``'s ``par[3:11]``, and their default values.
MORE = {
    "play": 0.0,
    "slack": 0.0,
    "nu": 0.0,
    "eta": 0.0,
    "pinch": 0.0,
    "rate": 0.0,
    "vref": 1.0,
    "delta": 0.0,
}


@dataclass(frozen=True)
class Element:
    """Bouc-Wen beta, gamma, mu and any of :data:`MORE` given as (name, value) pairs."""

    beta: float
    gamma: float
    mu: float
    more: tuple[tuple[str, float], ...] = ()

    def get(self, name: str) -> float:
        return dict(self.more).get(name, MORE[name])

    def with_(self, name: str, value: float) -> Element:
        return replace(self, more=(*((k, v) for k, v in self.more if k != name), (name, value)))

    @property
    def w_u(self) -> float:
        return float((self.beta + self.gamma) ** (-1.0 / self.mu))


@dataclass(frozen=True)
class System:
    g: Gs
    el: Element
    terms: tuple[tuple[str, float], ...] = ()  # parallel terms added to y: name -> value
    lag: float = 0.0
    pi_u: float = 0.0

    def term(self, name: str) -> float:
        return dict(self.terms).get(name, 0.0)


@dataclass(frozen=True)
class Plan:
    omegas: tuple[float, ...]
    amps: tuple[float, ...]
    periods: int
    settle: int
    samples: int


@numba.njit(cache=True)
def _f(s, t, a, b, c, gain, amp, om, dly, par, radii):  # noqa: PLR0913
    """par = beta, gamma, mu, play, slack, nu, eta, pinch, rate, vref, delta, w_u, lag, pi on."""
    n = a.shape[0]
    ds = np.zeros(s.size)
    tt = t - dly
    ud = amp * math.sin(om * tt) if tt > 0.0 else 0.0
    udv = amp * om * math.cos(om * tt) if tt > 0.0 else 0.0
    if n > 0:
        x = 0.0
        xv = 0.0
        for i in range(n):
            r = b[i] * ud
            for j in range(n):
                r += a[i, j] * s[j]
            ds[i] = r
            x += c[i] * s[i]
            xv += c[i] * r
    else:
        x = gain * ud
        xv = gain * udv
    z = s[n]
    gap = par[4]
    v = xv
    if gap > 0.0 and abs(x) <= gap:
        v = 0.0
    xs = 0.0 if (gap > 0.0 and abs(x) <= gap) else (x - math.copysign(gap, x) if gap > 0.0 else x)
    if par[3] > 0.0:
        d = xs - s[n + 2]
        if not ((d >= par[3] - TOL and v > 0.0) or (d <= -par[3] + TOL and v < 0.0)):
            v = 0.0
        ds[n + 2] = v
    sz = 1.0 if z > 0.0 else (-1.0 if z < 0.0 else 0.0)
    zm = abs(z) ** par[2]
    core = par[0] * abs(v) * zm * sz + par[1] * v * zm + par[10] * v * zm * sz
    dz = v - (1.0 + par[5] * s[n + 1]) * (1.0 + par[8] * abs(v) / par[9]) * core
    if par[7] > 0.0:
        sv = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
        q = (z * sv - 0.1 * par[11]) / (0.2 * par[11])
        dz = dz * (1.0 - par[7] * math.exp(-q * q))
    ds[n] = dz / (1.0 + par[6] * s[n + 1])
    ds[n + 1] = z * v
    if par[12] > 0.0:
        ds[n + 3] = (z - s[n + 3]) / par[12]
    if par[13] > 0.0:
        uv = amp * om * math.cos(om * t)
        u = amp * math.sin(om * t)
        for k in range(radii.size):
            d = u - s[n + 4 + k]
            if (d >= radii[k] - TOL and uv > 0.0) or (d <= -radii[k] + TOL and uv < 0.0):
                ds[n + 4 + k] = uv
    return ds


def _inputs(sy: System, amp: float, om: float, umin: float) -> tuple[Any, ...]:
    a, b, c = _canon(sy.g)
    el = sy.el
    par = np.array(
        [el.beta, el.gamma, el.mu, *map(el.get, MORE), el.w_u, sy.lag, 1.0 if sy.pi_u > 0 else 0.0]
    )
    radii = umin * 0.06 * np.arange(1, NSTOP + 1)
    return a, b, c, float(sy.g.gain), float(amp), float(om), float(sy.g.delay), par, radii


def grid(pl: Plan, i: int) -> np.ndarray:
    dt = 2.0 * math.pi / pl.omegas[i] / pl.samples
    return np.arange((pl.settle + pl.periods) * pl.samples) * dt


def trajectory(sy: System, pl: Plan, i: int) -> np.ndarray:
    """States on the sample grid of experiment i (rows: time), by VODE's variable-order Adams method."""
    args = _inputs(sy, pl.amps[i], pl.omegas[i], min(pl.amps))
    tg = grid(pl, i)
    s0 = np.zeros(_canon(sy.g)[0].shape[0] + 4 + NSTOP)
    hmax = 2.0 * math.pi / pl.omegas[i] / 64.0
    r = ode(lambda t, y: _f(y, t, *args))
    r.set_integrator("vode", method="adams", rtol=RTOL, atol=ATOL, nsteps=100000, max_step=hmax)
    r.set_initial_value(s0, 0.0)
    out = np.empty((tg.size, s0.size))
    out[0] = s0
    for k in range(1, tg.size):
        out[k] = r.integrate(tg[k])
        if not r.successful():
            raise RuntimeError(f"vode failed at t = {tg[k]:.4g}")
    return out


@numba.njit(cache=True)
def _rk4(s0, tgrid, sub, a, b, c, gain, amp, om, dly, par, radii):  # noqa: PLR0913
    out = np.empty((tgrid.size, s0.size))
    s = s0.copy()
    out[0] = s
    h = (tgrid[1] - tgrid[0]) / sub
    for k in range(tgrid.size - 1):
        t = tgrid[k]
        for _ in range(sub):
            k1 = _f(s, t, a, b, c, gain, amp, om, dly, par, radii)
            k2 = _f(s + 0.5 * h * k1, t + 0.5 * h, a, b, c, gain, amp, om, dly, par, radii)
            k3 = _f(s + 0.5 * h * k2, t + 0.5 * h, a, b, c, gain, amp, om, dly, par, radii)
            k4 = _f(s + h * k3, t + h, a, b, c, gain, amp, om, dly, par, radii)
            s = s + h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
            t += h
        out[k + 1] = s
    return out


def rk4(sy: System, pl: Plan, i: int, sub: int = 32) -> np.ndarray:
    args = _inputs(sy, pl.amps[i], pl.omegas[i], min(pl.amps))
    s0 = np.zeros(_canon(sy.g)[0].shape[0] + 4 + NSTOP)
    return np.asarray(_rk4(s0, grid(pl, i), sub, *args))


def measured(sy: System, pl: Plan, i: int, st: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t, u and the noise-free y of experiment i from its states (rows: time)."""
    t = grid(pl, i)
    om, amp = pl.omegas[i], pl.amps[i]
    a, b, c = _canon(sy.g)
    n = a.shape[0]
    u, uv, ua = amp * np.sin(om * t), amp * om * np.cos(om * t), -amp * om * om * np.sin(om * t)
    tt = t - sy.g.delay
    live = tt > 0
    ud = np.where(live, amp * np.sin(om * tt), 0.0)
    udv = np.where(live, amp * om * np.cos(om * tt), 0.0)
    if n:
        sv = st[:, :n] @ a.T + np.outer(ud, b)
        x, xv = st[:, :n] @ c, sv @ c
        xa = sv @ (a.T @ c) + float(c @ b) * udv
    else:
        x, xv = sy.g.gain * ud, sy.g.gain * udv
        xa = np.where(live, -sy.g.gain * amp * om * om * np.sin(om * tt), 0.0)
    y = (st[:, n + 3] if sy.lag > 0 else st[:, n]).copy()
    vec = {"stiffness": u, "viscous": uv, "inertia": ua, "coulomb": np.sign(uv), "offset": np.ones_like(t)}
    vec |= {"stiffness@x": x, "viscous@x": xv, "inertia@x": xa, "coulomb@x": np.sign(xv)}
    for name, val in sy.terms:
        y = y + val * vec[name]
    if sy.pi_u > 0:
        radii = min(pl.amps) * 0.06 * np.arange(1, NSTOP + 1)
        y = y + sy.pi_u * np.sum(u[:, None] - st[:, n + 4 :], axis=1) / float(radii.sum())
    return t, u, y


def simulate(sy: System, pl: Plan) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return [measured(sy, pl, i, trajectory(sy, pl, i)) for i in range(len(pl.omegas))]


def with_effect(sy: System, name: str, v: float) -> System:
    if name in MORE:
        return replace(sy, el=sy.el.with_(name, v))
    if name in ("lag", "pi_u"):
        return replace(sy, **{name: v})
    return replace(sy, terms=(*sy.terms, (name, v)))


def hum_rate() -> float:
    """The hum: 50 Hz, in rad/s."""
    return 2.0 * math.pi * 50.0


def noise(kind: str, sd: float, t: np.ndarray, y: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """y plus noise of the kind: ar2 (band-limited: poles 0.95 exp(+-i 0.3), sd), quant (white sd, then
    rounded to 0.5 sd), hum (white sd plus a 50 Hz sine of RMS sd, random phase), white."""
    w = rng.normal(0.0, sd, t.size)
    if kind == "white":
        return y + w
    if kind == "ar2":
        r, th = 0.95, 0.3
        e = lfilter([1.0], [1.0, -2.0 * r * math.cos(th), r * r], rng.normal(size=t.size + 500))[500:]
        return y + sd * e / float(np.std(e))
    if kind == "quant":
        q = 0.5 * sd
        return q * np.round((y + w) / q)
    if kind == "hum":
        return y + w + sd * math.sqrt(2.0) * np.sin(hum_rate() * t + rng.uniform(0.0, 2.0 * math.pi))
    raise ValueError(kind)


def recordings(runs: list[tuple[np.ndarray, ...]], pl: Plan, kind: str, sd: float, seed: int) -> list[Any]:
    import bouc_wen_id as bw

    recs = []
    for i, (t, u, y) in enumerate(runs):
        rng = np.random.default_rng([46, seed, i])
        recs.append(
            bw.Recording(
                t - 0.5 * math.pi / pl.omegas[i],  # u = U sin(w t) = U cos(w t') on t' = t - T/4, as bw asks
                u,
                noise(kind, sd, t, y, rng),
                pl.amps[i],
                pl.omegas[i],
                settle_periods=pl.settle,
                metadata={"name": f"x{i}_w{pl.omegas[i]:g}_U{pl.amps[i]:.3g}", "source": "review46/sim46.py"},
            )
        )
    return recs

"""An independent simulator for review 47: implicit trapezoidal steps (Crank-Nicolson) solved by Newton.

Nothing from bouc_wen_id but ``bw.Recording`` / ``bw.Measurement`` (in :func:`recordings`). It differs from
review 44 (RK4), 45 (DOP853) and 46 (VODE Adams) on purpose:

* the first-order system is integrated by the **implicit trapezoidal rule**, each step solved by Newton's
  method on a finite-difference Jacobian (``SUB`` steps a sample; :func:`rk4` integrates the same right-hand
  side by a fine fixed-step RK4 as the check);
* G is written in **controllable** canonical form by hand; u = U cos(w t) from rest at t = 0;
* the Bouc-Wen element keeps its **alpha** (the library identifies alpha = 1 with G -> alpha G: the truths of
  terms on x, nu and eta are divided by alpha);
* rate-independent operators are applied **exactly on the sample grid** after the integration: a
  Prandtl-Ishlinskii loop on x (8 plays, radii 0.1..0.8 of max |x|, weights 1/k) and backlash on the
  measured output (a play operator on y);
* Dahl friction on u with exponent 2 (``F' = sigma u' (1 - sgn(u') F / Fc)^2``): not the library's Dahl
  (exponent 1), a member of the same family.

States: [G (n), z, e (dissipated energy, e' = z v), F (Dahl on u)].
``z' = (alpha v - nuf ratef (beta |v| |z|^mu sgn z + gamma v |z|^mu + delta v |z|^mu sgn z)) pinch / etaf``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np
from scipy.signal import lfilter

SUB = 8
NEWTON = 12


@dataclass(frozen=True)
class Gs:
    """G(s) = num(s)/den(s), coefficients highest power first; ``den == ()`` is a pure gain."""

    num: tuple[float, ...] = ()
    den: tuple[float, ...] = ()
    gain: float = 1.0

    def at(self, w: float) -> complex:
        if not self.den:
            return complex(self.gain)
        s = 1j * w
        return complex(np.polyval(self.num, s) / np.polyval(self.den, s))


def two_mode(w1: float, z1: float, w2: float, z2: float) -> Gs:
    """Two modes in parallel (unit static gain each half): two resonances."""
    d1 = np.array([1.0, 2 * z1 * w1, w1 * w1])
    d2 = np.array([1.0, 2 * z2 * w2, w2 * w2])
    num = 0.5 * w1 * w1 * d2 + 0.5 * w2 * w2 * d1
    return Gs(tuple(num), tuple(np.polymul(d1, d2)))


def nonmin(zero: float, tau: float) -> Gs:
    """(1 - s/zero) / (tau s + 1)^2: a right-half-plane zero."""
    return Gs((-1.0 / zero, 1.0), tuple(np.polymul([tau, 1.0], [tau, 1.0])))


def integrator(k: float, eps: float, tau: float) -> Gs:
    """k / ((s + eps)(tau s + 1)): an integrator above eps, phase near -90 deg and beyond."""
    return Gs((k,), tuple(np.polymul([1.0, eps], [tau, 1.0])))


def lowpass(tau: float) -> Gs:
    return Gs((1.0 / tau,), (1.0, 1.0 / tau))


def _ctrl(g: Gs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Controllable canonical form of a strictly proper num/den."""
    if not g.den:
        return np.zeros((0, 0)), np.zeros(0), np.zeros(0)
    den = np.asarray(g.den, float) / g.den[0]
    n = den.size - 1
    raw = np.asarray(g.num, float) / g.den[0]
    num = np.zeros(n)
    num[n - raw.size :] = raw
    a = np.zeros((n, n))
    a[: n - 1, 1:] = np.eye(n - 1)
    a[n - 1, :] = -den[1:][::-1]
    b = np.zeros(n)
    b[n - 1] = 1.0
    return a, b, num[::-1].copy()


#: The element's further parameters (``_f``'s ``par[4:12]`` in this order) and their defaults.
MORE = dict(nu=0.0, eta=0.0, pinch=0.0, rate=0.0, vref=1.0, delta=0.0, dahl_fc=0.0, dahl_sigma=0.0)


@dataclass(frozen=True)
class Element:
    """alpha, beta, gamma, mu and any of :data:`MORE` as sorted (name, value) pairs."""

    alpha: float
    beta: float
    gamma: float
    mu: float
    more: tuple[tuple[str, float], ...] = ()

    def get(self, name: str) -> float:
        return {**MORE, **dict(self.more)}[name]

    def with_(self, name: str, value: float) -> Element:
        return replace(self, more=tuple(sorted({**dict(self.more), name: value}.items())))

    @property
    def w_u(self) -> float:
        return float((self.alpha / (self.beta + self.gamma)) ** (1.0 / self.mu))


@dataclass(frozen=True)
class System:
    g: Gs
    el: Element
    terms: tuple[tuple[str, float], ...] = ()
    pi_x: float = 0.0
    backlash: float = 0.0


@dataclass(frozen=True)
class Plan:
    omegas: tuple[float, ...]
    amps: tuple[float, ...]
    periods: int
    settles: tuple[int, ...]
    samples: tuple[float, ...]  # samples per period (not whole for a Measurement plan)


@numba.njit(cache=True)
def _sign(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@numba.njit(cache=True)
def _f(s, t, a, b, c, gain, amp, om, par):  # noqa: PLR0913
    """par = alpha, beta, gamma, mu, nu, eta, pinch, rate, vref, delta, dahl_fc, dahl_sigma, w_u."""
    n = a.shape[0]
    ds = np.zeros(s.size)
    u = amp * math.cos(om * t)
    uv = -amp * om * math.sin(om * t)
    if n > 0:
        ds[:n] = b * u
        for j in range(n):  # column by column: each row summed in the order b u + a_i0 s_0 + a_i1 s_1 ...
            ds[:n] += a[:, j] * s[j]
        xv = 0.0
        for i in range(n):
            xv += c[i] * ds[i]
    else:
        xv = gain * uv
    z, v = s[n], xv
    shape = par[1] * abs(v) * _sign(z) + par[2] * v + par[9] * v * _sign(z)
    widen = (1.0 + par[4] * s[n + 1]) * (1.0 + par[7] * abs(v) / par[8])
    dz = par[0] * v - widen * shape * abs(z) ** par[3]
    if par[6] > 0.0:  # Foliente: q = 0.1, zeta2 = 0.2 of w_u
        q = (z * _sign(v) / par[12] - 0.1) / 0.2
        dz *= 1.0 - par[6] * math.exp(-q * q)
    ds[n] = dz / (1.0 + par[5] * s[n + 1])
    ds[n + 1] = z * v
    if par[10] > 0.0:
        m = 1.0 - _sign(uv) * s[n + 2] / par[10]
        ds[n + 2] = par[11] * uv * m * abs(m)
    return ds


@numba.njit(cache=True)
def _trap(s0, tgrid, sub, a, b, c, gain, amp, om, par):  # noqa: PLR0913
    """Implicit trapezoidal steps, Newton on a forward-difference Jacobian; states on the sample grid."""
    m = s0.size
    out = np.empty((tgrid.size, m))
    s = s0.copy()
    out[0] = s
    h = (tgrid[1] - tgrid[0]) / sub
    eye = np.eye(m)
    jac = np.empty((m, m))
    for k in range(tgrid.size - 1):
        t = tgrid[0] + k * (tgrid[1] - tgrid[0])
        for _ in range(sub):
            f0 = _f(s, t, a, b, c, gain, amp, om, par)
            s1 = s + h * f0
            for _it in range(NEWTON):
                f1 = _f(s1, t + h, a, b, c, gain, amp, om, par)
                r = s1 - s - 0.5 * h * (f0 + f1)
                for j in range(m):
                    e = 1e-7 * max(1.0, abs(s1[j]))
                    sp = s1.copy()
                    sp[j] += e
                    jac[:, j] = (_f(sp, t + h, a, b, c, gain, amp, om, par) - f1) / e
                d = np.linalg.solve(eye - 0.5 * h * jac, r)
                s1 = s1 - d
                if np.max(np.abs(d)) < 1e-13 * (1.0 + np.max(np.abs(s1))):
                    break
            s = s1
            t += h
        out[k + 1] = s
    return out


@numba.njit(cache=True)
def _rk4(s0, tgrid, sub, a, b, c, gain, amp, om, par):  # noqa: PLR0913
    out = np.empty((tgrid.size, s0.size))
    s = s0.copy()
    out[0] = s
    h = (tgrid[1] - tgrid[0]) / sub
    for k in range(tgrid.size - 1):
        t = tgrid[0] + k * (tgrid[1] - tgrid[0])
        for _ in range(sub):
            stage = _f(s, t, a, b, c, gain, amp, om, par)
            acc = stage.copy()
            for frac, weight in ((0.5, 2.0), (0.5, 2.0), (1.0, 1.0)):
                stage = _f(s + frac * h * stage, t + frac * h, a, b, c, gain, amp, om, par)
                acc += weight * stage
            s = s + h * acc / 6.0
            t += h
        out[k + 1] = s
    return out


def _inputs(sy: System, amp: float, om: float) -> tuple[Any, ...]:
    a, b, c = _ctrl(sy.g)
    el = sy.el
    par = np.array([el.alpha, el.beta, el.gamma, el.mu, *map(el.get, MORE), el.w_u])
    return a, b, c, float(sy.g.gain), float(amp), float(om), par


def grid(pl: Plan, i: int) -> np.ndarray:
    dt = 2.0 * math.pi / pl.omegas[i] / pl.samples[i]
    return np.arange(int(round((pl.settles[i] + pl.periods) * pl.samples[i]))) * dt


def trajectory(sy: System, pl: Plan, i: int, check: bool = False, sub: int = SUB) -> np.ndarray:
    args = _inputs(sy, pl.amps[i], pl.omegas[i])
    s0 = np.zeros(_ctrl(sy.g)[0].shape[0] + 3)
    return np.asarray((_rk4 if check else _trap)(s0, grid(pl, i), sub, *args))


def play(x: np.ndarray, r: float) -> np.ndarray:
    """The play operator of half-width r on a sampled signal (exact for a signal monotone between samples)."""
    out = np.empty_like(x)
    p = float(np.clip(0.0, x[0] - r, x[0] + r))
    for k, xk in enumerate(x):
        p = min(max(p, xk - r), xk + r)
        out[k] = p
    return out


def sgn(v: np.ndarray) -> np.ndarray:
    """sign(v), 0 within 1e-9 of max |v|: a sample on a reversal (sin(w t) = 1e-16 at t = T/2) is 0, not a
    rounding error's +-1 (it made +-f spikes each half period: the diagnosis flagged them as outliers)."""
    return np.where(np.abs(v) > 1e-9 * float(np.max(np.abs(v))), np.sign(v), 0.0)


def measured(sy: System, pl: Plan, i: int, st: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t, u and the noise-free y of experiment i from its states (rows: time)."""
    t = grid(pl, i)
    om, amp = pl.omegas[i], pl.amps[i]
    a, b, c = _ctrl(sy.g)
    n = a.shape[0]
    u, uv, ua = amp * np.cos(om * t), -amp * om * np.sin(om * t), -amp * om * om * np.cos(om * t)
    if n:
        sv = st[:, :n] @ a.T + np.outer(u, b)
        x, xv = st[:, :n] @ c, sv @ c
        xa = sv @ (a.T @ c) + float(c @ b) * uv
    else:
        x, xv, xa = sy.g.gain * u, sy.g.gain * uv, sy.g.gain * ua
    y = st[:, n] + st[:, n + 2]
    vec = {"stiffness": u, "viscous": uv, "inertia": ua, "coulomb": sgn(uv), "offset": np.ones_like(t)}
    vec |= {"stiffness@x": x, "viscous@x": xv, "inertia@x": xa, "coulomb@x": sgn(xv)}
    for name, val in sy.terms:
        y = y + val * vec[name]
    if sy.pi_x > 0:
        xm = float(np.max(np.abs(x)))
        ks = np.arange(1, 9)
        pis = sum((x - play(x, 0.1 * k * xm)) / k for k in ks)
        y = y + sy.pi_x * pis / float(np.sum(0.1 * ks * xm / ks))
    if sy.backlash > 0:
        y = play(y, sy.backlash)
    return t, u, y


def simulate(sy: System, pl: Plan, check: bool = False) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return [measured(sy, pl, i, trajectory(sy, pl, i, check)) for i in range(len(pl.omegas))]


def with_effect(sy: System, name: str, v: float) -> System:
    if name in MORE:
        return replace(sy, el=sy.el.with_(name, v))
    if name in ("pi_x", "backlash"):
        return replace(sy, **{name: v})
    return replace(sy, terms=(*sy.terms, (name, v)))


def noise(kind: str, sd: float, t: np.ndarray, y: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """y plus noise: hetero (sd proportional to |y - mean| + a floor of 0.3 RMS, overall RMS sd), outliers
    (white sd, 2 % of samples at +-10 sd), drift (white sd, and a gain drifting linearly by 2 % over the
    record), ar1 (white sd plus AR(1) 0.95 of sd), white."""
    w = rng.normal(0.0, 1.0, t.size)
    if kind == "white":
        return y + sd * w
    if kind == "hetero":
        yc = np.abs(y - y.mean())
        scale = yc + 0.3 * float(np.sqrt(np.mean(yc**2)))
        scale = scale / float(np.sqrt(np.mean(scale**2)))
        return y + sd * scale * w
    if kind == "outliers":
        hit = rng.random(t.size) < 0.02
        return y + sd * w + hit * 10.0 * sd * rng.choice([-1.0, 1.0], t.size)
    if kind == "drift":
        return y * (1.0 + 0.02 * (t - t[0]) / (t[-1] - t[0])) + sd * w
    if kind == "ar1":
        e = lfilter([1.0], [1.0, -0.95], rng.normal(size=t.size + 300))[300:]
        return y + sd * w + sd * e / float(np.std(e))
    raise ValueError(kind)


def recordings(runs: list[tuple[np.ndarray, ...]], pl: Plan, kind: str, sd: float, seed: int) -> list[Any]:
    """bw.Recording per experiment; a plan with a non-whole number of samples per period gives
    bw.Measurement (the record from the end of settling on; the library finds the frequency itself)."""
    import bouc_wen_id as bw

    recs: list[Any] = []
    for i, (t, u, y) in enumerate(runs):
        rng = np.random.default_rng([47, seed, i])
        yn = noise(kind, sd, t, y, rng)
        name = f"x{i}_w{pl.omegas[i]:g}_U{pl.amps[i]:.3g}"
        meta = {"name": name, "source": "review47/sim47.py"}
        if float(pl.samples[i]).is_integer():
            recs.append(
                bw.Recording(t, u, yn, pl.amps[i], pl.omegas[i], settle_periods=pl.settles[i], metadata=meta)
            )
        else:
            cut = int(round(pl.settles[i] * pl.samples[i]))
            recs.append(
                bw.Measurement(
                    t[cut:],
                    u[cut:],
                    yn[cut:],
                    nominal_frequency=pl.omegas[i],
                    name=name,
                    metadata={"source": meta["source"]},
                )
            )
    return recs

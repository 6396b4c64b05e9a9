"""An independent Wiener-Bouc-Wen simulator for review 44 (nothing from bouc_wen_id but ``Recording``).

Plant: ``u = U cos(omega t)`` -> delay + rational G(s) (state space, solved in closed form from rest) -> x
-> [slack dead zone] -> [play] -> Bouc-Wen (eq. 2a, alpha = 1, own RK4 on a grid twice as fine as the
sampling, with optional Baber-Noori strength/stiffness degradation, Foliente pinching, a rate-dependent
width) -> w; ``y = w + m uddot (or m xddot) + Dahl(u) + Iwan(u) + noise``. The feedback plant
``m y'' + c y' + k y + z = u`` has its own RK4. Noise: white, AR(1) or quantised, all from seeds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Optional

import numba
import numpy as np

TWO_PI = 2.0 * math.pi
SUB = 2  # RK4 steps per sample


# ---- linear part
@dataclass(frozen=True)
class Linear:
    """G(s) = num(s)/den(s) e^{-delay s}, strictly proper, stable; coefficients highest power first."""

    num: tuple[float, ...]
    den: tuple[float, ...]
    delay: float = 0.0
    label: str = ""

    def response(self, omega: float) -> complex:
        s = 1j * omega
        return complex(np.polyval(self.num, s) / np.polyval(self.den, s) * np.exp(-s * self.delay))

    def ss(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        den = np.asarray(self.den, float)
        den = den / den[0]
        n = den.size - 1
        num = np.zeros(n)
        b = np.asarray(self.num, float) / float(self.den[0])
        num[n - b.size :] = b
        a = np.zeros((n, n))
        a[:-1, 1:] = np.eye(n - 1)
        a[-1, :] = -den[1:][::-1]
        bb = np.zeros(n)
        bb[-1] = 1.0
        c = num[::-1].copy()
        return a, bb, c


def resonant(wn: float, zeta: float, delay: float = 0.0, k: float = 1.0) -> Linear:
    return Linear((k * wn * wn,), (1.0, 2.0 * zeta * wn, wn * wn), delay, f"res(wn={wn},z={zeta},d={delay})")


def first_order(tau: float, delay: float = 0.0, k: float = 1.0) -> Linear:
    return Linear((k / tau,), (1.0, 1.0 / tau), delay, f"fo(tau={tau},d={delay})")


def two_pole(t1: float, t2: float, delay: float = 0.0, k: float = 1.0) -> Linear:
    return Linear((k,), (t1 * t2, t1 + t2, 1.0), delay, f"2p(t1={t1},t2={t2},d={delay})")


def linear_drive(
    g: Linear, amp: float, omega: float, t: np.ndarray, steady: bool = False
) -> tuple[np.ndarray, ...]:
    """x, xdot, xddot of G driven from rest by ``amp cos(omega (t - delay))`` (zero before the delay).

    Closed form: the steady particular solution ``Re[(j w I - A)^-1 B U e^{j w (t - d)}]`` plus the
    homogeneous solution through the modes of A that cancels it at ``t = d``.
    """
    a, b, c = g.ss()
    n = a.shape[0]
    tau = t - g.delay
    on = tau >= 0.0
    sp_c = np.linalg.solve(1j * omega * np.eye(n) - a, b) * amp  # complex amplitude of the state
    ph = np.exp(1j * omega * np.where(on, tau, 0.0))
    s_p = np.real(sp_c[:, None] * ph[None, :])
    lam, v = np.linalg.eig(a)
    coef = np.linalg.solve(v, np.real(sp_c).astype(complex))  # s_p(0) in modal coordinates
    modes = np.exp(lam[:, None] * np.where(on, tau, 0.0)[None, :])
    s_h = -np.real(v @ (coef[:, None] * modes))
    if steady:  # the particular solution alone, extended before the delay
        s_p = np.real(sp_c[:, None] * np.exp(1j * omega * tau)[None, :])
        on = np.ones_like(on)
        s_h = 0.0 * s_p
    s = np.where(on[None, :], s_p + s_h, 0.0)
    ud = np.where(on, amp * np.cos(omega * tau), 0.0)
    udd = np.where(on, -amp * omega * np.sin(omega * tau), 0.0)
    sdot = a @ s + np.outer(b, ud)
    sddot = a @ sdot + np.outer(b, udd)
    return c @ s, c @ sdot, c @ sddot


# ---- hysteresis
@dataclass(frozen=True)
class Hyst:
    beta: float = 1.2
    gamma: float = 0.3
    mu: float = 1.5
    play: float = 0.0  # backlash half-width before the element
    slack: float = 0.0  # dead zone half-width before the element (outside the library)
    nu: float = 0.0  # strength degradation delta_nu (nu = 1 + nu e)
    eta: float = 0.0  # stiffness degradation delta_eta (eta = 1 + eta e)
    pinch: float = 0.0  # Foliente zeta1, q = 0.1, zeta2 = 0.2 of w_u
    rate: float = 0.0  # rate-dependent width: beta, gamma times (1 + rate |xpdot| / vref)
    vref: float = 1.0

    @property
    def w_u(self) -> float:
        return (1.0 / (self.beta + self.gamma)) ** (1.0 / self.mu)


@numba.njit(cache=False)
def _bw_rate(w, v, beta, gamma, mu, nuf, etaf, pinch, wu, ratef):
    aw = abs(w)
    p = aw ** (mu - 1.0) if aw > 0.0 else 0.0
    r = v - nuf * ratef * (beta * abs(v) * p * w + gamma * v * p * aw)
    if pinch > 0.0:
        sg = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
        d = (w * sg - 0.1 * wu) / (0.2 * wu)
        r *= 1.0 - pinch * math.exp(-d * d)
    return r / etaf


@numba.njit(cache=False)
def _bw_run(xp, hf, beta, gamma, mu, nu, eta, pinch, wu, rate, vref):
    """w at every point of the fine grid ``xp`` (spacing hf), by RK4 in the travel: over each interval
    ``dw/dxp`` at the interval's direction, so a play's engagement costs no accuracy (the element is rate
    independent but for the rate factor, taken from the interval's mean speed)."""
    out = np.zeros(xp.size)
    w = 0.0
    e = 0.0
    for i in range(xp.size - 1):
        dx = xp[i + 1] - xp[i]
        if dx != 0.0:
            sg = 1.0 if dx > 0.0 else -1.0
            ratef = 1.0 + rate * abs(dx) / hf / vref
            k1 = _bw_rate(w, sg, beta, gamma, mu, 1.0 + nu * e, 1.0 + eta * e, pinch, wu, ratef) * sg
            l1 = w
            w2 = w + 0.5 * dx * k1
            e2 = e + 0.5 * dx * l1
            k2 = _bw_rate(w2, sg, beta, gamma, mu, 1.0 + nu * e2, 1.0 + eta * e2, pinch, wu, ratef) * sg
            l2 = w2
            w3 = w + 0.5 * dx * k2
            e3 = e + 0.5 * dx * l2
            k3 = _bw_rate(w3, sg, beta, gamma, mu, 1.0 + nu * e3, 1.0 + eta * e3, pinch, wu, ratef) * sg
            l3 = w3
            w4 = w + dx * k3
            e4 = e + dx * l3
            k4 = _bw_rate(w4, sg, beta, gamma, mu, 1.0 + nu * e4, 1.0 + eta * e4, pinch, wu, ratef) * sg
            l4 = w4
            w += dx / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            e += dx / 6.0 * (l1 + 2.0 * l2 + 2.0 * l3 + l4)
        out[i + 1] = w
    return out


@numba.njit(cache=False)
def _play(x, xd, b):
    """Exact discrete play operator on a fine grid and its rate (xd where the play is engaged)."""
    xp = np.empty(x.size)
    vd = np.zeros(x.size)
    p = x[0]
    for i in range(x.size):
        lo = x[i] - b
        hi = x[i] + b
        if p < lo:
            p = lo
        elif p > hi:
            p = hi
        xp[i] = p
        if (p == lo and xd[i] > 0.0) or (p == hi and xd[i] < 0.0):
            vd[i] = xd[i]
    return xp, vd


def hysteresis(hy: Hyst, x: np.ndarray, xd: np.ndarray, h: float) -> np.ndarray:
    """w on the coarse grid from x, x' on the fine grid (spacing h/2)."""
    if hy.slack > 0.0:
        inside = np.abs(x) <= hy.slack
        x = np.where(inside, 0.0, x - np.sign(x) * hy.slack)
        xd = np.where(inside, 0.0, xd)
    if hy.play > 0.0:
        x, _ = _play(x, xd, hy.play)
    return _bw_run(
        np.ascontiguousarray(x),
        h / 2.0,
        hy.beta,
        hy.gamma,
        hy.mu,
        hy.nu,
        hy.eta,
        hy.pinch,
        hy.w_u,
        hy.rate,
        hy.vref,
    )


# ---- parallel loops
@numba.njit(cache=False)
def _dahl(ud, h, fc, sigma):
    """F' = sigma u' (1 - sgn(u') F / fc), RK4 on the fine grid of u'."""
    m = (ud.size - 1) // 2
    out = np.zeros(m + 1)
    f = 0.0
    for k in range(m):
        v0 = ud[2 * k]
        v1 = ud[2 * k + 1]
        v2 = ud[2 * k + 2]
        k1 = sigma * v0 * (1.0 - math.copysign(1.0, v0) * f / fc)
        f1 = f + 0.5 * h * k1
        k2 = sigma * v1 * (1.0 - math.copysign(1.0, v1) * f1 / fc)
        f2 = f + 0.5 * h * k2
        k3 = sigma * v1 * (1.0 - math.copysign(1.0, v1) * f2 / fc)
        f3 = f + h * k3
        k4 = sigma * v2 * (1.0 - math.copysign(1.0, v2) * f3 / fc)
        f += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        out[k + 1] = f
    return out


def iwan(u: np.ndarray, level: float, stiffness: float, elements: int = 24) -> np.ndarray:
    """Parallel Jenkins elements (spring + slider), yield forces uniform on (0, 2 level / elements], total
    saturated force ``level``; each element's force is the exact clip of its spring on the sampled u."""
    f_y = level * 2.0 * np.arange(1, elements + 1) / (elements * (elements + 1))
    k_i = stiffness / elements
    f = np.zeros(elements)
    out = np.empty(u.size)
    prev = u[0]
    for i in range(u.size):
        f = np.clip(f + k_i * (u[i] - prev), -f_y, f_y)
        prev = u[i]
        out[i] = f.sum()
    return out


# ---- feedback plant
@numba.njit(cache=False)
def _feedback(amp, omega, h, n, m, c, k, beta, gamma, mu):
    """m y'' + c y' + k y + z = u, z' = y' - beta|y'||z|^(mu-1) z - gamma y'|z|^mu; y at steps of h."""
    out = np.zeros(n + 1)
    s = np.zeros(3)
    for i in range(n):
        t = i * h
        ks = np.empty((4, 3))
        for j in range(4):
            tj = t + (0.0 if j == 0 else (h if j == 3 else 0.5 * h))
            st = s.copy()
            if j == 1 or j == 2:
                st = s + 0.5 * h * ks[j - 1]
            elif j == 3:
                st = s + h * ks[2]
            y, v, z = st[0], st[1], st[2]
            az = abs(z)
            p = az ** (mu - 1.0) if az > 0.0 else 0.0
            ks[j, 0] = v
            ks[j, 1] = (amp * math.cos(omega * tj) - c * v - k * y - z) / m
            ks[j, 2] = v - beta * abs(v) * p * z - gamma * v * p * az
        s = s + h / 6.0 * (ks[0] + 2.0 * ks[1] + 2.0 * ks[2] + ks[3])
        out[i + 1] = s[0]
    return out


# ---- plant, design
@dataclass(frozen=True)
class Design:
    omegas: tuple[float, ...]
    amps: tuple[float, ...]
    periods: int = 20
    settle: int = 10
    samples: int = 256
    label: str = ""
    steady_start: bool = False  # x the steady sine from t = 0 (no ring-down of G; the library's own start)


@dataclass(frozen=True)
class Plant:
    g: Linear
    hy: Hyst = field(default_factory=Hyst)
    inertia_u: float = 0.0
    inertia_x: float = 0.0
    dahl_fc: float = 0.0
    dahl_sigma: float = 0.0
    iwan_level: float = 0.0
    iwan_k: float = 0.0
    feedback: Optional[tuple[float, float, float]] = None  # (m, c, k) of the feedback structure


@dataclass(frozen=True)
class Noise:
    kind: str = "white"  # white | ar1 | quant
    sd: float = 0.01
    phi: float = 0.0  # AR(1) coefficient
    step: float = 0.0  # quantisation step (a white dither of sd/2 below it)


def run_one(p: Plant, d: Design, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Noise-free t, u, y of experiment ``i``."""
    omega, amp = d.omegas[i], d.amps[i]
    n = (d.settle + d.periods) * d.samples
    dt = TWO_PI / omega / d.samples
    t = np.arange(n) * dt
    u = amp * np.cos(omega * t)
    if p.feedback is not None:
        m, c, k = p.feedback
        y = _feedback(amp, omega, dt / SUB, (n - 1) * SUB, m, c, k, p.hy.beta, p.hy.gamma, p.hy.mu)[::SUB]
        return t, u, y
    h = dt / SUB
    tf = np.arange((n - 1) * 2 * SUB + 1) * (h / 2.0)
    x, xd, xdd = linear_drive(p.g, amp, omega, tf, d.steady_start)
    y = hysteresis(p.hy, x, xd, h)[:: 2 * SUB].copy()
    if p.inertia_u:
        y += p.inertia_u * (-amp * omega * omega * np.cos(omega * t))
    if p.inertia_x:
        y += p.inertia_x * xdd[:: 2 * SUB]
    if p.dahl_fc > 0.0:
        ud = -amp * omega * np.sin(omega * tf)
        y += _dahl(ud, h, p.dahl_fc, p.dahl_sigma)[::SUB]
    if p.iwan_level > 0.0:
        y += iwan(u, p.iwan_level, p.iwan_k)
    return t, u, y


def run(p: Plant, d: Design) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return [run_one(p, d, i) for i in range(len(d.omegas))]


def noise(nz: Noise, n: int, rng: np.random.Generator) -> np.ndarray:
    if nz.kind == "white":
        return rng.normal(0.0, nz.sd, n)
    if nz.kind == "ar1":
        e = rng.normal(0.0, nz.sd * math.sqrt(1.0 - nz.phi**2), n)
        out = np.empty(n)
        prev = rng.normal(0.0, nz.sd)
        for i in range(n):
            prev = nz.phi * prev + e[i]
            out[i] = prev
        return out
    raise ValueError(nz.kind)


def noisy(y: np.ndarray, nz: Noise, rng: np.random.Generator) -> np.ndarray:
    if nz.kind == "quant":
        yy = y + rng.normal(0.0, 0.5 * nz.sd, y.size)
        return nz.step * np.round(yy / nz.step)
    return y + noise(nz, y.size, rng)


def steady(runs: list[tuple[np.ndarray, np.ndarray, np.ndarray]], d: Design) -> np.ndarray:
    return np.stack([r[2][d.settle * d.samples :] for r in runs])


def size(p: Plant, plain: Plant, d: Design, sd: float) -> float:
    """RMS of the effect in the steady records over the averaged noise sd (sd / sqrt(periods))."""
    diff = steady(run(p, d), d) - steady(run(plain, d), d)
    return float(np.sqrt(np.mean(diff**2)) / (sd / math.sqrt(d.periods)))


def nonlinear_size(p: Plant, d: Design, sd: float) -> float:
    """RMS of the averaged periods' content beyond the fundamental, over the averaged noise sd."""
    tot = []
    for _, _, y in run(p, d):
        avg = y[d.settle * d.samples :].reshape(d.periods, d.samples).mean(axis=0)
        spec = np.fft.rfft(avg) / d.samples
        spec[:2] = 0.0
        tot.append(2.0 * np.sum(np.abs(spec) ** 2))
    return float(np.sqrt(np.mean(tot)) / (sd / math.sqrt(d.periods)))


def with_value(p: Plant, effect: str, v: float) -> Plant:
    if effect in ("play", "slack", "nu", "eta", "pinch", "rate"):
        return replace(p, hy=replace(p.hy, **{effect: v}))
    if effect == "dahl":
        return replace(p, dahl_fc=v, dahl_sigma=p.dahl_sigma)
    if effect == "iwan":
        return replace(p, iwan_level=v)
    return replace(p, **{effect: v})


def calibrate(p: Plant, effect: str, d: Design, sd: float, target: float, hi: float) -> tuple[float, float]:
    """The effect's value whose size is ``target`` (bisection in log value), and the size reached."""
    lo_v, hi_v = hi * 1e-4, hi
    plain = with_value(p, effect, 0.0)
    s_hi = size(with_value(p, effect, hi_v), plain, d, sd)
    if s_hi < target:
        return hi_v, s_hi
    v, s = hi_v, s_hi
    for _ in range(14):
        v = math.sqrt(lo_v * hi_v)
        s = size(with_value(p, effect, v), plain, d, sd)
        if abs(s / target - 1.0) < 0.04:
            break
        if s < target:
            lo_v = v
        else:
            hi_v = v
    return v, s


def recordings(p: Plant, d: Design, nz: Noise, seed: int, truth: Optional[dict[str, float]] = None) -> list:
    import bouc_wen_id as bw

    rng = np.random.default_rng([44, seed])
    out = []
    for i, (t, u, y) in enumerate(run(p, d)):
        out.append(
            bw.Recording(
                t,
                u,
                noisy(y, nz, rng),
                d.amps[i],
                d.omegas[i],
                settle_periods=d.settle,
                metadata={"name": f"e{i}_w{d.omegas[i]:g}_U{d.amps[i]:g}", "source": "review44/sim44.py"},
            )
        )
    return out

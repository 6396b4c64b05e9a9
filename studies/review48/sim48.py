"""An independent simulator for review 48: scipy's Radau (implicit Runge-Kutta, order 5) with tight
tolerances, its dense output resampled on the sample grid.

Nothing from bouc_wen_id but ``bw.Recording`` (in :func:`recordings`). It differs from reviews 44 (RK4),
45 (DOP853), 46 (VODE Adams) and 47 (implicit trapezoid, Newton) on purpose:

* the first-order system is integrated by **Radau IIA** (``scipy.integrate.solve_ivp``, rtol 1e-6,
  atol 1e-8, a step at most 1/8 period), and the states are read from its **dense output** at the samples;
  :func:`rk4_states` integrates the same right-hand side by a fixed-step RK4 (64 steps a sample) as the check;
* G comes from ``scipy.signal.tf2ss`` (so biproper G, a lead, has its direct feedthrough D), and may carry a
  **pure delay**: G's input is u(t - T), nothing moves before T;
* the input may carry a **third harmonic** (an actuator's distortion) and a **DC offset**;
* rate-independent operators outside the library are applied on the sample grid after the integration:
  Dahl friction on u with **exponent 0.5** (solved in closed form between reversals) and a **Preisach**
  operator of a few relays on x; Coulomb friction is an exact sign on the grid.

States: [G (n), z, e (dissipated energy), d (the element's travel), yl (sensor lag), z2 (a second element)].
``d' = xp' - rho z`` (xp: x through a play of half-width b; rho: a series dashpot), and
``z' = h(z, d') (alpha d' - nuf d' |z|^mu (beta sgn(d' z) + gamma + delta sgn z)) / etaf``,
beta and gamma times ``1 + drift t / t_end`` (a temperature drift over the record).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numba
import numpy as np
from scipy.integrate import solve_ivp
from scipy.signal import tf2ss

#: Parameters of the element's right-hand side (``par`` in this order) and their defaults.
PAR = dict(
    alpha=1.0, beta=0.5, gamma=0.5, mu=1.0, nu=0.0, eta=0.0, pinch=0.0, delta=0.0, rho=0.0, play=0.0,
    lag=0.0, drift=0.0, bw2=0.0, a2=1.0, b2=2.0, g2=-1.0, mu2=1.0, t_end=1.0, w_u=1.0,
)  # fmt: skip
KEYS = tuple(PAR)


@dataclass(frozen=True)
class Plant:
    """G(s) = num/den (highest power first), a pure delay on G's input, and the element's parameters."""

    num: tuple[float, ...]
    den: tuple[float, ...]
    delay: float = 0.0
    par: tuple[tuple[str, float], ...] = ()
    post: tuple[tuple[str, float], ...] = ()  # terms added on the grid: name -> value

    def get(self, name: str) -> float:
        return {**PAR, **dict(self.par)}[name]

    def at(self, w: float) -> complex:
        s = 1j * w
        return complex(np.polyval(self.num, s) / np.polyval(self.den, s) * np.exp(-s * self.delay))

    @property
    def w_u(self) -> float:
        return float((self.get("alpha") / (self.get("beta") + self.get("gamma"))) ** (1.0 / self.get("mu")))

    def with_(self, name: str, value: float) -> Plant:
        if name in PAR:
            return replace(self, par=tuple(sorted({**dict(self.par), name: value}.items())))
        return replace(self, post=tuple(sorted({**dict(self.post), name: value}.items())))


@dataclass(frozen=True)
class Design:
    """Per experiment: frequency, amplitude U, recorded and settling periods; samples a period (all)."""

    omegas: tuple[float, ...]
    amps: tuple[float, ...]
    periods: tuple[int, ...]
    settles: tuple[int, ...]
    samples: int
    h3: float = 0.0  # third harmonic in u, a fraction of U
    dc: float = 0.0  # DC offset in u, a fraction of U
    extra: dict[str, Any] = field(default_factory=dict)


@numba.njit(cache=True)
def _sgn(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@numba.njit(cache=True)
def _drive(t, amp, om, h3, dc, delay):  # noqa: PLR0913
    """G's input and its derivative at t (0 before the delay)."""
    tg = t - delay
    if tg < 0.0:
        return 0.0, 0.0
    u = amp * (math.cos(om * tg) + h3 * math.cos(3.0 * om * tg)) + amp * dc
    return u, -amp * om * (math.sin(om * tg) + 3.0 * h3 * math.sin(3.0 * om * tg))


@numba.njit(cache=True)
def rhs(t, s, a, b, c, dd, inp, par):  # noqa: PLR0913
    """inp = amp, om, h3, dc, delay; par in the order of :data:`KEYS`."""
    n = a.shape[0]
    out = np.zeros(s.size)
    ug, ugv = _drive(t, inp[0], inp[1], inp[2], inp[3], inp[4])
    xv = dd * ugv
    for i in range(n):
        acc = b[i] * ug
        for j in range(n):
            acc += a[i, j] * s[j]
        out[i] = acc
        xv += c[i] * acc
    x = dd * ug
    for i in range(n):
        x += c[i] * s[i]
    z, e, d = s[n], s[n + 1], s[n + 2]
    xpv = xv
    if par[9] > 0.0:  # play: the travel d follows x once the gap reaches b (d holds xp here)
        gap = x - d
        xpv = xv if gap * _sgn(xv) >= par[9] * (1.0 - 1e-9) else 0.0
    v = xpv - par[8] * z
    grow = 1.0 + par[11] * t / par[17]
    az = abs(z) ** par[3]
    shape = par[1] * grow * _sgn(v * z) + par[2] * grow + par[7] * _sgn(z)
    dz = par[0] * v - (1.0 + par[4] * e) * v * az * shape
    if par[6] > 0.0:  # Foliente: centre 0.1, width 0.2 of w_u
        q = (z * _sgn(v) - 0.1 * par[18]) / (0.2 * par[18])
        dz *= 1.0 - par[6] * math.exp(-q * q)
    out[n] = dz / (1.0 + par[5] * e)
    out[n + 1] = z * v
    out[n + 2] = 0.0 if par[9] == 0.0 else xpv  # the played x, kept only when there is a play
    if par[10] > 0.0:
        out[n + 3] = (z - s[n + 3]) / par[10]
    if par[12] != 0.0:
        z2 = s[n + 4]
        out[n + 4] = xv * (par[13] - abs(z2) ** par[16] * (par[14] * _sgn(xv * z2) + par[15]))
    return out


@numba.njit(cache=True)
def _rk4(s0, t0, tgrid, sub, a, b, c, dd, inp, par):  # noqa: PLR0913
    out = np.zeros((tgrid.size, s0.size))
    s = s0.copy()
    t = t0
    for k in range(tgrid.size):
        if tgrid[k] < t0:
            continue
        nstep = max(1, int(math.ceil((tgrid[k] - t) / (tgrid[1] - tgrid[0]) * sub - 1e-9)))
        h = (tgrid[k] - t) / nstep
        for _ in range(nstep if tgrid[k] > t else 0):
            k1 = rhs(t, s, a, b, c, dd, inp, par)
            k2 = rhs(t + 0.5 * h, s + 0.5 * h * k1, a, b, c, dd, inp, par)
            k3 = rhs(t + 0.5 * h, s + 0.5 * h * k2, a, b, c, dd, inp, par)
            k4 = rhs(t + h, s + h * k3, a, b, c, dd, inp, par)
            s = s + h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
            t += h
        out[k] = s
    return out


@numba.njit(cache=True)
def jac(t, s, a, b, c, dd, inp, par):  # noqa: PLR0913
    """Forward differences of :func:`rhs`, a fixed relative step (scipy's own adaptive step overflows on
    the states that a plant leaves unused)."""
    f0 = rhs(t, s, a, b, c, dd, inp, par)
    out = np.empty((s.size, s.size))
    for j in range(s.size):
        e = 1e-7 * max(1.0, abs(s[j]))
        sp = s.copy()
        sp[j] += e
        out[:, j] = (rhs(t, sp, a, b, c, dd, inp, par) - f0) / e
    return out


def _ss(p: Plant) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    a, b, c, d = tf2ss(p.num, p.den)
    return np.ascontiguousarray(a), np.ascontiguousarray(b[:, 0]), np.ascontiguousarray(c[0]), float(d[0, 0])


def grid(d: Design, i: int) -> np.ndarray:
    dt = 2.0 * math.pi / d.omegas[i] / d.samples
    return np.arange((d.settles[i] + d.periods[i]) * d.samples) * dt


def _args(p: Plant, d: Design, i: int) -> tuple[Any, ...]:
    a, b, c, dd = _ss(p)
    inp = np.array([d.amps[i], d.omegas[i], d.h3, d.dc, p.delay])
    t = grid(d, i)
    par = np.array([p.get(k) for k in KEYS])
    par[KEYS.index("t_end")] = t[-1]
    par[KEYS.index("w_u")] = p.w_u
    return a, b, c, dd, inp, par


def states(p: Plant, d: Design, i: int) -> np.ndarray:
    """Radau with dense output, resampled on the sample grid (rows: time; zero before the delay). A play
    (discontinuous in x') is left out here: :func:`output` runs the element along the played path."""
    a, b, c, dd, inp, par = _args(p, d, i)
    par[KEYS.index("play")] = 0.0
    t = grid(d, i)
    m = a.shape[0] + 5
    period = 2.0 * math.pi / d.omegas[i]
    sol = solve_ivp(
        lambda tt, ss: rhs(tt, ss, a, b, c, dd, inp, par),
        (p.delay, t[-1] + 1e-9),
        np.zeros(m),
        method="Radau",
        jac=lambda tt, ss: jac(tt, ss, a, b, c, dd, inp, par),
        rtol=1e-6,
        atol=1e-8,
        max_step=period / 8.0,
        dense_output=True,
    )
    if not sol.success:
        raise RuntimeError(sol.message)
    out = np.zeros((t.size, m))
    on = t >= p.delay
    out[on] = sol.sol(t[on]).T
    return out


def rk4_states(p: Plant, d: Design, i: int, sub: int = 64) -> np.ndarray:
    a, b, c, dd, inp, par = _args(p, d, i)
    return np.asarray(_rk4(np.zeros(a.shape[0] + 5), p.delay, grid(d, i), sub, a, b, c, dd, inp, par))


def dahl_half(u: np.ndarray, sigma: float, fc: float) -> np.ndarray:
    """Dahl friction of exponent 0.5 on a sampled u monotone between samples, in closed form:
    dF/du = sigma sqrt(1 - s F / Fc) (s = sgn du), so sqrt(1 - s F / Fc) falls linearly in |du| to 0."""
    out = np.zeros_like(u)
    f = 0.0
    for k in range(1, u.size):
        du = u[k] - u[k - 1]
        sg = 1.0 if du > 0 else -1.0
        r = math.sqrt(max(0.0, 1.0 - sg * f / fc)) - sigma * abs(du) / (2.0 * fc)
        f = sg * fc * (1.0 - max(r, 0.0) ** 2)
        out[k] = f
    return out


def preisach(x: np.ndarray, xm: float) -> np.ndarray:
    """Five relays on x (switch up at a_k, down at b_k < a_k, outputs +-1), weights 1, 0.8, ..., 0.2."""
    ups = np.array([0.1, 0.3, 0.5, 0.2, 0.6]) * xm
    downs = np.array([-0.1, 0.0, -0.4, -0.5, 0.2]) * xm
    wts = np.array([1.0, 0.8, 0.6, 0.4, 0.2])
    state = -np.ones(5)
    out = np.zeros_like(x)
    for k, xk in enumerate(x):
        state = np.where(xk >= ups, 1.0, np.where(xk <= downs, -1.0, state))
        out[k] = float(wts @ state)
    return out


@numba.njit(cache=True)
def path_element(xp, alpha, beta, gamma, mu, sub):  # noqa: PLR0913
    """z along the path of xp (rate independent): dz/dxp = alpha - |z|^mu (beta sgn(dxp z) + gamma), RK4 in
    xp, ``sub`` steps a sample (xp is monotone between samples, so the path's end values suffice)."""
    z = np.zeros(xp.size)
    for k in range(1, xp.size):
        h = (xp[k] - xp[k - 1]) / sub
        sg = 1.0 if h > 0.0 else -1.0
        w = z[k - 1]
        for _ in range(sub):
            k1 = alpha - abs(w) ** mu * (beta * _sgn(sg * w) + gamma)
            w2 = w + 0.5 * h * k1
            k2 = alpha - abs(w2) ** mu * (beta * _sgn(sg * w2) + gamma)
            w3 = w + 0.5 * h * k2
            k3 = alpha - abs(w3) ** mu * (beta * _sgn(sg * w3) + gamma)
            w4 = w + h * k3
            k4 = alpha - abs(w4) ** mu * (beta * _sgn(sg * w4) + gamma)
            w = w + h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
        z[k] = w
    return z


def play_op(x: np.ndarray, r: float) -> np.ndarray:
    """The play operator of half-width r on a sampled signal, starting at 0 (x from rest)."""
    out = np.empty_like(x)
    q = 0.0
    for k, xk in enumerate(x):
        q = min(max(q, xk - r), xk + r)
        out[k] = q
    return out


def output(p: Plant, d: Design, i: int, st: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t, u (as measured: with its distortion and offset from t = 0) and the noise-free y."""
    t = grid(d, i)
    a, b, c, dd = _ss(p)
    n = a.shape[0]
    amp, om = d.amps[i], d.omegas[i]

    def wave(tt: np.ndarray, k: int) -> np.ndarray:  # k-th derivative of u's wave: (m om)^k cos(. + k pi/2)
        ph = (om * tt)[:, None] * np.array([1.0, 3.0]) + k * math.pi / 2
        return amp * (np.cos(ph) @ (np.array([1.0, d.h3]) * (om * np.array([1.0, 3.0])) ** k))

    u, uv, ua = wave(t, 0) + amp * d.dc, wave(t, 1), wave(t, 2)
    tg, on = t - p.delay, t >= p.delay
    ug, ugv, uga = (on * (wave(tg, k) + (amp * d.dc if k == 0 else 0.0)) for k in range(3))
    sv = st[:, :n] @ a.T + np.outer(ug, b)
    x, xv = st[:, :n] @ c + dd * ug, sv @ c + dd * ugv
    xa = sv @ (a.T @ c) + float(c @ b) * ugv + dd * uga
    y = st[:, n + 3] if p.get("lag") > 0 else st[:, n].copy()
    if p.get("play") > 0 and not st[:, n + 2].any():  # Radau ran without the play: the element by its path
        g = [p.get(k) for k in ("alpha", "beta", "gamma", "mu")]
        y = path_element(play_op(x, p.get("play")), *g, 16)
    if p.get("bw2"):
        y = y + p.get("bw2") * st[:, n + 4]
    vec = {"stiffness": u, "viscous": uv, "inertia": ua, "offset": np.ones_like(t)}
    vec |= {"stiffness@x": x, "viscous@x": xv, "inertia@x": xa}
    vec |= {"coulomb": _sign(uv), "coulomb@x": _sign(xv)}
    for name, val in p.post:
        if name == "dahl_half":
            y = y + dahl_half(u, val, 0.05 * p.w_u)
        elif name == "preisach":
            y = y + val * preisach(x, float(np.max(np.abs(x))))
        else:
            y = y + val * vec[name]
    return t, u, y


def _sign(v: np.ndarray) -> np.ndarray:
    """sign(v), 0 within 1e-9 of max |v| (a sample on a reversal is 0, not a rounding error's +-1)."""
    return np.where(np.abs(v) > 1e-9 * float(np.max(np.abs(v))), np.sign(v), 0.0)


def simulate(p: Plant, d: Design, check: bool = False) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    return [output(p, d, i, (rk4_states if check else states)(p, d, i)) for i in range(len(d.omegas))]


def pink(n: int, rng: np.random.Generator) -> np.ndarray:
    """1/f noise by shaping white noise's spectrum (unit sd)."""
    spec = np.fft.rfft(rng.normal(size=n))
    f = np.arange(spec.size, dtype=float)
    f[0] = 1.0
    x = np.fft.irfft(spec / np.sqrt(f), n)
    return x / float(np.std(x))


def noise(
    kind: str, sd: float, t: np.ndarray, y: np.ndarray, adc: float, rng: np.random.Generator
) -> np.ndarray:
    """q10 / q12: an ADC of 10 / 12 bits over the range +-adc, after white noise sd (the driver: 0.3 LSB, 0);
    hum: white plus a 2 sd hum at 37.7 rad/s (not a harmonic); t3: Student-t with 3 dof scaled to sd; pink;
    white."""
    if kind in ("q10", "q12"):
        step = 2.0 * adc / 2 ** int(kind[1:])
        base = y + sd * rng.normal(size=t.size)  # sd: 0.3 LSB on q10, 0 on q12 (drive48.noise_sd)
        return step * np.round(np.clip(base, -adc, adc) / step)
    if kind == "hum":
        return y + sd * rng.normal(size=t.size) + 2.0 * sd * np.sin(37.7 * t + rng.uniform(0, 2 * np.pi))
    if kind == "t3":
        return y + sd * rng.standard_t(3, size=t.size) / math.sqrt(3.0)
    if kind == "pink":
        return y + sd * pink(t.size, rng)
    if kind == "white":
        return y + sd * rng.normal(size=t.size)
    raise ValueError(kind)


def recordings(
    runs: list[tuple[np.ndarray, ...]], d: Design, kind: str, sd: float, adc: float, seed: int
) -> list[Any]:
    import bouc_wen_id as bw

    recs: list[Any] = []
    for i, (t, u, y) in enumerate(runs):
        rng = np.random.default_rng([48, seed, i])
        name = f"x{i}_w{d.omegas[i]:g}_U{d.amps[i]:.3g}"
        meta = {"name": name, "source": "review48/sim48.py"}
        yn = noise(kind, sd, t, y, adc, rng)
        recs.append(
            bw.Recording(t, u, yn, d.amps[i], d.omegas[i], settle_periods=d.settles[i], metadata=meta)
        )
    return recs

"""An independent simulator for review 45: the whole cascade as ONE ODE, by scipy's ``solve_ivp``.

Nothing from bouc_wen_id but ``bw.Recording`` (in :func:`recordings`). Unlike review 44's sim44 (closed-form
G, RK4 in the travel), every state is integrated together by DOP853 (rtol 1e-9, atol 1e-12):

    u = U cos(w t) (t >= 0) -> pure delay d (closed form: the delayed input U cos(w (t - d)), zero before d)
      -> G(s) in state space (scipy.signal.tf2ss; or a pure gain) -> x
      -> [slack dead zone] -> [play: xp' = x' when engaged] -> Bouc-Wen z (alpha = 1) with Baber-Noori
         nu, eta (e' = z xp'), Foliente pinching (q = 0.1, zeta2 = 0.2 w_u), Song-Der Kiureghian asymmetry
         delta, a rate-dependent width (beta, gamma times 1 + a |xp'| / vref)
      -> [sensor lag: ym' = (z - ym) / tau]; in parallel a Dahl loop on x (own state) and a
         Prandtl-Ishlinskii loop on u (8 weighted play states on u).
    y = z (or ym) + k u + c u' + m u'' + f sgn(u') + the same on x + y0 + Dahl(x) + PI(u) + noise.

Coulomb is a true sign here (the library smooths it by tanh over 1 % of the peak speed).
Noise: Student-t (3 dof), pink (1/f, by FFT shaping), white plus a slow baseline wander, white plus rare
spikes (0.1 % of samples at +-20 sd); every draw from ``np.random.default_rng([45, seed, experiment])``.
:func:`rk4_check` integrates the same right-hand side by a fixed-step RK4 (a second method).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np
from scipy.integrate import solve_ivp
from scipy.signal import tf2ss

TWO_PI = 2.0 * math.pi
RTOL = 1e-9
ATOL = 1e-12
PI_RADII = tuple(0.05 * k for k in range(1, 9))  # PI loop on u: play radii, fractions of U_min


@dataclass(frozen=True)
class Linear:
    """G(s) = num/den e^{-delay s} (coefficients highest power first); ``num = den = ()`` for a pure gain."""

    num: tuple[float, ...]
    den: tuple[float, ...]
    delay: float = 0.0
    gain: float = 1.0  # used when den == ()
    label: str = ""

    def response(self, omega: float) -> complex:
        s = 1j * omega
        base = self.gain if not self.den else np.polyval(self.num, s) / np.polyval(self.den, s)
        return complex(base * np.exp(-s * self.delay))

    def ss(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if not self.den:
            return np.zeros((0, 0)), np.zeros(0), np.zeros(0)
        a, b, c, d = tf2ss(self.num, self.den)
        assert abs(float(d.ravel()[0])) < 1e-14, "G must be strictly proper"
        return np.ascontiguousarray(a), np.ascontiguousarray(b[:, 0]), np.ascontiguousarray(c[0])


def two_modes(w1: float, w2: float, zeta: float, share1: float, delay: float = 0.0) -> Linear:
    """Modal sum ``share1 w1^2/(s^2+2 zeta w1 s+w1^2) + (1-share1) w2^2/(...)``: DC gain 1."""
    d1 = np.array([1.0, 2 * zeta * w1, w1 * w1])
    d2 = np.array([1.0, 2 * zeta * w2, w2 * w2])
    num = np.polyadd(share1 * w1 * w1 * d2, (1 - share1) * w2 * w2 * d1)
    return Linear(tuple(num), tuple(np.polymul(d1, d2)), delay, label=f"modes {w1},{w2} z{zeta}")


def nmp(wn: float, zeta: float, zero: float) -> Linear:
    """wn^2 (1 - s/zero)/(s^2 + 2 zeta wn s + wn^2): a right-half-plane zero, DC gain 1."""
    return Linear((-wn * wn / zero, wn * wn), (1.0, 2 * zeta * wn, wn * wn), label=f"nmp wn{wn} zero+{zero}")


def first_order(tau: float, delay: float) -> Linear:
    return Linear((1.0 / tau,), (1.0, 1.0 / tau), delay, label=f"fo tau{tau} d{delay:.3f}")


def pure_gain(k: float, delay: float) -> Linear:
    return Linear((), (), delay, gain=k, label=f"gain {k} d{delay}")


@dataclass(frozen=True)
class Hyst:
    beta: float
    gamma: float
    mu: float
    delta: float = 0.0  # asymmetry
    play: float = 0.0
    slack: float = 0.0
    nu: float = 0.0
    eta: float = 0.0
    pinch: float = 0.0
    rate: float = 0.0
    vref: float = 1.0

    @property
    def w_u(self) -> float:
        return float((1.0 / (self.beta + self.gamma)) ** (1.0 / self.mu))


@dataclass(frozen=True)
class Plant:
    g: Linear
    hy: Hyst
    # parallel terms, each on u and on x (_x)
    stiffness: float = 0.0
    stiffness_x: float = 0.0
    viscous: float = 0.0
    viscous_x: float = 0.0
    coulomb: float = 0.0
    coulomb_x: float = 0.0
    inertia: float = 0.0
    inertia_x: float = 0.0
    offset: float = 0.0
    lag: float = 0.0  # sensor lag tau
    dahl_x: float = 0.0  # Dahl on x: level fc (sigma = dahl_x / dahl_x_travel)
    dahl_x_travel: float = 1.0
    pi_u: float = 0.0  # PI loop on u: its saturated level (8 stops of equal weight)


@dataclass(frozen=True)
class Design:
    omegas: tuple[float, ...]
    amps: tuple[float, ...]
    periods: tuple[int, ...]
    settle: int = 15
    samples: int = 200
    label: str = ""


@dataclass(frozen=True)
class Noise:
    kind: str  # t3 | pink | wander | spikes | white
    sd: float = 0.01


@numba.njit(cache=True)
def _rhs(t, s, a, b, c, gain, amp, om, delay, hp, fl, pir, piw):  # noqa: PLR0913
    """d/dt of [G states (n), z, e, xp, ym, F_dahl, pi states (8)].

    hp = beta, gamma, mu, delta, play, slack, nu, eta, pinch, rate, vref, wu, lag, dahl_fc, dahl_sigma;
    fl = flags (play on, lag on, dahl on, pi on)."""
    n = a.shape[0]
    out = np.zeros(s.size)
    on = t >= delay
    ud = amp * math.cos(om * (t - delay)) if on else 0.0
    if n > 0:
        for i in range(n):
            acc = b[i] * ud
            for j in range(n):
                acc += a[i, j] * s[j]
            out[i] = acc
        x = 0.0
        xd = 0.0
        for i in range(n):
            x += c[i] * s[i]
            xd += c[i] * out[i]
    else:
        x = gain * ud
        xd = -gain * amp * om * math.sin(om * (t - delay)) if on else 0.0
    beta, gamma, mu, delta = hp[0], hp[1], hp[2], hp[3]
    play, slack, dnu, deta, pinch, rate, vref, wu = hp[4], hp[5], hp[6], hp[7], hp[8], hp[9], hp[10], hp[11]
    z = s[n]
    e = s[n + 1]
    # slack dead zone
    if slack > 0.0:
        if abs(x) <= slack:
            xs = 0.0
            xsd = 0.0
        else:
            xs = x - math.copysign(slack, x)
            xsd = xd
    else:
        xs = x
        xsd = xd
    # play
    if fl[0]:
        dd = xs - s[n + 2]
        if (dd >= play and xsd > 0.0) or (dd <= -play and xsd < 0.0):
            v = xsd
        else:
            v = 0.0
        out[n + 2] = v
    else:
        v = xsd
    az = abs(z)
    pw = az**mu
    sz = 1.0 if z > 0.0 else (-1.0 if z < 0.0 else 0.0)
    nuf = 1.0 + dnu * e
    etaf = 1.0 + deta * e
    ratef = 1.0 + rate * abs(v) / vref
    r = v - nuf * ratef * (beta * abs(v) * pw * sz + gamma * v * pw + delta * v * pw * sz)
    if pinch > 0.0:
        sv = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
        q = (z * sv - 0.1 * wu) / (0.2 * wu)
        r *= 1.0 - pinch * math.exp(-q * q)
    out[n] = r / etaf
    out[n + 1] = z * v
    if fl[1]:
        out[n + 3] = (z - s[n + 3]) / hp[12]
    if fl[2]:
        sx = 1.0 if xd > 0.0 else (-1.0 if xd < 0.0 else 0.0)
        out[n + 4] = hp[14] * xd * (1.0 - sx * s[n + 4] / hp[13])
    if fl[3]:
        u = amp * math.cos(om * t)
        uv = -amp * om * math.sin(om * t)
        for k in range(pir.size):
            dk = u - s[n + 5 + k]
            if (dk >= pir[k] and uv > 0.0) or (dk <= -pir[k] and uv < 0.0):
                out[n + 5 + k] = uv
    return out


def _args(p: Plant, amp: float, om: float, umin: float) -> tuple[Any, ...]:
    a, b, c = p.g.ss()
    hy = p.hy
    hp = np.array(
        [
            hy.beta,
            hy.gamma,
            hy.mu,
            hy.delta,
            hy.play,
            hy.slack,
            hy.nu,
            hy.eta,
            hy.pinch,
            hy.rate,
            hy.vref,
            hy.w_u,
            max(p.lag, 1e-300),
            max(p.dahl_x, 1e-300),
            p.dahl_x / p.dahl_x_travel,
        ]
    )
    fl = np.array([hy.play > 0.0, p.lag > 0.0, p.dahl_x > 0.0, p.pi_u > 0.0])
    pir = np.array(PI_RADII) * umin
    return a, b, c, float(p.g.gain), float(amp), float(om), float(p.g.delay), hp, fl, pir, np.zeros(pir.size)


def _state0(p: Plant, amp: float, umin: float) -> np.ndarray:
    n = p.g.ss()[0].shape[0]
    s0 = np.zeros(n + 5 + len(PI_RADII))
    r = np.array(PI_RADII) * umin
    s0[n + 5 :] = np.clip(0.0, amp - r, amp + r)  # each PI play consistent with u(0) = U
    return s0


def states(p: Plant, d: Design, i: int, umin: float) -> tuple[np.ndarray, np.ndarray]:
    """t and the state trajectory (solve_ivp, DOP853) of experiment i, split at the delay's start."""
    om, amp = d.omegas[i], d.amps[i]
    n = (d.settle + d.periods[i]) * d.samples
    dt = TWO_PI / om / d.samples
    t = np.arange(n) * dt
    args = _args(p, amp, om, umin)
    s0 = _state0(p, amp, umin)
    cuts = [0.0] + ([p.g.delay] if p.g.delay > 0 else []) + [t[-1] + 0.5 * dt]
    out = np.empty((s0.size, n))
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        sel = (t >= lo) & (t < hi)
        te = np.append(t[sel], hi) if hi < t[-1] else t[sel]
        sol = solve_ivp(
            lambda tt, ss: _rhs(tt, ss, *args),
            (lo, hi),
            s0,
            method="DOP853",
            t_eval=te,
            rtol=RTOL,
            atol=ATOL,
            max_step=dt * 4,
        )
        if sol.status != 0:
            raise RuntimeError(sol.message)
        out[:, sel] = sol.y[:, : int(sel.sum())]
        s0 = np.asarray(sol.y[:, -1])
    return t, out


def output(p: Plant, d: Design, i: int, t: np.ndarray, st: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """u and the noise-free y of experiment i from its state trajectory."""
    om, amp = d.omegas[i], d.amps[i]
    a, b, c = p.g.ss()
    n = a.shape[0]
    u = amp * np.cos(om * t)
    uv = -amp * om * np.sin(om * t)
    ua = -amp * om * om * np.cos(om * t)
    tau = t - p.g.delay
    on = tau >= 0
    ud = np.where(on, amp * np.cos(om * tau), 0.0)
    udv = np.where(on, -amp * om * np.sin(om * tau), 0.0)
    uda = np.where(on, -amp * om * om * np.cos(om * tau), 0.0)
    if n:
        sd = a @ st[:n] + np.outer(b, ud)
        x, xv = c @ st[:n], c @ sd
        xa = c @ (a @ sd) + float(c @ b) * udv
    else:
        x, xv, xa = p.g.gain * ud, p.g.gain * udv, p.g.gain * uda
    y = st[n + 3].copy() if p.lag > 0 else st[n].copy()
    y += p.stiffness * u + p.viscous * uv + p.inertia * ua + p.coulomb * np.sign(uv)
    y += p.stiffness_x * x + p.viscous_x * xv + p.inertia_x * xa + p.coulomb_x * np.sign(xv)
    y += p.offset
    if p.dahl_x > 0:
        y += st[n + 4]
    if p.pi_u > 0:
        # each stop's force u - p_k saturates at its radius r_k: the sum saturates at pi_u
        y += p.pi_u * np.sum(u[None, :] - st[n + 5 :], axis=0) / (sum(PI_RADII) * umin_of(d))
    return u, y


def umin_of(d: Design) -> float:
    return float(min(d.amps))


def run(p: Plant, d: Design) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    res = []
    for i in range(len(d.omegas)):
        t, st = states(p, d, i, umin_of(d))
        u, y = output(p, d, i, t, st)
        res.append((t, u, y))
    return res


def steady(runs: list[tuple[np.ndarray, np.ndarray, np.ndarray]], d: Design) -> list[np.ndarray]:
    return [r[2][d.settle * d.samples :] for r in runs]


def size(
    runs: list[tuple[np.ndarray, ...]], plain: list[tuple[np.ndarray, ...]], d: Design, sd: float
) -> float:
    """RMS of (effect minus plain) over the steady samples / (sd / sqrt(N)), N the median periods."""
    diff = np.concatenate([a - b for a, b in zip(steady(runs, d), steady(plain, d))])
    return float(np.sqrt(np.mean(diff**2)) / (sd / math.sqrt(float(np.median(d.periods)))))


def noise(nz: Noise, n: int, dt: float, rng: np.random.Generator) -> np.ndarray:
    if nz.kind == "white":
        return rng.normal(0.0, nz.sd, n)
    if nz.kind == "t3":
        return nz.sd * rng.standard_t(3, n) / math.sqrt(3.0)
    if nz.kind == "pink":
        f = np.fft.rfftfreq(n, dt)
        spec = (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)) / np.sqrt(np.maximum(f, f[1]))
        spec[0] = 0.0
        e = np.fft.irfft(spec, n)
        return nz.sd * e / float(np.std(e))
    if nz.kind == "wander":
        # white sd plus a baseline of RMS sd: 3 sines of 0.2 to 1 cycle over the record, random phases
        tt = np.arange(n) * dt
        base = np.zeros(n)
        for _ in range(3):
            fr = rng.uniform(0.2, 1.0) / (n * dt) * 2 * math.pi
            base += math.sqrt(2.0 / 3.0) * np.sin(fr * tt + rng.uniform(0, 2 * math.pi))
        return rng.normal(0.0, nz.sd, n) + nz.sd * base
    if nz.kind == "spikes":
        e = rng.normal(0.0, nz.sd, n)
        k = rng.random(n) < 0.001
        e[k] += 20.0 * nz.sd * rng.choice([-1.0, 1.0], int(k.sum()))
        return e
    raise ValueError(nz.kind)


def recordings(runs: list[tuple[np.ndarray, ...]], d: Design, nz: Noise, seed: int) -> list[Any]:
    import bouc_wen_id as bw

    out = []
    for i, (t, u, y) in enumerate(runs):
        rng = np.random.default_rng([45, seed, i])
        out.append(
            bw.Recording(
                t,
                u,
                y + noise(nz, y.size, float(t[1] - t[0]), rng),
                d.amps[i],
                d.omegas[i],
                settle_periods=d.settle,
                metadata={"name": f"e{i}_w{d.omegas[i]:g}_U{d.amps[i]:.4g}", "source": "review45/sim45.py"},
            )
        )
    return out


@numba.njit(cache=True)
def _rk4(t_end, h, s0, a, b, c, gain, amp, om, delay, hp, fl, pir, piw, every):
    m = int(round(t_end / h))
    s = s0.copy()
    out = np.empty((s.size, m // every + 1))
    out[:, 0] = s
    for k in range(m):
        t = k * h
        k1 = _rhs(t, s, a, b, c, gain, amp, om, delay, hp, fl, pir, piw)
        k2 = _rhs(t + 0.5 * h, s + 0.5 * h * k1, a, b, c, gain, amp, om, delay, hp, fl, pir, piw)
        k3 = _rhs(t + 0.5 * h, s + 0.5 * h * k2, a, b, c, gain, amp, om, delay, hp, fl, pir, piw)
        k4 = _rhs(t + h, s + h * k3, a, b, c, gain, amp, om, delay, hp, fl, pir, piw)
        s = s + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (k + 1) % every == 0:
            out[:, (k + 1) // every] = s
    return out


def rk4_check(p: Plant, d: Design, i: int, sub: int = 64) -> float:
    """Max |y_solve_ivp - y_rk4| of experiment i, RK4 at ``sub`` steps per sample."""
    om = d.omegas[i]
    n = (d.settle + d.periods[i]) * d.samples
    dt = TWO_PI / om / d.samples
    t, st = states(p, d, i, umin_of(d))
    args = _args(p, d.amps[i], om, umin_of(d))
    st4 = _rk4((n - 1) * dt, dt / sub, _state0(p, d.amps[i], umin_of(d)), *args, sub)
    _, y1 = output(p, d, i, t, st)
    _, y2 = output(p, d, i, t, st4[:, :n])
    return float(np.max(np.abs(y1 - y2)))


def with_value(p: Plant, effect: str, v: float) -> Plant:
    if effect in ("play", "slack", "nu", "eta", "pinch", "rate", "delta"):
        return replace(p, hy=replace(p.hy, **{effect: v}))
    return replace(p, **{effect: v})


def latent(p: Plant, d: Design) -> np.ndarray:
    return np.array([abs(p.g.response(w)) * a for w, a in zip(d.omegas, d.amps)])

"""An independent generator of sine recordings for the diagnosis bench (issue 18, item 5).

Nothing here calls the library's simulator: the recordings are made ANOTHER way, so that a verdict that
holds on them does not only hold on the library's own integrator.

- **G** is integrated exactly: its state-space form (controllable canonical, built here) driven by a delayed
  cosine that starts from rest is solved in closed form, steady sinusoid plus the homogeneous transient
  ``V exp(Lambda t) V^-1`` (eigen-decomposition), so ``x``, ``xdot`` and ``xddot`` are exact on any grid.
- **The hysteresis** is integrated here by classical RK4 along its input's path: the exact ``x`` on a grid
  of half steps, the rate constant over each (sub-cycled where G's start from rest makes a large
  increment), so a rate-independent element is integrated exactly wherever x does not reverse inside a
  half step. Its own rate function: Bouc-Wen with asymmetry, Baber-Noori strength and stiffness
  degradation, pinching, a rate-dependent width; play and a mid-travel dead zone on the path; vectorised
  over experiments and trial parameter values.
- **The output** is ``y = y0 + Lag_tau[w + terms on u + terms on x + outside parallel elements]``, the lag
  solved exactly for a piecewise-linear input on the fine grid; **noise** is white Gaussian from a seeded
  stream of this module (1 % of the saturation level).

Plants vary per seed: G first order, resonant second order (zeta 0.1-0.5) with a delay (x lags u by up to
half a period at the highest frequency), or nearly flat over the band; five frequencies around the corner or
resonance; two saturating latent amplitudes. Null cases may add a low-amplitude experiment below saturation
whose loop centre is still settling after the settle periods.

Effects are sized as the RMS of their noise-free contribution over the averaged periods in units of the
averaged noise sd ``NOISE_SD / sqrt(PERIODS)``: exactly for effects linear in their parameter, by a
log-log interpolation over a vectorised sweep otherwise (the achieved size is returned).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

P = 128  # samples per period
PERIODS = 16  # averaged periods
SETTLE = 10  # settle periods (declared to the diagnosis as a user would)
SUBSTEPS = 3  # samples are split in SUBSTEPS steps of two RK4 half steps each
NOISE_SD = 0.01  # 1 % of the saturation level |w| -> 1
FREQ_FACTORS = (0.5, 0.75, 1.0, 1.4, 2.0)  # around the corner / resonance
X_LEVELS = (1.2, 3.0)  # latent amplitudes |x| (saturation at |w| = 1, alpha = 1)
LOW_LEVEL = 0.15  # the null cases' extra experiment, below saturation: its loop centre settles slowly
SHAPES = ("first", "resonant", "flat")

#: Mechanical terms (each at two places: on the measured input u, on the hysteresis' input x = G u).
MECHANICAL = ("stiffness", "viscous", "inertia", "coulomb")
PLACES = ("u", "x")
#: Effects in the library today (named as the registry spells them; place is that of the registry).
LIBRARY_OTHER = ("offset", "asymmetry", "play", "sensor_lag", "degradation")
#: Baber-Noori terms being added to the library (branch ``bn``): outside rows until they exist.
BABER_NOORI = ("stiffness_degradation", "pinching")
#: Spencer's MR-damper series dashpot: the element driven by its own travel, ``ddot = xdot - rho w`` (the
#: dashpot in series creeps at ``qdot = rho w`` under the element's force), integrated here in time with x's
#: mean rate over each half step (not the library's scheme).
SPENCER = ("series_dashpot",)
#: Physics outside the library: a rate-dependent loop width, a parallel Dahl loop, a mid-travel slack gap.
OUTSIDE = ("rate_width", "dahl", "slack_gap")
#: Outside physics appended after the others (their rows keep the earlier rows' seeds): a parallel Iwan
#: (Prandtl-Ishlinskii) loop on x, a weighted sum of elastic-perfectly-plastic elements with spread yield
#: travels: a piecewise-linear, kinked loop of another hysteresis family.
IWAN = ("iwan",)
#: The Iwan loop's yield travels (fractions of the plant's smallest latent level) and weights (sum 1).
IWAN_YIELDS = (0.08, 0.16, 0.3, 0.5, 0.8)
IWAN_WEIGHTS = (0.3, 0.25, 0.2, 0.15, 0.1)
#: Outside physics of the Dahl element's family, appended after the Iwan rows (issue 18: do not tune to one
#: generator): Dahl's own loop with his brittle exponent 2 on x (the library's element is exponent 1), and a
#: Prandtl-Ishlinskii operator on u with a continuous, uniform density of yield travels (PI_STOPS stops by
#: the midpoint rule, all updated at once in NumPy), a loop of spread stops made another way than the Iwan's.
FAMILY = ("dahl_n2", "pi_u")
#: The PI operator's yield travels: a uniform density over these fractions of the smallest input amplitude.
PI_RANGE = (0.05, 0.9)
PI_STOPS = 64
#: Dahl's exponent per generator effect: the library row's is the library's law (exponent 1), solved
#: exactly along each sample step (not the library's closed-form steady loop).
DAHL_EXPONENT = {"dahl": 1.0, "dahl_n2": 2.0}
#: Effects whose contribution is linear in their parameter (sized in one shot).
LINEAR = (*MECHANICAL, "offset", "dahl", "iwan", *FAMILY)
#: The Coulomb row's tanh smoothing, a fraction of the peak velocity: drawn per plant, log-uniform over this
#: range (real dry friction has no fixed width; a fixed 1 % only ever met the library's own width).
COULOMB_EPS_RANGE = (0.002, 0.05)
MAX_INCREMENT = 0.05  # largest path increment of one RK4 step of the hysteresis (x ~ 1)


@dataclass(frozen=True)
class Plant:
    """A seeded plant and its experiment plan (alpha = 1, beta + gamma = 1: |w| saturates at 1)."""

    shape: str
    num: FloatArray  # G numerator (highest power first), strictly proper
    den: FloatArray
    delay: float
    beta: float
    gamma: float
    mu: float
    omegas: FloatArray
    amplitudes: FloatArray  # U per experiment
    levels: FloatArray  # latent |x| per experiment
    seed: int
    #: Initial hysteretic state per experiment (None: from rest). A low-amplitude experiment run after a
    #: saturating one starts from its remanent w, so its loop centre is still settling.
    w0: Optional[FloatArray] = None

    def freqresp(self, om: FloatArray) -> NDArray[np.complex128]:
        s = 1j * np.asarray(om)
        return np.polyval(self.num, s) / np.polyval(self.den, s) * np.exp(-self.delay * s)


def make_plant(seed: int, shape: Optional[str] = None, low_amplitude: bool = False) -> Plant:
    """A seeded plant: G's shape (chosen by the seed unless given), its delay, the hysteresis, the plan."""
    rng = np.random.default_rng([seed, 18])
    shape = shape or SHAPES[int(rng.integers(len(SHAPES)))]
    k = float(rng.uniform(0.5, 2.0))
    if shape == "resonant":
        wn = TWO_PI * float(rng.uniform(1.0, 5.0))
        zeta = float(rng.uniform(0.1, 0.5))
        num, den, centre = np.array([k * wn * wn]), np.array([1.0, 2 * zeta * wn, wn * wn]), wn
    elif shape == "first":
        wc = TWO_PI * float(rng.uniform(1.0, 5.0))
        num, den, centre = np.array([k * wc]), np.array([1.0, wc]), wc
    else:  # near-flat: the corner 20x above the highest tested frequency
        centre = TWO_PI * float(rng.uniform(0.5, 3.0))
        wc = 20.0 * centre * max(FREQ_FACTORS)
        num, den = np.array([k * wc]), np.array([1.0, wc])
    omegas = centre * np.asarray(FREQ_FACTORS)
    g0 = np.polyval(num, 1j * omegas) / np.polyval(den, 1j * omegas)
    lag_g = float(-np.unwrap(np.angle(g0))[-1])
    # x lags u by up to half a period at the highest frequency (none for the near-flat G).
    room = max(math.pi - lag_g, 0.0) / float(omegas[-1])
    delay = 0.0 if shape == "flat" else float(rng.uniform(0.0, 1.0)) * room
    mu = float(rng.uniform(1.3, 2.5))
    ratio = float(rng.uniform(-0.3, 0.6))  # gamma / beta
    beta = 1.0 / (1.0 + ratio)
    om = np.repeat(omegas, len(X_LEVELS))
    levels = np.tile(np.asarray(X_LEVELS), len(omegas))
    w0 = np.zeros(om.size)
    if low_amplitude:
        om = np.append(om, omegas[len(omegas) // 2])
        levels = np.append(levels, LOW_LEVEL)
        w0 = np.append(w0, float(rng.choice([-1.0, 1.0])) * float(rng.uniform(0.2, 0.6)))
    plant = Plant(shape, num, den, delay, beta, ratio * beta, mu, om, levels, levels, seed)
    g = np.abs(plant.freqresp(om))
    return Plant(shape, num, den, delay, beta, ratio * beta, mu, om, levels / g, levels, seed, w0)


# ------------------------------------------------------------------------------------------------------
# G, exactly


def _state_space(num: FloatArray, den: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Controllable canonical (A, B, C) of a strictly proper ``num/den``."""
    a = den / den[0]
    n = a.size - 1
    b = np.zeros(n)
    c = np.zeros(n)
    nn = num / den[0]
    c[: nn.size] = nn[::-1]  # x = sum c_i s_i with s_i the i-th derivative of the canonical state
    amat = np.zeros((n, n))
    amat[:-1, 1:] = np.eye(n - 1)
    amat[-1, :] = -a[1:][::-1]
    b[-1] = 1.0
    return amat, b, c


def latent(p: Plant, t: FloatArray, i: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Exact ``x, xdot, xddot`` of experiment ``i`` at times ``t`` (u = U cos(omega t) from rest at 0)."""
    amat, b, c = _state_space(p.num, p.den)
    om, amp = float(p.omegas[i]), float(p.amplitudes[i])
    tau = np.asarray(t) - p.delay
    on = tau >= 0.0
    # Steady state of s' = A s + B U cos(om tau): s = Re[S e^{j om tau}], S = (j om I - A)^-1 B U.
    n = b.size
    big = np.linalg.solve(1j * om * np.eye(n) - amat, b * amp)
    ph = np.exp(1j * om * np.where(on, tau, 0.0))
    s_ss = np.real(big[:, None] * ph[None, :])
    # Homogeneous part from s(0) = 0 at tau = 0: exp(A tau) (0 - Re S).
    lam, vec = np.linalg.eig(amat)
    coef = np.linalg.solve(vec, -np.real(big).astype(np.complex128))
    s_h = np.real(vec @ (coef[:, None] * np.exp(lam[:, None] * np.where(on, tau, 0.0)[None, :])))
    s = np.where(on[None, :], s_ss + s_h, 0.0)
    ud = np.where(on, amp * np.cos(om * tau), 0.0)
    udd = np.where(on, -amp * om * np.sin(om * tau), 0.0)
    sd = amat @ s + b[:, None] * ud[None, :]
    sdd = amat @ sd + b[:, None] * udd[None, :]
    return c @ s, c @ sd, c @ sdd


# ------------------------------------------------------------------------------------------------------
# The hysteresis and the output, by RK4 in time


@dataclass
class Effect:
    """One concealed effect: its name, place and parameter values (one per trial, broadcast)."""

    name: Optional[str] = None
    place: str = ""
    values: FloatArray = field(default_factory=lambda: np.zeros(1))


def _grid(p: Plant, i: int, total: int) -> tuple[FloatArray, float]:
    """The half-step grid of experiment ``i``: 2 SUBSTEPS points per sample, and the sampling step."""
    dt = TWO_PI / float(p.omegas[i]) / P
    return np.arange(2 * SUBSTEPS * total + 1) * (dt / (2 * SUBSTEPS)), dt


def _play(x: FloatArray, b: FloatArray) -> FloatArray:
    """Play of half-width ``b`` (trials x experiments) along ``x`` (experiments x grid), from rest."""
    if _jit is not None:
        return _jit.play(np.ascontiguousarray(x), np.ascontiguousarray(b))
    xp = np.empty(b.shape + (x.shape[1],))
    cur = np.clip(np.zeros_like(b), x[None, :, 0] - b, x[None, :, 0] + b)
    for j in range(x.shape[1]):
        cur = np.clip(cur, x[None, :, j] - b, x[None, :, j] + b)
        xp[..., j] = cur
    return xp


#: Effects that change the hysteresis' own integration; the others add to its output or filter it, so their
#: runs reuse the plain hysteresis of the same plant (the same arrays, bit for bit).
IN_HYSTERESIS = (
    "play",
    "slack_gap",
    "asymmetry",
    "degradation",
    "stiffness_degradation",
    "pinching",
    "rate_width",
    "series_dashpot",
)


@dataclass
class Base:
    """What every run of one plant shares: the half-step grids, the exact latent path, the RK4 steps, and
    (once computed) the plain hysteresis ``w`` (1 x experiments x steps + 1)."""

    total: int
    grids: list[tuple[FloatArray, float]]
    x: FloatArray
    xd: FloatArray
    xdd: FloatArray
    h: FloatArray
    wf: Optional[FloatArray] = None


def base(p: Plant, total: Optional[int] = None) -> Base:
    """The grids and exact latent ``x, xdot, xddot`` of every experiment of ``p`` (shared by its runs)."""
    total = total or (SETTLE + PERIODS) * P
    grids = [_grid(p, i, total) for i in range(p.omegas.size)]
    lat = [latent(p, g, i) for i, (g, _) in enumerate(grids)]
    x = np.stack([v[0] for v in lat])
    xd = np.stack([v[1] for v in lat])
    xdd = np.stack([v[2] for v in lat])
    h = np.array([g[1] / SUBSTEPS for g in grids])  # RK4 step: two half-grid intervals
    return Base(total, grids, x, xd, xdd, h)


def run(p: Plant, eff: Effect, total: Optional[int] = None, shared: Optional[Base] = None) -> FloatArray:
    """Noise-free outputs (trials x experiments x samples) of the plant with ``eff`` at every trial value.

    ``shared``: the plant's :func:`base` (same ``total``), reused across runs instead of recomputed."""
    b = shared if shared is not None else base(p, total)
    if total is not None and total != b.total:
        raise ValueError(f"run: total {total} differs from the shared base's {b.total}")
    nv = eff.values.size
    ne = p.omegas.size
    val = eff.values[:, None] * np.ones((1, ne))
    name = eff.name
    if name in IN_HYSTERESIS or b.wf is None:
        wf = _hysteresis(p, name, val, b)
        if name not in IN_HYSTERESIS:
            b.wf = wf[:1]
    else:
        wf = np.broadcast_to(b.wf, (nv,) + b.wf.shape[1:])
    v = wf
    v = v + _parallel(p, eff, val, b.x[:, ::2], b.xd[:, ::2], b.xdd[:, ::2], b.grids)
    if name == "sensor_lag":
        v = _lag(v, val, b.h)
    if name == "offset":
        v = v + val[..., None]
    return np.ascontiguousarray(v[..., :-1:SUBSTEPS])


def _hysteresis(p: Plant, name: Optional[str], val: FloatArray, b: Base) -> FloatArray:
    """``w`` (trials x experiments x steps + 1) of the hysteresis with effect ``name`` at values ``val``."""
    nv, ne = val.shape
    x, h = b.x, b.h
    # Every hysteresis here is driven along its input's path: the mean rate over each half step, constant
    # there, so RK4 integrates w along x exactly wherever x does not reverse inside the half step (the
    # rate-dependent width sees that mean rate). Play drives it along the played path, the slack gap along
    # x with its mid-travel dead zone taken out.
    path = np.broadcast_to(x[None], (nv,) + x.shape)
    if name == "play":
        path = _play(x, val)
    if name == "slack_gap":  # a dead zone of half-width g at mid-travel: a loose joint's clearance
        path = x[None] - np.clip(x[None], -val[..., None], val[..., None])
    rate = np.diff(path, axis=-1) / (0.5 * h)[None, :, None]
    beta, gamma, mu = p.beta, p.gamma, p.mu
    zero = np.zeros_like(val)
    delta = val if name == "asymmetry" else zero
    dnu = val if name == "degradation" else zero
    deta = val if name == "stiffness_degradation" else zero
    zeta1 = val if name == "pinching" else zero
    rwidth = val if name == "rate_width" else zero
    rho = val if name == "series_dashpot" else zero
    vref = np.median(p.levels * p.omegas)
    w0 = np.zeros((nv, ne)) + (0.0 if p.w0 is None else p.w0[None, :])
    if _jit is not None:
        sw = np.stack([rwidth, dnu, delta, zeta1, deta, rho])
        return _jit.rk4(w0, np.ascontiguousarray(rate), h, SUBSTEPS * b.total, mu, beta, gamma, vref, sw)

    def f(w: FloatArray, e: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        d = d - rho * w  # the element's own travel rate behind a series dashpot (0 without one)
        aw = np.abs(w) ** (mu - 1.0)
        b_eff = beta * np.exp(rwidth * np.tanh(np.abs(d) / vref - 1.0))
        nu = 1.0 + dnu * e
        hyst = b_eff * np.abs(d) * aw * w + gamma * d * aw * np.abs(w) + delta * d * aw * w
        pinch = 1.0 - zeta1 * np.exp(-((((w * np.sign(d)) - 0.1) / 0.2) ** 2))
        return pinch * (d - nu * hyst) / (1.0 + deta * e), w * d

    return _rk4(f, w0, rate, h, SUBSTEPS * b.total)


def _rk4(
    f: Callable[[FloatArray, FloatArray, FloatArray], tuple[FloatArray, FloatArray]],
    w: FloatArray,
    rate: FloatArray,
    h: FloatArray,
    nstep: int,
) -> FloatArray:
    """Classical RK4 of (w, e) along the path, ``w`` at every step (trials x experiments x steps + 1).

    ``rate`` is the constant rate of each half step; a half step whose increment exceeds ``MAX_INCREMENT``
    (G's start from rest through a fast pole) is cut into equal parts, so RK4 stays in its stable range."""
    e = np.zeros_like(w)
    wf = np.empty(w.shape + (nstep + 1,))
    wf[..., 0] = w
    half = 0.5 * h[None, :]
    for k in range(2 * nstep):
        d = rate[..., k]
        parts = max(1, math.ceil(float(np.max(np.abs(d * half))) / MAX_INCREMENT))
        hh = half / parts
        for _ in range(parts):
            k1 = f(w, e, d)
            k2 = f(w + 0.5 * hh * k1[0], e + 0.5 * hh * k1[1], d)
            k3 = f(w + 0.5 * hh * k2[0], e + 0.5 * hh * k2[1], d)
            k4 = f(w + hh * k3[0], e + hh * k3[1], d)
            w = w + hh / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
            e = e + hh / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
        if k % 2 == 1:
            wf[..., (k + 1) // 2] = w
    return wf


def coulomb_width(seed: int) -> float:
    """The plant's Coulomb smoothing width (fraction of peak velocity), from its own stream of the seed."""
    lo, hi = COULOMB_EPS_RANGE
    rng = np.random.default_rng([seed, 41])
    return float(np.exp(rng.uniform(math.log(lo), math.log(hi))))


def _parallel(
    p: Plant,
    eff: Effect,
    val: FloatArray,
    x: FloatArray,
    xd: FloatArray,
    xdd: FloatArray,
    grids: list[tuple[FloatArray, float]],
) -> FloatArray:
    """Mechanical terms on u or on x, and the outside parallel Dahl loop (trials x experiments x grid)."""
    name = eff.name
    if name in MECHANICAL:
        if eff.place == "x":
            sig0, sig1, sig2 = x, xd, xdd
            vmax = (p.levels * p.omegas)[:, None]
        else:
            t = np.stack([g[0][::2] for g in grids])
            om, amp = p.omegas[:, None], p.amplitudes[:, None]
            sig0, sig1, sig2 = (
                amp * np.cos(om * t),
                -amp * om * np.sin(om * t),
                -amp * om * om * np.cos(om * t),
            )
            vmax = amp * om
        sig = {
            "stiffness": sig0,
            "viscous": sig1,
            "inertia": sig2,
            "coulomb": np.tanh(sig1 / (coulomb_width(p.seed) * vmax)),
        }[name]
        return val[..., None] * sig[None]
    if name in DAHL_EXPONENT:  # dF/dxi = sigma (1 - s F)^n along travel xi in direction s: exact per step
        sigma = 1.0 / (0.2 * float(p.levels.min()))
        n = DAHL_EXPONENT[name]
        if _jit is not None:
            return val[..., None] * _jit.dahl(np.ascontiguousarray(x), sigma, n)[None]
        fd = np.zeros(x.shape[0])
        out = np.zeros(x.shape)
        for j in range(1, x.shape[1]):
            dx = x[:, j] - x[:, j - 1]
            sgn = np.sign(dx)
            g0 = np.clip(1.0 - sgn * fd, 0.0, 2.0)
            g1 = g0 * np.exp(-sigma * np.abs(dx)) if n == 1.0 else g0 / (1.0 + sigma * np.abs(dx) * g0)
            fd = np.where(sgn != 0.0, sgn * (1.0 - g1), fd)
            out[:, j] = fd
        return val[..., None] * out[None]
    if name == "pi_u":  # a Prandtl-Ishlinskii operator on u: every stop clipped at once, exact per step
        t = np.stack([g[0][::2] for g in grids])
        u = p.amplitudes[:, None] * np.cos(p.omegas[:, None] * t)
        lo, hi = PI_RANGE
        yields = (lo + (hi - lo) * (np.arange(PI_STOPS) + 0.5) / PI_STOPS) * float(p.amplitudes.min())
        z = np.zeros((u.shape[0], PI_STOPS))
        out = np.zeros(u.shape)
        for j in range(1, u.shape[1]):
            z = np.clip(z + (u[:, j] - u[:, j - 1])[:, None] / yields[None, :], -1.0, 1.0)
            out[:, j] = z.mean(axis=1)
        return val[..., None] * out[None]
    if name == "iwan":  # stops z_k = clip(z_k + dx / r_k, -1, 1): exact along each monotone sample step
        yields = np.asarray(IWAN_YIELDS) * float(p.levels.min())
        weights = np.asarray(IWAN_WEIGHTS)
        if _jit is not None:
            return val[..., None] * _jit.iwan(np.ascontiguousarray(x), yields, weights)[None]
        return val[..., None] * _iwan_loop_numpy(x, yields, weights)[None]
    return np.zeros((1, 1, 1))


def _iwan_loop_numpy(x: FloatArray, yields: FloatArray, weights: FloatArray) -> FloatArray:
    """The Iwan loop of ``_parallel`` on every experiment at once (experiments x grid), from rest."""
    z = np.zeros((x.shape[0], yields.size))
    out = np.zeros(x.shape)
    for j in range(1, x.shape[1]):
        dx = x[:, j] - x[:, j - 1]
        z = np.clip(z + dx[:, None] / yields[None, :], -1.0, 1.0)
        out[:, j] = z @ weights
    return out


def _lag(v: FloatArray, tau: FloatArray, h: FloatArray) -> FloatArray:
    """``v`` seen through ``1/(tau s + 1)`` from rest, exact for a piecewise-linear ``v`` on the grid."""
    if _jit is not None:
        return _jit.lag(np.ascontiguousarray(v), np.ascontiguousarray(tau), h)
    hh = h[None, :]  # the full-step grid spacing
    tt = np.maximum(tau, 1e-300)
    a = np.exp(-hh / tt)
    out = np.empty_like(v)
    y = np.zeros(v.shape[:2])
    out[..., 0] = y
    for j in range(1, v.shape[2]):
        s = (v[..., j] - v[..., j - 1]) / hh
        y = v[..., j] - tt * s + a * (y - v[..., j - 1] + tt * s)
        out[..., j] = y
    return out


# ------------------------------------------------------------------------------------------------------
# Sizing and recordings


def _steady(y: FloatArray) -> FloatArray:
    return y[..., SETTLE * P :]


def contribution(p: Plant, eff: Effect, plain: FloatArray, shared: Optional[Base] = None) -> FloatArray:
    """RMS of each trial value's contribution over the averaged periods, in averaged-noise-sd units."""
    return _contribution(p, eff, plain, shared)[0]


def _contribution(
    p: Plant, eff: Effect, plain: FloatArray, shared: Optional[Base]
) -> tuple[FloatArray, FloatArray]:
    """:func:`contribution` and the run it measured (trials x experiments x samples)."""
    y = run(p, eff, shared=shared)
    size = np.sqrt(np.mean((_steady(y) - _steady(plain)) ** 2, axis=(1, 2))) / (NOISE_SD / math.sqrt(PERIODS))
    return size, y


def upper_value(p: Plant, name: str) -> float:
    """The largest value tried for a nonlinear effect (its physical range)."""
    return {
        "asymmetry": 0.9 * (p.beta + p.gamma),
        "play": 0.5 * float(p.levels.min()),
        "slack_gap": 0.5 * float(p.levels.min()),
        "sensor_lag": 0.5 / float(p.omegas.max()),
        "degradation": 0.05,
        "stiffness_degradation": 0.05,
        "pinching": 0.9,
        "rate_width": 0.5,
        # The creep rate: the force rolls off below the velocity rho w_u = rho (saturation at 1), about
        # |x| omega at the top of the band.
        "series_dashpot": 3.0 * float(np.max(p.levels * p.omegas)),
    }[name]


def calibrate(p: Plant, name: str, place: str, size: float) -> tuple[float, float]:
    """(value, achieved size) of effect ``name`` at ``place`` whose contribution is ``size`` noise sd."""
    value, got, _ = _calibrate(p, name, place, size, base(p))
    return value, got


def _calibrate(p: Plant, name: str, place: str, size: float, b: Base) -> tuple[float, float, FloatArray]:
    """:func:`calibrate` and the noise-free run at the value found (experiments x samples)."""
    plain = run(p, Effect(), shared=b)
    if name in LINEAR:
        unit = float(contribution(p, Effect(name, place, np.ones(1)), plain, b)[0])
        value = size / unit
        return value, size, run(p, Effect(name, place, np.array([value])), shared=b)[0]
    hi = upper_value(p, name)
    vals = hi * np.logspace(-3.0, 0.0, 7)
    c = contribution(p, Effect(name, place, vals), plain, b)
    ok = np.isfinite(c) & (c > 0)
    if not np.any(ok):
        raise FloatingPointError(f"{name}: no finite contribution over {vals}")
    lv, lc = np.log(vals[ok]), np.log(c[ok])
    order = np.argsort(lc)
    v = float(np.exp(np.interp(math.log(size), lc[order], lv[order])))
    cv, y = _contribution(p, Effect(name, place, np.array([v])), plain, b)
    got = float(cv[0])
    if got > 0:  # one secant correction in log-log
        slope = np.polyfit(lv, lc, 1)[0] if lv.size > 1 else 1.0
        v = min(hi, v * math.exp((math.log(size) - math.log(got)) / max(slope, 0.2)))
        cv, y = _contribution(p, Effect(name, place, np.array([v])), plain, b)
        got = float(cv[0])
    return v, got, y[0]  # the last run was at v: reused, not re-run


def recordings(
    p: Plant, y: FloatArray, seed: int, settle: int = SETTLE, noise_sd: float = NOISE_SD
) -> list[object]:
    """``bouc_wen_id.Recording`` objects of noisy outputs ``y`` (experiments x samples), as a user's files."""
    import bouc_wen_id as bw

    rng = np.random.default_rng([seed, 7])
    out: list[object] = []
    for i in range(p.omegas.size):
        n = y.shape[-1]
        dt = TWO_PI / float(p.omegas[i]) / P
        t = np.arange(n) * dt
        u = float(p.amplitudes[i]) * np.cos(float(p.omegas[i]) * t)
        yy = y[i] + rng.normal(0.0, noise_sd, n)
        out.append(
            bw.Recording(
                t,
                u,
                yy,
                float(p.amplitudes[i]),
                float(p.omegas[i]),
                settle_periods=settle,
                metadata={"name": f"exp{i}", "source": "benches/generator.py"},
            )
        )
    return out


#: RMS misfit of the best cascade (the plain model) to the feedback structure's averaged periods, in
#: averaged-noise sd at NOISE_SD: sqrt((chi2 - dof) / N) of the diagnosis' plain fit, median over seeds
#: 7000-7007 (4.3 to 5.9; benches/diagnosis.py's structure rows report the achieved size per case).
FEEDBACK_SIZE = 4.4


def feedback_outputs(p: Plant, total: Optional[int] = None) -> tuple[FloatArray, FloatArray]:
    """Outputs of the feedback structure ``m y'' + c y' + k y + z = u``, ``z`` Bouc-Wen of ``y`` (outside).

    Tuned to the plant's band: ``k + 1 = m omega_c^2`` at the band's centre, damping ratio 0.2; RK4 in time.
    """
    total = total or (SETTLE + PERIODS) * P
    centre = float(np.median(p.omegas))
    kk = 1.0
    m = (kk + 1.0) / centre**2
    c = 2 * 0.2 * math.sqrt((kk + 1.0) * m)
    om = p.omegas
    # Input amplitudes that give |y| near the plan's latent levels (equivalent linear z ~ y).
    amp = p.levels * np.abs(-m * om**2 + 1j * c * om + kk + 1.0)
    h = TWO_PI / om / P / SUBSTEPS
    st = np.zeros((3, om.size))  # y, y', z
    if _jit is not None:
        pw = np.array([p.mu, p.beta, p.gamma])
        return _jit.feedback(amp, om, h, total, m, c, kk, pw), amp
    out = np.zeros((om.size, total))

    def f(s: FloatArray, t: FloatArray) -> FloatArray:
        y, yd, z = s
        u = amp * np.cos(om * t)
        aw = np.abs(z) ** (p.mu - 1.0)
        zd = yd - p.beta * np.abs(yd) * aw * z - p.gamma * yd * aw * np.abs(z)
        return np.stack([yd, (u - c * yd - kk * y - z) / m, zd])

    for k in range(SUBSTEPS * total):
        t = k * h
        if k % SUBSTEPS == 0:
            out[:, k // SUBSTEPS] = st[0]
        k1 = f(st, t)
        k2 = f(st + 0.5 * h * k1, t + 0.5 * h)
        k3 = f(st + 0.5 * h * k2, t + 0.5 * h)
        k4 = f(st + h * k3, t + h)
        st = st + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return out, amp


@dataclass(frozen=True)
class Case:
    """One bench case: its recordings and what is hidden in them."""

    kind: str  # "library", "pending" (a term being added), "outside", "null"
    name: Optional[str]
    place: str
    size: float  # requested
    achieved: float
    value: float
    seed: int
    shape: str
    recordings: list[object]


def make_case(kind: str, name: Optional[str], place: str, size: float, seed: int) -> Case:
    """A seeded case: plant, effect sized to ``size`` averaged-noise sd, noisy recordings."""
    p = make_plant(seed, low_amplitude=kind == "null")
    if name == "feedback":
        y, amp = feedback_outputs(p)
        q = Plant(p.shape, p.num, p.den, 0.0, p.beta, p.gamma, p.mu, p.omegas, amp, p.levels, seed)
        # Sized by the noise: the cascade's misfit is FEEDBACK_SIZE averaged-noise sd at NOISE_SD (measured).
        sd = NOISE_SD * FEEDBACK_SIZE / size if size > 0 else NOISE_SD
        return Case(
            kind, name, "", size, math.nan, math.nan, seed, p.shape, recordings(q, y, seed, noise_sd=sd)
        )
    if name is None:
        return Case(kind, None, "", 0.0, 0.0, 0.0, seed, p.shape, recordings(p, run(p, Effect())[0], seed))
    value, got, y = _calibrate(p, name, place, size, base(p))
    return Case(kind, name, place, size, got, value, seed, p.shape, recordings(p, y, seed))


# ------------------------------------------------------------------------------------------------------
# The same loops compiled (numba, the ``bench`` extra), used when numba imports: one element at a time, the
# same arithmetic in the same order as the NumPy loops above (which stay the definition). Set the
# environment variable ``BENCH_GENERATOR_NUMBA=0`` (or ``use_numba(False)``) to run the NumPy loops.


def _f_scalar(
    w: float, e: float, d: float, mu: float, beta: float, gamma: float, vref: float, sw: FloatArray
) -> tuple[float, float]:
    """The rate function of ``_hysteresis`` for one element; ``sw`` = (rwidth, dnu, delta, zeta1, deta,
    rho)."""
    d = d - sw[5] * w  # the element's own travel rate behind a series dashpot (0 without one)
    aw = abs(w) ** (mu - 1.0)
    b_eff = beta * math.exp(sw[0] * math.tanh(abs(d) / vref - 1.0))
    nu = 1.0 + sw[1] * e
    hyst = b_eff * abs(d) * aw * w + gamma * d * aw * abs(w) + sw[2] * d * aw * w
    sd = 1.0 if d > 0.0 else (-1.0 if d < 0.0 else 0.0)
    q = ((w * sd) - 0.1) / 0.2
    pinch = 1.0 - sw[3] * math.exp(-(q * q))
    return pinch * (d - nu * hyst) / (1.0 + sw[4] * e), w * d


def _rk4_loop(
    w0: FloatArray,
    rate: FloatArray,
    h: FloatArray,
    nstep: int,
    mu: float,
    beta: float,
    gamma: float,
    vref: float,
    sw: FloatArray,
) -> FloatArray:
    """``_rk4`` of ``_hysteresis``'s rate function, element by element (``sw``: 6 x trials x experiments)."""
    nv, ne = w0.shape
    wf = np.empty((nv, ne, nstep + 1))
    w = w0.copy()
    e = np.zeros_like(w0)
    wf[:, :, 0] = w
    half = 0.5 * h
    for k in range(2 * nstep):
        big = 0.0
        for i in range(nv):
            for j in range(ne):
                big = max(big, abs(rate[i, j, k] * half[j]))
        parts = max(1, math.ceil(big / MAX_INCREMENT))
        for i in range(nv):
            for j in range(ne):
                d = rate[i, j, k]
                hh = half[j] / parts
                s = sw[:, i, j]
                wi, ei = w[i, j], e[i, j]
                for _ in range(parts):
                    k1w, k1e = _f_scalar(wi, ei, d, mu, beta, gamma, vref, s)
                    k2w, k2e = _f_scalar(
                        wi + 0.5 * hh * k1w, ei + 0.5 * hh * k1e, d, mu, beta, gamma, vref, s
                    )
                    k3w, k3e = _f_scalar(
                        wi + 0.5 * hh * k2w, ei + 0.5 * hh * k2e, d, mu, beta, gamma, vref, s
                    )
                    k4w, k4e = _f_scalar(wi + hh * k3w, ei + hh * k3e, d, mu, beta, gamma, vref, s)
                    wi = wi + hh / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w)
                    ei = ei + hh / 6.0 * (k1e + 2.0 * k2e + 2.0 * k3e + k4e)
                w[i, j], e[i, j] = wi, ei
                if k % 2 == 1:
                    wf[i, j, (k + 1) // 2] = wi
    return wf


def _play_loop(x: FloatArray, b: FloatArray) -> FloatArray:
    """``_play`` element by element."""
    nv, ne = b.shape
    xp = np.empty((nv, ne, x.shape[1]))
    for i in range(nv):
        for j in range(ne):
            cur = min(max(0.0, x[j, 0] - b[i, j]), x[j, 0] + b[i, j])
            for m in range(x.shape[1]):
                cur = min(max(cur, x[j, m] - b[i, j]), x[j, m] + b[i, j])
                xp[i, j, m] = cur
    return xp


def _lag_loop(v: FloatArray, tau: FloatArray, h: FloatArray) -> FloatArray:
    """``_lag`` element by element."""
    nv, ne, n = v.shape
    out = np.empty((nv, ne, n))
    for i in range(nv):
        for j in range(ne):
            hh = h[j]
            tt = max(tau[i, j], 1e-300)
            a = math.exp(-hh / tt)
            y = 0.0
            out[i, j, 0] = y
            for m in range(1, n):
                s = (v[i, j, m] - v[i, j, m - 1]) / hh
                y = v[i, j, m] - tt * s + a * (y - v[i, j, m - 1] + tt * s)
                out[i, j, m] = y
    return out


def _iwan_loop(x: FloatArray, yields: FloatArray, weights: FloatArray) -> FloatArray:
    """The Iwan loop of ``_parallel`` element by element (experiments x grid)."""
    out = np.zeros(x.shape)
    z = np.zeros(yields.size)
    for i in range(x.shape[0]):
        z[:] = 0.0
        for j in range(1, x.shape[1]):
            dx = x[i, j] - x[i, j - 1]
            acc = 0.0
            for k in range(yields.size):
                z[k] = min(max(z[k] + dx / yields[k], -1.0), 1.0)
                acc += z[k] * weights[k]
            out[i, j] = acc
    return out


def _dahl_loop(x: FloatArray, sigma: float, n: float) -> FloatArray:
    """The Dahl loop of ``_parallel`` element by element (experiments x grid), exponent ``n`` (1 or 2)."""
    out = np.zeros(x.shape)
    for i in range(x.shape[0]):
        fd = 0.0
        for j in range(1, x.shape[1]):
            dx = x[i, j] - x[i, j - 1]
            sgn = 1.0 if dx > 0.0 else (-1.0 if dx < 0.0 else 0.0)
            g0 = min(max(1.0 - sgn * fd, 0.0), 2.0)
            g1 = g0 * math.exp(-sigma * abs(dx)) if n == 1.0 else g0 / (1.0 + sigma * abs(dx) * g0)
            if sgn != 0.0:
                fd = sgn * (1.0 - g1)
            out[i, j] = fd
    return out


def _feedback_loop(
    amp: FloatArray, om: FloatArray, h: FloatArray, total: int, m: float, c: float, kk: float, pw: FloatArray
) -> FloatArray:
    """``feedback_outputs``' RK4 element by element; ``pw`` = (mu, beta, gamma)."""
    ne = om.size
    out = np.zeros((ne, total))
    for j in range(ne):
        st = np.zeros(3)
        ks = np.zeros((4, 3))
        for k in range(SUBSTEPS * total):
            t = k * h[j]
            if k % SUBSTEPS == 0:
                out[j, k // SUBSTEPS] = st[0]
            for q in range(4):
                frac = (0.0, 0.5, 0.5, 1.0)[q]
                tq = t if q == 0 else (t + 0.5 * h[j] if q < 3 else t + h[j])
                y = st[0] + frac * h[j] * ks[q - 1, 0] if q > 0 else st[0]
                yd = st[1] + frac * h[j] * ks[q - 1, 1] if q > 0 else st[1]
                z = st[2] + frac * h[j] * ks[q - 1, 2] if q > 0 else st[2]
                u = amp[j] * math.cos(om[j] * tq)
                aw = abs(z) ** (pw[0] - 1.0)
                ks[q, 0] = yd
                ks[q, 1] = (u - c * yd - kk * y - z) / m
                ks[q, 2] = yd - pw[1] * abs(yd) * aw * z - pw[2] * yd * aw * abs(z)
            for r in range(3):
                st[r] = st[r] + h[j] / 6.0 * (ks[0, r] + 2 * ks[1, r] + 2 * ks[2, r] + ks[3, r])
    return out


class _Jit:
    """The compiled loops (numba.njit of the ``_*_loop`` functions above), built once per process."""

    def __init__(self, numba: Any) -> None:
        global _f_scalar
        njit = numba.njit(cache=True)
        _f_scalar = njit(_f_scalar)  # the loops call it by its global name: compiled calls compiled
        self.rk4 = njit(_rk4_loop)
        self.play = njit(_play_loop)
        self.lag = njit(_lag_loop)
        self.dahl = njit(_dahl_loop)
        self.iwan = njit(_iwan_loop)
        self.feedback = njit(_feedback_loop)


def use_numba(on: bool) -> bool:
    """Run the compiled loops (``on`` and numba imports) or the NumPy ones; returns whether compiled."""
    global _jit, _compiled
    _jit = None
    if on:
        try:
            import numba
        except ImportError:
            return False
        _compiled = _compiled or _Jit(numba)
        _jit = _compiled
    return _jit is not None


_compiled: Optional[_Jit] = None
_jit: Optional[_Jit] = None
use_numba(os.environ.get("BENCH_GENERATOR_NUMBA", "1") != "0")


# ------------------------------------------------------------------------------------------------------
# A cache of generated cases (benches/diagnosis.py --cache DIR): an npz of the recordings' arrays and a json
# of the case's metadata, keyed by (kind, name, place, size, seed, generator version).


def version() -> str:
    """This generator's version: a hash of this file's text, and which loops run (compiled or NumPy)."""
    text = Path(__file__).read_bytes()
    return hashlib.sha256(text).hexdigest()[:16] + ("-numba" if _jit is not None else "-numpy")


def cached_case(
    kind: str, name: Optional[str], place: str, size: float, seed: int, cache: Optional[Path]
) -> Case:
    """:func:`make_case`, read from ``cache`` when this generator version already made it, else made and
    stored there (a damaged or foreign entry is made again and overwritten); no cache (None): made."""
    if cache is None:
        return make_case(kind, name, place, size, seed)
    key = json.dumps([kind, name, place, float(size), int(seed), version()])
    stem = cache / hashlib.sha256(key.encode()).hexdigest()[:24]
    npz, meta = stem.with_suffix(".npz"), stem.with_suffix(".json")
    if npz.exists() and meta.exists():
        try:
            return _load_case(npz, meta, key)
        except (OSError, ValueError, KeyError, TypeError):
            pass
    case = make_case(kind, name, place, size, seed)
    cache.mkdir(parents=True, exist_ok=True)
    recs: list[Any] = case.recordings
    arrays = {f"{a}{i}": np.asarray(getattr(r, a)) for i, r in enumerate(recs) for a in ("t", "u", "y")}
    info = {
        "key": key,
        "case": [
            case.kind,
            case.name,
            case.place,
            case.size,
            case.achieved,
            case.value,
            case.seed,
            case.shape,
        ],
        "recordings": [[r.amplitude, r.frequency, r.settle_periods, dict(r.metadata)] for r in recs],
    }
    # Written under temporary names, then renamed: a reader never sees half a file.
    with open(f"{npz}.tmp", "wb") as fh:
        np.savez(fh, **arrays)
    Path(f"{meta}.tmp").write_text(json.dumps(info))
    os.replace(f"{npz}.tmp", npz)
    os.replace(f"{meta}.tmp", meta)
    return case


def _load_case(npz: Path, meta: Path, key: str) -> Case:
    import bouc_wen_id as bw

    info = json.loads(meta.read_text())
    if info["key"] != key:
        raise KeyError(f"{meta}: stored for {info['key']}, not {key}")
    with np.load(npz) as z:
        recs: list[object] = [
            bw.Recording(z[f"t{i}"], z[f"u{i}"], z[f"y{i}"], amp, freq, settle_periods=settle, metadata=md)
            for i, (amp, freq, settle, md) in enumerate(info["recordings"])
        ]
    kind, name, place, size, achieved, value, seed, shape = info["case"]
    return Case(kind, name, place, size, achieved, value, seed, shape, recs)

"""A blind test of `bw.diagnose`: a third generator, made from the public documents only.

The project's other generators (benches/generator.py, concealed.py, diagnosis_designs.py) were not read to
make this one. It was written from README.md, docs/diagnosis.md's term table, issue 18 and the seed paper,
as a new user would, and it differs from them on purpose:

* **G** is a state-space realisation with its own states, split into its modes, each stepped exactly
  for an input linear between grid points (first-order hold, two points per sample), from rest under a
  raised-cosine start of the sine: a two-mass structure (two modes,
  force on mass 2, displacement of mass 1), a first-order lag behind a pure delay (the state trajectory
  read back through a delay buffer, its dense output at t - T), and a lightly damped resonance (x lagging u
  by up to about half a period near the top of the band). No steady state is computed: the record starts
  after enough settling periods for the slowest mode to decay by e^-12.
* **The Bouc-Wen element** (2a) is integrated along its input's *path*, not in time: between two grid
  points the element sees the increment of x (through a play operator when there is one), and RK4 steps
  dw/dx along that increment (rate independent by construction); strength degradation and the dissipated
  energy e = int w dx ride along. mu in [1, 3], gamma/beta across (-0.9, 0.9), alpha in [0.5, 3].
* **Designs**: 3 frequencies x 3 stroke levels (recordings); 6 frequencies at one level plus one of them
  again at a second (recordings); 4 frequencies x 2 levels at ONE fixed sample rate, so that no period
  holds a whole number of samples (measurements: the public API refuses such a record as a `Recording`,
  which is reported). Each lab writes CSV files in the README's format and reads them with `bw.load`.
  `--design` runs every case on other designs instead (NEW_DESIGNS: one frequency at 5 amplitudes, two far
  frequencies, 4-6 periods after a short settle, unequal periods with one experiment below saturation, a
  first-order G without resonance, an actuator that clips the highest amplitude), written from the docs too.
* **Noise**: white at 0.5-2 % of the output RMS, AR(1), a coarse ADC (steps of one noise sd), or a slow
  linear drift of the output zero (1 noise sd over the record).
* **Effects** sized at 10x and 30x the averaged noise sd (RMS over the recorded periods of the noise-free
  output with minus without the effect), the library's terms and three of our own outside it: a Stribeck
  friction curve on u, a backlash (play) on the measured output, a Prandtl-Ishlinskii loop on x.

Scored by the public result only (status, named terms, alternatives, and for two outside effects the
verdict's words: a verdict naming only the term whose caveat names the truth as an equivalent that the
design cannot separate, with that caveat, is "family", as benches/diagnosis.py scores the Dahl element's
family caveat; see FAMILY). Run:

    python benches/blind.py --quick                        # <= 2 min
    python benches/blind.py --cases 6 --null 20 --outside 6 --workers 2 --json blind.json
    python benches/blind.py --replay viscous@x:10:3        # one case again, with its summary
    python benches/blind.py --design amp_sweep,clipped --cases 1 --null 6 --outside 2 --workers 2
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import importlib
import json
import math
import os
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

Array = NDArray[np.float64]
GENERATOR_VERSION = 2

#: The library's terms, as this bench hides them, with the code name `diagnose` should report.
LIBRARY = (
    "stiffness", "stiffness@x", "viscous", "viscous@x", "inertia", "inertia@x", "coulomb", "coulomb@x",
    "offset", "asymmetry", "play", "sensor_lag", "degradation",
)  # fmt: skip
#: Physics outside the library (docs/diagnosis.md lists neither): the honest verdict is "unexplained".
OUTSIDE = ("stribeck", "output_backlash", "prandtl_ishlinskii")
PLANTS = ("two_dof", "lag_delay", "resonance")
DESIGNS = ("grid3x3", "six_plus_one", "fixed_rate")
#: Other experiment designs a user records (--design; never drawn, so the default run is unchanged):
#: amp_sweep     5 amplitudes at ONE frequency (a term on u and on x cannot be told apart there);
#: two_far       two frequencies far apart (the ends of G's band), two levels each;
#: few_periods   the 3 x 3 grid with 4-6 recorded periods after a short settle (4 periods, the ramp's 3
#:               included): the slowest mode of G may not have decayed;
#: unequal       3 frequencies x 2 levels with 8-50 periods each, plus one experiment below saturation;
#: first_order   the 3 x 3 grid on a first-order G with no delay and omega tau <= 0.3 (x within 17 degrees
#:               of u, no resonance), whatever plant the seed drew;
#: clipped       the 3 x 3 grid written as lab measurements (u with its own small noise), the highest
#:               level's actuator clipping a little (flat tops at 95-98 % of its amplitude): the
#:               measured u is what drives G.
NEW_DESIGNS = ("amp_sweep", "two_far", "few_periods", "unequal", "first_order", "clipped")
NOISES = ("white", "ar1", "adc", "drift")
RECORD_PERIODS = 30
#: Settling before the record: the slowest mode of G decays by e^-SETTLE_DECAY (20 periods at least).
SETTLE_DECAY = 12.0
#: The slow drift of the output zero: this many noise sd from the first recorded sample to the last.
DRIFT = 1.0
#: Sharpness of the dry friction this bench hides: sign(v) smoothed over 0.5 % of the peak velocity
#: (sharper than the library's default 1 %: a real contact does not know the library's smoothing).
FRICTION_EPS = 0.005


# --------------------------------------------------------------------------------------------- linear G
@dataclass(frozen=True)
class Linear:
    """x = G u with G(s) = c (sI - a)^-1 b e^{-s delay}, strictly proper, its own states."""

    kind: str
    a: Array
    b: Array
    c: Array
    delay: float
    band: tuple[float, float]
    slowest: float  # the slowest decay rate of its modes (1/s), for the settling time
    info: dict[str, float] = field(default_factory=dict)

    def response(self, omega: float) -> complex:
        n = self.a.shape[0]
        h = self.c @ np.linalg.solve(1j * omega * np.eye(n) - self.a, self.b)
        return complex(h) * complex(np.exp(-1j * omega * self.delay))


def two_dof(rng: np.random.Generator) -> Linear:
    """Two masses on springs, Rayleigh damping; the force on mass 2, the displacement of mass 1."""
    m1, m2 = 1.0, float(rng.uniform(0.3, 1.0))
    w0 = float(rng.uniform(2.0, 8.0))
    k1 = w0**2
    k2 = k1 * float(rng.uniform(0.5, 1.5))
    mm = np.diag([m1, m2])
    kk = np.array([[k1 + k2, -k2], [-k2, k2]])
    lam, _ = np.linalg.eig(np.linalg.solve(mm, kk))
    wn = np.sqrt(np.sort(lam.real))
    z1, z2 = float(rng.uniform(0.04, 0.08)), float(rng.uniform(0.04, 0.08))
    # Rayleigh c = a0 M + a1 K with the two modal damping ratios chosen
    coef = np.linalg.solve(np.array([[1 / (2 * wn[0]), wn[0] / 2], [1 / (2 * wn[1]), wn[1] / 2]]), [z1, z2])
    cc = coef[0] * mm + coef[1] * kk
    minv = np.linalg.inv(mm)
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ kk, -minv @ cc]])
    b = np.concatenate([np.zeros(2), minv @ np.array([0.0, 1.0])])
    c0 = np.array([1.0, 0.0, 0.0, 0.0])
    dc = float(c0 @ np.linalg.solve(-a, b))
    info = {"m2": m2, "k1": k1, "k2": k2, "a0": float(coef[0]), "a1": float(coef[1]), "dc": dc}
    slow = float(min(z1 * wn[0], z2 * wn[1]))
    return Linear("two_dof", a, b, c0 / dc, 0.0, (0.5 * wn[0], 0.85 * wn[1]), slow, info)


def lag_delay(rng: np.random.Generator) -> Linear:
    """1/(tau s + 1) behind a pure delay T (phase at the top of the band about 150-175 degrees)."""
    tau = float(rng.uniform(0.05, 0.3))
    delay = tau * float(rng.uniform(0.35, 0.6))
    a, b, c = np.array([[-1 / tau]]), np.array([1 / tau]), np.array([1.0])
    return Linear("lag_delay", a, b, c, delay, (0.3 / tau, 3.0 / tau), 1 / tau, {"tau": tau})


def resonance(rng: np.random.Generator) -> Linear:
    """wn^2/(s^2 + 2 zeta wn s + wn^2), lightly damped, a small delay; the band crosses the resonance."""
    wn, zeta = float(rng.uniform(3.0, 15.0)), float(rng.uniform(0.05, 0.12))
    delay = float(rng.uniform(0.0, 0.2)) / wn
    a = np.array([[0.0, 1.0], [-(wn**2), -2 * zeta * wn]])
    b, c = np.array([0.0, wn**2]), np.array([1.0, 0.0])
    return Linear("resonance", a, b, c, delay, (0.4 * wn, 1.6 * wn), zeta * wn, {"wn": wn, "zeta": zeta})


def first_order(rng: np.random.Generator) -> Linear:
    """1/(tau s + 1) with no delay, tested well below its corner (omega tau in 0.03-0.3): x nearly in phase
    with u, |G| flat to 4 %: no resonance, nothing that tells a term on x from one on u but the small lag."""
    tau = float(rng.uniform(0.05, 0.3))
    a, b, c = np.array([[-1 / tau]]), np.array([1 / tau]), np.array([1.0])
    return Linear("first_order", a, b, c, 0.0, (0.03 / tau, 0.3 / tau), 1 / tau, {"tau": tau})


LINEAR = {"two_dof": two_dof, "lag_delay": lag_delay, "resonance": resonance, "first_order": first_order}


# ------------------------------------------------------------------------------------- plant and design
@dataclass(frozen=True)
class Hysteresis:
    alpha: float
    beta: float
    gamma: float
    mu: float

    @property
    def saturation(self) -> float:
        """w on a saturated loading branch: alpha = (beta + gamma) w^mu."""
        return float((self.alpha / (self.beta + self.gamma)) ** (1 / self.mu))


def draw_hysteresis(rng: np.random.Generator) -> Hysteresis:
    mu = float(rng.uniform(1.0, 3.0))
    ratio = float(rng.uniform(-0.9, 0.9))  # gamma / beta, inside the admissible beta > |gamma|
    alpha = float(rng.uniform(0.5, 3.0))
    wu = float(rng.uniform(0.5, 2.0))  # the saturation level chosen, beta from it
    beta = alpha / wu**mu / (1 + ratio)
    return Hysteresis(alpha, beta, ratio * beta, mu)


@dataclass(frozen=True)
class Experiment:
    omega: float
    amplitude: float
    dt: float  # sample interval
    settle: int  # samples simulated before the record
    n: int  # samples recorded
    recording: bool  # a whole number of samples per period (Recording) or a lab measurement
    periods: int = RECORD_PERIODS  # periods recorded (after the settle)
    clip: float = 0.0  # the actuator's limit as a fraction of the amplitude (0: no clipping)


def design(kind: str, g: Linear, hy: Hysteresis, rng: np.random.Generator) -> list[Experiment]:
    """The experiments: frequencies across G's band, each amplitude set for a stroke of x (the lab's
    displacement level, `level` times the element's yield displacement w_u / alpha)."""
    lo, hi = g.band
    jit = rng.uniform(0.97, 1.03, 8)
    xy = hy.saturation / hy.alpha
    periods = [RECORD_PERIODS] * 12
    clip: dict[int, float] = {}
    short_settle = False
    if kind in ("first_order", "clipped", "few_periods"):
        pairs = [(f, lv) for f in np.geomspace(lo, hi, 3) * jit[:3] for lv in (1.3, 2.2, 4.0)]
        if kind == "few_periods":
            periods = [int(rng.integers(4, 7))] * 9
            short_settle = True
        if kind == "clipped":
            level = float(rng.uniform(0.95, 0.98))
            clip = {i: level for i in (2, 5, 8)}  # every frequency's highest level
    elif kind == "amp_sweep":
        f0 = math.sqrt(lo * hi) * float(jit[0])
        pairs = [(f0, lv) for lv in (1.3, 1.8, 2.5, 3.5, 5.0)]
    elif kind == "two_far":
        pairs = [(f, lv) for f in (lo * jit[0], hi * jit[1]) for lv in (1.5, 3.5)]
    elif kind == "unequal":
        fr = np.geomspace(lo, hi, 3) * jit[:3]
        pairs = [(f, lv) for f in fr for lv in (1.5, 3.5)] + [(fr[1], 0.6)]  # 0.6: below saturation
        periods = [int(p) for p in rng.choice([8, 12, 20, 30, 50], len(pairs))]
    elif kind == "grid3x3":
        pairs = [(f, lv) for f in np.geomspace(lo, hi, 3) * jit[:3] for lv in (1.3, 2.2, 4.0)]
    elif kind == "six_plus_one":
        fr = np.geomspace(lo, hi, 6) * jit[:6]
        pairs = [(f, 2.5) for f in fr] + [(fr[2], 1.4)]
    elif kind == "fixed_rate":
        pairs = [(f, lv) for f in np.geomspace(lo, hi, 4) * jit[:4] for lv in (1.5, 3.5)]
    else:
        raise ValueError(f"unknown design {kind!r}")
    p_rec = int(rng.choice([160, 200, 240]))
    fs = float(rng.uniform(96.0, 104.0)) * hi * 1.03 / (2 * math.pi)  # ~100 samples at the top frequency
    out = []
    for i, (omega, level) in enumerate(pairs):
        period = 2 * math.pi / float(omega)
        settle_t = max(20 * period, SETTLE_DECAY / g.slowest) + g.delay
        if short_settle:
            settle_t = 4 * period + g.delay
        amp = float(level * xy / abs(g.response(float(omega))))
        if kind == "fixed_rate":
            dt = 1.0 / fs
            out.append(
                Experiment(
                    float(omega), amp, dt, int(settle_t / dt), int(RECORD_PERIODS * period / dt), False
                )
            )
        else:
            dt = period / p_rec
            k = math.ceil(settle_t / period)
            np_ = periods[i]
            out.append(
                Experiment(
                    float(omega), amp, dt, k * p_rec, np_ * p_rec, kind != "clipped", np_, clip.get(i, 0.0)
                )
            )
    return out


# ------------------------------------------------------------------------------------------ simulation
RAMP_PERIODS = 3.0


def drive(e: Experiment, t: Array) -> tuple[Array, Array, Array]:
    """u, du/dt, d2u/dt2 of the raised-cosine start of U cos(omega t) (analytic)."""
    tr = RAMP_PERIODS * 2 * math.pi / e.omega
    q = np.clip(t / tr, 0.0, 1.0)
    on = (t > 0) & (t < tr)
    env = np.where(t <= 0, 0.0, 0.5 * (1 - np.cos(math.pi * q)))
    d1 = np.where(on, 0.5 * math.pi / tr * np.sin(math.pi * q), 0.0)
    d2 = np.where(on, 0.5 * (math.pi / tr) ** 2 * np.cos(math.pi * q), 0.0)
    c, s = np.cos(e.omega * t), np.sin(e.omega * t)
    w, a = e.omega, e.amplitude
    u, ud = a * env * c, a * (d1 * c - env * w * s)
    udd = a * (d2 * c - 2 * d1 * w * s - env * w * w * c)
    if e.clip > 0:  # the actuator's limit: flat tops, the velocity zero on them (its jump is not carried)
        lim = e.clip * a
        on_top = np.abs(u) >= lim
        u, ud, udd = np.clip(u, -lim, lim), np.where(on_top, 0.0, ud), np.where(on_top, 0.0, udd)
    return u, ud, udd


def linear_signals(g: Linear, e: Experiment, t: Array) -> tuple[Array, Array, Array]:
    """x, dx/dt, d2x/dt2 from G's own states, started from rest.

    The realisation is split into its modes (a = V diag(lam) V^-1); each modal state is stepped exactly
    for an input linear between grid points (first-order hold, `lfilter`). The pure delay is a shifted
    buffer: the states are computed on the grid t - T, where the input is zero before it starts.
    """
    lam, vec = np.linalg.eig(g.a)
    bm = np.linalg.solve(vec, g.b.astype(complex))
    cm = g.c @ vec
    h = float(t[1] - t[0])
    # x, dx/dt and d2x/dt2 are G applied to u, du/dt and d2u/dt2 (u and du/dt are zero at the start), so
    # each keeps the hold's relative accuracy (derivatives of the states would lose it at low omega tau)
    drives = drive(e, t - g.delay)
    outs = [np.zeros(t.size, complex) for _ in drives]
    for li, bi, ci in zip(lam, bm, cm):
        a = np.exp(li * h)
        g0 = np.expm1(li * h) / li
        g1 = (np.expm1(li * h) - li * h) / li**2
        for acc, v in zip(outs, drives):
            acc += ci * lfilter([g1 / h, g0 - g1 / h], [1.0, -a], bi * v)
    x, xd, xdd = (o.real.copy() for o in outs)
    if e.clip > 0:  # the clipped drive's acceleration has impulses where the velocity jumps: differentiate
        xdd = np.gradient(xd, h)
    return x, xd, xdd


def _rate(w: float, e: float, sg: float, asym: float, dnu: float, al: float, be: float, ga: float,
          mu: float) -> float:  # fmt: skip
    """dw/dx of (2a) on a branch of sign sg, with the asymmetry and the degradation factor."""
    aw = abs(w)
    return al - (1.0 + dnu * e) * aw ** (mu - 1.0) * (be * sg * w + ga * aw + asym * w)  # type: ignore[no-any-return]


def _hysteresis_kernel(x: Array, play: float, asym: float, dnu: float, al: float, be: float, ga: float,
                       mu: float, out: Array) -> None:  # fmt: skip
    """w along the path of each row of x: RK4 in the path variable (w and the energy e = int w dx)."""
    rows, n = x.shape
    for r in range(rows):
        w = 0.0
        en = 0.0
        xp = x[r, 0]
        out[r, 0] = 0.0
        for k in range(1, n):
            new = min(max(xp, x[r, k] - play), x[r, k] + play)
            d = new - xp
            xp = new
            sg = 1.0 if d > 0 else (-1.0 if d < 0 else 0.0)
            k1 = rate(w, en, sg, asym, dnu, al, be, ga, mu)
            w2 = w + 0.5 * d * k1
            k2 = rate(w2, en + 0.5 * d * w, sg, asym, dnu, al, be, ga, mu)
            w3 = w + 0.5 * d * k2
            k3 = rate(w3, en + 0.5 * d * w2, sg, asym, dnu, al, be, ga, mu)
            w4 = w + d * k3
            k4 = rate(w4, en + d * w3, sg, asym, dnu, al, be, ga, mu)
            en = en + d / 6 * (w + 2 * w2 + 2 * w3 + w4)
            w = w + d / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            out[r, k] = w


try:  # optional: the same loops compiled (much faster; the plain Python loops give the same numbers)
    import numba

    rate = numba.njit(_rate)
    _kernel = numba.njit(_hysteresis_kernel)
except ImportError:  # pragma: no cover - depends on the environment
    rate = _rate
    _kernel = _hysteresis_kernel


def hysteresis(x: Array, hy: Hysteresis, play: float = 0.0, asym: float = 0.0, dnu: float = 0.0) -> Array:
    """w (rows: independent runs) of the Bouc-Wen element (2a) driven along x, through a play operator of
    half-width `play`, with the asymmetry `asym` and the strength degradation nu = 1 + dnu e."""
    out = np.empty_like(x)
    _kernel(np.ascontiguousarray(x, dtype=float), float(play), float(asym), float(dnu), hy.alpha, hy.beta,
            hy.gamma, hy.mu, out)  # fmt: skip
    return out


def play_operator(v: Array, b: Array) -> Array:
    """Play operators of half-widths b (rows) on one sampled path v (exact on the samples)."""
    out = np.empty((b.size, v.size))
    p = np.full(b.size, v[0])
    for k in range(v.size):
        p = np.clip(p, v[k] - b, v[k] + b)
        out[:, k] = p
    return out


def first_order_lag(s: Array, dt: float, tau: float) -> Array:
    """The exact lag of a piecewise-linear input (first-order hold), from rest."""
    if tau <= 0:
        return s
    a = math.exp(-dt / tau)
    b0 = 1 - tau / dt * (1 - a)
    b1 = tau / dt * (1 - a) - a
    return np.asarray(lfilter([b0, b1], [1.0, -a], s), dtype=float)


def smooth_sign(v: Array, vmax: float) -> Array:
    return np.tanh(v / (FRICTION_EPS * vmax))  # type: ignore[no-any-return]


@dataclass
class Signals:
    """One experiment simulated on its fine grid (SUB points per sample)."""

    e: Experiment
    t: Array
    u: Array
    ud: Array
    udd: Array
    x: Array
    xd: Array
    xdd: Array


SUB = 2


def signals(g: Linear, e: Experiment) -> Signals:
    t = np.arange((e.settle + e.n) * SUB) * (e.dt / SUB)
    u, ud, udd = drive(e, t)
    x, xd, xdd = linear_signals(g, e, t)
    return Signals(e, t, u, ud, udd, x, xd, xdd)


INNER = {"play": "play", "asymmetry": "asym", "degradation": "dnu"}


def element(sig: list[Signals], hy: Hysteresis, effect: str = "null", p: float = 0.0) -> Array:
    """w of every experiment (rows, padded to the longest), with an effect inside the element if any."""
    kw = {INNER[effect]: p} if effect in INNER else {}
    n = max(s.t.size for s in sig)
    xs = np.stack([np.pad(s.x, (0, n - s.t.size), mode="edge") for s in sig])
    return hysteresis(xs, hy, **kw)


def output(
    sig: list[Signals], hy: Hysteresis, effect: str, p: float, plain: Optional[Array] = None
) -> list[Array]:
    """The noise-free measured output of every experiment with the effect at value p, on the record
    (`plain`: the element's w without effect, reused when the effect is not inside the element)."""
    w_all = element(sig, hy, effect, p) if (effect in INNER or plain is None) else plain
    outs = []
    for i, s in enumerate(sig):
        y = w_all[i, : s.t.size] + extra(s, effect, p)
        if effect == "sensor_lag":
            y = first_order_lag(y, s.e.dt / SUB, p)
        y = y[(s.e.settle * SUB) :: SUB]
        if effect == "output_backlash":
            y = play_operator(y, np.array([p]))[0]
        if effect == "offset":
            y = y + p
        outs.append(y)
    return outs


def extra(s: Signals, effect: str, p: float) -> Array | float:
    """The additive physics of one effect (the mechanical terms at their place, the outside loops)."""
    e = s.e
    vu = e.amplitude * e.omega
    ax = float(np.abs(s.x[e.settle * SUB :]).max())
    table = {
        "stiffness": lambda: s.u, "viscous": lambda: s.ud, "inertia": lambda: s.udd,
        "coulomb": lambda: smooth_sign(s.ud, vu),
        "stiffness@x": lambda: s.x, "viscous@x": lambda: s.xd, "inertia@x": lambda: s.xdd,
        "coulomb@x": lambda: smooth_sign(s.xd, ax * e.omega),
    }  # fmt: skip
    if effect in table:
        return p * table[effect]()
    if effect == "stribeck":
        # Stribeck: a static level falling from 2.5x the Coulomb level to it above v_s, v_s a PHYSICAL
        # velocity (a fixed fraction of the mid-band peak velocity): the curve's shape differs per experiment
        vs = s.e.amplitude * s.e.omega * 0.15 if STRIBECK_VS is None else STRIBECK_VS
        return p * smooth_sign(s.ud, vu) * (1.0 + 1.5 * np.exp(-((s.ud / vs) ** 2)))
    if effect == "prandtl_ishlinskii":
        radii = np.linspace(1, 6, 6) / 6 * 0.6 * X_MIN
        weights = 1.0 - np.arange(6) / 7
        return p * (weights @ play_operator(s.x, radii))  # type: ignore[no-any-return]
    return 0.0


#: Set per case (the Stribeck velocity and the smallest stroke, physical constants of the device).
STRIBECK_VS: Optional[float] = None
X_MIN = 1.0


# -------------------------------------------------------------------------------------------- one case
@dataclass
class Case:
    effect: str  # a library code name, an outside effect, or "null"
    size: float  # x the averaged noise sd (0 for a null)
    index: int
    seed: int
    noise: Optional[str] = None  # this noise kind (--noise), else drawn from the seed
    drift: float = DRIFT  # the drift of the output zero over the record, in noise sd (noise "drift")
    design: Optional[str] = None  # this experiment design (--design), else drawn from the seed

    @property
    def key(self) -> str:
        return f"{self.effect}:{self.size:g}:{self.index}" + (f":{self.design}" if self.design else "")


def rms(parts: list[Array]) -> float:
    return float(np.sqrt(np.mean(np.concatenate(parts) ** 2)))


def size_effect(sig: list[Signals], hy: Hysteresis, effect: str, target: float, y0: list[Array],
                plain: Array) -> tuple[float, list[Array]]:  # fmt: skip
    """The value p whose contribution (with minus without) has RMS `target` over the recorded periods."""
    if effect == "offset":
        return target, output(sig, hy, effect, target, plain)
    p = {"play": 0.02 * X_MIN, "asymmetry": 0.05 * (hy.beta + hy.gamma), "sensor_lag": 0.01 / sig[0].e.omega,
         "output_backlash": 0.01 * rms(y0), "degradation": 1e-3}.get(effect, 1.0)  # fmt: skip
    linear = effect not in ("play", "asymmetry", "sensor_lag", "output_backlash", "degradation")
    for _ in range(1 if linear else 8):
        y = output(sig, hy, effect, p, plain)
        got = rms([a - b for a, b in zip(y, y0)])
        if got <= 0 or not math.isfinite(got):
            raise RuntimeError(f"{effect} at {p} contributes {got}")
        ratio = target / got
        if abs(ratio - 1) < 0.02:
            break
        p *= ratio if linear else float(np.clip(ratio, 0.2, 5.0)) ** (0.9 if effect == "degradation" else 1.0)
    else:
        return p, output(sig, hy, effect, p, plain)
    return p, y


def add_noise(
    y: list[Array],
    kind: str,
    pct: float,
    rng: np.random.Generator,
    drift: float = DRIFT,
    periods: Optional[list[int]] = None,
) -> tuple[list[Array], float]:
    """Measured outputs and the averaged noise sd (the noise sd of a mean over the recorded periods; RMS
    over the experiments when they record unequal numbers of periods)."""
    periods = periods or [RECORD_PERIODS]
    sigma = pct * rms(y)
    out = []
    for v in y:
        if kind == "ar1":
            phi = float(rng.uniform(0.5, 0.85))
            e = rng.normal(0.0, sigma * math.sqrt(1 - phi**2), v.size)
            v = v + lfilter([1.0], [1.0, -phi], e)
        else:
            v = v + rng.normal(0.0, sigma, v.size)
        if kind == "drift":
            v = v + float(rng.choice([-1, 1])) * drift * sigma * np.linspace(0.0, 1.0, v.size)
        if kind == "adc":
            v = sigma * np.round(v / sigma)  # an ADC whose step is one noise sd
        out.append(v)
    spread = sigma * (math.sqrt(1 + 1 / 12) if kind == "adc" else 1.0)
    return out, spread * math.sqrt(float(np.mean([1.0 / p for p in periods])))


def make_case(case: Case) -> dict[str, Any]:
    """Draw the plant, design and noise from the case's seed; simulate; size; return the lab's files' data."""
    global STRIBECK_VS, X_MIN
    rng = np.random.default_rng(case.seed)
    plant = str(rng.choice(PLANTS))
    g = LINEAR["first_order" if case.design == "first_order" else plant](rng)
    plant = g.kind
    hy = draw_hysteresis(rng)
    dkind = str(rng.choice(DESIGNS))
    dkind = case.design or dkind  # drawn either way: the rest of the case stays the seed's
    exps = design(dkind, g, hy, rng)
    nkind = str(rng.choice(NOISES))
    nkind = case.noise or nkind  # the draw is made either way: the plant and design stay the case's
    pct = float(rng.uniform(0.005, 0.02))
    sig = [signals(g, e) for e in exps]
    X_MIN = min(float(np.abs(s.x[s.e.settle * SUB :]).max()) for s in sig)
    STRIBECK_VS = 0.15 * float(np.median([e.amplitude * e.omega for e in exps]))
    plain = element(sig, hy)
    y0 = output(sig, hy, "null", 0.0, plain)
    npers = [e.periods for e in exps]
    _, avg_sd = add_noise(y0, nkind, pct, np.random.default_rng(0), periods=npers)
    value = 0.0
    y = y0
    if case.effect != "null":
        value, y = size_effect(sig, hy, case.effect, case.size * avg_sd, y0, plain)
    got = rms([a - b for a, b in zip(y, y0)]) / avg_sd
    ym, _ = add_noise(y, nkind, pct, rng, case.drift, npers)
    u = [s.u[(s.e.settle * SUB) :: SUB] for s in sig]
    if dkind in ("fixed_rate", "clipped"):  # a lab's input channel: its own small noise
        u = [v + rng.normal(0.0, 5e-4 * e.amplitude, v.size) for v, e in zip(u, exps)]
    info = {"plant": plant, "g": g.info, "delay": g.delay, "alpha": hy.alpha, "beta": hy.beta,
            "gamma": hy.gamma, "mu": hy.mu, "design": dkind, "noise": nkind, "noise_pct": 100 * pct,
            "value": value, "size_got": got, "avg_sd": avg_sd, "periods": npers,
            "clip": [e.clip for e in exps],
            "phase_max_deg": max(-math.degrees(np.angle(g.response(e.omega))) % 360 for e in exps),
            }  # fmt: skip
    return {"info": info, "exps": exps, "u": u, "y": ym}


# ---------------------------------------------------------------------------------- the user's files
def write_csv(path: Path, e: Experiment, u: Array, y: Array) -> None:
    t = np.arange(u.size) * e.dt
    if e.recording:
        head = ['format: "bouc_wen_id.recording"', "version: 1", f"amplitude: {e.amplitude!r}",
                f"frequency: {e.omega!r}", "settle_periods: 0"]  # fmt: skip
    else:
        head = ['format: "bouc_wen_id.measurement"', "version: 1", f"nominal_frequency: {e.omega * 1.01!r}"]
    head.append('units: {"u": "mm", "y": "N"}')
    body = np.column_stack([t, u, y])
    np.savetxt(path, body, fmt="%.12g", delimiter=",", header="\n".join(head) + "\nt,u,y", comments="")
    text = path.read_text().splitlines()
    path.write_text("\n".join(["# " + h for h in head] + text[len(head) :]) + "\n")


def probe_non_integer(seed: int) -> str:
    """Does the public API take, as `Recording`s, records whose period is not a whole number of samples
    (a lab's fixed rate)? The answer is a finding: where it refuses, the measurement path is the way."""
    import bouc_wen_id as bw

    rng = np.random.default_rng(seed)
    g = LINEAR["lag_delay"](rng)
    hy = draw_hysteresis(rng)
    e = design("fixed_rate", g, hy, rng)[0]
    sig = signals(g, e)
    y = output([sig], hy, "null", 0.0)[0]
    t = np.arange(y.size) * e.dt
    try:
        rec = bw.Recording(t, e.amplitude * np.cos(e.omega * t), y, amplitude=e.amplitude, frequency=e.omega)
    except Exception as exc:  # the finding is the error's name
        return f"Recording() refuses it: {type(exc).__name__}: {str(exc)[:200]}"
    try:
        bw.diagnose([rec])
    except Exception as exc:
        return f"Recording() accepts it, diagnose refuses it: {type(exc).__name__}: {str(exc)[:200]}"
    return "accepted by Recording() and diagnose"


def score(case: Case, d: Any) -> tuple[str, str]:
    """(category, what was named): right, place, wrong, unexplained, adequate; nulls: adequate, named,
    unexplained, input (:func:`_input_said`); outside: unexplained, family (the caveated equivalent,
    FAMILY), named, partly, adequate."""
    named = [t.term for t in d.named]
    status = str(d.status)
    if case.design == "clipped":  # the input's own waveform is not device physics: the input IS distorted
        named = [n for n in named if n != "distortion"]
        if not named and status == "explained":  # the measured input alone explains it: the final model fits
            status = "adequate"
    alts = [(a.term, a.rival) for a in d.alternatives]
    text = ",".join(named) + ("" if not alts else " | alt " + ",".join(f"{a}~{r}" for a, r in alts))
    if case.effect == "null" or case.effect in OUTSIDE:
        if status == "adequate":
            return "adequate", text
        if case.effect == "null" and not named and _input_said(str(getattr(d, "verdict", ""))):
            return "input", text  # a misfit the verdict puts on the measured input's own harmonics
        if named and _family(case.effect, named, str(getattr(d, "verdict", ""))):
            return "family", text
        if named:
            return ("named" if status == "explained" else "partly"), text
        return "unexplained", text
    truth = case.effect
    if truth in named or any(r == truth and a in named for a, r in alts):
        return "right", text
    base = truth.split("@")[0]
    if any(n.split("@")[0] == base for n in named):
        return "place", text
    if named:
        return "wrong", text
    return ("adequate" if status == "adequate" else "unexplained"), text


def run_case(case: Case) -> dict[str, Any]:
    import bouc_wen_id as bw

    t0 = time.perf_counter()
    rec: dict[str, Any] = {"key": case.key, "effect": case.effect, "size": case.size, "seed": case.seed}
    try:
        made = make_case(case)
        rec.update(made["info"])
        rec["t_sim"] = time.perf_counter() - t0
        with tempfile.TemporaryDirectory() as tmp:
            paths = []
            for i, (e, u, y) in enumerate(zip(made["exps"], made["u"], made["y"])):
                paths.append(Path(tmp) / f"run_{i:02d}.csv")
                write_csv(paths[-1], e, u, y)
            items = bw.load(paths)
            t1 = time.perf_counter()
            d = bw.diagnose(items)
            rec["t_diag"] = time.perf_counter() - t1
        rec["category"], rec["named"] = score(case, d)
        rec.update(status=d.status, verdict=d.verdict, final_p=float(d.final.p_value),
                   plain_p=float(d.plain.p_value))  # fmt: skip
        rec["bad_explained"] = d.status == "explained" and float(d.final.p_value) < 0.05
        rec["weak_remainder"] = any(r.kind == "borderline" for r in d.readings)  # scored by status as before
        rec["input_named"] = any(t.term == "distortion" for t in d.named)
        rec["pair_step"] = [
            list(getattr(st, "pair", ())) or "tried" for st in d.steps if getattr(st, "pairs", ())
        ]
        rec["place_alts"] = [f"{a.term}~{a.rival}" for a in d.alternatives if _other_place(a.term, a.rival)]
        if case.effect in LIBRARY:  # the true model's own LR test, and why a miss missed (oracle.py)
            import oracle

            rec.update(oracle.truth_lr(d, case.effect), right_place=rec["category"] == "right")
            rec["cause"] = oracle.cause(rec)
    except Exception as exc:  # a crash is a finding, with its text; a named error of the library is apart
        import bouc_wen_id.errors as bwe

        rec["category"] = "refused" if isinstance(exc, bwe.BoucWenIdError) else "error"
        rec["verdict"] = f"{type(exc).__name__}: {exc}"
        rec["trace"] = traceback.format_exc()[-1500:]
    rec["seconds"] = time.perf_counter() - t0
    return rec


# ---------------------------------------------------------------------------------------------- driver
def cases(args: argparse.Namespace) -> list[Case]:
    out: list[Case] = []

    def add(effect: str, size: float, k: int) -> None:
        tag = (LIBRARY + OUTSIDE + ("null",)).index(effect)
        seed = int(np.random.SeedSequence([args.seed, tag, int(size), k]).generate_state(1)[0])
        for dz in designs:
            out.append(Case(effect, size, k, seed, args.noise, args.drift, dz))

    designs: list[Optional[str]] = [None] if args.design is None else list(args.design.split(","))
    sizes = [float(s) for s in args.sizes.split(",")]
    effects = LIBRARY if args.only is None else tuple(e for e in args.only.split(",") if e in LIBRARY)
    for eff in effects:
        for s in sizes:
            for k in range(args.cases):
                add(eff, s, k)
    outside = OUTSIDE if args.only is None else tuple(e for e in args.only.split(",") if e in OUTSIDE)
    for eff in outside:
        for j in range(args.outside):
            add(eff, sizes[j % len(sizes)], j)
    if args.only is None or "null" in args.only.split(","):
        for k in range(args.null):
            add("null", 0.0, k)
    return out


def quick_cases(args: argparse.Namespace) -> list[Case]:
    pick = [("viscous@x", 30), ("inertia", 30), ("coulomb@x", 10), ("offset", 10), ("play", 30),
            ("sensor_lag", 30), ("stiffness@x", 10), ("null", 0), ("null", 0), ("stribeck", 30)]  # fmt: skip
    out = []
    for k, (eff, s) in enumerate(pick):
        tag = (LIBRARY + OUTSIDE + ("null",)).index(eff)
        sd = int(np.random.SeedSequence([args.seed, tag, s, k]).generate_state(1)[0])
        out.append(Case(eff, float(s), k, sd, args.noise, args.drift))
    return out


GOOD = {"lib": ("right",), "null": ("adequate",), "outside": ("unexplained", "family")}
COLUMNS = (
    "right", "place", "wrong", "unexplained", "family", "adequate", "input", "named", "partly", "refused",
    "error",
)  # fmt: skip

#: An outside effect, the terms a library caveat ties to it, and the module and mark of each caveat: a
#: verdict naming only such terms, each with the caveat that names the truth as the equivalent IN ITS
#: HEADLINE, is "family" (as benches/diagnosis.py scores the Dahl element with its family caveat). A
#: diagnosis with the caveat only in its details (before diagnosis/readings.py) is "named".
FAMILY: dict[str, dict[str, tuple[str, str]]] = {
    "output_backlash": {"play": ("caveats", "PLAY_MARK")},
    # a rate-independent loop: a viscous damping's rate caveat names it too (diagnosis/rate_rival.py)
    "prandtl_ishlinskii": {
        "stiffness@x": ("masing", "MASING_MARK"),
        "viscous": ("rate_rival", "RATE_MARK"),
        "viscous@x": ("rate_rival", "RATE_MARK"),
    },
}


def _other_place(a: str, b: str) -> bool:
    """Are two code names one term at two places (viscous and viscous@x)?"""
    return a != b and a.split("@")[0] == b.split("@")[0]


def _input_said(verdict: str) -> bool:
    """Does the verdict say the measured input is not a sine (diagnosis.input_note's mark)? A null with a
    distorted input whose misfit the verdict leaves "unexplained" with that clause and no term named is
    scored "input": the input's harmonics through G above the band are the truth here, and the verdict
    names them; it is counted apart from "adequate" (the model does not fit)."""
    try:
        mark = getattr(importlib.import_module("bouc_wen_id.diagnosis.input_note"), "MARK", None)
    except ImportError:
        mark = None
    return bool(mark) and str(mark).lstrip("; ") in verdict


def _family(effect: str, named: list[str], verdict: str) -> bool:
    """Every named term is one whose caveat names the outside ``effect`` (:data:`FAMILY`), with that caveat
    in the verdict's HEADLINE (its first clause: diagnosis/readings.py); a caveat only in the details reads
    as a confident name to a user who reads the headline."""
    if effect not in FAMILY or not named:
        return False
    head = verdict.split("; ", 1)[0]  # the headline's qualifiers hold no "; " (verdict_text.clauses)
    for term in named:
        if term not in FAMILY[effect]:
            return False
        module, attr = FAMILY[effect][term]
        try:
            mark = getattr(importlib.import_module(f"bouc_wen_id.diagnosis.{module}"), attr, None)
        except ImportError:
            mark = None
        if not (mark and str(mark) in head):
            return False
    return True


def group(rec: dict[str, Any]) -> str:
    return "null" if rec["effect"] == "null" else ("outside" if rec["effect"] in OUTSIDE else "lib")


def table(recs: list[dict[str, Any]]) -> str:
    rows: dict[tuple[str, float], list[dict[str, Any]]] = {}
    for r in recs:
        rows.setdefault((r["effect"], r["size"]), []).append(r)
    lines = ["| effect | size | n | good | " + " | ".join(COLUMNS) + " | bad expl | s/diag (median) |",
             "|---|---|---|---|" + "---|" * len(COLUMNS) + "---|---|"]  # fmt: skip
    order = {e: i for i, e in enumerate(LIBRARY + ("null",) + OUTSIDE)}
    for (eff, size), rs in sorted(rows.items(), key=lambda kv: (order[kv[0][0]], kv[0][1])):
        cnt = {c: sum(r["category"] == c for r in rs) for c in COLUMNS}
        good = sum(r["category"] in GOOD[group(r)] for r in rs)
        bad = sum(bool(r.get("bad_explained")) for r in rs)
        sec = float(np.median([r.get("t_diag", math.nan) for r in rs]))
        lines.append(f"| {eff} | {size:g} | {len(rs)} | {good} | " + " | ".join(str(cnt[c]) for c in COLUMNS)
                     + f" | {bad} | {sec:.1f} |")  # fmt: skip
    for gname in ("lib", "null", "outside"):
        rs = [r for r in recs if group(r) == gname]
        if rs:
            good = sum(r["category"] in GOOD[gname] for r in rs)
            lines.append(f"| **all {gname}** | | {len(rs)} | {good} ({100 * good / len(rs):.0f} %) |"
                         + " |" * (len(COLUMNS) + 2))  # fmt: skip
    return "\n".join(lines)


def breakdown(recs: list[dict[str, Any]], key: str) -> str:
    """Good verdicts per group (library effects, nulls, outside) and per value of `key` (noise, design...)."""
    values = sorted({str(r.get(key)) for r in recs})
    lines = [
        f"| {key} | " + " | ".join(f"{g} good/n" for g in GOOD) + ' | says "not settled" |',
        "|---|---|---|---|---|",
    ]
    for v in values:
        rs = [r for r in recs if str(r.get(key)) == v]
        cells = []
        for gname in GOOD:
            sub = [r for r in rs if group(r) == gname]
            cells.append(f"{sum(r['category'] in GOOD[gname] for r in sub)}/{len(sub)}")
        stuck = sum("not settled" in str(r.get("verdict", "")) for r in rs)
        lines.append(f"| {v} | " + " | ".join(cells) + f" | {stuck} |")
    return "\n".join(lines)


def failures(recs: list[dict[str, Any]]) -> str:
    out = []
    for r in recs:
        if r["category"] not in GOOD[group(r)]:
            where = f"{r.get('plant')}, {r.get('design')}, {r.get('noise')}"
            out.append(f"- {r['key']} seed={r['seed']} [{where}, "
                       f"mu={r.get('mu', math.nan):.2f}] {r['category']}: named={r.get('named', '')!r} :: "
                       f"{r.get('verdict', '')}")  # fmt: skip
    return "\n".join(out) if out else "(none)"


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="10 cases, <= 2 min")
    ap.add_argument("--seed", type=int, default=2026, help="every random number derives from it")
    ap.add_argument("--cases", type=int, default=6, help="cases per library effect and size")
    ap.add_argument("--null", type=int, default=20)
    ap.add_argument("--outside", type=int, default=6, help="cases per outside effect (sizes alternate)")
    ap.add_argument("--sizes", default="10,30")
    ap.add_argument("--only", default=None, help="comma list of effects (and/or 'null')")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--json", default=None, help="write every case's record here")
    ap.add_argument("--noise", choices=NOISES, default=None, help="this noise for every case (else drawn)")
    ap.add_argument(
        "--drift", type=float, default=DRIFT, help="drift of the output zero over the record (sd)"
    )
    ap.add_argument(
        "--design",
        default=None,
        help=f"comma list of designs for every case (else drawn): {', '.join(DESIGNS + NEW_DESIGNS)}",
    )
    ap.add_argument("--report", default=None, help="print the tables and failures of a --json file again")
    ap.add_argument(
        "--replay", default=None, help="EFFECT:SIZE:INDEX with the same --seed: one case, summary"
    )
    args = ap.parse_args(argv)
    if args.design is not None:
        unknown = set(args.design.split(",")) - set(DESIGNS + NEW_DESIGNS)
        if unknown:
            ap.error(f"unknown design(s) {sorted(unknown)}")
    if args.report:
        doc = json.loads(Path(args.report).read_text())
        _print(doc["cases"], doc["wall"], doc.get("probe_non_integer", ""))
        return 0
    if args.replay:
        eff, size, k, *dz = args.replay.split(":")
        tag = (LIBRARY + OUTSIDE + ("null",)).index(eff)
        sd = int(np.random.SeedSequence([args.seed, tag, int(float(size)), int(k)]).generate_state(1)[0])
        rec = run_case(Case(eff, float(size), int(k), sd, args.noise, args.drift, dz[0] if dz else None))
        print(json.dumps({k2: v for k2, v in rec.items() if k2 != "trace"}, indent=1, default=str))
        return 0
    todo = quick_cases(args) if args.quick else cases(args)
    print(f"{len(todo)} cases, {args.workers} worker(s), generator v{GENERATOR_VERSION}", file=sys.stderr)
    t0 = time.perf_counter()
    recs: list[dict[str, Any]] = []
    if args.workers > 1:
        with cf.ProcessPoolExecutor(args.workers) as pool:
            futs = [pool.submit(run_case, c) for c in todo]
            for f in cf.as_completed(futs):
                recs.append(f.result())
                _progress(recs[-1], len(recs), len(todo))
    else:
        for c in todo:
            recs.append(run_case(c))
            _progress(recs[-1], len(recs), len(todo))
    wall = time.perf_counter() - t0
    probe = probe_non_integer(args.seed)
    _print(recs, wall, probe)
    if args.json:
        doc = {"seed": args.seed, "version": GENERATOR_VERSION, "wall": wall, "probe_non_integer": probe}
        Path(args.json).write_text(json.dumps({**doc, "cases": recs}, indent=1, default=str))
    return 0


def design_table(recs: list[dict[str, Any]]) -> str:
    """One row per experiment design: the library cases' outcomes, the nulls, the outside effects, the
    verdicts that say "not settled", and the place alternatives reported (term~rival at the other place)."""
    head = (
        "| design | lib n | right (as alt) | place | wrong | unexpl | adequate | refused | error | "
        "not settled"
        " | place alts (lib) | nulls adequate | outside good | bad expl | s/diag |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for dz in sorted({str(r.get("design")) for r in recs}):
        rs = [r for r in recs if str(r.get("design")) == dz]
        lib = [r for r in rs if group(r) == "lib"]
        nul = [r for r in rs if group(r) == "null"]
        out = [r for r in rs if group(r) == "outside"]

        def n(cat: str, sub: list[dict[str, Any]] = lib) -> int:
            return sum(r["category"] == cat for r in sub)

        def named_first(r: dict[str, Any]) -> list[str]:
            return str(r.get("named", "")).split(" | ")[0].split(",")

        as_alt = sum(r["category"] == "right" and r["effect"] not in named_first(r) for r in lib)
        stuck = sum("not settled" in str(r.get("verdict", "")) for r in rs)
        alts = sum(bool(r.get("place_alts")) for r in lib)
        good_o = sum(r["category"] in GOOD["outside"] for r in out)
        bad = sum(bool(r.get("bad_explained")) for r in rs)
        sec = float(np.median([r.get("t_diag", math.nan) for r in rs]))
        lines.append(
            f"| {dz} | {len(lib)} | {n('right')} ({as_alt}) | {n('place')} | {n('wrong')} | "
            f"{n('unexplained')} | {n('adequate')} | {n('refused', rs)} | {n('error', rs)} | "
            f"{stuck} | {alts} | "
            f"{n('adequate', nul)}/{len(nul)} | {good_o}/{len(out)} | {bad} | {sec:.1f} |"
        )
    return "\n".join(lines)


def _print(recs: list[dict[str, Any]], wall: float, probe: str) -> None:
    if len({str(r.get("design")) for r in recs}) > 1 or any(r.get("key", "").count(":") == 3 for r in recs):
        print(design_table(recs) + "\n")
    print(table(recs))
    for key in ("noise", "design", "plant"):
        print("\n" + breakdown(recs, key))
    print(f"\n{len(recs)} diagnoses, wall {wall:.0f} s\n\nFailures:\n" + failures(recs))
    print("\nA fixed-rate record (no whole number of samples per period) as a Recording: " + probe)


def _progress(r: dict[str, Any], i: int, n: int) -> None:
    print(
        f"[{i}/{n}] {r['key']} {r['category']} {r.get('seconds', 0):.1f}s {r.get('verdict', '')[:110]}",
        file=sys.stderr,
        flush=True,
    )


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())

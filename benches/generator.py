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

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Optional

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
#: Effects whose contribution is linear in their parameter (sized in one shot).
LINEAR = (*MECHANICAL, "offset", "dahl")
COULOMB_EPS = 0.01  # tanh smoothing as a fraction of the peak velocity
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
    xp = np.empty(b.shape + (x.shape[1],))
    cur = np.clip(np.zeros_like(b), x[None, :, 0] - b, x[None, :, 0] + b)
    for j in range(x.shape[1]):
        cur = np.clip(cur, x[None, :, j] - b, x[None, :, j] + b)
        xp[..., j] = cur
    return xp


def run(p: Plant, eff: Effect, total: Optional[int] = None) -> FloatArray:
    """Noise-free outputs (trials x experiments x samples) of the plant with ``eff`` at every trial value."""
    total = total or (SETTLE + PERIODS) * P
    nv = eff.values.size
    ne = p.omegas.size
    grids = [_grid(p, i, total) for i in range(ne)]
    lat = [latent(p, g, i) for i, (g, _) in enumerate(grids)]
    x = np.stack([v[0] for v in lat])
    xd = np.stack([v[1] for v in lat])
    xdd = np.stack([v[2] for v in lat])
    h = np.array([g[1] / SUBSTEPS for g in grids])  # RK4 step: two half-grid intervals
    val = eff.values[:, None] * np.ones((1, ne))
    name = eff.name
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

    def f(w: FloatArray, e: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
        d = d - rho * w  # the element's own travel rate behind a series dashpot (0 without one)
        aw = np.abs(w) ** (mu - 1.0)
        b_eff = beta * np.exp(rwidth * np.tanh(np.abs(d) / vref - 1.0))
        nu = 1.0 + dnu * e
        hyst = b_eff * np.abs(d) * aw * w + gamma * d * aw * np.abs(w) + delta * d * aw * w
        pinch = 1.0 - zeta1 * np.exp(-((((w * np.sign(d)) - 0.1) / 0.2) ** 2))
        return pinch * (d - nu * hyst) / (1.0 + deta * e), w * d

    w0 = np.zeros((nv, ne)) + (0.0 if p.w0 is None else p.w0[None, :])
    wf = _rk4(f, w0, rate, h, SUBSTEPS * total)
    v = wf
    v = v + _parallel(p, eff, val, x[:, ::2], xd[:, ::2], xdd[:, ::2], grids)
    if name == "sensor_lag":
        v = _lag(v, val, h)
    if name == "offset":
        v = v + val[..., None]
    return np.ascontiguousarray(v[..., :-1:SUBSTEPS])


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
            "coulomb": np.tanh(sig1 / (COULOMB_EPS * vmax)),
        }[name]
        return val[..., None] * sig[None]
    if name == "dahl":  # dF/dxi = sigma (1 - s F)^2 along travel xi in direction s: solved exactly per step
        sigma = 1.0 / (0.2 * float(p.levels.min()))
        fd = np.zeros(x.shape[0])
        out = np.zeros(x.shape)
        for j in range(1, x.shape[1]):
            dx = x[:, j] - x[:, j - 1]
            sgn = np.sign(dx)
            g0 = np.clip(1.0 - sgn * fd, 0.0, 2.0)
            g1 = g0 / (1.0 + sigma * np.abs(dx) * g0)
            fd = np.where(sgn != 0.0, sgn * (1.0 - g1), fd)
            out[:, j] = fd
        return val[..., None] * out[None]
    return np.zeros((1, 1, 1))


def _lag(v: FloatArray, tau: FloatArray, h: FloatArray) -> FloatArray:
    """``v`` seen through ``1/(tau s + 1)`` from rest, exact for a piecewise-linear ``v`` on the grid."""
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


def contribution(p: Plant, eff: Effect, plain: FloatArray) -> FloatArray:
    """RMS of each trial value's contribution over the averaged periods, in averaged-noise-sd units."""
    y = run(p, eff)
    return np.sqrt(np.mean((_steady(y) - _steady(plain)) ** 2, axis=(1, 2))) / (NOISE_SD / math.sqrt(PERIODS))


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
    plain = run(p, Effect())
    if name in LINEAR:
        unit = float(contribution(p, Effect(name, place, np.ones(1)), plain)[0])
        return size / unit, size
    hi = upper_value(p, name)
    vals = hi * np.logspace(-3.0, 0.0, 7)
    c = contribution(p, Effect(name, place, vals), plain)
    ok = np.isfinite(c) & (c > 0)
    if not np.any(ok):
        raise FloatingPointError(f"{name}: no finite contribution over {vals}")
    lv, lc = np.log(vals[ok]), np.log(c[ok])
    order = np.argsort(lc)
    v = float(np.exp(np.interp(math.log(size), lc[order], lv[order])))
    got = float(contribution(p, Effect(name, place, np.array([v])), plain)[0])
    if got > 0:  # one secant correction in log-log
        slope = np.polyfit(lv, lc, 1)[0] if lv.size > 1 else 1.0
        v = min(hi, v * math.exp((math.log(size) - math.log(got)) / max(slope, 0.2)))
        got = float(contribution(p, Effect(name, place, np.array([v])), plain)[0])
    return v, got


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
    value, got = calibrate(p, name, place, size)
    y = run(p, Effect(name, place, np.array([value])))[0]
    return Case(kind, name, place, size, got, value, seed, p.shape, recordings(p, y, seed))

"""Recordings with a concealed effect: the generator behind ``benches/diagnosis.py`` (design.md 10.5).

Every case is a seeded plant (first-order G with a small delay, a Bouc-Wen element saturating at w = 1),
measured at four frequencies and two amplitudes (x at 0.8 and 2 times the saturation level), with white
output noise of sd ``NOISE_SD`` and ``PERIODS`` averaged periods of ``P`` samples after ``SETTLE`` settling
ones. The effect's size is the RMS of its contribution over the steady periods (output with the effect
minus output without, noise-free), in units of the averaged output's noise sd ``NOISE_SD / sqrt(PERIODS)``.

- Library terms are simulated by the library itself (``simulate`` with ``WienerPlant.terms``), time
  domain, from rest: an integrator independent of the steady-loop fit that names them. Degradation too:
  its energy state runs from rest through the settling periods, so the record drifts throughout.
- Physics outside the library (pinching, a hysteretic force fed back into a mass-spring) are integrated
  here in NumPy, vectorised over the experiments; ``degrading_records`` (the same Baber-Noori model in
  NumPy) stays as an independent check of the library's degradation term.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import terms as T
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

P = 128
PERIODS = 16
SETTLE = 10
SUBSTEPS = 8
NOISE_SD = 0.01
FREQS_HZ = (0.5, 1.0, 2.0, 4.0)
X_LEVELS = (0.8, 2.0)

#: The library's terms and how to build each with a parameter value (plain units: y ~ 1, u ~ 1).
LIBRARY: dict[str, Callable[[float], object]] = {
    "offset": lambda v: T.Offset(v),
    "stiffness": lambda v: T.Stiffness(v),
    "viscous": lambda v: T.Viscous(v),
    "inertia": lambda v: T.Inertia(v),
    "coulomb": lambda v: T.Coulomb(v),
    "sensor_lag": lambda v: T.SensorLag(v),
    "asymmetry": lambda v: T.Asymmetry(v),
    "play": lambda v: T.Play(v),
    "degradation": lambda v: T.Degradation(v),
}
#: Terms whose contribution is linear in the parameter (the size is set in one shot).
LINEAR = ("offset", "stiffness", "viscous", "inertia", "coulomb")


@dataclass(frozen=True)
class Base:
    """A seeded plant and its experiment plan."""

    plant: bw.WienerPlant
    omegas: FloatArray
    amplitudes: FloatArray
    gains: FloatArray
    phases: FloatArray


def base(seed: int) -> Base:
    rng = np.random.default_rng(seed)
    tc = float(rng.uniform(0.02, 0.15))
    delay = float(rng.uniform(0.0, 0.02))
    k = float(rng.uniform(0.5, 2.0))
    mu = float(rng.uniform(1.3, 2.5))
    ratio = float(rng.uniform(-0.3, 0.6))  # gamma / beta
    beta = 1.0 / (1.0 + ratio)  # beta + gamma = 1: saturation at |w| = 1
    lin = bw.TransferFunction([k], [tc, 1.0], delay=delay)
    plant = bw.WienerPlant(lin, bw.BoucWen(beta=beta, gamma=ratio * beta, mu=mu))
    om = np.repeat(TWO_PI * np.asarray(FREQS_HZ), len(X_LEVELS))
    xs = np.tile(np.asarray(X_LEVELS), len(FREQS_HZ))
    g, ph = lin.gain_phase(om)
    return Base(plant, om, xs / g, g, ph)


def _plan(b: Base, noise_sd: float, seed: int) -> bw.SinePlan:
    return bw.SinePlan(
        b.omegas,
        b.amplitudes,
        settle_periods=SETTLE,
        periods=PERIODS,
        samples_per_period=P,
        substeps=SUBSTEPS,
        noise_sd=noise_sd,
        seed=seed,
    )


def _steady(recs: Sequence[bw.Recording]) -> FloatArray:
    return np.concatenate([np.asarray(r.y[SETTLE * P :]) for r in recs])


def _with_terms(b: Base, terms: tuple[object, ...]) -> bw.WienerPlant:
    return bw.WienerPlant(b.plant.linear, b.plant.hysteresis, terms=terms)  # type: ignore[call-arg]


def contribution_rms(b: Base, term: str, value: float) -> float:
    plain = _steady(bw.simulate(b.plant, _plan(b, 0.0, 0)))
    aug = _steady(bw.simulate(_with_terms(b, (LIBRARY[term](value),)), _plan(b, 0.0, 0)))
    return float(np.sqrt(np.mean((aug - plain) ** 2)))


def calibrate(b: Base, term: str, size: float) -> float:
    """The term's parameter whose contribution has RMS ``size * NOISE_SD / sqrt(PERIODS)``."""
    target = size * NOISE_SD / math.sqrt(PERIODS)
    if term in LINEAR:
        return target / contribution_rms(b, term, 1.0)
    hi = {
        "sensor_lag": 0.5 / float(b.omegas.max()),
        "asymmetry": 0.9,
        "play": 0.5 * float(X_LEVELS[0]),
        "degradation": 0.05,  # nu grows by ~0.05 E per period: a 30x drift is far below this
    }[term]
    lo = hi * 1e-6
    for _ in range(40):  # bisection in log: the contribution grows with the parameter
        mid = math.sqrt(lo * hi)
        if contribution_rms(b, term, mid) < target:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.01:
            break
    return math.sqrt(lo * hi)


def library_case(
    term: str | None, size: float, seed: int, noise_sd: float = NOISE_SD
) -> tuple[list[bw.Recording], float]:
    """A case with ``term`` (None: the plain model) at ``size``; (recordings, parameter value)."""
    b = base(seed)
    if term == "distortion":
        return distortion_case(b, size, seed, noise_sd)
    if term is None:
        return bw.simulate(b.plant, _plan(b, noise_sd, seed)), 0.0
    value = calibrate(b, term, size)
    return bw.simulate(_with_terms(b, (LIBRARY[term](value),)), _plan(b, noise_sd, seed)), value


#: Noise sd of a case's "noise-free" twin: small enough that the residual is the term's own, large enough
#: for the estimators' noise-floor estimates to stay positive.
TWIN_NOISE_SD = 1e-6


def left_size(term: str, size: float, seed: int) -> float:
    """What the plain model cannot absorb of a case's term: the RMS of the refined plain fit's residual on
    the case's noise-free twin (the output offset ``identify`` removes counted back in: the plain loop has
    none), in units of the averaged output's noise sd; NaN when ``identify`` refuses the twin (a 30x
    distorted input is not a sine: ``FrequencyMismatchError``).

    The size of a case is its term's whole contribution; a term the linear part absorbs to first order (a
    sensor lag is a delay in G) leaves far less, and that remainder is all any test can see."""
    import warnings

    recs, _ = library_case(term, size, seed, noise_sd=TWIN_NOISE_SD)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = bw.identify(recs)
    except bw.BoucWenIdError:
        return math.nan
    res = np.concatenate(
        [np.asarray(e.ybar) + e.offset - np.asarray(e.model) for e in r.experiments if e.model is not None]
    )
    return float(np.sqrt(np.mean(res**2))) / (NOISE_SD / math.sqrt(PERIODS))


# --------------------------------------------------------------------------------------------------------
# Physics outside the library, integrated here (vectorised over the experiments).


def _bw_rate(w: FloatArray, xd: FloatArray, beta: float, gamma: float, mu: float) -> FloatArray:
    aw = np.abs(w) ** mu
    out: FloatArray = xd - beta * np.abs(xd) * aw * np.sign(w) - gamma * xd * aw
    return out


def _record(b: Base, y_steady_period: FloatArray, seed: int) -> list[bw.Recording]:
    """Recordings made of the steady period repeated, plus seeded noise (settling already done)."""
    rng = np.random.default_rng(seed)
    recs = []
    for i, (om, amp) in enumerate(zip(b.omegas, b.amplitudes)):
        t = np.arange(PERIODS * P) * (TWO_PI / om / P)
        y = np.tile(y_steady_period[i], PERIODS) + rng.normal(0.0, NOISE_SD, t.size)
        recs.append(
            bw.Recording(
                t,
                amp * np.cos(om * t),
                y,
                float(amp),
                float(om),
                settle_periods=0,
                metadata={"name": f"exp{i}"},
            )
        )
    return recs


def pinched_period(b: Base, zeta1: float, zeta2: float = 0.2, q: float = 0.1, cycles: int = 16) -> FloatArray:
    """The steady loop of Baber-Noori pinching, h(w) = 1 - zeta1 exp(-((w sgn xdot - q)/zeta2)^2)."""
    h = b.plant.hysteresis
    a = b.gains * b.amplitudes
    n = P * SUBSTEPS
    dth = TWO_PI / n
    w = np.zeros_like(a)
    out = np.zeros((a.size, P))
    for c in range(cycles):
        for k in range(n):
            th = k * dth - b.phases  # x = A cos(theta - phi), grid theta = omega t

            def f(ww: FloatArray, t: FloatArray) -> FloatArray:
                xd = -a * np.sin(t)
                pinch = 1.0 - zeta1 * np.exp(-((((ww * np.sign(xd)) - q) / zeta2) ** 2))
                return pinch * _bw_rate(ww, xd, h.beta, h.gamma, h.mu)

            if c == cycles - 1 and k % SUBSTEPS == 0:
                out[:, k // SUBSTEPS] = w
            k1 = f(w, th)
            k2 = f(w + 0.5 * dth * k1, th + 0.5 * dth)
            k3 = f(w + 0.5 * dth * k2, th + 0.5 * dth)
            k4 = f(w + dth * k3, th + dth)
            w = w + dth / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return out


def feedback_period(b: Base, mass: float, cycles: int = 8) -> FloatArray:
    """The hysteretic force fed back into a mass-spring (not a Wiener cascade), steady output z.

    ``m q'' = k_s (x - q) - z - c q'``, ``z' = BW(q')``, driven by the Wiener x of the base plant; the
    output is the hysteretic force z. Integrated in theta = omega t (vectorised over the experiments).
    """
    h = b.plant.hysteresis
    a = b.gains * b.amplitudes
    om = b.omegas
    ks, damp = 4.0, 0.4
    n = P * SUBSTEPS
    dth = TWO_PI / n
    s = np.zeros((3, a.size))  # q, qdot, z
    out = np.zeros((a.size, P))

    def f(st: FloatArray, th: float) -> FloatArray:
        q, qd, z = st
        x = a * np.cos(th - b.phases)
        qdd = (ks * (x - q) - z - damp * qd) / mass
        return np.stack([qd, qdd, _bw_rate(z, qd, h.beta, h.gamma, h.mu)]) / om

    for c in range(cycles):
        for k in range(n):
            th = k * dth
            if c == cycles - 1 and k % SUBSTEPS == 0:
                out[:, k // SUBSTEPS] = s[2]
            k1 = f(s, th)
            k2 = f(s + 0.5 * dth * k1, th + 0.5 * dth)
            k3 = f(s + 0.5 * dth * k2, th + 0.5 * dth)
            k4 = f(s + dth * k3, th + dth)
            s = s + dth / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return out


def degrading_records(b: Base, rate: float, seed: int) -> list[bw.Recording]:
    """Baber-Noori strength degradation: ``nu = 1 + rate e`` with ``e' = w x'`` (dissipated energy).

    Integrated from rest over settle + averaged periods, so the loop drifts through the record.
    """
    h = b.plant.hysteresis
    a = b.gains * b.amplitudes
    rng = np.random.default_rng(seed)
    total = (SETTLE + PERIODS) * P
    n = total * SUBSTEPS
    dth = TWO_PI / (P * SUBSTEPS)
    w = np.zeros_like(a)
    e = np.zeros_like(a)
    ys = np.zeros((a.size, total))

    def f(ww: FloatArray, ee: FloatArray, t: float) -> tuple[FloatArray, FloatArray]:
        xd = -a * np.sin(t - b.phases)
        nu = 1.0 + rate * ee
        aw = np.abs(ww) ** h.mu
        wd = xd - nu * (h.beta * np.abs(xd) * aw * np.sign(ww) + h.gamma * xd * aw)
        return wd, ww * xd

    for k in range(n):
        if k % SUBSTEPS == 0:
            ys[:, k // SUBSTEPS] = w
        th = k * dth
        k1 = f(w, e, th)
        k2 = f(w + 0.5 * dth * k1[0], e + 0.5 * dth * k1[1], th + 0.5 * dth)
        k3 = f(w + 0.5 * dth * k2[0], e + 0.5 * dth * k2[1], th + 0.5 * dth)
        k4 = f(w + dth * k3[0], e + dth * k3[1], th + dth)
        w = w + dth / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        e = e + dth / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    recs = []
    for i, (om, amp) in enumerate(zip(b.omegas, b.amplitudes)):
        t = np.arange(total) * (TWO_PI / om / P)
        y = ys[i] + rng.normal(0.0, NOISE_SD, total)
        recs.append(
            bw.Recording(
                t,
                amp * np.cos(om * t),
                y,
                float(amp),
                float(om),
                settle_periods=SETTLE,
                metadata={"name": f"exp{i}"},
            )
        )
    return recs


def outside_case(kind: str, seed: int) -> list[bw.Recording]:
    """A case of physics outside the library: ``pinching`` or ``feedback`` (``degradation``, now a library
    term, is kept for comparison with the earlier tables)."""
    b = base(seed)
    if kind == "pinching":
        return _record(b, pinched_period(b, zeta1=0.6), seed)
    if kind == "feedback":
        return _record(b, feedback_period(b, mass=0.02), seed)
    if kind == "degradation":
        return degrading_records(b, rate=0.002, seed=seed)
    raise ValueError(kind)


# --------------------------------------------------------------------------------------------------------
# A distorted actuator (design.md 9.5): the true input carries harmonics 2 and 3 of seeded phases, the same
# shape at every experiment, and the true G acts on each harmonic at its own frequency (not the quasi-static
# G the fitted term assumes). Integrated here (RK4 along the exact steady x), vectorised over experiments.

#: Relative amplitudes of harmonics 2 and 3 of the input per unit of the distortion scale.
DISTORTION_SHAPE = (0.5, 1.0)


def distortion_coefficients(seed: int) -> NDArray[np.complex128]:
    """``c_k`` (k = 2, 3) of the input per unit scale: ``u = U Re[e^{i w t} + s sum_k c_k e^{i k w t}]``."""
    rng = np.random.default_rng(seed + 77)
    ph = rng.uniform(0.0, TWO_PI, len(DISTORTION_SHAPE))
    return np.asarray(DISTORTION_SHAPE) * np.exp(1j * ph)


def _x_path(b: Base, coeffs: NDArray[np.complex128], theta: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Steady ``x`` and ``dx/dtheta`` (experiments x len(theta)) through the true G at every harmonic."""
    x = np.zeros((b.omegas.size, theta.size))
    xd = np.zeros_like(x)
    for k, c in enumerate(np.concatenate([[1.0 + 0.0j], coeffs]), start=1):
        if c == 0:
            continue
        g, ph = b.plant.linear.gain_phase(k * b.omegas)
        z = (b.amplitudes * g * np.exp(-1j * ph) * c)[:, None] * np.exp(1j * k * theta)[None, :]
        x += z.real
        xd += (1j * k * z).real
    return x, xd


def distorted_period(b: Base, coeffs: NDArray[np.complex128], cycles: int = 8) -> FloatArray:
    """The steady Bouc-Wen output y = w on the grid, driven along the exact steady x of a distorted input."""
    h = b.plant.hysteresis
    n = P * SUBSTEPS
    dth = TWO_PI / n
    # x' at the RK4 stage points: k * dth / 2 for k = 0 .. 2n.
    _, xd = _x_path(b, coeffs, np.arange(2 * n + 1) * (0.5 * dth))
    w = np.zeros(b.omegas.size)
    out = np.zeros((b.omegas.size, P))
    for c in range(cycles):
        for k in range(n):
            if c == cycles - 1 and k % SUBSTEPS == 0:
                out[:, k // SUBSTEPS] = w
            x0, xm, x1 = xd[:, 2 * k], xd[:, 2 * k + 1], xd[:, 2 * k + 2]
            k1 = _bw_rate(w, x0, h.beta, h.gamma, h.mu)
            k2 = _bw_rate(w + 0.5 * dth * k1, xm, h.beta, h.gamma, h.mu)
            k3 = _bw_rate(w + 0.5 * dth * k2, xm, h.beta, h.gamma, h.mu)
            k4 = _bw_rate(w + dth * k3, x1, h.beta, h.gamma, h.mu)
            w = w + dth / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return out


def distortion_case(
    b: Base, size: float, seed: int, noise_sd: float = NOISE_SD
) -> tuple[list[bw.Recording], float]:
    """Recordings of the plain plant under a distorted input whose effect has RMS ``size`` noise sd; (recs,
    the distortion scale s)."""
    shape = distortion_coefficients(seed)
    plain = distorted_period(b, 0.0 * shape)
    target = size * NOISE_SD / math.sqrt(PERIODS)

    def rms(sc: float) -> float:
        return float(np.sqrt(np.mean((distorted_period(b, sc * shape) - plain) ** 2)))

    sc = 0.01
    for _ in range(4):  # secant on the nearly linear growth of the contribution
        sc *= target / rms(sc)
    rng = np.random.default_rng(seed)
    y_period = distorted_period(b, sc * shape)
    recs = []
    for i, (om, amp) in enumerate(zip(b.omegas, b.amplitudes)):
        t = np.arange(PERIODS * P) * (TWO_PI / om / P)
        u = amp * np.real(
            np.exp(1j * om * t) + sum(sc * c * np.exp(1j * k * om * t) for k, c in enumerate(shape, 2))
        )
        y = np.tile(y_period[i], PERIODS) + rng.normal(0.0, noise_sd, t.size)
        recs.append(
            bw.Recording(t, u, y, float(amp), float(om), settle_periods=0, metadata={"name": f"exp{i}"})
        )
    return recs, sc

"""Time-domain identification of the Wiener cascade (issue #20): estimates against the Cramer-Rao bound.

The data are made by an independent integrator, not the library's simulator: ``scipy.integrate.solve_ivp``
(DOP853, rtol 1e-10) on ``G`` realised by ``scipy.signal.tf2ss`` (another state basis than the library's
companion form), driven by the *analytic* multisine ``u(t - tau)`` (no interpolation of samples), then
sampled; white Gaussian noise is added to ``y = w``.  Each seed draws new noise (and, in ``--phases`` mode,
new random phases of the multisine); :func:`bouc_wen_id.fit_time_domain` starts from the truth perturbed by
10 % in every parameter.

For each plant the table prints, per parameter: the truth, the mean estimate, the empirical standard
deviation over the seeds, the Cramer-Rao standard deviation ``sqrt(diag(sigma^2 (J^T J)^-1))`` at the truth on
that design (``bouc_wen_id.timedomain.cramer_rao_bound``), and their ratio (1 = efficient; the issue asks
<= 1.5).

Run: ``python benches/timedomain.py --quick`` (6 seeds per plant, < 2 min on 2 cores) or without
``--quick`` (30 seeds).
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.terms import (
    COULOMB_SMOOTHING,
    PINCHING_CENTRE,
    PINCHING_WIDTH,
    Asymmetry,
    Coulomb,
    CoulombX,
    Degradation,
    Inertia,
    InertiaX,
    Offset,
    Pinching,
    Play,
    SensorLag,
    Stiffness,
    StiffnessDegradation,
    StiffnessX,
    Term,
    Viscous,
    ViscousX,
)
from bouc_wen_id.timedomain import Structure, cramer_rao_bound


@dataclass(frozen=True)
class Case:
    """A plant and its multisine design."""

    name: str
    num: tuple[float, ...]
    den: tuple[float, ...]
    delay: float
    beta: float
    gamma: float
    mu: float
    f_lo: float  # Hz, band of the multisine
    f_hi: float
    rms: float  # input RMS
    fs: float  # Hz
    duration: float  # s
    noise: float  # output noise SD, relative to the output RMS
    random: bool = (
        False  # a random input (Shinozuka: random frequencies in the band) instead of the multisine
    )

    def plant(self) -> bw.WienerPlant:
        return bw.WienerPlant(
            bw.TransferFunction(self.num, self.den, self.delay), bw.BoucWen(self.beta, self.gamma, self.mu)
        )

    def structure(self) -> Structure:
        return Structure(len(self.num) - 1, len(self.den) - 1, delay=self.delay > 0)


CASES = (
    # Resonant second order (f0 ~ 3.2 Hz, zeta 0.2), no delay.
    Case("resonant", (400.0,), (1.0, 8.0, 400.0), 0.0, 0.8, 0.2, 1.6, 0.3, 8.0, 1.0, 400.0, 6.0, 0.02),
    # First order with a zero and a delay of 12.3 ms.
    Case(
        "first order + delay",
        (0.4, 20.0),
        (1.0, 20.0),
        0.0123,
        1.0,
        -0.3,
        2.2,
        0.3,
        8.0,
        1.2,
        400.0,
        6.0,
        0.02,
    ),
)


def multisine(case: Case, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequencies (Hz), amplitudes and random phases of a flat multisine of RMS ``case.rms``."""
    rng = np.random.default_rng(seed)
    df = 1.0 / case.duration
    f = np.arange(max(1, round(case.f_lo / df)), round(case.f_hi / df) + 1) * df
    amp = np.full(f.size, case.rms * np.sqrt(2.0 / f.size))
    if case.random:  # a realisation of a band-limited Gaussian process (Shinozuka's spectral representation)
        f = np.sort(rng.uniform(case.f_lo, case.f_hi, 4 * f.size))
        amp = case.rms * np.sqrt(2.0 / f.size) * rng.rayleigh(1.0 / np.sqrt(2.0), f.size)
    return f, amp, rng.uniform(0.0, 2.0 * np.pi, f.size)


def independent_record(case: Case, seed: int, phase_seed: int = 0) -> tuple[np.ndarray, ...]:
    """``(t, u, y, w)``: the clean ``w`` from solve_ivp on the analytic input, ``y`` with noise of ``seed``.

    The multisine is faded in over its first 0.3 s (a smooth start from rest: the library's model takes
    ``u = 0`` before the first sample, as the experiment does).
    """
    t, u, w = _clean(case, phase_seed)
    rng = np.random.default_rng(10_000 + seed)
    y = w + case.noise * float(np.std(w)) * rng.standard_normal(t.size)
    return t, u, y, w


@functools.lru_cache(maxsize=16)
def _clean(case: Case, phase_seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The noise-free record (cached: the Monte-Carlo draws only new noise on one design)."""
    from scipy.integrate import solve_ivp  # type: ignore[import-untyped]
    from scipy.signal import tf2ss  # type: ignore[import-untyped]

    f, amp, ph = multisine(case, phase_seed)
    om = 2.0 * np.pi * f
    ramp = 0.3

    def u_of(t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        s = np.clip(tt / ramp, 0.0, 1.0)
        env = s * s * (3.0 - 2.0 * s)
        denv = np.where((tt > 0) & (tt < ramp), 6.0 * s * (1.0 - s) / ramp, 0.0)
        arg = np.outer(tt, om) + ph
        base = np.sin(arg) @ amp
        dbase = (np.cos(arg) * om) @ amp
        on = tt >= 0.0
        return np.where(on, env * base, 0.0), np.where(on, denv * base + env * dbase, 0.0)

    a, b, c, d = tf2ss(np.asarray(case.num), np.asarray(case.den))
    c, b = c.ravel(), b.ravel()
    dd = float(np.asarray(d).ravel()[0]) if np.size(d) else 0.0

    def rhs(t: float, z: np.ndarray) -> np.ndarray:
        v, vdot = u_of(t - case.delay)
        xs, w = z[:-1], z[-1]
        dxs = a @ xs + b * v[0]
        xdot = float(c @ dxs) + dd * vdot[0]
        aw = abs(w) ** case.mu
        wdot = xdot - case.beta * abs(xdot) * np.sign(w) * aw - case.gamma * xdot * aw
        return np.append(dxs, wdot)

    n = int(round(case.duration * case.fs))
    t = np.arange(n) / case.fs
    sol = solve_ivp(
        rhs, (0.0, t[-1]), np.zeros(a.shape[0] + 1), method="DOP853", t_eval=t, rtol=1e-10, atol=1e-12
    )
    w = sol.y[-1]
    u = u_of(t)[0]
    for a_ in (t, u, w):
        a_.setflags(write=False)
    return t, u, w


def _analytic_input(case: Case, phase_seed: int) -> Callable[[float], tuple[float, float, float]]:
    """``t -> (u, udot, uddot)`` of the faded-in multisine (0 before t = 0), analytic."""
    f, amp, ph = multisine(case, phase_seed)
    om = 2.0 * np.pi * f
    ramp = 0.3

    def u_of(t: float) -> tuple[float, float, float]:
        if t <= 0.0:
            return 0.0, 0.0, 0.0
        s = min(t / ramp, 1.0)
        env = s * s * (3.0 - 2.0 * s)
        denv = 6.0 * s * (1.0 - s) / ramp if t < ramp else 0.0
        ddenv = (6.0 - 12.0 * s) / ramp**2 if t < ramp else 0.0
        arg = om * t + ph
        sn, cs = np.sin(arg), np.cos(arg)
        base, dbase, ddbase = float(sn @ amp), float((cs * om) @ amp), float(-(sn * om * om) @ amp)
        return env * base, denv * base + env * dbase, ddenv * base + 2.0 * denv * dbase + env * ddbase

    return u_of


#: The terms' values of the bench's term rows (alpha = 1 units of the cases: y ~ 1, u ~ 1).
TERM_VALUES: dict[type[Term], float] = {
    Offset: 0.1,
    Stiffness: 0.3,
    Viscous: 0.01,
    Inertia: 2e-4,
    Coulomb: 0.05,
    SensorLag: 0.01,
    Asymmetry: 0.3,
    Play: 0.05,
    Degradation: 0.05,
    StiffnessDegradation: 0.1,
    Pinching: 0.3,
    StiffnessX: 0.3,
    ViscousX: 0.02,
    InertiaX: 2e-4,
    CoulombX: 0.05,
}


def clean_with_term(
    case: Case, kind: type[Term], value: float, phase_seed: int = 0
) -> tuple[np.ndarray, ...]:
    """:func:`clean_with_terms` with one term."""
    return clean_with_terms(case, ((kind, value),), phase_seed)


@functools.lru_cache(maxsize=64)
def clean_with_terms(
    case: Case, terms: tuple[tuple[type[Term], float], ...], phase_seed: int = 0
) -> tuple[np.ndarray, ...]:
    """``(t, u, y)``: the noise-free output of the case's plant with terms, by an integrator independent of
    the library's: solve_ivp (DOP853) on ``tf2ss`` of G with the terms' states (the energy of degradation,
    the sensor lag's output) and the analytic input; play by the exact play operator on a fine grid (64
    points per sample) of solve_ivp's x with Bouc-Wen integrated along the played path (RK4 in ``xp``: the
    element is rate independent; play only alone). Conventions as docs/design.md 9.4 (``Vmax`` the largest
    ``|udot|`` (``|xdot|`` for the friction on x) over the samples)."""
    from scipy.integrate import solve_ivp
    from scipy.signal import tf2ss

    u_of = _analytic_input(case, phase_seed)
    a, b, c, d = tf2ss(np.asarray(case.num), np.asarray(case.den))
    c, b = c.ravel(), b.ravel()
    dd = float(np.asarray(d).ravel()[0]) if np.size(d) else 0.0
    nx = a.shape[0]
    n = int(round(case.duration * case.fs))
    t = np.arange(n) / case.fs
    p = dict.fromkeys(TERM_VALUES, 0.0)
    for kind, value in terms:
        if kind not in TERM_VALUES:
            raise ValueError(f"the independent generator does not simulate the term {kind.kind!r}")
        p[kind] = value
    if p[Play] and len(terms) > 1:
        raise ValueError("the independent generator simulates play alone")
    beta, gamma, mu, delta = case.beta, case.gamma, case.mu, p[Asymmetry]
    w_u = (1.0 / (beta + gamma)) ** (1.0 / mu)

    def kin(tt: float, xs: np.ndarray) -> tuple[float, float, float, np.ndarray]:
        v, vd, vdd = u_of(tt - case.delay)
        dxs = a @ xs + b * v
        x = float(c @ xs) + dd * v
        xd = float(c @ dxs) + dd * vd
        xdd = float(c @ (a @ dxs + b * vd)) + dd * vdd
        return x, xd, xdd, dxs

    def rate(xpd: float, w: float, e: float) -> float:
        aw = abs(w) ** mu
        nu = 1.0 + p[Degradation] * e
        r = xpd - nu * (beta * abs(xpd) * np.sign(w) * aw + gamma * xpd * aw + delta * xpd * np.sign(w) * aw)
        r /= 1.0 + p[StiffnessDegradation] * e
        z = (w * np.sign(xpd) - PINCHING_CENTRE * w_u) / (PINCHING_WIDTH * w_u)
        return float(r * (1.0 - p[Pinching] * np.exp(-z * z)))

    vmax = max(abs(u_of(tk)[1]) for tk in t)
    eps = COULOMB_SMOOTHING
    xmax = 1.0

    def forcing(tt: float, xs: np.ndarray, w: float) -> float:
        uu, ud, udd = u_of(tt)
        x, xd, xdd, _ = kin(tt, xs)
        f = w + p[Stiffness] * uu + p[Viscous] * ud + p[Inertia] * udd
        f += p[Coulomb] * np.tanh(ud / (eps * vmax))
        f += p[StiffnessX] * x + p[ViscousX] * xd + p[InertiaX] * xdd
        return float(f + p[CoulombX] * np.tanh(xd / (eps * xmax)))

    if p[CoulombX]:  # the friction's scale: the largest |xdot| at the samples (a linear pass)
        lin = solve_ivp(
            lambda tt, z: kin(tt, z)[3],
            (0.0, t[-1]),
            np.zeros(nx),
            method="DOP853",
            t_eval=t,
            rtol=1e-10,
            atol=1e-12,
        )
        xmax = max(abs(kin(tk, lin.y[:, k])[1]) for k, tk in enumerate(t))
    if p[Play]:
        return _played(case, t, u_of, kin, p[Play], rate, nx)
    tau = p[SensorLag]

    def rhs(tt: float, z: np.ndarray) -> np.ndarray:
        xs, w, e, ys = z[:nx], z[nx], z[nx + 1], z[nx + 2]
        _, xd, _, dxs = kin(tt, xs)
        wd = rate(xd, w, e)
        ysd = (forcing(tt, xs, w) - ys) / tau if tau > 0 else 0.0
        return np.concatenate([dxs, [wd, w * xd, ysd]])

    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(nx + 3), method="DOP853", t_eval=t, rtol=1e-10, atol=1e-12)
    if tau > 0:
        y = sol.y[nx + 2].copy()
    else:
        y = np.array([forcing(tk, sol.y[:nx, k], sol.y[nx, k]) for k, tk in enumerate(t)])
    y += p[Offset]
    u = np.array([u_of(tk)[0] for tk in t])
    return t, u, y


def _played(
    case: Case,
    t: np.ndarray,
    u_of: Callable[[float], tuple[float, float, float]],
    kin: Callable[[float, np.ndarray], tuple[float, float, float, np.ndarray]],
    b: float,
    rate: Callable[[float, float, float], float],
    nx: int,
) -> tuple[np.ndarray, ...]:
    """Play: x on a fine grid by solve_ivp, the exact play operator on it, w by RK4 along the played path."""
    from scipy.integrate import solve_ivp

    fine = np.linspace(0.0, t[-1], (t.size - 1) * 64 + 1)
    lin = solve_ivp(
        lambda tt, z: kin(tt, z)[3],
        (0.0, t[-1]),
        np.zeros(nx),
        method="DOP853",
        t_eval=fine,
        rtol=1e-11,
        atol=1e-13,
    )
    x = np.array([kin(tk, lin.y[:, k])[0] for k, tk in enumerate(fine)])
    w, xp = 0.0, min(max(0.0, x[0] - b), x[0] + b)
    out = np.empty(t.size)
    for j in range(fine.size):
        if j % 64 == 0:
            out[j // 64] = w
        new = min(max(xp, x[j] - b), x[j] + b)
        dxp = new - xp
        if dxp != 0.0:
            k1 = rate(dxp, w, 0.0)
            k2 = rate(dxp, w + 0.5 * k1, 0.0)
            k3 = rate(dxp, w + 0.5 * k2, 0.0)
            k4 = rate(dxp, w + k3, 0.0)
            w += (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
        xp = new
    u = np.array([u_of(tk)[0] for tk in t])
    return t, u, out


def perturbed_start(case: Case, factor: float = 1.1) -> bw.WienerPlant:
    """The truth with every parameter off by ``factor`` (alternating up and down)."""
    num = np.array(case.num) * factor
    den = np.array(case.den)
    den[1:] = den[1:] / factor
    return bw.WienerPlant(
        bw.TransferFunction(num, den, case.delay * factor),
        bw.BoucWen(case.beta * factor, case.gamma / factor, case.mu / factor),
    )


def monte_carlo(case: Case, seeds: int, *, substeps: int = 2) -> dict[str, object]:
    """Fits over ``seeds`` noise draws on one design; returns the table's columns."""
    truth = case.plant()
    s = case.structure()
    t, u, _, w = independent_record(case, 0)
    sd = case.noise * float(np.std(w))
    names, crb = cramer_rao_bound(truth, (t, u, w), sd, structure=s, substeps=substeps)
    true_vec = s.pack(truth)[s.free]
    est = []
    seconds = []
    for seed in range(seeds):
        t, u, y, _ = independent_record(case, seed)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = bw.fit_time_domain(
                (t, u, y), start=perturbed_start(case), delay=s.delay, substeps=substeps, multistart=False
            )
        seconds.append(time.perf_counter() - t0)
        est.append(fit.parameters)
    e = np.array(est)
    return {
        "names": names,
        "truth": true_vec,
        "mean": e.mean(axis=0),
        "std": e.std(axis=0, ddof=1),
        "crb": np.sqrt(np.diag(crb)),
        "seconds": float(np.mean(seconds)),
        "estimates": e,
    }


#: The term rows: (case index, term) -- the terms on x on the resonant plant, the others on the first-order
#: plant with a delay (the terms on u with an exact regressor are tested in tests/test_timedomain.py).
TERM_ROWS: tuple[tuple[int, type[Term]], ...] = (
    (1, Coulomb),
    (1, SensorLag),
    (1, Asymmetry),
    (1, Play),
    (1, Degradation),
    (1, StiffnessDegradation),
    (1, Pinching),
    (0, StiffnessX),
    (0, ViscousX),
    (0, InertiaX),
    (0, CoulombX),
)


def term_plant(case: Case, kind: type[Term], value: float) -> bw.WienerPlant:
    p = case.plant()
    return bw.WienerPlant(p.linear, p.hysteresis, (kind(value),))  # type: ignore[call-arg]


def term_monte_carlo(case: Case, kind: type[Term], seeds: int, *, substeps: int = 2) -> dict[str, object]:
    """Fits of the plant with one term over ``seeds`` noise draws on data from :func:`clean_with_term`; the
    start is the truth perturbed by 10 % and the term at half its value."""
    value = TERM_VALUES[kind]
    truth = term_plant(case, kind, value)
    s = Structure(len(case.num) - 1, len(case.den) - 1, delay=case.delay > 0, terms=(kind,))
    t, u, y = clean_with_term(case, kind, value)
    sd = case.noise * float(np.std(y))
    names, crb = cramer_rao_bound(truth, (t, u, y), sd, structure=s, substeps=substeps)
    p0 = perturbed_start(case)
    start = bw.WienerPlant(p0.linear, p0.hysteresis, (kind(0.5 * value),))  # type: ignore[call-arg]
    est, inside, seconds = [], [], []
    for seed in range(seeds):
        rng = np.random.default_rng(20_000 + seed)
        yn = y + sd * rng.standard_normal(y.size)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = bw.fit_time_domain(
                (t, u, yn), start=start, delay=s.delay, substeps=substeps, multistart=False
            )
        seconds.append(time.perf_counter() - t0)
        est.append(fit.parameters)
        lo, hi = fit.interval(kind.symbol)
        inside.append(lo <= value <= hi)
    e = np.array(est)
    return {
        "names": names,
        "truth": s.pack(truth)[s.free],
        "mean": e.mean(axis=0),
        "std": e.std(axis=0, ddof=1),
        "crb": np.sqrt(np.diag(crb)),
        "seconds": float(np.mean(seconds)),
        "estimates": e,
        "inside": float(np.mean(inside)),
        "symbol": kind.symbol,
    }


def term_table(seeds: int) -> float:
    """The term rows; returns the largest SD/CRB ratio of the terms' parameters."""
    print(
        f"\n## the library's terms, one at a time ({seeds} seeds each; data: solve_ivp with the terms' "
        "states, play by the exact operator on a 64x finer grid)"
    )
    print(
        f"{'term':>22} {'plant':>6} {'truth':>9} {'mean':>9} {'emp. SD':>9} {'CRB SD':>9} {'ratio':>6} "
        f"{'bias/CRB':>8} {'in 95%':>6} {'worst other':>11} {'s/fit':>6}"
    )
    worst = 0.0
    for ci, kind in TERM_ROWS:
        case = CASES[ci]
        r = term_monte_carlo(case, kind, seeds)
        names: tuple[str, ...] = r["names"]  # type: ignore[assignment]
        i = names.index(str(r["symbol"]))
        ratio = r["std"] / r["crb"]  # type: ignore[operator]
        tr, mean, sd, crb = (float(r[k][i]) for k in ("truth", "mean", "std", "crb"))  # type: ignore[index]
        worst = max(worst, sd / crb)
        others = float(np.max(np.delete(ratio, i)))
        print(
            f"{kind.kind:>22} {'res.' if ci == 0 else '1st+d':>6} {tr:>9.4g} {mean:>9.4g} {sd:>9.3g} "
            f"{crb:>9.3g} "
            f"{sd / crb:>6.2f} {(mean - tr) / crb:>8.2f} {float(r['inside']):>6.0%} {others:>11.2f} "  # type: ignore[arg-type]
            f"{float(r['seconds']):>6.2f}"  # type: ignore[arg-type]
        )
    return worst


def sine_comparison() -> None:
    """The same sine recordings (library simulator) fed to identify and to fit_time_domain."""
    plant = bw.WienerPlant(bw.TransferFunction([400.0], [1.0, 8.0, 400.0]), bw.BoucWen(0.8, 0.2, 1.6))
    freqs = np.array([6.0, 12.0, 20.0, 30.0, 45.0])
    plan = bw.SinePlan(freqs, 1.0, settle_periods=8, periods=6, samples_per_period=128, noise_sd=0.01, seed=4)
    recs = bw.simulate(plant, plan)
    t0 = time.perf_counter()
    sine = bw.identify(recs, method="refined")
    t1 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = bw.fit_time_domain(recs, order=(0, 2))
    t2 = time.perf_counter()
    print(
        "\n## the same sine recordings: identify(method='refined') vs fit_time_domain(order=(0, 2)) "
        f"({t1 - t0:.1f} s vs {t2 - t1:.1f} s incl. its identify start; "
        f"whiteness p = {fit.adequacy.p_value:.2f})"
    )
    se = sine.standard_errors or {}
    print(f"{'':>6} {'truth':>6} {'identify':>20} {'fit_time_domain':>20}")
    for name, tr in (("beta", 0.8), ("gamma", 0.2), ("mu", 1.6)):
        a = f"{getattr(sine, name):.5f} +- {se[name]:.5f}"
        b = f"{fit.value(name):.5f} +- {fit.standard_errors[name]:.5f}"
        print(f"{name:>6} {tr:>6} {a:>20} {b:>20}")
    g = fit.plant.linear.freqresp(freqs)
    print(f"{'omega':>6} {'|G| identify':>20} {'|G| time':>9} {'phase identify':>20} {'phase time':>10}")
    for w_i, e, gi in zip(freqs, sine.experiments, g):
        a = f"{e.gain:.5f} +- {e.gain_se:.5f}"
        b = f"{e.phase:.5f} +- {e.phase_se:.5f}"
        print(f"{w_i:>6} {a:>20} {abs(gi):>9.5f} {b:>20} {(-np.angle(gi)) % (2 * np.pi):>10.5f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="6 seeds per plant (< 2 min)")
    parser.add_argument("--seeds", type=int, default=None)
    args = parser.parse_args(argv)
    seeds = args.seeds or (6 if args.quick else 30)
    print(f"# time-domain Wiener fit vs Cramer-Rao bound, {seeds} seeds per plant (data: solve_ivp DOP853)")
    worst = 0.0
    for case in CASES:
        r = monte_carlo(case, seeds)
        print(
            f"\n## {case.name}: G = {case.num}/{case.den}, delay {case.delay} s, multisine "
            f"{case.f_lo}-{case.f_hi} Hz, {case.duration} s at {case.fs} Hz, noise {case.noise:.0%} of y RMS;"
            " "
            f"{r['seconds']:.2f} s per fit"
        )
        print(
            f"{'param':>6} {'truth':>11} {'mean':>11} {'emp. SD':>10} {'CRB SD':>10} {'ratio':>6} "
            f"{'bias/CRB':>8}"
        )
        names: tuple[str, ...] = r["names"]  # type: ignore[assignment]
        for i, name in enumerate(names):
            tr, mean, sd, crb = (float(r[k][i]) for k in ("truth", "mean", "std", "crb"))  # type: ignore[index]
            worst = max(worst, sd / crb)
            print(
                f"{name:>6} {tr:>11.5g} {mean:>11.5g} {sd:>10.3g} {crb:>10.3g} {sd / crb:>6.2f} "
                f"{(mean - tr) / crb:>8.2f}"
            )
    print(f"\nlargest empirical SD / CRB SD: {worst:.2f}")
    term_worst = term_table(seeds)
    print(f"\nlargest empirical SD / CRB SD of a term's parameter: {term_worst:.2f}")
    sine_comparison()
    return 0


if __name__ == "__main__":
    sys.exit(main())

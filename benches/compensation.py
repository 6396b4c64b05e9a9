"""Feedforward hysteresis compensation (issue 21, item 1): tracking error on plants simulated another way.

Plants (alpha = 1, beta + gamma = 1: the hysteresis saturates at |w| = 1), each with a resonance and a delay:

- ``piezo``: a stage, ``G = wn^2/(s^2 + 2 zeta wn s + wn^2) exp(-T s)``, 150 Hz, zeta 0.1, T = 0.5 ms;
  Bouc-Wen beta 0.7, gamma 0.3, mu 1.3; sampled at 10 kHz; references at 70 % of saturation, 2-30 Hz.
- ``damper``: an MR-damper-like actuator with a non-minimum-phase zero,
  ``G = wn^2 (1 - s/z)/(s^2 + 2 zeta wn s + wn^2) exp(-T s)``, 25 Hz, zeta 0.25, z = 2 pi 60 rad/s,
  T = 2 ms; beta 1.5, gamma -0.5, mu 2; 4 kHz; references at 85 % of saturation, 0.5-6 Hz.
- ``piezo+terms``: the piezo with an augmented output ``y = y0 + Lag[w + k u + c udot]`` (offset 0.05,
  parallel stiffness 0.2, viscous damping 2e-4 s, sensor lag 0.2 ms): the compensator includes the terms.
  Its identified model: the augmented fit (``fit_augmented``) with the plant's terms given (which terms, not
  their values) on the same kind of noisy sine experiments as the piezo's, G then fitted to its (g, phi)
  points (``fit_transfer_function``); the plain ``identify`` refuses these data (mu -> 1: the viscous term
  beside the hysteresis), so the terms are what makes an identified model possible at all.

The plant is simulated here, not by the library: the command is interpolated by a cubic spline onto a grid
four times finer, G by ``scipy.signal.lsim`` (matrix exponentials) on the delayed spline, the hysteresis by
RK4 in the path variable (``dw/dx = h(w, sgn dx)``, exact for a rate-independent element between fine
points), the terms from the spline's exact derivatives, the lag by ``lsim``.  The identified models come
from noisy sine experiments on the same simulator (1 % of saturation, seeded), through ``bw.identify`` and
``fit_transfer_function``.

References: a sine, a multisine (5 tones, Schroeder phases) and a band-limited random signal (seeded),
each faded in over its first 10 % from rest.  The error is the RMS of ``y - y_ref`` over the last 80 %, in
% of the reference's RMS.  Commands compared on the same plant:

- ``none``: the reference scaled by the best static gain (no compensation);
- ``inverse linear``: ``G`` inverted (the same filter, preview and non-minimum-phase handling), then the
  hysteresis replaced by its best linear stand-in: a gain and a constant phase lead (``a r - b H[r]``, ``H``
  the Hilbert transform) fitted on the model to minimise the tracking error;
- ``true model`` / ``identified``: :func:`bouc_wen_id.compensate` on the true plant / the identified model.

Targets (issue 21): >= 10x less error than both baselines with the true model, >= 3x with the identified one.

Usage: ``python benches/compensation.py [--quick] [--seed S] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from typing import Any, Optional, Union

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.augmented import AugExperiment, AugParams, fit_augmented
from bouc_wen_id.terms import Offset, Place, SensorLag, Stiffness, Term, Viscous
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline
from scipy.signal import lsim

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi
FINE = 4  # fine grid per sample
NOISE = 0.01  # noise sd of the identification experiments (saturation at 1)
WINDOW = 0.2  # the error is measured after this share of the reference


@dataclass(frozen=True)
class Case:
    name: str
    plant: bw.WienerPlant
    fs: float
    level: float
    band: tuple[float, float]  # reference band, Hz
    sine_hz: float
    ident_hz: tuple[float, ...]


def cases() -> list[Case]:
    wn = TWO_PI * 150.0
    piezo_g = bw.TransferFunction([wn**2], [1.0, 2 * 0.1 * wn, wn**2], 0.0005)
    piezo = bw.WienerPlant(piezo_g, bw.BoucWen(0.7, 0.3, 1.3))
    wd, z = TWO_PI * 25.0, TWO_PI * 60.0
    damper_g = bw.TransferFunction([-(wd**2) / z, wd**2], [1.0, 2 * 0.25 * wd, wd**2], 0.002)
    damper = bw.WienerPlant(damper_g, bw.BoucWen(1.5, -0.5, 2.0))
    terms: tuple[Term, ...] = (Offset(0.05), Stiffness(0.2), Viscous(2e-4), SensorLag(2e-4))
    aug = bw.WienerPlant(piezo_g, piezo.hysteresis, terms)
    return [
        Case("piezo", piezo, 10000.0, 0.7, (2.0, 30.0), 10.0, (5.0, 20.0, 60.0, 110.0, 150.0, 200.0)),
        Case("damper", damper, 4000.0, 0.85, (0.5, 6.0), 2.0, (1.0, 3.0, 8.0, 18.0, 25.0, 35.0)),
        Case("piezo+terms", aug, 10000.0, 0.7, (2.0, 30.0), 10.0, (5.0, 20.0, 60.0, 110.0, 150.0, 200.0)),
    ]


# ------------------------------------------------------------------------------------------------------
# The independent plant


def _path_rk4(x: FloatArray, hy: bw.BoucWen) -> FloatArray:
    """Bouc-Wen along the path x by RK4 in x: ``dw/dx = alpha - |w|^mu (beta sgn(dx w) + gamma)``."""
    a, b, g, mu = hy.alpha, hy.beta, hy.gamma, hy.mu
    out = np.empty_like(x)
    w = hy.w0
    out[0] = w
    dxs = np.diff(x)

    def f(v: float, s: float) -> float:
        return a - abs(v) ** mu * (b * s * (1.0 if v > 0 else -1.0 if v < 0 else 0.0) + g)

    for i, dx in enumerate(dxs.tolist()):
        s = 1.0 if dx > 0 else -1.0
        k1 = f(w, s) * dx
        k2 = f(w + 0.5 * k1, s) * dx
        k3 = f(w + 0.5 * k2, s) * dx
        k4 = f(w + k3, s) * dx
        w += (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
        out[i + 1] = w
    return out


def plant_output(plant: bw.WienerPlant, t: FloatArray, u: FloatArray) -> FloatArray:
    """The plant's noise-free output at the samples, simulated without the library."""
    dt = float(t[1] - t[0])
    tf = np.arange((t.size - 1) * FINE + 1) * (dt / FINE)
    spline = CubicSpline(t, u)
    lin = plant.linear
    td = tf - lin.delay
    ud = np.where(td >= 0.0, spline(np.maximum(td, 0.0)), 0.0)
    _, x, _ = lsim((lin.num, lin.den), ud, tf)
    w = _path_rk4(np.concatenate(([0.0], np.asarray(x))), plant.hysteresis)[1:]
    v = w + 0.0
    xf = np.asarray(x)
    for term in plant.terms:
        if term.place == Place.X and isinstance(term, Stiffness):
            v = v + term.k * xf
        elif term.place == Place.X and isinstance(term, Viscous):
            v = v + term.c * np.gradient(xf, tf, edge_order=2)
        elif isinstance(term, Stiffness):
            v = v + term.k * spline(tf)
        elif isinstance(term, Viscous):
            v = v + term.c * spline(tf, 1)
    lag = next((t for t in plant.terms if isinstance(t, SensorLag)), None)
    if isinstance(lag, SensorLag) and lag.tau > 0:
        _, v, _ = lsim(([1.0], [lag.tau, 1.0]), v, tf, X0=[v[0] / 1.0 * lag.tau])
    off = next((t for t in plant.terms if isinstance(t, Offset)), None)
    y0 = off.y0 if isinstance(off, Offset) else 0.0
    return np.asarray(v[::FINE] + y0)


def identified(case: Case, seed: int, periods: int) -> Union[bw.IdentificationResult, bw.WienerPlant]:
    """Noisy sine experiments on the independent plant, identified by the library: ``bw.identify`` for a
    plain plant; for an augmented one, the augmented fit with the plant's terms (their values unknown,
    :func:`identified_augmented`)."""
    recs = recordings(case, seed, periods)
    if not case.plant.terms:
        return bw.identify(recs)
    return identified_augmented(case, recs)


def recordings(case: Case, seed: int, periods: int) -> list[bw.Recording]:
    """Sine experiments (latent amplitude 1.8: saturating loops) with white noise of sd NOISE, seeded."""
    rng = np.random.default_rng(seed)
    recs = []
    p = 256
    settle = 8
    for hz in case.ident_hz:
        om = TWO_PI * hz
        g = abs(complex(case.plant.linear(1j * om)))
        amp = 1.8 / g  # the latent amplitude |x| = 1.8: saturating loops
        n = (settle + periods) * p
        t = np.arange(n) * (1.0 / hz / p)
        u = amp * np.cos(om * t)
        y = plant_output(case.plant, t, u) + NOISE * rng.standard_normal(n)
        recs.append(bw.Recording(t, u, y, amp, om, settle_periods=settle))
    return recs


def identified_augmented(case: Case, recs: list[bw.Recording]) -> bw.WienerPlant:
    """The augmented model with ``case.plant``'s terms (which terms: known; their values, the Bouc-Wen
    parameters and each experiment's (g, phi): fitted jointly by ``fit_augmented`` on the averaged steady
    periods), then G fitted to the (g, phi) points by ``fit_transfer_function``: the model ``compensate``
    inverts, terms included. The plain ``identify`` cannot start it: on these data (a viscous term beside
    the hysteresis) it drives mu to 1 and refuses. Start read off the loops, nothing from the truth: the
    saturation level at 0.8 of the median half peak-to-peak, mu 1.5, each phase the fundamental's lag of
    ybar, the latent amplitude at 2 and 5 saturation levels (the lower cost kept)."""
    exps = []
    for r in recs:
        p, s = int(r.samples_per_period), int(r.settle_periods)
        n = int(r.whole_periods) - s
        rows = np.asarray(r.y[s * p : (s + n) * p]).reshape(n, p)
        exps.append(
            AugExperiment(
                ybar=rows.mean(axis=0),
                amplitude=float(r.amplitude),
                frequency=float(r.frequency),
                grid_phase=float(np.mod(r.frequency * float(r.t[0]), TWO_PI)),
                weight=n / NOISE**2,
            )
        )
    kinds = tuple(t.kind for t in case.plant.terms)
    fy = 0.8 * float(np.median([0.5 * np.ptp(e.ybar) for e in exps]))
    mu = 1.5
    sat = fy ** (-mu)
    phases = np.array([-float(np.angle(np.fft.rfft(e.ybar)[1])) + e.grid_phase for e in exps])
    best = None
    for reach in (2.0, 5.0):
        gains = np.array([reach * fy / abs(e.amplitude) for e in exps])
        start = AugParams(0.6 * sat, 0.4 * sat, mu, kinds, np.zeros(len(kinds)), gains, phases)
        try:
            cand = fit_augmented(exps, start)
        except bw.BoucWenIdError:
            continue
        if best is None or cand.cost < best.cost:
            best = cand
    if best is None:
        raise RuntimeError("the augmented fit failed from every start")
    fit = best.params
    omega = np.array([e.frequency for e in exps])
    g = bw.fit_transfer_function(omega=omega, response=fit.gains * np.exp(-1j * fit.phases)).transfer_function
    terms = tuple(bw.terms.TERMS[k](v) for k, v in zip(fit.terms, fit.values))  # type: ignore[call-arg]
    return bw.WienerPlant(g, bw.BoucWen(fit.beta, fit.gamma, fit.mu), terms)


# ------------------------------------------------------------------------------------------------------
# References and commands


def references(case: Case, seconds: float, seed: int) -> dict[str, tuple[FloatArray, FloatArray]]:
    n = int(round(seconds * case.fs))
    t = np.arange(n) / case.fs
    fade = np.minimum(t / (0.1 * seconds), 1.0) ** 2 * (3.0 - 2.0 * np.minimum(t / (0.1 * seconds), 1.0))
    lo, hi = case.band
    tones = np.geomspace(lo, hi, 5)
    ms = sum(np.cos(TWO_PI * f * t + math.pi * k * (k + 1) / 5) for k, f in enumerate(tones))
    rng = np.random.default_rng(seed)
    spec = np.fft.rfft(rng.standard_normal(4 * n))
    freqs = np.fft.rfftfreq(4 * n, 1.0 / case.fs)
    spec[(freqs < lo) | (freqs > hi)] = 0.0
    rnd = np.fft.irfft(spec, 4 * n)[:n]
    out = {}
    for name, sig in (("sine", np.sin(TWO_PI * case.sine_hz * t)), ("multisine", ms), ("random", rnd)):
        sig = fade * sig
        out[name] = (t, case.level * sig / np.max(np.abs(sig)))
    return out


def _fit_gain(model: bw.WienerPlant, t: FloatArray, u: FloatArray, target: FloatArray) -> float:
    """The gain a minimising ``|Y(a u) - target|`` (two secant rounds on the model)."""
    a = 1.0
    for _ in range(3):
        _, _, y = bw.simulate_input(model, t, a * u, output=True)
        y = y - y[0]
        a *= float(np.dot(target, target) / max(np.dot(y, target), 1e-300))
    return a


def _best_linear(model: bw.WienerPlant, t: FloatArray, dyn: FloatArray, target: FloatArray) -> FloatArray:
    """``a dyn - b H[dyn]`` (H the Hilbert transform: a constant phase lead) with ``(a, b)`` minimising the
    model's tracking error: the best linear compensator with the hysteresis as a describing function."""
    from scipy.optimize import least_squares
    from scipy.signal import hilbert

    quad = np.imag(hilbert(dyn))
    k = int(WINDOW * t.size)

    def res(p: FloatArray) -> FloatArray:
        _, _, y = bw.simulate_input(model, t, p[0] * dyn - p[1] * quad, output=True)
        return np.asarray((y - y[0] - target)[k:])

    a0 = _fit_gain(model, t, dyn, target)
    p = least_squares(res, [a0, 0.0], diff_step=1e-4, max_nfev=60).x
    return np.asarray(p[0] * dyn - p[1] * quad)


def baselines(model: bw.WienerPlant, t: FloatArray, y_ref: FloatArray) -> dict[str, FloatArray]:
    """No compensation (best static gain) and the inverse linear model (G inverted, then the best gain and
    constant phase lead for the hysteresis, fitted on the model)."""
    from bouc_wen_id.compensation import _invert_linear, _linear_inverse

    off = next((t for t in model.terms if isinstance(t, Offset)), None)
    y0 = off.y0 if isinstance(off, Offset) else 0.0
    target = y_ref - y0
    dt = float(t[1] - t[0])
    g0 = float(np.real(model.linear(0.0)))
    static = target / g0
    inv = _linear_inverse(model.linear, bw.compensation._default_cutoff(y_ref, dt), "stable")
    dyn = _invert_linear(inv, target, dt, model.linear.delay)
    return {
        "none": _fit_gain(model, t, static, target) * static,
        "inverse linear": _best_linear(model, t, dyn, target),
    }


def error(plant: bw.WienerPlant, t: FloatArray, u: FloatArray, y_ref: FloatArray) -> float:
    y = plant_output(plant, t, u)
    k = int(WINDOW * t.size)
    e = (y - y_ref)[k:]
    return float(100.0 * np.sqrt(np.mean(e**2)) / np.sqrt(np.mean((y_ref[k:] - y_ref[k:].mean()) ** 2)))


def run_case(case: Case, quick: bool, seed: int) -> list[dict[str, Any]]:
    seconds = (3.0 if case.name == "damper" else 0.6) * (1 if quick else 2)
    ident: Union[None, bw.IdentificationResult, bw.WienerPlant] = None
    t0 = time.perf_counter()
    if case.ident_hz:
        ident = identified(case, seed, 6 if quick else 16)
    t_ident = time.perf_counter() - t0
    rows = []
    for ref_name, (t, y_ref) in references(case, seconds, seed).items():
        row: dict[str, Any] = {"plant": case.name, "reference": ref_name}
        for name, u in baselines(case.plant, t, y_ref).items():
            row[name] = error(case.plant, t, u, y_ref)
        t1 = time.perf_counter()
        comp = bw.compensate(case.plant, y_ref, t)
        row["compensate s"] = time.perf_counter() - t1
        row["true model"] = error(case.plant, t, comp.u, y_ref)
        row["predicted"] = 100.0 * comp.tracking_error
        row["choices"] = comp.choices
        if ident is not None:
            ci = bw.compensate(ident, y_ref, t)
            row["identified"] = error(case.plant, t, ci.u, y_ref)
            row["identified model"] = ci.choices["model"] + (
                f" (augmented fit, terms known: {describe(ident)})"
                if isinstance(ident, bw.WienerPlant)
                else ""
            )
            row["identify s"] = t_ident
        rows.append(row)
    return rows


def describe(plant: bw.WienerPlant) -> str:
    h = plant.hysteresis
    parts = [f"beta {h.beta:.4g}, gamma {h.gamma:.4g}, mu {h.mu:.4g}"]
    parts += [f"{t.kind} {t.value:.4g}" for t in plant.terms]
    g = plant.linear
    parts.append(f"G {g.num.size - 1} zero(s) {g.den.size - 1} pole(s), delay {g.delay:.4g} s")
    return "; ".join(parts)


def table(rows: list[dict[str, Any]]) -> str:
    head = (
        f"{'plant':12} {'reference':10} {'none %':>8} {'lin.inv %':>9} {'true %':>8} {'ident %':>8} "
        f"{'x none':>7} {'x lin':>7} {'xi none':>7} {'xi lin':>7}  meets"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        base = min(r["none"], r["inverse linear"])
        true_ratio = base / r["true model"]
        ident = r.get("identified", math.nan)
        ident_ratio = base / ident if ident == ident else math.nan
        meets = true_ratio >= 10 and (ident_ratio != ident_ratio or ident_ratio >= 3)
        lines.append(
            f"{r['plant']:12} {r['reference']:10} {r['none']:8.3g} {r['inverse linear']:9.3g} "
            f"{r['true model']:8.3g} {ident:8.3g} {r['none'] / r['true model']:7.1f} "
            f"{r['inverse linear'] / r['true model']:7.1f} {r['none'] / ident:7.1f} "
            f"{r['inverse linear'] / ident:7.1f}  {'yes' if meets else 'NO'}"
        )
    return "\n".join(lines)


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter references and identification experiments")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None, help="write the rows here")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    rows: list[dict[str, Any]] = []
    for case in cases():
        rows += run_case(case, args.quick, args.seed)
        print(f"[{case.name}: done at {time.perf_counter() - start:.0f} s]", file=sys.stderr)
    print(table(rows))
    print()
    for r in rows:
        if r["reference"] == "sine":
            print(f"{r['plant']}: " + "; ".join(f"{k}: {v}" for k, v in r["choices"].items()))
            if "identified model" in r:
                print(f"  identified: {r['identified model']}")
    print(
        f"\ntotal {time.perf_counter() - start:.0f} s ({'quick' if args.quick else 'full'}, seed {args.seed})"
    )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1, default=str)
    return 0


if __name__ == "__main__":
    sys.exit(main())

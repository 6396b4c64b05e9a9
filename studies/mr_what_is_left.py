"""MR damper: what is left after the diagnosis (issue 18), with numbers.

The issue asks for a held-out NRMSE <= 0.03 at every coil current with the same named physics at every level.
This study measures, per current level (the six files of ``../shared/data/real/mr-damper-utfsm`` diagnosed
jointly, as ``studies/diagnose_real.py`` groups them):

1. **The floor**: the held-out NRMSE a perfect model would get given the data's own period-to-period
   spread and the preprocessing. The averaged period's error is estimated by averaging each half of the
   steady stretch separately (``|ybar_1 - ybar_2| / 2``: white noise, chatter and any drift between the
   halves), beside the averaging's own noise (``(2K+1) sigma^2 / n`` per grid point); the harmonics cut by
   the averaging (``K`` kept) are measured on the stretch up to harmonic 120 (or the record's Nyquist).
2. **Where the misfit sits**: the diagnosis's final model's residual on the averaged periods, per
   experiment: its energy by harmonic (DC, odd, even, above 5) and by phase of the cycle counted from the
   last reversal of the input (the concentration: the share of the residual energy in a zone over the
   zone's share of the cycle).
3. **Which extension closes it**, as forced fits (the diagnosis's selection is not changed): (a) common
   term sets from the library, Spencer's model among them (offset ``-k1 x0``, ``stiffness@x`` = k1,
   ``series_dashpot`` = 1/c1, ``viscous`` ~ c0, with the asymmetry), each with its leave-one-experiment-out
   NRMSE as the diagnosis computes it; (b) the Bouc-Wen element with its condition beta >= |gamma| relaxed
   (a local bounded least-squares on the library's exact outputs and Jacobians: diagnostic only); (c) a
   Dahl friction element across the hysteretic element when the installed build has the term
   (``dahl@x``); (d) the time-domain fit on the raw records (``bw.fit_time_domain``, one shared gain and
   delay, Spencer's terms), which does not rely on averaging.
4. **Whether parameters move smoothly with current** under one term set forced at every level: values with
   their standard errors, the element's saturation force, and the held-out NRMSE per level; and the yield
   travel the free per-experiment gain implies (``w_u / |g_i|``), which a rate-independent element with
   ``x = u`` would hold fixed.

Nothing here is random (no draws; the fits are deterministic from the library's own starts), so a rerun on
the same code prints the same tables. Usage: ``python studies/mr_what_is_left.py [--data DIR] [--levels
0,0.25,...] [--no-time-domain] [--json OUT]``; about 4-5 minutes on two shared cores.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Optional

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.augmented import AugExperiment, AugFit, AugParams, augmented_output
from bouc_wen_id.diagnosis.fitting import (
    Scale,
    fit_from,
    fit_own,
    fit_with,
    physical,
    scaled,
    subset,
    substeps_for,
)
from bouc_wen_id.diagnosis.select import folds, held_out
from bouc_wen_id.errors import BoucWenIdError
from bouc_wen_id.signal._harmonic_ls import harmonic_basis
from bouc_wen_id.terms import TERMS
from scipy.optimize import least_squares

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # the sibling modules import by name (studies/ is not a package)
    sys.path.insert(0, str(HERE))
TARGET = 0.03
#: Phase zones of the cycle, degrees after the last reversal of the input (u = U cos z reverses at z = 0, pi).
ZONES = ((0, 15), (15, 45), (45, 135), (135, 165), (165, 180))
ZONE_NAMES = ("0-15 after rev.", "15-45", "45-135 mid-stroke", "135-165", "165-180 before rev.")
#: Highest harmonic measured on the raw stretch for the truncation floor.
HIGH_HARMONIC = 120
#: The forced common term sets (3a, 4). Spencer: offset = -k1 x0, stiffness@x = k1, series_dashpot = 1/c1,
#: viscous ~ c0 (c0 << c1: to first order a dashpot across the whole damper), asymmetry for the MR loop's
#: unequal branches.
SETS: tuple[tuple[str, ...], ...] = (
    ("viscous", "asymmetry"),
    ("offset", "viscous", "asymmetry"),
    ("offset", "viscous", "asymmetry", "stiffness@x"),
    ("offset", "viscous", "asymmetry", "stiffness@x", "series_dashpot"),
    ("offset", "viscous", "asymmetry", "stiffness@x", "series_dashpot", "viscous@x"),
    ("offset", "viscous", "asymmetry", "stiffness@x", "coulomb"),
)
#: The set of part 4 (Spencer's terms) and of the relaxed-element and time-domain checks.
COMMON = SETS[3]
RELAXED_SET = SETS[1]
DAHL_SETS: tuple[tuple[str, ...], ...] = (SETS[1] + ("dahl@x",), SETS[3] + ("dahl@x",))


def _adapters() -> Any:
    """The data sets' adapters (the sibling ``_adapters.py``)."""
    import _adapters

    return _adapters


def load_levels(data: Path, levels: Optional[Sequence[float]]) -> list[tuple[str, list[bw.Measurement]]]:
    """(label, the six files' Measurements) per coil current."""
    A = _adapters()
    blocks = [A.load_mr_damper(data / A.DATASETS["mr-damper"] / f) for f in A.MR_FILES]
    out = []
    for k, current in enumerate(A.MR_CURRENTS):
        if levels is None or any(abs(current - c) < 1e-9 for c in levels):
            out.append((f"{current:g} A", [b[k] for b in blocks]))
    return out


def _quiet(fn: Any, *a: Any, **kw: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*a, **kw)


def _median(v: Sequence[float]) -> float:
    return float(np.median(np.asarray(v, dtype=np.float64))) if len(v) else math.nan


# ------------------------------------------------------------------------------------------------------
# 1. The floor


def _harmonic_fit(th: np.ndarray, y: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    basis = harmonic_basis(th, k)
    sol = np.linalg.lstsq(basis, y, rcond=None)[0]
    return sol, y - basis @ sol


def floor_of(m: bw.Measurement) -> dict[str, float]:
    """The averaged period's own error over its spread (split halves and averaging noise), and the
    harmonics the averaging cuts."""
    ap = _quiet(bw.average_measurement, m)[0]
    t = m.t[ap.start : ap.stop] - ap.time_origin
    y = m.y[ap.start : ap.stop]
    th = ap.frequency * t
    k, p = ap.harmonics, ap.ybar.size
    grid = 2.0 * math.pi * np.arange(p) / p
    spread = float(np.linalg.norm(ap.ybar - ap.ybar.mean()))
    whole = math.floor((th[-1] - th[0]) / (2.0 * math.pi) / 2.0)
    first = th < th[0] + 2.0 * math.pi * whole
    s1, _ = _harmonic_fit(th[first], y[first], k)
    s2, _ = _harmonic_fit(th[~first], y[~first], k)
    g = harmonic_basis(grid, k)
    split = float(np.linalg.norm(g @ (s1 - s2))) / 2.0 / spread
    noise = math.sqrt(p * (2 * k + 1) * ap.noise_var / y.size) / spread
    per_period = 2.0 * math.pi / (ap.frequency * (m.t[1] - m.t[0]))
    kbig = int(min(HIGH_HARMONIC, per_period / 2.0 - 2.0))
    cut = 0.0
    if kbig > k:
        sb, rb = _harmonic_fit(th, y, kbig)
        c = sb[1::2] + 1j * sb[2::2]
        noise_c = 4.0 * float(rb @ rb) / (y.size - (2 * kbig + 1)) / y.size
        # The noise's expected power taken off the sum (per harmonic, clipping would leave a bias).
        excess = float(np.sum(np.abs(c[k:]) ** 2)) - noise_c * (kbig - k)
        cut = math.sqrt(max(excess, 0.0) / float(np.sum(np.abs(c[:k]) ** 2)))
    return {
        "harmonics": float(k),
        "samples_per_period": per_period,
        "periods": float(ap.periods),
        "split_half": split,
        "noise": noise,
        "cut": cut,
        "floor": math.hypot(max(split, noise), cut),
    }


def beyond_nyquist(m: bw.Measurement, k: int) -> float:
    """Energy above harmonic ``k`` relative to harmonics 1..k on a finely sampled record: a proxy for what
    a record sampled at 2k + 1 points per period (the 5 Hz file) cannot hold."""
    ap = _quiet(bw.average_measurement, m)[0]
    th = ap.frequency * (m.t[ap.start : ap.stop] - ap.time_origin)
    sol, _ = _harmonic_fit(th, m.y[ap.start : ap.stop], HIGH_HARMONIC)
    c = np.abs(sol[1::2] + 1j * sol[2::2]) ** 2
    return math.sqrt(float(c[k:].sum() / c[:k].sum()))


# ------------------------------------------------------------------------------------------------------
# 2. Where the misfit sits


def localise(e: AugExperiment, y: np.ndarray) -> dict[str, Any]:
    """The residual's energy by harmonic and by phase of the cycle (concentration per zone)."""
    r = e.ybar - y
    p = r.size
    z = 2.0 * math.pi * np.arange(p) / p + e.grid_phase
    a = np.mod(np.degrees(z), 180.0)
    a[a >= 180.0] = 0.0  # a reversal that rounds up to 180 degrees is the reversal itself
    c = np.fft.rfft(r) / p
    en = np.abs(c) ** 2
    en[1:] *= 2.0
    tot = float(en.sum())
    conc = []
    for lo, hi in ZONES:
        sel = (a >= lo) & (a < hi)
        conc.append(float(r[sel] @ r[sel]) / float(r @ r) / float(sel.mean()))
    return {
        "nrmse": float(np.linalg.norm(r) / np.linalg.norm(e.ybar - e.ybar.mean())),
        "dc": float(en[0]) / tot,
        "odd": float(en[1::2].sum()) / tot,
        "even": float(en[2::2].sum()) / tot,
        "h1": float(en[1]) / tot,
        "h2_5": float(en[2:6].sum()) / tot,
        "above5": float(en[6:].sum()) / tot,
        "zones": conc,
    }


# ------------------------------------------------------------------------------------------------------
# 3a / 4. Forced term sets


@dataclass
class Level:
    label: str
    ms: list[bw.Measurement]
    diagnosis: Any
    scale: Scale
    sx: list[AugExperiment]
    substeps: int


@dataclass
class PlainOnly:
    """The part of a Diagnosis the forced fits need, without running the selection (``--dahl-only``)."""

    experiments: list[Any]
    plain_fit: AugFit
    settings: dict[str, Any]


def prepare_level(label: str, ms: list[bw.Measurement], diagnose: bool = True) -> Level:
    """The level's diagnosis (or only its plain fit) and its experiments as the diagnosis scaled them."""
    d: Any
    if diagnose:
        d = _quiet(bw.diagnose, ms, y_unit="N", u_unit="mm")
    else:
        from bouc_wen_id.diagnosis.data import prepare
        from bouc_wen_id.diagnosis.fitting import fit_plain, scale_of

        exps = _quiet(prepare, ms)
        sc = scale_of(exps)
        sx0 = scaled(exps, sc)
        plain = _quiet(fit_plain, exps, sx0, sc, substeps_for([e.ybar.size for e in sx0]))
        d = PlainOnly(exps, plain, {"scale": {"y": sc.y, "u": sc.u}})
    s = Scale(**d.settings["scale"])
    sx = scaled(list(d.experiments), s)
    return Level(label, ms, d, s, sx, substeps_for([e.ybar.size for e in sx]))


def forced(lv: Level, terms: Sequence[str]) -> Optional[AugFit]:
    """The plain fit plus ``terms``, added in order from the diagnosis's own starts for each."""
    f: AugFit = lv.diagnosis.plain_fit
    for term in terms:
        if term in f.params.terms:
            continue
        g = _quiet(fit_with, lv.sx, f, term, lv.substeps)
        if g is None:
            return None
        f = g
    return f


def held_out_nrmse(lv: Level, fit: AugFit) -> tuple[float, ...]:
    ho = _quiet(held_out, lv.sx, lv.diagnosis.plain_fit, fit, lv.substeps)
    return tuple(ho.nrmse_after) if ho is not None else ()


def saturation_force(p: AugParams, s: Scale) -> float:
    """The element's saturation level ``(beta + gamma)^(-1/mu)`` in N (alpha = 1)."""
    return float((p.beta + p.gamma) ** (-1.0 / p.mu) * s.y)


def term_values(fit: AugFit, s: Scale) -> dict[str, tuple[float, float]]:
    return {t: physical(fit, s, t) for t in fit.params.terms}


# ------------------------------------------------------------------------------------------------------
# 3b. beta >= |gamma| relaxed (diagnostic only)


def _vector(p: AugParams) -> np.ndarray:
    own = np.column_stack([p.gains, p.phases]).ravel()
    return np.concatenate([[p.beta, p.gamma, max(p.mu, 1.0 + 1e-4)], p.values, own])


def relaxed_fit(sx: Sequence[AugExperiment], start: AugParams, substeps: int) -> tuple[AugParams, float]:
    """Bounded least squares (scipy's trf) on the library's exact outputs and Jacobians with only
    ``1 < mu <= 10`` bounded: beta and gamma free (beta + gamma > 0 for a saturating loop; a step that
    leaves it is refused by the core and costed as a wall)."""
    nt, n = len(start.terms), sum(e.ybar.size for e in sx)

    def unpack(v: np.ndarray) -> AugParams:
        g, ph = v[3 + nt :: 2].copy(), v[4 + nt :: 2].copy()
        return AugParams(v[0], v[1], v[2], start.terms, v[3 : 3 + nt], g, ph)

    memo: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def evaluate(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        key = v.tobytes()
        if key not in memo:
            memo.clear()
            r, jac, row = np.empty(n), np.zeros((n, v.size)), 0
            try:
                for i, e in enumerate(sx):
                    o = augmented_output(e, unpack(v), i, substeps=substeps, jacobian=True)
                    w, p = math.sqrt(e.weight), e.ybar.size
                    r[row : row + p] = w * (o.y - e.ybar)
                    jac[row : row + p, : 3 + nt] = w * o.jacobian
                    jac[row : row + p, 3 + nt + 2 * i : 5 + nt + 2 * i] = w * o.own_jacobian
                    row += p
            except BoucWenIdError:
                r, jac = np.full(n, 1e8), np.zeros((n, v.size))
            memo[key] = (r, jac)
        return memo[key]

    best: Optional[tuple[AugParams, float]] = None
    total = start.beta + start.gamma
    for ratio in (None, 2.0, 5.0):  # the start itself, then gamma = 2 and 5 times beta at its saturation
        st = (
            start
            if ratio is None
            else replace(start, beta=total / (1 + ratio), gamma=total * ratio / (1 + ratio))
        )
        v0 = _vector(st)
        lo, hi = np.full(v0.size, -np.inf), np.full(v0.size, np.inf)
        lo[2], hi[2] = 1.0 + 1e-6, 10.0
        res = least_squares(
            lambda v: evaluate(v)[0],
            v0,
            jac=lambda v: evaluate(v)[1],
            bounds=(lo, hi),
            x_scale="jac",
            max_nfev=60,
        )
        cost = float(res.fun @ res.fun)
        if best is None or cost < best[1]:
            best = (unpack(res.x), cost)
    assert best is not None
    return best


def relaxed_held_out(lv: Level, start: AugParams) -> tuple[float, ...]:
    """Leave-one-experiment-out NRMSE of the relaxed element (physics on the others, then own g, phi)."""
    out = []
    for j in folds(len(lv.sx)):
        keep = [i for i in range(len(lv.sx)) if i != j]
        sub, st = subset(lv.sx, start, keep)
        par, _ = relaxed_fit(sub, st, lv.substeps)
        e = lv.sx[j]
        _, y = _quiet(fit_own, e, par, float(start.gains[j]), float(start.phases[j]), lv.substeps)
        out.append(float(np.linalg.norm(e.ybar - y) / np.linalg.norm(e.ybar - e.ybar.mean())))
    return tuple(out)


# ------------------------------------------------------------------------------------------------------
# 3d. The time-domain fit on the raw records


#: Periods of each record's steady stretch fitted in the time domain (the first half period is G's and the
#: element's settling from the estimated initial state: ``estimate_w0``).
TD_PERIODS = 2.5
TD_MAX_ITER = 40


def time_domain(lv: Level, fit: AugFit) -> dict[str, Any]:
    """``fit_time_domain`` on each file's first ``TD_PERIODS`` steady periods (raw samples, no averaging),
    one shared gain and delay (the measured displacement is the damper's), ``fit``'s terms, from ``fit``'s
    values; per record the raw NRMSE and the raw noise over the record's spread."""
    s, p = lv.scale, fit.params
    gain = float(np.median(np.abs(p.gains))) * s.y / s.u
    hyst = bw.BoucWen(beta=p.beta / s.y**p.mu, gamma=p.gamma / s.y**p.mu, mu=p.mu)
    terms = tuple(TERMS[t](physical(fit, s, t)[0]) for t in p.terms)
    plant = bw.WienerPlant(bw.TransferFunction([gain], [1.0], delay=0.01), hyst, terms)
    recs, noise = [], []
    for m in lv.ms:
        ap = _quiet(bw.average_measurement, m)[0]
        step = float(m.t[1] - m.t[0])
        a = ap.start
        b = min(ap.stop, a + int(round(TD_PERIODS * 2.0 * math.pi / ap.frequency / step)))
        y = m.y[a:b]
        recs.append((m.t[a:b] - m.t[a], m.u[a:b] - ap.offset_u, y))
        noise.append(math.sqrt(ap.noise_var) / float(np.std(y)))
    t0 = time.perf_counter()
    td = _quiet(
        bw.fit_time_domain,
        recs,
        start=plant,
        delay=True,
        estimate_w0=True,
        terms=p.terms,
        max_iter=TD_MAX_ITER,
        multistart=False,
    )
    names = list(td.parameter_names)
    par = dict(zip(names, (float(v) for v in td.parameters)))
    return {
        "nrmse": list(td.nrmse),
        "noise": noise,
        "model": [math.sqrt(max(a * a - b * b, 0.0)) for a, b in zip(td.nrmse, noise)],
        "beta": par.get("beta", math.nan),
        "gamma": par.get("gamma", math.nan),
        "mu": par.get("mu", math.nan),
        "reason": str(td.reason),
        "at_bound": list(td.at_bound),
        "seconds": time.perf_counter() - t0,
    }


# ------------------------------------------------------------------------------------------------------
# Printing


def _fmt(v: float, nd: int = 3) -> str:
    return "-" if not math.isfinite(v) else f"{v:.{nd}f}"


def print_floor(
    rows: dict[str, list[dict[str, float]]], today: dict[str, tuple[float, ...]], proxy: float
) -> None:
    print("\n## 1. The floor: the averaged period's own error over its spread (per experiment)\n")
    print(
        "| level | split halves (median; max) | averaging noise (median; max) | harmonics cut | "
        "floor median | "
        "today's held-out median (max) | median / floor |"
    )
    print("|---|---|---|---|---|---|---|")
    for lab, fl in rows.items():
        sp = [r["split_half"] for r in fl]
        nz = [r["noise"] for r in fl]
        cut = max(r["cut"] for r in fl)
        flo = _median([r["floor"] for r in fl])
        ho = today.get(lab, ())
        med = _median(list(ho))
        print(
            f"| {lab} | {_median(sp):.4f}; {max(sp):.4f} | {_median(nz):.4f}; {max(nz):.4f} | {cut:.1e} | "
            f"{flo:.4f} | {med:.3f} ({max(ho) if ho else math.nan:.3f}) | {med / flo:.1f} |"
        )
    print(
        f"\nThe 5 Hz file holds 39 samples per period (K = 18 harmonics, Nyquist): on the 4 Hz file the "
        f"harmonics "
        f"above 18 carry {proxy:.4f} of the spread of 1..18 (a proxy for what the 5 Hz average cannot hold)."
    )


def print_localisation(lab: str, d: Any, locs: list[dict[str, Any]]) -> None:
    f = d.final_fit
    print(
        f"\n### {lab}: final model {'+'.join(f.params.terms) or 'plain'} (beta {f.params.beta:.3f}, gamma "
        f"{f.params.gamma:.3f}, mu {f.params.mu:.3f}, active {', '.join(f.active) or 'none'})"
    )
    print(f"the diagnosis's localisation: {d.after.describe()}")
    print("\n| experiment | NRMSE | DC | h1 | h2-5 | >5 | even | " + " | ".join(ZONE_NAMES) + " |")
    print("|---|" + "---|" * (6 + len(ZONES)))
    for e, r in zip(d.experiments, locs):
        z = " | ".join(f"{v:.2f}" for v in r["zones"])
        print(
            f"| {e.source.split(' ')[0]} | {r['nrmse']:.3f} | {r['dc']:.2f} | {r['h1']:.2f} | "
            f"{r['h2_5']:.2f} | "
            f"{r['above5']:.2f} | {r['even']:.2f} | {z} |"
        )


def print_sets(results: dict[str, dict[str, Any]], sets: Sequence[tuple[str, ...]]) -> None:
    labs = list(results)
    print(
        "\n## 3a. Forced common term sets: held-out NRMSE median (max) per level; cost relative to the "
        "plain fit\n"
    )
    print("| term set | " + " | ".join(labs) + " |")
    print("|---|" + "---|" * len(labs))
    for terms in sets:
        key = "+".join(terms)
        cells = []
        for lab in labs:
            r = results[lab]["sets"].get(key)
            if r is None:
                cells.append("fit failed")
                continue
            cells.append(f"{_median(r['held_out']):.3f} ({max(r['held_out']):.3f}); {r['cost_ratio']:.2f}")
        print(f"| {key} | " + " | ".join(cells) + " |")


def print_common(results: dict[str, dict[str, Any]], terms: tuple[str, ...]) -> None:
    key = "+".join(terms)
    print(f"\n## 4. One term set at every level ({key}): values ± standard errors\n")
    cols = ["beta", "gamma", "mu", "F_sat (N)"] + list(terms) + ["held-out median", "max", "active"]
    print("| level | " + " | ".join(cols) + " |")
    print("|---|" + "---|" * len(cols))
    for lab, res in results.items():
        r = res["sets"].get(key)
        if r is None:
            print(f"| {lab} | fit failed |")
            continue
        vals = " | ".join(f"{r['values'][t][0]:.4g} ± {r['values'][t][1]:.2g}" for t in terms)
        print(
            f"| {lab} | {r['beta']:.3f} | {r['gamma']:.3f} | {r['mu']:.3f} | {r['f_sat']:.0f} | {vals} | "
            f"{_median(r['held_out']):.3f} | {max(r['held_out']):.3f} | {', '.join(r['active']) or '-'} |"
        )


def print_yield(results: dict[str, dict[str, Any]]) -> None:
    print("\n## 4b. The yield travel the free gain implies, w_u / |g_i| (mm), final model of the diagnosis\n")
    first = next(iter(results.values()))
    heads = [f"{f:.2f} Hz, {u:.1f} mm" for f, u in first["yield_exps"]]
    print("| level | " + " | ".join(heads) + " | max/min | slope in log U, log omega |")
    print("|---|" + "---|" * (len(heads) + 2))
    for lab, r in results.items():
        y = r["yield"]
        print(
            f"| {lab} | " + " | ".join(f"{v:.3f}" for v in y) + f" | {max(y) / min(y):.1f} | "
            f"{r['yield_slopes'][0]:+.2f}, {r['yield_slopes'][1]:+.2f} |"
        )


def print_alone(results: dict[str, dict[str, Any]]) -> None:
    print("\n## 3e. Each experiment fitted alone (every parameter free per experiment; in-sample NRMSE)\n")
    keys = sorted({k for r in results.values() for k in r.get("alone", {})}, key=len)
    print("| level | " + " | ".join(f"{k}: median (max)" for k in keys) + " |")
    print("|---|" + "---|" * len(keys))
    for lab, r in results.items():
        a = r.get("alone", {})
        cells = [f"{_median(a[k]):.3f} ({max(a[k]):.3f})" if k in a else "-" for k in keys]
        print(f"| {lab} | " + " | ".join(cells) + " |")


def print_extensions(results: dict[str, dict[str, Any]]) -> None:
    print("\n## 3b-3d. The element relaxed, Dahl friction, the time domain\n")
    print(
        "| level | relaxed (3b): cost / constrained, beta, gamma, mu | "
        "held-out median (max) vs constrained | "
        "Dahl on x (3c): held-out median (max) | time domain (3d): raw NRMSE median, its model part, noise |"
    )
    print("|---|---|---|---|---|")
    for lab, r in results.items():
        rx = r.get("relaxed")
        cell_b = cell_h = cell_d = cell_t = "not run"
        if rx is not None:
            cell_b = f"{rx['cost_ratio']:.4f}, {rx['beta']:.3f}, {rx['gamma']:.3f}, {rx['mu']:.3f}"
            cell_h = f"{_median(rx['held_out']):.3f} ({max(rx['held_out']):.3f}) vs {_median(rx['base']):.3f}"
        dahl = r.get("dahl")
        if dahl is not None:
            cell_d = "; ".join(
                f"{k}: {_median(v['held_out']):.3f} ({max(v['held_out']):.3f})" if v else f"{k}: failed"
                for k, v in dahl.items()
            )
        else:
            cell_d = "term not in this build"
        td = r.get("time_domain")
        if td is not None:
            cell_t = (
                f"{_median(td['nrmse']):.3f}, {_median(td['model']):.3f}, {_median(td['noise']):.3f} "
                f"(beta {td['beta']:.3g}, gamma {td['gamma']:.3g}, mu {td['mu']:.3f}; {td['reason']})"
            )
        print(f"| {lab} | {cell_b} | {cell_h} | {cell_d} | {cell_t} |")


# ------------------------------------------------------------------------------------------------------
# The run


def _set_result(lv: Level, fit: AugFit) -> dict[str, Any]:
    p = fit.params
    return {
        "cost_ratio": fit.cost / lv.diagnosis.plain_fit.cost,
        "beta": p.beta,
        "gamma": p.gamma,
        "mu": p.mu,
        "f_sat": saturation_force(p, lv.scale),
        "values": term_values(fit, lv.scale),
        "held_out": held_out_nrmse(lv, fit),
        "active": list(fit.active),
    }


def _yield(lv: Level) -> tuple[list[float], list[tuple[float, float]], tuple[float, float]]:
    """Yield travel w_u / |g_i| in mm per experiment, and its slopes in log U and log omega."""
    p, s = lv.diagnosis.final_fit.params, lv.scale
    wu = (p.beta + p.gamma) ** (-1.0 / p.mu)
    exps = lv.diagnosis.experiments
    trav = [wu / abs(float(g)) * s.u for g in p.gains]
    a = np.column_stack(
        [np.ones(len(exps)), [math.log(e.amplitude) for e in exps], [math.log(e.frequency) for e in exps]]
    )
    coef = np.linalg.lstsq(a, np.log(trav), rcond=None)[0]
    heads = [(e.frequency / (2.0 * math.pi), e.amplitude) for e in exps]
    return trav, heads, (float(coef[1]), float(coef[2]))


def each_alone(lv: Level, fit: AugFit) -> list[float]:
    """In-sample NRMSE of ``fit``'s model fitted to each experiment alone (every parameter free per
    experiment): what the element and terms can draw when nothing has to hold across frequencies."""
    out = []
    for i, e in enumerate(lv.sx):
        sub, st = subset(lv.sx, fit.params, [i])
        f = _quiet(fit_from, sub, st, lv.substeps)
        out.append(
            math.nan
            if f is None
            else float(np.linalg.norm(e.ybar - f.outputs[0]) / np.linalg.norm(e.ybar - e.ybar.mean()))
        )
    return out


def run_level(lv: Level, args: argparse.Namespace) -> dict[str, Any]:
    d = lv.diagnosis
    out: dict[str, Any] = {}
    if not args.dahl_only:
        out["verdict"] = d.verdict
        out["today"] = tuple(d.held_out.nrmse_after) if d.held_out else ()
        out["localisation"] = [localise(e, y) for e, y in zip(lv.sx, d.final_fit.outputs)]
        out["yield"], out["yield_exps"], out["yield_slopes"] = _yield(lv)
    sets: dict[str, Any] = {}
    fits: dict[str, AugFit] = {}
    for terms in () if args.dahl_only else SETS:
        f = forced(lv, terms)
        key = "+".join(terms)
        if f is not None:
            fits[key] = f
        sets[key] = None if f is None else _set_result(lv, f)
    out["sets"] = sets
    base = fits.get("+".join(RELAXED_SET))
    if base is not None:
        out["alone"] = {"+".join(RELAXED_SET): each_alone(lv, base)}
    if base is not None and not args.no_relaxed:
        par, cost = relaxed_fit(lv.sx, base.params, lv.substeps)
        out["relaxed"] = {
            "cost_ratio": cost / base.cost,
            "beta": par.beta,
            "gamma": par.gamma,
            "mu": par.mu,
            "held_out": relaxed_held_out(lv, par),
            "base": sets["+".join(RELAXED_SET)]["held_out"],
        }
    if "dahl@x" in TERMS:
        out["dahl"] = {}
        for terms in DAHL_SETS:
            f = forced(lv, terms)
            out["dahl"]["+".join(terms)] = None if f is None else _set_result(lv, f)
    common = fits.get("+".join(COMMON))
    if common is not None:
        out.setdefault("alone", {})["+".join(COMMON)] = each_alone(lv, common)
    if common is not None and not args.no_time_domain:
        try:
            out["time_domain"] = time_domain(lv, common)
        except BoucWenIdError as exc:
            print(f"{lv.label}: time-domain fit refused: {type(exc).__name__}: {exc}", file=sys.stderr)
    return out


def main(argv: Optional[list[str]] = None) -> int:
    A = _adapters()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=A.default_data_dir())
    ap.add_argument("--levels", default=None, help="coil currents, e.g. 0,0.5 (default: all five)")
    ap.add_argument("--no-time-domain", action="store_true")
    ap.add_argument("--no-relaxed", action="store_true")
    ap.add_argument("--dahl-only", action="store_true", help="only the Dahl sets (a build with the term)")
    ap.add_argument("--json", type=Path, default=None, help="write every number to this file")
    args = ap.parse_args(argv)
    if not (args.data / A.DATASETS["mr-damper"]).is_dir():
        print(f"error: the MR damper data are not under {args.data}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    levels = None if args.levels is None else [float(v) for v in args.levels.split(",")]
    loaded = load_levels(args.data, levels)
    floors = {lab: [floor_of(m) for m in ms] for lab, ms in loaded}
    m4 = next(m for m in loaded[0][1] if "4Hz" in m.name)
    proxy = beyond_nyquist(m4, 18)
    results: dict[str, dict[str, Any]] = {}
    print(f"bouc_wen_id from {Path(bw.__file__).parent}; Dahl term in this build: {'dahl@x' in TERMS}")
    for lab, ms in loaded:
        tl = time.perf_counter()
        lv = prepare_level(lab, ms, diagnose=not args.dahl_only)
        results[lab] = run_level(lv, args)
        results[lab]["diagnosis"] = lv.diagnosis
        print(f"{lab}: done in {time.perf_counter() - tl:.0f} s", file=sys.stderr, flush=True)
    diagnoses = {lab: r.pop("diagnosis") for lab, r in results.items()}
    if not args.dahl_only:
        print_floor(floors, {k: v["today"] for k, v in results.items()}, proxy)
        print(
            "\n## 2. Where the final model's misfit sits (residual energy shares; zone concentration, 1 = "
            "even)"
        )
        for lab, r in results.items():
            print_localisation(lab, diagnoses[lab], r["localisation"])
        print_sets(results, SETS)
        print_common(results, COMMON)
        print_yield(results)
        print_alone(results)
    print_extensions(results)
    print(f"\n(run: {time.perf_counter() - t0:.0f} s wall)")
    if args.json is not None:
        args.json.write_text(json.dumps({"floors": floors, "levels": results}, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

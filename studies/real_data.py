"""Identify the plain Wiener-Bouc-Wen model on four sets of real hysteresis recordings, honestly.

Run from the repository root (the package must be importable, e.g. ``PYTHONPATH=python``)::

    python studies/real_data.py            # all four data sets, ~2 min
    python studies/real_data.py --doc-only # docs/real-data.md from results.json

For every usable experiment (one steady stretch of one record) the script

1. reads the raw files with the adapters of ``studies/_adapters.py`` into ``Measurement`` objects;
2. cuts the record into steady segments (``find_steady_segments``: kept and dropped stretches with reasons)
   and averages each kept segment (``synchronous_average``, any number of samples per period);
3. identifies it on its own with ``identify(..., method="refined")`` (and ``"profile"`` for comparison),
   recording the result with its 95 % intervals and adequacy test, or the named error the library refuses
   it with; a fit refused at the upper end of the mu bracket is retried once on ``mu in (1, 40]`` (a sharper
   yield is physically meaningful; the lower end, mu -> 1, is the model's own limit and is not widened);
4. runs a *cross-check outside the library*: a bounded multi-start least-squares fit of the same plain
   Bouc-Wen steady loop (the library's own loop solver, ``bouc_wen_id._core.steady_loop``) within the same
   admissible set (beta >= |gamma|, beta + gamma > 0, 1 < mu <= 40).  It has no uncertainty; it says how
   close the library came to the best loop the plain model can draw, and how well that loop fits at all;
5. fits experiments jointly (shared beta, gamma, mu; one |G| and phase each): the MR damper per coil
   current across its six frequencies, the friction damper's frequency sweep, the wire-rope A2 sweep and
   the four B-H frequencies, trying every experiment as the ``reference`` (the start) and keeping the
   lowest cost;
6. writes ``results.json`` and a handful of figures into ``--out`` and generates ``docs/real-data.md`` from
   ``results.json`` (the prose lives in this file, so regenerating keeps it).

Everything is deterministic: rerunning after a library change refreshes the numbers and the document.
The data are read from ``--data`` (default ``../shared/data/real`` next to the repository) and never
copied.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import traceback
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Optional

import _adapters as ad  # examples/ is not a package: this file's folder is on sys.path when run
import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import _core
from bouc_wen_id.plotting import panel_grid
from bouc_wen_id.signal import AveragedPeriod, SegmentReport, average_segments
from bouc_wen_id.validation import z_value
from numpy.typing import NDArray

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.figure import Figure

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi
#: Two-sided 95 % normal quantile.
Z95 = z_value(0.95)
REPO = Path(__file__).resolve().parents[1]
#: The library's default bracket, and the wider one tried when a fit ends on its upper end.
MU_BRACKET = (1.0, 10.0)
WIDE_MU_BRACKET = (1.0, 40.0)
#: A fit is "on a constraint" when beta - |gamma| or beta + gamma is below this fraction of |beta| + |gamma|.
CONSTRAINT_RTOL = 1e-6
DATASET_ORDER = ("mr-damper", "friction-damper", "wire-rope", "bh-microwire")
DATASET_TITLES = {
    "mr-damper": "MR damper (UTFSM, MTS machine)",
    "friction-damper": "Banded rotary friction damper with backlash (ARTS-Lab BRFD)",
    "wire-rope": "Wire-rope isolator on a shaker (SUPMECA)",
    "bh-microwire": "B-H loops of an amorphous microwire (DYK-Team)",
}


# ------------------------------------------------------------------------------------------------------
# Experiments


@dataclass
class Spec:
    """One record to process: a Measurement with where it came from."""

    dataset: str
    file: str
    block: Optional[int]
    label: str
    measurement: bw.Measurement
    #: Extra traces for the segments figure (name -> samples on the measurement's time axis).
    extra: dict[str, FloatArray] = field(default_factory=dict)


def load_specs(data_dir: Path, dataset: str) -> list[Spec]:
    """Every record of one data set, through its adapter."""
    folder = data_dir / ad.DATASETS[dataset]
    specs: list[Spec] = []
    if dataset == "mr-damper":
        for name in ad.MR_FILES:
            for b, m in enumerate(ad.load_mr_damper(folder / name)):
                specs.append(Spec(dataset, name, b, m.name, m))
    elif dataset == "friction-damper":
        for name in ad.FRICTION_FILES:
            m = ad.load_friction_damper(folder / name)
            specs.append(Spec(dataset, name, None, m.name, m))
    elif dataset == "wire-rope":
        for name in ad.WIRE_ROPE_FILES:
            m = ad.load_wire_rope(folder / name)
            specs.append(Spec(dataset, name, None, m.name, m))
    elif dataset == "bh-microwire":
        for name in ad.BH_FILES:
            raw = ad.load_bh_raw(folder / name)
            m = ad.load_bh_loop(folder / name)
            specs.append(Spec(dataset, name, None, raw.name, m, extra={"dB/dt (col 0)": raw.dbdt}))
    else:
        raise KeyError(f"unknown data set {dataset!r}; choose from {', '.join(DATASET_ORDER)}")
    return specs


@contextmanager
def captured(into: list[dict[str, str]]) -> Iterator[None]:
    """Record every warning raised inside (category and message, each once) into ``into``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for w in caught:
        entry = {"category": w.category.__name__, "message": str(w.message)}
        if entry not in into:
            into.append(entry)


def _num(v: Optional[float]) -> Optional[float]:
    """JSON has no NaN: non-finite or missing values are null."""
    return None if v is None or not math.isfinite(float(v)) else float(v)


def _estimate(value: float, se: Optional[float]) -> dict[str, Any]:
    se_ = _num(se)
    ci = None if se_ is None else [value - Z95 * se_, value + Z95 * se_]
    return {"value": _num(value), "se": se_, "ci95": ci}


def _wrap_pi(phi: float) -> float:
    """A phase in (-pi, pi]."""
    return math.pi - (math.pi - phi) % TWO_PI


def constraint_of(beta: float, gamma: float) -> Optional[str]:
    """Which Bouc-Wen condition (beta >= |gamma|, beta + gamma > 0) an estimate sits on, if any."""
    scale = abs(beta) + abs(gamma)
    if scale == 0.0 or not math.isfinite(scale):
        return None
    if (beta - gamma) <= CONSTRAINT_RTOL * scale:
        return "beta = gamma"
    if (beta + gamma) <= CONSTRAINT_RTOL * scale:
        return "beta = -gamma"
    return None


def _error(exc: BaseException) -> dict[str, Any]:
    named = isinstance(exc, bw.BoucWenIdError)
    out: dict[str, Any] = {"class": type(exc).__name__, "message": str(exc), "named": named}
    if isinstance(exc, bw.SearchAtBoundError):
        out["bound"] = exc.bound
        out["lower"] = exc.lower
    if not named:
        out["traceback"] = traceback.format_exc(limit=6)
    return out


def summarise(result: bw.IdentificationResult, warns: list[dict[str, str]]) -> dict[str, Any]:
    """The JSON record of an identification result (95 % intervals from the library)."""
    out: dict[str, Any] = {
        "outcome": "identified",
        "method": result.method,
        "mu_bracket": list(result.settings["mu_bracket"]),
        "reference": result.reference,
        "cost": _num(result.cost),
        "iterations": result.iterations,
        "constraint": constraint_of(result.beta, result.gamma),
        "warnings": warns,
    }
    for name in ("beta", "gamma", "mu"):
        value = float(getattr(result, name))
        if result.standard_errors is not None:
            lo, hi = result.interval(name)
            out[name] = {"value": value, "se": _num(result.standard_errors[name]), "ci95": [lo, hi]}
        else:
            out[name] = {"value": value, "se": None, "ci95": None}
    out["experiments"] = [
        {
            "source": e.source,
            "frequency_hz": e.frequency / TWO_PI,
            "gain": _estimate(e.gain, e.gain_se),
            "phase": _estimate(e.phase, e.phase_se),
            "nrmse": _num(e.nrmse),
            "noise_sd": _num(e.noise_sd),
            "averaged_points": e.samples_per_period,
            "periods_equivalent": _num(e.periods),
            "harmonics": e.harmonics,
        }
        for e in result.experiments
    ]
    a = result.adequacy
    out["adequacy"] = (
        None
        if a is None
        else {
            "statistic": _num(a.statistic),
            "dof": a.dof,
            "noise_dof": a.noise_dof,
            "ratio": _num(a.statistic / a.dof),
            "p_value": _num(a.p_value),
        }
    )
    return out


def identify_record(
    items: Sequence[AveragedPeriod],
    *,
    method: str = "refined",
    reference: int = 0,
    mu_bracket: tuple[float, float] = MU_BRACKET,
) -> tuple[dict[str, Any], Optional[bw.IdentificationResult]]:
    """``bw.identify`` with its warnings recorded; a refusal is recorded with its error's name.

    Anything but a :class:`bouc_wen_id.BoucWenIdError` is a library bug: it is recorded as
    ``outcome = "library bug"`` (with a traceback) rather than stopping the whole run.
    """
    warns: list[dict[str, str]] = []
    try:
        with captured(warns):
            # identify() is annotated with Recording only, but takes AveragedPeriod and Measurement too.
            result = bw.identify(
                list(items),  # type: ignore[arg-type]
                method=method,  # type: ignore[arg-type]
                reference=reference,
                mu_bracket=mu_bracket,
            )
    except bw.BoucWenIdError as exc:
        return {
            "outcome": "refused",
            "method": method,
            "mu_bracket": list(mu_bracket),
            "reference": reference,
            "error": _error(exc),
            "warnings": warns,
        }, None
    except Exception as exc:  # noqa: BLE001 - a library bug is recorded, not fatal
        return {
            "outcome": "library bug",
            "method": method,
            "mu_bracket": list(mu_bracket),
            "reference": reference,
            "error": _error(exc),
            "warnings": warns,
        }, None
    return summarise(result, warns), result


def at_upper_bound(record: dict[str, Any]) -> bool:
    err = record.get("error") or {}
    return (
        record["outcome"] == "refused"
        and err.get("class") == "SearchAtBoundError"
        and err.get("lower") is False
    )


def identify_with_retry(
    items: Sequence[AveragedPeriod], *, reference: int = 0
) -> tuple[dict[str, Any], Optional[bw.IdentificationResult], Optional[dict[str, Any]]]:
    """Refined fit on the default bracket; once more on ``(1, 40]`` when it ended on mu's upper end.

    Returns the record kept (the retry's when there was one), its result, and the first attempt when a
    retry was made.
    """
    rec, res = identify_record(items, reference=reference)
    if not at_upper_bound(rec):
        return rec, res, None
    rec2, res2 = identify_record(items, reference=reference, mu_bracket=WIDE_MU_BRACKET)
    return rec2, res2, rec


# ------------------------------------------------------------------------------------------------------
# Cross-check: a bounded multi-start fit of the same steady loop (outside the library)


@dataclass
class CrossCheck:
    beta: float
    gamma: float
    mu: float
    gain: float
    phase: float
    nrmse: float
    loop: FloatArray
    starts: int
    evaluations: int
    #: The library's adequacy statistic for this loop: (N / sigma^2) |ybar - w|^2 over P - 5 dof.
    adequacy_ratio: Optional[float] = None
    adequacy_p: Optional[float] = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "beta": self.beta,
            "gamma": self.gamma,
            "mu": self.mu,
            "gain": self.gain,
            "phase": self.phase,
            "nrmse": self.nrmse,
            "constraint": constraint_of(self.beta, self.gamma),
            "mu_at_lower_bound": self.mu <= 1.0 + 1e-4,
            "starts": self.starts,
            "evaluations": self.evaluations,
            "adequacy_ratio": _num(self.adequacy_ratio),
            "adequacy_p": _num(self.adequacy_p),
        }


def crosscheck(ap: AveragedPeriod, mu_hi: float = WIDE_MU_BRACKET[1]) -> Optional[CrossCheck]:
    """Least squares of the plain Bouc-Wen steady loop on one averaged period, from 16 starts.

    Unknowns ``(s, d, mu, A, phi)`` with ``beta = (s + d)/2``, ``gamma = (s - d)/2`` (so the Bouc-Wen
    conditions are the box ``s > 0, d >= 0``), ``1 < mu <= mu_hi``, ``x = A cos(theta - phi)`` in units where
    the output peaks at 1 and the input amplitude is 1; SciPy's bounded trust-region reflective solver
    with the loop's analytic sensitivities.  Starts: ``mu = 2``, ``A`` in {1.5, 6}, 8 phases.
    """
    from scipy.optimize import least_squares  # type: ignore[import-untyped]

    s_y = float(np.max(np.abs(ap.ybar)))
    if not s_y > 0.0:
        return None
    yb = ap.ybar / s_y
    p = yb.size
    substeps = max(2, math.ceil(2048 / p))
    spread = float(np.linalg.norm(yb - yb.mean()))
    cache: dict[str, Any] = {}

    def loop(x: FloatArray) -> tuple[Optional[FloatArray], Optional[FloatArray]]:
        key = tuple(float(v) for v in x)
        if cache.get("key") != key:
            s, d, mu, amp, phi = key
            try:
                w, jac, _, _ = _core.steady_loop(amp, 0.5 * (s + d), 0.5 * (s - d), mu, phi, p, substeps)
                cache.update(key=key, w=np.asarray(w), jac=np.asarray(jac))
            except bw.BoucWenIdError:
                cache.update(key=key, w=None, jac=None)
        return cache["w"], cache["jac"]

    def residual(x: FloatArray) -> FloatArray:
        w, _ = loop(x)
        if w is None or not np.all(np.isfinite(w)):
            return np.full(p, 10.0)
        out: FloatArray = w - yb
        return out

    def jacobian(x: FloatArray) -> FloatArray:
        _, j = loop(x)
        if j is None or not np.all(np.isfinite(j)):
            return np.zeros((p, 5))
        return np.column_stack(
            [0.5 * (j[:, 0] + j[:, 1]), 0.5 * (j[:, 0] - j[:, 1]), j[:, 2], j[:, 3], j[:, 4]]
        )

    lower = [1e-9, 0.0, 1.0 + 1e-6, -np.inf, -np.inf]
    upper = [np.inf, np.inf, mu_hi, np.inf, np.inf]
    best: Any = None
    starts = evaluations = 0
    for amp0 in (1.5, 6.0):
        for phi0 in np.linspace(0.0, TWO_PI, 8, endpoint=False):
            x0 = np.array([1.0, 1.0, 2.0, amp0, phi0])
            starts += 1
            try:
                sol = least_squares(
                    residual, x0, jac=jacobian, bounds=(lower, upper), max_nfev=60, x_scale="jac"
                )
            except (ValueError, np.linalg.LinAlgError):
                continue
            evaluations += int(sol.nfev)
            if best is None or sol.cost < best.cost:
                best = sol
    if best is None:
        return None
    s, d, mu, amp, phi = (float(v) for v in best.x)
    w, _ = loop(best.x)
    if w is None:
        return None
    if amp < 0:
        amp, phi = -amp, phi + math.pi
    beta, gamma = 0.5 * (s + d), 0.5 * (s - d)
    # The same F-test as the library's adequacy (5 parameters: beta, gamma, mu, |G|, phi).
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    loop_phys = np.asarray(w * s_y, dtype=np.float64)
    ratio = p_value = None
    dof = p - 5
    if ap.noise_var > 0 and math.isfinite(ap.noise_var) and dof > 0 and ap.noise_dof > 0:
        stat = ap.periods / ap.noise_var * float(np.sum((ap.ybar - loop_phys) ** 2))
        ratio, p_value = stat / dof, float(fdtrc(dof, ap.noise_dof, stat / dof))
    return CrossCheck(
        beta=beta / s_y**mu,
        gamma=gamma / s_y**mu,
        mu=mu,
        gain=amp * s_y / ap.amplitude,
        phase=phi % TWO_PI,
        nrmse=float(np.linalg.norm(w - yb)) / spread,
        loop=loop_phys,
        starts=starts,
        evaluations=evaluations,
        adequacy_ratio=ratio,
        adequacy_p=p_value,
    )


# ------------------------------------------------------------------------------------------------------
# One record -> its experiments


@dataclass
class Outcome:
    """One experiment's JSON record and what the figures need."""

    record: dict[str, Any]
    spec: Spec
    report: Optional[SegmentReport] = None
    averaged: Optional[AveragedPeriod] = None
    result: Optional[bw.IdentificationResult] = None
    cross: Optional[CrossCheck] = None


def fundamental(ap: AveragedPeriod) -> tuple[float, float, float]:
    """The output's fundamental on the averaged grid: amplitude, its phase lead over the input (deg), and
    the NRMSE of the best linear (spring + dashpot) model, i.e. of the fundamental alone."""
    p = ap.ybar.size
    theta = TWO_PI * np.arange(p) / p
    a = 2.0 / p * float(ap.ybar @ np.cos(theta))
    b = 2.0 / p * float(ap.ybar @ np.sin(theta))
    fitted = a * np.cos(theta) + b * np.sin(theta)
    spread = float(np.linalg.norm(ap.ybar - ap.ybar.mean()))
    nrmse = float(np.linalg.norm(ap.ybar - fitted)) / spread if spread > 0 else math.nan
    return math.hypot(a, b), math.degrees(-math.atan2(b, a)), nrmse


def process(spec: Spec, *, cross: bool = True) -> list[Outcome]:
    """Steady segments, averaging, identification (single) and cross-check of one record."""
    m = spec.measurement
    base: dict[str, Any] = {
        "dataset": spec.dataset,
        "file": spec.file,
        "block": spec.block,
        "label": spec.label,
        "name": m.name,
        "units": dict(m.units),
        "channels": dict(m.channels),
        "metadata": dict(m.metadata),
        "nominal_hz": None if m.nominal_frequency is None else m.nominal_frequency / TWO_PI,
        "sample_rate_hz": m.sample_rate,
        "samples": len(m),
    }
    pre_warns: list[dict[str, str]] = []
    try:
        with captured(pre_warns):
            m.check()
            found = average_segments(m, name=spec.label)
            report = found.report
    except Exception as exc:  # noqa: BLE001 - named refusal or library bug, recorded
        status = "refused" if isinstance(exc, bw.BoucWenIdError) else "library bug"
        rec = {**base, "segment": None, "status": status, "stage": "preprocessing", "error": _error(exc)}
        rec["preprocessing"] = {"warnings": pre_warns, "kept": [], "dropped": []}
        return [Outcome(rec, spec)]
    pre = {
        "warnings": pre_warns,
        "kept": [[s.start, s.stop, s.periods] for s in report.kept],
        "dropped": [[a, b, why] for a, b, why in report.dropped],
    }
    outcomes = []
    for i, (seg, fit) in enumerate(zip(report.kept, report.fits)):
        rec = {**base, "segment": i, "preprocessing": pre}
        f_hz = fit.frequency / TWO_PI
        rec["segment_t"] = [float(m.t[seg.start]), float(m.t[seg.stop - 1])]
        rec["frequency_hz"] = f_hz
        rec["frequency_se_hz"] = _num(fit.frequency_se / TWO_PI)
        nominal = base["nominal_hz"]
        rec["frequency_offset_pct"] = None if nominal is None else 100.0 * (f_hz / nominal - 1.0)
        rec["periods"] = seg.periods
        rec["samples_per_period"] = TWO_PI / (fit.frequency * m.dt)
        rec["input"] = {"amplitude": fit.amplitude, "offset": fit.offset, "thd": _num(fit.thd)}
        # Averaged with the segments (signal.average_segments): its warnings are the preprocessing's.
        avg_warns: list[dict[str, str]] = []
        ap = found.periods[i]
        amp1, lead, lin = fundamental(ap)
        rec["averaged"] = {
            "points": ap.samples_per_period,
            "harmonics": ap.harmonics,
            "periods_equivalent": ap.periods,
            "noise_sd": _num(math.sqrt(ap.noise_var) if ap.noise_var >= 0 else math.nan),
            "noise_dof": ap.noise_dof,
            "output_offset": ap.offset_y,
            "output_peak_to_peak": float(np.ptp(ap.ybar)),
            "output_fundamental": amp1,
            "output_phase_lead_deg": lead,
            "linear_nrmse": lin,
            "warnings": avg_warns,
        }
        ident, result, first = identify_with_retry([ap])
        rec["identification"] = ident
        if first is not None:
            rec["first_attempt"] = first
        rec["profile"], _ = identify_record([ap], method="profile")
        rec["status"] = ident["outcome"]
        xc = crosscheck(ap) if cross else None
        rec["crosscheck"] = None if xc is None else xc.to_dict()
        outcomes.append(Outcome(rec, spec, report, ap, result, xc))
    return outcomes


# ------------------------------------------------------------------------------------------------------
# Joint fits


def joint_groups(outcomes: Sequence[Outcome]) -> list[tuple[str, str, list[Outcome]]]:
    """(dataset, label, members) of the joint fits: one averaged period per member, in frequency order."""
    usable = [o for o in outcomes if o.averaged is not None and o.record.get("segment") == 0]
    groups: list[tuple[str, str, list[Outcome]]] = []
    for current in ad.MR_CURRENTS:
        members = [
            o
            for o in usable
            if o.spec.dataset == "mr-damper" and o.record["metadata"]["coil_current_A"] == f"{current:g}"
        ]
        if members:
            groups.append(("mr-damper", f"{current:g} A, six frequencies", members))
    members = [o for o in usable if o.spec.dataset == "friction-damper" and "0.5amplitude" in o.spec.file]
    if members:
        groups.append(("friction-damper", "0.5 in, 0.25-2 Hz", members))
    members = [o for o in usable if o.spec.dataset == "wire-rope" and o.spec.file.endswith("_A2.txt")]
    if members:
        groups.append(("wire-rope", "level A2, 16-22 Hz", members))
    members = [o for o in usable if o.spec.dataset == "bh-microwire"]
    if members:
        groups.append(("bh-microwire", "50-250 kHz", members))
    return groups


@dataclass
class Joint:
    record: dict[str, Any]
    members: list[Outcome]
    result: Optional[bw.IdentificationResult]


def joint_fit(dataset: str, label: str, members: list[Outcome]) -> Joint:
    """A joint refined fit, started from each member as the reference in turn; the lowest cost wins."""
    items = [o.averaged for o in members if o.averaged is not None]
    attempts = []
    best: Optional[tuple[dict[str, Any], bw.IdentificationResult]] = None
    for r in range(len(items)):
        rec, res, first = identify_with_retry(items, reference=r)
        brief: dict[str, Any] = {"reference": r, "outcome": rec["outcome"], "mu_bracket": rec["mu_bracket"]}
        if first is not None:
            brief["first_attempt"] = first["error"]["class"]
        if res is None:
            brief["error"] = rec["error"]["class"]
        else:
            brief["cost"] = rec["cost"]
            brief["mu"] = rec["mu"]["value"]
            if best is None or res.cost < best[1].cost:
                best = (rec, res)
        attempts.append(brief)
    record: dict[str, Any] = {
        "dataset": dataset,
        "label": label,
        "members": [o.spec.label for o in members],
        "attempts": attempts,
    }
    if best is None:
        errors = sorted({a["error"] for a in attempts if "error" in a})
        record["status"] = "refused"
        record["errors"] = errors
        record["identification"] = identify_record(items)[0]
        return Joint(record, members, None)
    record["status"] = "identified"
    record["identification"] = best[0]
    return Joint(record, members, best[1])


# ------------------------------------------------------------------------------------------------------
# Figures


def _short(o: Outcome) -> str:
    return (
        o.spec.label if o.record.get("segment", 0) in (0, None) else f"{o.spec.label} #{o.record['segment']}"
    )


def figure_segments(specs: Sequence[Spec], outcomes: Sequence[Outcome], ncols: int) -> Figure:
    """Each record's input and output (each scaled to its peak) against time, kept segments shaded."""
    fig, axes = panel_grid(len(specs), ncols, (2.6, 1.7))
    for ax, spec in zip(axes, specs):
        m = spec.measurement
        t = m.t - m.t[0]
        step = max(1, len(m) // 6000)

        def norm(x: FloatArray) -> FloatArray:
            c = x - np.median(x)
            out: FloatArray = c / max(float(np.max(np.abs(c))), 1e-300)
            return out

        ax.plot(t[::step], norm(m.y)[::step], lw=0.4, color="C0", label="y (output)")
        ax.plot(t[::step], norm(m.u)[::step], lw=0.6, color="C1", label="u (input)")
        for name, x in spec.extra.items():
            ax.plot(t[::step], norm(x)[::step], lw=0.4, color="C2", alpha=0.7, label=name)
        for o in outcomes:
            if o.spec is spec and o.report is not None:
                for seg in o.report.kept:
                    ax.axvspan(t[seg.start], t[seg.stop - 1], color="C2", alpha=0.15, lw=0)
                break
        ax.set_title(spec.label, fontsize=7)
        ax.tick_params(labelsize=6)
        ax.set_yticks([])
    axes[0].legend(fontsize=5, loc="lower left")
    fig.suptitle("Records (each channel scaled to its peak); shaded: the steady segments kept", fontsize=9)
    fig.supxlabel("time in the record (s)", fontsize=8)
    return fig


def _model_loop(o: Outcome) -> tuple[Optional[FloatArray], str]:
    if o.result is not None and o.result.experiments[0].model is not None:
        return o.result.experiments[0].model, "library"
    if o.cross is not None:
        return o.cross.loop, "cross-check"
    return None, ""


def figure_loops(outcomes: Sequence[Outcome], ncols: int) -> Figure:
    """Averaged loops against the measured input: data, the library's model, the cross-check's."""
    usable = [o for o in outcomes if o.averaged is not None]
    fig, axes = panel_grid(len(usable), ncols, (2.6, 2.3))
    for ax, o in zip(axes, usable):
        ap = o.averaged
        assert ap is not None
        u = np.append(ap.input_grid(), ap.input_grid()[:1])
        ax.plot(u, np.append(ap.ybar, ap.ybar[:1]), lw=1.3, color="C0", label="measured (averaged)")
        ident = o.record["identification"]
        if o.result is not None and o.result.experiments[0].model is not None:
            w = o.result.experiments[0].model
            ax.plot(u, np.append(w, w[:1]), "--", lw=1.0, color="C3", label="library fit")
        if o.cross is not None:
            w = o.cross.loop
            ax.plot(u, np.append(w, w[:1]), ":", lw=1.0, color="k", label="cross-check fit")
        if ident["outcome"] == "identified":
            head = f"NRMSE {ident['experiments'][0]['nrmse']:.3g}"
        else:
            head = f"refused: {ident['error']['class']}"
        xc = o.record.get("crosscheck")
        if xc:
            head += f"; x-check {xc['nrmse']:.3g}"
        ax.set_title(f"{_short(o)}\n{head}", fontsize=6.5)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    if usable:
        axes[0].legend(fontsize=5)
        units = usable[0].record["units"]
        fig.supxlabel(f"input u - offset ({units['u']})", fontsize=8)
        fig.supylabel(f"output y - offset ({units['y']})", fontsize=8)
    fig.suptitle(
        "Averaged loops against the measured input\nmeasured (blue), library refined fit (red dashed), "
        "cross-check fit (black dotted)",
        fontsize=8,
    )
    return fig


def figure_residuals(outcomes: Sequence[Outcome], ncols: int) -> Figure:
    """Averaged output minus model over one period (the library's fit, else the cross-check's)."""
    usable = [o for o in outcomes if o.averaged is not None and _model_loop(o)[0] is not None]
    fig, axes = panel_grid(len(usable), ncols, (2.6, 1.9))
    for ax, o in zip(axes, usable):
        ap = o.averaged
        assert ap is not None
        w, which = _model_loop(o)
        assert w is not None
        t = ap.times()
        ax.plot(t, ap.ybar - w, lw=0.9, color="C0" if which == "library" else "0.3")
        noise = o.record["averaged"]["noise_sd"]
        if noise is not None and ap.periods > 0:
            band = 2.0 * noise / math.sqrt(ap.periods)
            ax.axhspan(-band, band, color="C1", alpha=0.3, lw=0, zorder=0)
        ax.axhline(0.0, color="k", lw=0.4)
        ax.set_title(f"{_short(o)} ({which})", fontsize=6.5)
        ax.tick_params(labelsize=6)
        ax.grid(True, alpha=0.3)
    fig.suptitle(
        "Residual ybar - model over one period: library fit (blue) or, when refused,\nthe cross-check fit "
        "(grey); orange band: +-2 sigma/sqrt(N), the noise of the average",
        fontsize=8,
    )
    fig.supxlabel("time from the input's phase zero (s)", fontsize=8)
    return fig


def figure_bode(
    outcomes: Sequence[Outcome], joints: Sequence[Joint], group_of: Callable[[Outcome], str]
) -> Figure:
    """|G| and phi at each experiment's frequency: single fits (95 % CI), joint fits, cross-checks."""
    fig, (ax_g, ax_p) = panel_grid(2, 1, (5.9, 2.75))
    groups: dict[str, list[Outcome]] = {}
    for o in outcomes:
        if o.averaged is not None:
            groups.setdefault(group_of(o), []).append(o)
    for k, (name, members) in enumerate(groups.items()):
        color = f"C{k % 10}"
        for o in members:
            f = o.record["frequency_hz"]
            ident = o.record["identification"]
            if ident["outcome"] == "identified":
                e = ident["experiments"][0]
                g, ph = e["gain"], e["phase"]
                g_err = Z95 * g["se"] if g["se"] is not None else 0.0
                p_err = Z95 * ph["se"] if ph["se"] is not None else 0.0
                ax_g.errorbar([f], [g["value"]], yerr=[g_err], fmt="o", color=color, ms=4, capsize=2)
                ax_p.errorbar(
                    [f], [_wrap_pi(ph["value"])], yerr=[p_err], fmt="o", color=color, ms=4, capsize=2
                )
            if o.cross is not None:
                ax_g.plot([f], [o.cross.gain], "x", color=color, ms=5)
                ax_p.plot([f], [_wrap_pi(o.cross.phase)], "x", color=color, ms=5)
        ax_g.plot([], [], "s", color=color, label=name)
    for j in joints:
        if j.result is None:
            continue
        name = group_of(j.members[0])
        k = list(groups).index(name) if name in groups else 0
        fs = [e.frequency / TWO_PI for e in j.result.experiments]
        ax_g.plot(fs, j.result.gains, "s--", mfc="none", color=f"C{k % 10}", ms=6, lw=0.6)
        ax_p.plot(
            fs, [_wrap_pi(p) for p in j.result.phases], "s--", mfc="none", color=f"C{k % 10}", ms=6, lw=0.6
        )
    ax_g.plot([], [], "o", color="0.4", label="single refined fit (95 % CI)")
    ax_g.plot([], [], "s", mfc="none", color="0.4", label="joint refined fit")
    ax_g.plot([], [], "x", color="0.4", label="cross-check (no CI)")
    from matplotlib.ticker import NullFormatter

    ax_g.set_xscale("log")
    ax_g.set_yscale("log")
    ax_p.set_xscale("log")
    for ax in (ax_g, ax_p):
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax_g.set_ylabel("|G(j omega)| (alpha-normalised)")
    ax_p.set_ylabel("phi = -angle G, wrapped to (-pi, pi] (rad)")
    ax_p.set_xlabel("frequency found (Hz)")
    for ax in (ax_g, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    ax_g.legend(fontsize=6)
    ax_g.set_title("Identified points of the linear part G", fontsize=9)
    return fig


def write_figures(
    dataset: str,
    specs: Sequence[Spec],
    outcomes: Sequence[Outcome],
    joints: Sequence[Joint],
    out: Path,
) -> list[str]:
    """The dataset's PNGs (segments, loops, residuals, Bode, and the library's loops of joint fits)."""
    from bouc_wen_id.plotting import plot_loops

    ncols = 5 if dataset == "mr-damper" else 3 if dataset in ("friction-damper", "wire-rope") else 2
    group_of: Callable[[Outcome], str]
    if dataset == "mr-damper":

        def group_of(o: Outcome) -> str:
            return f"{o.record['metadata']['coil_current_A']} A"

    elif dataset == "wire-rope":

        def group_of(o: Outcome) -> str:
            return f"level {o.record['metadata']['amplitude_level']}"

    elif dataset == "friction-damper":

        def group_of(o: Outcome) -> str:
            return f"{o.record['metadata']['nominal_amplitude_in']} in"

    else:

        def group_of(o: Outcome) -> str:
            return "B-H"

    figs: list[tuple[str, Figure]] = [
        (f"{dataset}-segments.png", figure_segments(specs, outcomes, ncols)),
        (f"{dataset}-loops.png", figure_loops(outcomes, ncols)),
        (f"{dataset}-residuals.png", figure_residuals(outcomes, ncols)),
        (f"{dataset}-bode.png", figure_bode(outcomes, joints, group_of)),
    ]
    for j in joints:
        if j.result is not None:
            slug = j.record["label"].split(",")[0].replace(" ", "").replace(".", "p")
            fig = plot_loops(j.result)
            fig.suptitle(f"Joint fit {j.record['label']}: measured (solid), model (dashed)", fontsize=9)
            figs.append((f"{dataset}-joint-{slug}.png", fig))
    names = []
    for name, fig in figs:
        fig.savefig(out / name, dpi=72, metadata={"Software": None})
        names.append(name)
    return names


# ------------------------------------------------------------------------------------------------------
# Run


def run(
    data_dir: Path, out: Path, datasets: Sequence[str], cross: bool = True, workers: int = 1
) -> dict[str, Any]:
    if not data_dir.is_dir():
        raise SystemExit(f"error: data directory {data_dir} not found (expected ../shared/data/real)")
    out.mkdir(parents=True, exist_ok=True)
    doc: dict[str, Any] = {
        "format": "bouc_wen_id.real_data",
        "version": 1,
        "library_version": bw.__version__,
        "command": "python studies/real_data.py",
        "settings": {
            "method": "refined",
            "mu_bracket": list(MU_BRACKET),
            "retry_mu_bracket": list(WIDE_MU_BRACKET),
            "constraint_rtol": CONSTRAINT_RTOL,
            "crosscheck": cross,
        },
        "experiments": [],
        "joint": [],
        "figures": {},
    }
    with _pool(workers) as pool:
        for dataset in datasets:
            _run_dataset(doc, pool, data_dir, out, dataset, cross)
    (out / "results.json").write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return doc


def _init_worker() -> None:
    # One rayon thread per worker process: the parallelism is across the records.
    os.environ["RAYON_NUM_THREADS"] = "1"


class _Serial:
    """A stand-in for a process pool: ``map`` in this process."""

    def map(self, fn: Callable[..., Any], *items: Any) -> Iterator[Any]:
        return map(fn, *items)

    def __enter__(self) -> _Serial:
        return self

    def __exit__(self, *exc: object) -> None:
        return None


def _pool(workers: int) -> Any:
    """Worker processes for the independent records and joint fits (``workers == 1``: this process)."""
    if workers <= 1:
        return _Serial()
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_worker)


def _process_spec(spec: Spec, cross: bool) -> list[Outcome]:
    return process(spec, cross=cross)


def _joint_fit_args(args: tuple[str, str, list[Outcome]]) -> Joint:
    return joint_fit(*args)


def _run_dataset(
    doc: dict[str, Any], pool: Any, data_dir: Path, out: Path, dataset: str, cross: bool
) -> None:
    """One data set's records (in parallel on ``pool``), joint fits and figures, into ``doc``."""
    t0 = time.perf_counter()
    specs = load_specs(data_dir, dataset)
    batches = pool.map(_process_spec, specs, [cross] * len(specs))
    outcomes = [o for batch in batches for o in batch]
    joints = list(pool.map(_joint_fit_args, joint_groups(outcomes)))
    doc["experiments"] += [o.record for o in outcomes]
    doc["joint"] += [j.record for j in joints]
    doc["figures"][dataset] = write_figures(dataset, specs, outcomes, joints, out)
    done = sum(o.record["status"] == "identified" for o in outcomes)
    print(
        f"{dataset}: {len(specs)} records, {len(outcomes)} experiments, {done} identified, "
        f"{len(outcomes) - done} refused ({time.perf_counter() - t0:.1f} s)",
        flush=True,
    )


# ------------------------------------------------------------------------------------------------------
# The document


def _g(v: Optional[float], digits: int = 4) -> str:
    if v is None or not math.isfinite(v):
        return "-"
    return f"{v:.{digits}g}"


def _ci(est: Optional[dict[str, Any]], digits: int = 4) -> str:
    if not est or est.get("value") is None:
        return "-"
    text = _g(est["value"], digits)
    if est.get("ci95"):
        lo, hi = est["ci95"]
        text += f" [{_g(lo, 3)}, {_g(hi, 3)}]"
    return text


def _phase_ci(est: Optional[dict[str, Any]]) -> str:
    """A phase and its interval on the branch (-pi, pi]."""
    if not est or est.get("value") is None:
        return "-"
    v = _wrap_pi(est["value"])
    text = f"{v:.3f}"
    if est.get("se") is not None:
        text += f" ± {Z95 * est['se']:.2g}"
    return text


def _outcome_cell(ident: dict[str, Any]) -> str:
    if ident["outcome"] == "identified":
        text = "identified"
        if ident.get("constraint"):
            text += f", **on {ident['constraint']}**"
        if list(ident["mu_bracket"]) != list(MU_BRACKET):
            text += f", mu in ({ident['mu_bracket'][0]:g}, {ident['mu_bracket'][1]:g}]"
        return text
    err = ident["error"]
    why = err["class"]
    if err["class"] == "SearchAtBoundError" and err.get("lower") is not None:
        why += " (mu -> 1)" if err["lower"] else f" (mu -> {err['bound']:g})"
    if ident["outcome"] == "library bug":
        why = f"**library bug**: {why}"
    return f"refused: {why}"


def _warn_cell(rec: dict[str, Any]) -> str:
    cats: dict[str, int] = {}
    for part in (rec.get("preprocessing", {}), rec.get("averaged", {}), rec.get("identification", {})):
        for w in part.get("warnings", []) if part else []:
            cats[w["category"]] = cats.get(w["category"], 0) + 1
    return ", ".join(sorted(cats)) or "-"


def _adequacy_cell(ident: dict[str, Any]) -> str:
    a = ident.get("adequacy")
    if not a:
        return "-"
    return f"{_g(a['ratio'], 3)} ({a['dof']} dof), p = {_g(a['p_value'], 2)}"


def data_table(recs: Sequence[dict[str, Any]]) -> list[str]:
    rows = [
        "| experiment | kept / dropped | f found (Hz) | vs nominal | periods | samples/period | input THD "
        "| noise sd | output lead (deg) | linear NRMSE |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in recs:
        pre = r.get("preprocessing", {})
        kept = len(pre.get("kept", []))
        reasons: dict[str, int] = {}
        for _, _, why in pre.get("dropped", []):
            reasons[why] = reasons.get(why, 0) + 1
        dropped = ", ".join(f"{k}" + (f" x{v}" if v > 1 else "") for k, v in sorted(reasons.items())) or "-"
        seg = "" if r.get("segment") in (0, None) else f" #{r['segment']}"
        if r.get("frequency_hz") is None:
            err = r.get("error", {})
            rows.append(f"| {r['label']}{seg} | refused ({err.get('class', '?')}) | | | | | | | | |")
            continue
        av = r.get("averaged", {})
        unit = r["units"]["y"].split(" ")[0]
        off = r["frequency_offset_pct"]
        off_cell = "-" if off is None else f"{off:+.3f} %"
        rows.append(
            f"| {r['label']}{seg} | {kept} / {dropped} | {r['frequency_hz']:.6g} "
            f"| {off_cell} "
            f"| {r['periods']:.2f} | {r['samples_per_period']:.2f} | {_g(r['input']['thd'], 2)} "
            f"| {_g(av.get('noise_sd'), 3)} {unit} | {_g(av.get('output_phase_lead_deg'), 3)} "
            f"| {_g(av.get('linear_nrmse'), 3)} |"
        )
    return rows


def ident_table(recs: Sequence[dict[str, Any]]) -> list[str]:
    rows = [
        "| experiment | outcome | beta [95 %] | gamma [95 %] | mu [95 %] | \\|G\\| [95 %] | phi (rad) ± 95 % "
        "| NRMSE | adequacy chi2/dof, p | cross-check NRMSE (mu, phi) | warnings |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in recs:
        seg = "" if r.get("segment") in (0, None) else f" #{r['segment']}"
        ident = r.get("identification")
        xc = r.get("crosscheck")
        xc_cell = "-"
        if xc:
            xc_cell = f"{xc['nrmse']:.3g} ({xc['mu']:.3g}, {_wrap_pi(xc['phase']):.2f})"
            if xc.get("constraint"):
                xc_cell += f", {xc['constraint']}"
        if ident is None:
            err = r.get("error", {})
            rows.append(
                f"| {r['label']}{seg} | refused before identification: {err.get('class', '?')} "
                f"| | | | | | | | | {_warn_cell(r)} |"
            )
            continue
        if ident["outcome"] != "identified":
            rows.append(
                f"| {r['label']}{seg} | {_outcome_cell(ident)} | | | | | | | | {xc_cell} | {_warn_cell(r)} |"
            )
            continue
        e = ident["experiments"][0]
        rows.append(
            f"| {r['label']}{seg} | {_outcome_cell(ident)} | {_ci(ident['beta'], 3)} "
            f"| {_ci(ident['gamma'], 3)} "
            f"| {_ci(ident['mu'], 3)} | {_ci(e['gain'], 4)} | {_phase_ci(e['phase'])} | {_g(e['nrmse'], 3)} "
            f"| {_adequacy_cell(ident)} | {xc_cell} | {_warn_cell(r)} |"
        )
    return rows


def joint_table(joints: Sequence[dict[str, Any]]) -> list[str]:
    rows: list[str] = []
    for j in joints:
        ident = j["identification"]
        tried = ", ".join(
            f"ref {a['reference']}: "
            + (f"cost {_g(a['cost'], 4)}" if a["outcome"] == "identified" else a.get("error", a["outcome"]))
            for a in j["attempts"]
        )
        rows.append(
            f"**Joint fit, {j['label']}** ({len(j['members'])} experiments). References tried: {tried}."
        )
        rows.append("")
        if j["status"] != "identified":
            rows.append(f"Refused for every reference: {', '.join(j.get('errors', []))}.")
            err = ident.get("error")
            if err:
                rows.append(f"With reference 0: `{err['class']}: {err['message']}`")
            rows.append("")
            continue
        rows.append(
            f"{_outcome_cell(ident)} with reference {ident['reference']}: beta = {_ci(ident['beta'], 3)}, "
            f"gamma = {_ci(ident['gamma'], 3)}, mu = {_ci(ident['mu'], 3)}; adequacy "
            f"{_adequacy_cell(ident)}."
        )
        rows.append("")
        rows.append("| experiment | f (Hz) | \\|G\\| [95 %] | phi (rad) ± 95 % | NRMSE |")
        rows.append("|---|---|---|---|---|")
        for name, e in zip(j["members"], ident["experiments"]):
            rows.append(
                f"| {name} | {e['frequency_hz']:.5g} | {_ci(e['gain'], 4)} | {_phase_ci(e['phase'])} "
                f"| {_g(e['nrmse'], 3)} |"
            )
        warns = sorted({w["category"] for w in ident.get("warnings", [])})
        if warns:
            rows.append("")
            rows.append(f"Warnings: {', '.join(warns)}.")
        rows.append("")
    return rows


def summary_table(recs_all: Sequence[dict[str, Any]], joints: Sequence[dict[str, Any]]) -> list[str]:
    """One row per data set: what was identified, refused, and how well anything fits."""
    rows = [
        "| data set | experiments | identified (on a constraint) | refused (error) | library NRMSE "
        "| cross-check NRMSE | linear NRMSE | joint fits identified |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for dataset in DATASET_ORDER:
        recs = [r for r in recs_all if r["dataset"] == dataset]
        if not recs:
            continue
        ident = [r for r in recs if r.get("status") == "identified"]
        on_c = [r for r in ident if r["identification"].get("constraint")]
        errors: dict[str, int] = {}
        for r in recs:
            if r.get("status") != "identified":
                err = (r.get("identification") or r).get("error", {})
                key = err.get("class", "?")
                if key == "SearchAtBoundError":
                    key += ", mu -> 1" if err.get("lower") else ", mu upper end"
                errors[key] = errors.get(key, 0) + 1
        refused = "; ".join(f"{v} ({k})" for k, v in sorted(errors.items())) or "0"
        js = [j for j in joints if j["dataset"] == dataset]
        rows.append(
            f"| {DATASET_TITLES[dataset]} | {len(recs)} | {len(ident)} ({len(on_c)}) | {refused} "
            f"| {_range([_lib_nrmse(r) for r in ident], '.3g')} "
            f"| {_range([r['crosscheck']['nrmse'] for r in recs if r.get('crosscheck')], '.3g')} "
            f"| {_range([r['averaged']['linear_nrmse'] for r in recs if r.get('averaged')], '.3g')} "
            f"| {sum(j['status'] == 'identified' for j in js)} of {len(js)} |"
        )
    return rows


def tally(recs: Sequence[dict[str, Any]]) -> str:
    """One sentence: how many experiments were identified, on a constraint, refused and why."""
    n = len(recs)
    ident = [r for r in recs if r.get("status") == "identified"]
    on_c = [r for r in ident if r["identification"].get("constraint")]
    refused: dict[str, int] = {}
    for r in recs:
        if r.get("status") == "identified":
            continue
        err = (r.get("identification") or r).get("error", {})
        key = err.get("class", "?")
        if key == "SearchAtBoundError":
            key += " (mu -> 1)" if err.get("lower") else " (mu at the upper end)"
        refused[key] = refused.get(key, 0) + 1
    parts = [f"{len(ident)} of {n} experiments identified"]
    if ident:
        parts[-1] += f" ({len(on_c)} of them on a Bouc-Wen constraint)"
    if refused:
        parts.append("refused: " + ", ".join(f"{v} x {k}" for k, v in sorted(refused.items())))
    bugs = [r for r in recs if r.get("status") == "library bug"]
    if bugs:
        parts.append(f"**{len(bugs)} library bug(s)**")
    nr = [r["identification"]["experiments"][0]["nrmse"] for r in ident]
    if nr:
        parts.append(f"library NRMSE {_range(nr, '.3g')}")
    xc = [r["crosscheck"]["nrmse"] for r in recs if r.get("crosscheck")]
    if xc:
        parts.append(f"cross-check NRMSE {_range(xc, '.3g')}")
    lin = [r["averaged"]["linear_nrmse"] for r in recs if r.get("averaged")]
    if lin:
        parts.append(f"best linear (spring + dashpot) NRMSE {_range(lin, '.3g')}")
    return "; ".join(parts) + "."


#: The page's prose, in a Markdown template next to this script (sections named like the keys below).
TEMPLATE = Path(__file__).with_name("real_data.md.in")


def prose() -> dict[str, str]:
    """The template's sections, by name (``intro``, ``mr_prose_before``, ..., ``rough_edges``)."""
    sections: dict[str, list[str]] = {}
    current: Optional[list[str]] = None
    for line in TEMPLATE.read_text(encoding="utf-8").splitlines():
        if line.startswith("<!-- section: ") and line.endswith(" -->"):
            current = sections.setdefault(line[len("<!-- section: ") : -len(" -->")], [])
        elif current is not None:
            current.append(line)
    return {name: "\n".join(body).strip("\n") + "\n" for name, body in sections.items()}


def _range(values: Sequence[Optional[float]], fmt: str, unit: str = "") -> str:
    vals = [float(v) for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return "-"
    lo, hi = min(vals), max(vals)
    a, b = f"{lo:{fmt}}", f"{hi:{fmt}}"
    if a == b:
        return f"{a}{unit}"
    return f"{a} to {b}{unit}" if lo < 0 else f"{a}-{b}{unit}"


def _lib_nrmse(r: dict[str, Any]) -> Optional[float]:
    ident = r.get("identification") or {}
    if ident.get("outcome") != "identified":
        return None
    value: Optional[float] = ident["experiments"][0]["nrmse"]
    return value


def _adeq_ratio(r: dict[str, Any]) -> Optional[float]:
    ident = r.get("identification") or {}
    a = ident.get("adequacy") if ident.get("outcome") == "identified" else None
    return None if not a else a["ratio"]


def _section_facts(dataset: str, recs: Sequence[dict[str, Any]]) -> dict[str, str]:
    ok = [r for r in recs if r.get("frequency_hz") is not None]
    av = [r for r in ok if r.get("averaged")]
    xcs = [r["crosscheck"] for r in av if r.get("crosscheck")]
    ident = [r for r in av if _lib_nrmse(r) is not None]
    mu1 = [
        r
        for r in av
        if r["identification"]["outcome"] == "refused" and r["identification"]["error"].get("lower")
    ]
    facts = {
        "freq_range": _range([r["frequency_offset_pct"] for r in ok], ".2f", " %"),
        "periods_range": _range([r["periods"] for r in ok], ".0f", " periods"),
        "lead_range": _range([r["averaged"]["output_phase_lead_deg"] for r in av], ".0f"),
        "lin_range": _range([r["averaged"]["linear_nrmse"] for r in av], ".2f"),
        "lib_range": _range([_lib_nrmse(r) for r in ident], ".3g"),
        "lib_phi_range": _range(
            [_wrap_pi(r["identification"]["experiments"][0]["phase"]["value"]) for r in ident], ".2f"
        ),
        "adeq_range": _range([_adeq_ratio(r) for r in ident], ".3g"),
        "xc_range": _range([x["nrmse"] for x in xcs], ".3g"),
        "xc_mu_range": _range([x["mu"] for x in xcs], ".2f"),
        "xc_phi_range": _range([_wrap_pi(x["phase"]) for x in xcs], ".2f"),
        "n_ident": str(len(ident)),
        "n_mu1": str(len(mu1)),
    }
    if dataset == "mr-damper":
        for key, current in (("f0", "0"), ("f1", "1")):
            amps = [
                0.5 * r["averaged"]["output_peak_to_peak"]
                for r in av
                if r["metadata"]["coil_current_A"] == current
            ]
            facts[key] = _range(amps, ".0f")
    if dataset == "friction-damper":
        sweep = [r for r in av if "0.5amplitude" in r["file"] and r.get("crosscheck")]
        facts["xc_gain_sweep"] = ", ".join(f"{r['crosscheck']['gain']:.3g}" for r in sweep) + " kip/in"
        facts["fr15_periods"] = _range([r["periods"] for r in ok if "1.5amplitude" in r["file"]], ".2f")
        facts["fr_freq"] = f"{max((abs(r['frequency_offset_pct']) for r in ok), default=math.nan):.3f} %"
    if dataset == "wire-rope":
        prov = {"16Hz_A2": 93, "18Hz_A2": 230, "20Hz_A2": 196, "22Hz_A2": 238, "18Hz_A4": 122, "22Hz_A4": 216}
        facts["freqs"] = ", ".join(f"{r['frequency_hz']:.3f}" for r in ok)
        facts["offsets"] = _range([r["frequency_offset_pct"] for r in ok], ".2f", " %")
        facts["distorted"] = str(
            sum(
                any(w["category"] == "DistortedInputWarning" for w in r["preprocessing"]["warnings"])
                for r in ok
            )
        )
        facts["prov_periods"] = "/".join(str(prov.get(r["label"], "?")) for r in ok)
        facts["kept_periods"] = "/".join(f"{r['periods']:.0f}" for r in ok)
        for key, level in (("lead_a2", "A2"), ("lead_a4", "A4")):
            leads = [
                r["averaged"]["output_phase_lead_deg"]
                for r in av
                if r["metadata"]["amplitude_level"] == level
            ]
            facts[key] = _range(leads, ".0f")
    if dataset == "bh-microwire":
        facts["kept"] = "/".join(f"{r['periods']:.0f}" for r in ok)
        facts["freqs"] = ", ".join(f"{r['frequency_hz'] / 1e3:.2f}" for r in ok)
    return facts


def _bracket_facts(recs_all: Sequence[dict[str, Any]]) -> dict[str, str]:
    retried = [r for r in recs_all if r.get("first_attempt")]
    parts = []
    for r in retried:
        ident = r["identification"]
        if ident["outcome"] == "identified":
            e = ident["experiments"][0]
            parts.append(f"{r['label']} then gave mu = {ident['mu']['value']:.3g} (NRMSE {e['nrmse']:.3g})")
        else:
            err = ident["error"]
            where = f"mu -> {err['bound']:g}" if err.get("bound") is not None else err["class"]
            parts.append(f"{r['label']} was refused again ({err['class']}, {where})")
    mu1 = [
        r
        for r in recs_all
        if r.get("identification", {}).get("outcome") == "refused"
        and r["identification"]["error"].get("lower")
    ]
    xc1 = [r for r in mu1 if r.get("crosscheck") and r["crosscheck"]["mu_at_lower_bound"]]
    return {
        "retries": "; ".join(parts) if parts else "none was needed",
        "n_mu1": str(len(mu1)),
        "xc_mu1": str(len(xc1)),
    }


def _rough_facts(recs_all: Sequence[dict[str, Any]]) -> dict[str, str]:
    ident = [r for r in recs_all if _lib_nrmse(r) is not None]
    on_c = [r for r in ident if r["identification"].get("constraint")]
    worse = [r for r in ident if (_lib_nrmse(r) or 0.0) >= 0.8]
    branch = [
        r for r in worse if r.get("crosscheck") and r["crosscheck"]["nrmse"] < 0.5 * (_lib_nrmse(r) or 0.0)
    ]
    ex_branch = "none"
    if branch:
        r = min(branch, key=lambda r: r["crosscheck"]["nrmse"] / (_lib_nrmse(r) or 1.0))
        e = r["identification"]["experiments"][0]
        ex_branch = (
            f"{r['label']}: library NRMSE {e['nrmse']:.3g} with phi = "
            f"{_wrap_pi(e['phase']['value']):.2f} rad, cross-check {r['crosscheck']['nrmse']:.3g} with "
            f"phi = {_wrap_pi(r['crosscheck']['phase']):.2f} rad"
        )
    mr_mu1 = [
        r
        for r in recs_all
        if r["dataset"] == "mr-damper"
        and r.get("identification", {}).get("outcome") == "refused"
        and r["identification"]["error"].get("lower")
    ]
    interior = [r for r in mr_mu1 if r.get("crosscheck") and r["crosscheck"]["mu"] > 1.2]
    mu1_all = [
        r
        for r in recs_all
        if r.get("identification", {}).get("outcome") == "refused"
        and r["identification"]["error"].get("lower")
    ]
    profile_mu1 = [
        r
        for r in mu1_all
        if r["profile"]["outcome"] == "refused" and r["profile"]["error"]["class"] == "SearchAtBoundError"
    ]
    ex_interior = ", ".join(f"{r['label']}: mu = {r['crosscheck']['mu']:.2f}" for r in interior[:3]) or "none"
    prov = {"16Hz_A2": 93, "18Hz_A2": 230, "20Hz_A2": 196, "22Hz_A2": 238, "18Hz_A4": 122, "22Hz_A4": 216}
    trims = [
        f"{r['label']}: {r['periods']:.0f} of {prov[r['label']]} periods kept"
        for r in recs_all
        if r["dataset"] == "wire-rope"
        and r.get("periods")
        and r["label"] in prov
        and r["periods"] < 0.9 * prov[r["label"]]
    ]
    return {
        "n_constraint": str(len(on_c)),
        "n_ident": str(len(ident)),
        "ex_constraint": ", ".join(r["label"] for r in on_c[:3]) or "none",
        "n_worse": str(len(worse)),
        "ex_worse": ", ".join(f"{r['label']} {_lib_nrmse(r):.3g}" for r in worse[:4]) or "none",
        "ex_branch": ex_branch,
        "n_interior": str(len(interior)),
        "n_mu1_all": str(len(mu1_all)),
        "n_profile_mu1": str(len(profile_mu1)),
        "n_mu1_mr": str(len(mr_mu1)),
        "ex_interior": ex_interior,
        "ex_trim": "; ".join(trims) or "none",
    }


def render(doc: dict[str, Any], doc_path: Path, out: Path) -> str:
    """docs/real-data.md from the results (``doc``); figure links relative to ``doc_path``."""
    recs_all: list[dict[str, Any]] = doc["experiments"]
    rel = Path(os.path.relpath(out, doc_path.parent))
    xcs = [r["crosscheck"] for r in recs_all if r.get("crosscheck")]
    text = prose()
    lines = [
        text["intro"].format(
            library=f"bouc_wen_id {doc['library_version']}",
            overall=tally(recs_all),
            xc_adequacy=_range([x.get("adequacy_ratio") for x in xcs], ".3g"),
            xc_p=_range([x.get("adequacy_p") for x in xcs], ".2g"),
            **_bracket_facts(recs_all),
        ),
        "",
    ]
    lines += summary_table(recs_all, doc["joint"]) + [""]
    key = {"mr-damper": "mr", "friction-damper": "friction", "wire-rope": "wire", "bh-microwire": "bh"}
    for dataset in DATASET_ORDER:
        recs = [r for r in recs_all if r["dataset"] == dataset]
        if not recs:
            continue
        before, after = text[f"{key[dataset]}_prose_before"], text[f"{key[dataset]}_prose_after"]
        facts = _section_facts(dataset, recs)
        figs = doc["figures"].get(dataset, [])
        lines += [f"## {DATASET_TITLES[dataset]}", "", before.format(**facts).rstrip(), ""]
        lines += [f"Outcome: {tally(recs)}", ""]
        lines += ["### Data: steady segments, frequency, noise", ""] + data_table(recs) + [""]
        for name in figs:
            if name.endswith("-segments.png"):
                lines += [f"![records and kept segments]({(rel / name).as_posix()})", ""]
        lines += ["### Identification, one experiment at a time", ""] + ident_table(recs) + [""]
        for name in figs:
            for suffix, alt in (("-loops.png", "averaged loops"), ("-residuals.png", "residuals")):
                if name.endswith(suffix):
                    lines += [f"![{alt}]({(rel / name).as_posix()})", ""]
        lines += [after.format(**facts).rstrip(), ""]
        joints = [j for j in doc["joint"] if j["dataset"] == dataset]
        if joints:
            lines += ["### Joint fits", ""] + joint_table(joints)
        for name in figs:
            if name.endswith("-bode.png"):
                lines += [f"![Bode points]({(rel / name).as_posix()})", ""]
        for name in figs:
            if "-joint-" in name:
                lines += [f"![joint fit loops]({(rel / name).as_posix()})", ""]
    lines.append(text["rough_edges"].format(**_rough_facts(recs_all)).rstrip())
    bugs = [r for r in recs_all if r.get("status") == "library bug"]
    if bugs:
        lines += ["", "**Exceptions that are not named errors (library bugs):**", ""]
        lines += [f"- {r['label']}: `{(r.get('identification') or r)['error']['class']}`" for r in bugs]
    lines += [
        "",
        "## Provenance and licenses",
        "",
        "- MR damper: DanielMaurelE/vRTHS_AMBC_MRdamper, MIT (c) 2022 mequiroz.",
        "- Friction damper: ARTS-Laboratory/Dataset-Friction-Damper-with-Backlash, CC BY-SA 4.0 "
        "(Coble, Huggins, "
        "Cao, Ricles, Downey); not redistributed, read from ../shared.",
        "- Wire-rope isolator: deepfe/Wire_rope_isolators, no license stated; read in place only.",
        "- B-H microwire: DYK-Team/Digital_BH-loop_algorithm, no license stated; read in place only.",
        "",
    ]
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data" / "real")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "real-data")
    parser.add_argument("--doc", type=Path, default=REPO / "docs" / "real-data.md", help="the generated page")
    parser.add_argument("--datasets", nargs="+", choices=DATASET_ORDER, default=list(DATASET_ORDER))
    parser.add_argument("--no-crosscheck", action="store_true", help="skip the multi-start cross-check")
    parser.add_argument("--doc-only", action="store_true", help="regenerate the page from results.json")
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="processes for the independent records (default: one per core; the results do not depend on it)",
    )
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    if args.doc_only:
        doc = json.loads((args.out / "results.json").read_text(encoding="utf-8"))
    else:
        doc = run(
            args.data.resolve(),
            args.out.resolve(),
            args.datasets,
            cross=not args.no_crosscheck,
            workers=args.workers,
        )
    args.doc.write_text(render(doc, args.doc.resolve(), args.out.resolve()), encoding="utf-8")
    what = f"{args.doc}" if args.doc_only else f"{args.out / 'results.json'}, the figures and {args.doc}"
    print(f"wrote {what} in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

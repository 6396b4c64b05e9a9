"""Identify the plain Wiener-Bouc-Wen model on four sets of real hysteresis recordings, honestly.

Run from the repository root (the package must be importable, e.g. ``PYTHONPATH=python``)::

    python studies/real_data.py            # all four data sets, ~2.5 min on 2 cores
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
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Optional

import _adapters as ad  # studies/ is not a package: this file's folder is on sys.path when run
import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import _core
from bouc_wen_id.signal import AveragedPeriod, SegmentReport, average_segments
from numpy.typing import NDArray
from real_data_figures import write_figures
from real_data_page import DATASET_ORDER, MU_BRACKET, TWO_PI, Z95, render

if TYPE_CHECKING:  # pragma: no cover - typing only
    pass

FloatArray = NDArray[np.float64]
REPO = Path(__file__).resolve().parents[1]
#: The wider mu bracket tried when a fit ends on the upper end of the default one.
WIDE_MU_BRACKET = (1.0, 40.0)
#: A fit is "on a constraint" when beta - |gamma| or beta + gamma is below this fraction of |beta| + |gamma|.
CONSTRAINT_RTOL = 1e-6


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
    except Exception as exc:  # noqa: BLE001 - a named refusal, or a library bug recorded, not fatal
        return {
            "outcome": "refused" if isinstance(exc, bw.BoucWenIdError) else "library bug",
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


Attempt = tuple[dict[str, Any], dict[str, Any], Optional[bw.IdentificationResult]]


def joint_attempt(members: list[Outcome], r: int) -> Attempt:
    """The joint refined fit of ``members`` from member ``r`` as the reference: (brief, record, result)."""
    items = [o.averaged for o in members if o.averaged is not None]
    rec, res, first = identify_with_retry(items, reference=r)
    brief: dict[str, Any] = {"reference": r, "outcome": rec["outcome"], "mu_bracket": rec["mu_bracket"]}
    if first is not None:
        brief["first_attempt"] = first["error"]["class"]
    if res is None:
        brief["error"] = rec["error"]["class"]
    else:
        brief["cost"] = rec["cost"]
        brief["mu"] = rec["mu"]["value"]
    return brief, rec, res


def joint_fit(
    dataset: str, label: str, members: list[Outcome], attempts: Optional[list[Attempt]] = None
) -> Joint:
    """A joint refined fit, started from each member as the reference in turn; the lowest cost wins.

    ``attempts``: the :func:`joint_attempt` of every reference, when they were run elsewhere (in parallel).
    """
    items = [o.averaged for o in members if o.averaged is not None]
    if attempts is None:
        attempts = [joint_attempt(members, r) for r in range(len(items))]
    best: Optional[tuple[dict[str, Any], bw.IdentificationResult]] = None
    for _, rec, res in attempts:
        if res is not None and (best is None or res.cost < best[1].cost):
            best = (rec, res)
    record: dict[str, Any] = {
        "dataset": dataset,
        "label": label,
        "members": [o.spec.label for o in members],
        "attempts": [brief for brief, _, _ in attempts],
    }
    if best is None:
        errors = sorted({b["error"] for b, _, _ in attempts if "error" in b})
        record["status"] = "refused"
        record["errors"] = errors
        record["identification"] = identify_record(items)[0]
        return Joint(record, members, None)
    record["status"] = "identified"
    record["identification"] = best[0]
    return Joint(record, members, best[1])


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
    # One rayon thread and one BLAS thread per worker process: the parallelism is across the records, and a
    # threaded OpenBLAS spins on the other core while it waits (bouc_wen_id._threads).
    os.environ["RAYON_NUM_THREADS"] = "1"
    from bouc_wen_id._threads import limit_blas_threads

    limit_blas_threads()


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


def _joint_attempt_args(args: tuple[list[Outcome], int]) -> Attempt:
    return joint_attempt(*args)


def _run_dataset(
    doc: dict[str, Any], pool: Any, data_dir: Path, out: Path, dataset: str, cross: bool
) -> None:
    """One data set's records (in parallel on ``pool``), joint fits and figures, into ``doc``."""
    t0 = time.perf_counter()
    specs = load_specs(data_dir, dataset)
    batches = pool.map(_process_spec, specs, [cross] * len(specs))
    outcomes = [o for batch in batches for o in batch]
    t1 = time.perf_counter()
    # Every (group, reference) start is an independent job: spread over the pool, then the best per group.
    groups = joint_groups(outcomes)
    jobs = [(members, r) for _, _, members in groups for r in range(len(members))]
    done_jobs = iter(list(pool.map(_joint_attempt_args, jobs)))
    joints = [
        joint_fit(ds, label, members, [next(done_jobs) for _ in members]) for ds, label, members in groups
    ]
    t2 = time.perf_counter()
    doc["experiments"] += [o.record for o in outcomes]
    doc["joint"] += [j.record for j in joints]
    doc["figures"][dataset] = write_figures(dataset, specs, outcomes, joints, out)
    done = sum(o.record["status"] == "identified" for o in outcomes)
    print(
        f"{dataset}: {len(specs)} records, {len(outcomes)} experiments, {done} identified, "
        f"{len(outcomes) - done} refused ({time.perf_counter() - t0:.1f} s: records {t1 - t0:.1f} s, "
        f"joint fits {t2 - t1:.1f} s, figures {time.perf_counter() - t2:.1f} s)",
        flush=True,
    )


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

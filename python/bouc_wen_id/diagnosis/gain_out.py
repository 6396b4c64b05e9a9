"""A drifting output gain said and divided out of the records, every record kept (session 48, review 47).

The drift test (settling.py) leaves out a record whose loop drifts from period to period when no
degradation explains it: "a transient not yet settled, or a sensor whose gain or zero drifts". A zero that
drifts is taken out before (zero_drift.py); a gain that drifts was not. Review 47 (failure 5: a 2 % linear
sensor gain drift over each record, config L) lost 7 of 9 effects to it: 5 of 8 records left out, the
effects named from the 3 left only as alternatives, and the advice "record more settling periods", which
would not help.

A gain drifting over a record (``y`` times ``1 + g t``: a load cell warming up, an amplifier's gain with
temperature) moves every period by ``g t`` times the recorded loop, its DC and every harmonic alike, in a
straight line over the periods. :func:`read` tells it from what else drifts, on each record's periods after
settling (harmonics 0..:data:`HARMONICS`, each period regressed on a constant, the period index ``t`` and
its square):

* the drift along the mean loop (``g``, one per record) is significant in every record the drift test left
  out (:data:`GAIN_LEVEL`): what moves them is a scale;
* no record drifts beyond its gain (the slope less ``g`` times the mean loop, an F-test on the harmonics'
  remaining directions): a loop centre settling, a degradation past saturation or a transient changes the
  loop's shape, which no gain does;
* no record's periods curve (the quadratic's F-test on every direction): a transient decays with periods,
  a gain drifting in a line does not.

Both refusals are tested at :data:`SHAPE_LEVEL`, Bonferroni over the records and the two tests; a refusal
(or too few periods to tell, under :data:`MIN_PERIODS`) leaves the diagnosis as it was. The noise is
pooled over the harmonics as white: under coloured noise the low harmonics' larger scatter makes both
refusal tests fire more readily (a false correction is the harm to avoid; a refused one is the drift
test's verdict as before).

When it reads a gain drift, each record is divided by its own ``1 + g t`` (``t`` in periods from its first
sample: each record brought to the gain at its start, where a sensor is zeroed and calibrated; at its own
mean gain instead, review 47's L records stayed 1.4 to 1.8 % apart, a misfit of its own that had
``inertia_x-10-L-1`` named viscous damping and a sensor lag in part) on copies, the diagnosis runs again on
them (:func:`rediagnosed`) and is kept when it leaves none of those records out; its verdict says the gain
drift and what to do about it (:func:`clause`), its notes each record's rate and standard error. ``g``'s
error ``dg`` scales the corrected averaged period by ``dg`` times the periods from the record's start to
the middle of those read (an extrapolation; about ``12 (reach / n)^2`` in chi-square along the loop): the
notes give each record's figure; the values' standard errors do not include it. Recordings, and lab
Measurements with one steady segment (the command line's path); anything else is left as it was.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np

from ..signal._harmonic_ls import harmonic_basis
from .result import Diagnosis
from .verdict_text import after_headline

#: Kill switch (tests compare with and without).
ENABLED = True
#: Harmonics of each period read (0..HARMONICS; fewer when the period has fewer samples).
HARMONICS = 15
#: Fewest periods after settling for a record to be read (three coefficients and a spread).
MIN_PERIODS = 6
#: Level of each left-out record's gain slope (two-sided): the drift there is a scale.
GAIN_LEVEL = 0.01
#: Family level of the refusals (a shape beyond the gain, a curvature), Bonferroni over records and tests.
SHAPE_LEVEL = 0.05
#: Level of the records' agreement on one clock of the gain's drift (:func:`_clock`).
CLOCK_LEVEL = 0.05
#: Where the diagnosis's settings keep the reading (JSON).
SETTING = "gain_drift"


@dataclass(frozen=True)
class Record:
    """One record's reading: the gain's rate per period (a fraction of the gain at the record's start), its
    standard error, the periods after settling and in the whole record, and the p-values of the gain,
    shape and curvature tests."""

    source: str
    rate: float
    se: float
    periods: int
    record_periods: int
    gain_p: float
    shape_p: float
    curve_p: float
    start: float  # the record's first sample (s): the rate is relative to the gain there
    period: float  # s
    reach: float = 0.0  # periods from the record's start to its stretch's middle (the extrapolation)


@dataclass(frozen=True)
class GainDrift:
    """A gain drift read on the set: each read record (by item index) and the corrected items."""

    records: dict[int, Record]
    items: tuple[Any, ...]
    clock: str = ""  # the clock of the one rate the records share (:data:`CLOCKS`), "" for their own

    def note(self) -> str:
        rows = ", ".join(
            f"{r.source} {100 * r.rate:+.3g} ± {100 * r.se:.2g} % a period (gain p = {r.gain_p:.2g}; beyond "
            f"the gain p = {r.shape_p:.2g}, curving p = {r.curve_p:.2g})"
            for r in self.records.values()
        )
        if self.clock:
            how = (
                f"one rate {self.clock} shared by the records (they agree on that clock), each record "
                "divided by 1 + g t (t in periods from its first sample: each at the gain of its start); "
                "that rate's error scales each averaged period by at most "
                f"{max(100 * r.se * r.reach for r in self.records.values()):.2g} %"
            )
        else:
            how = (
                "each record's own rate (they agree on no one clock), each divided by its own line over its "
                "value at the middle of the periods read (each kept at its mean gain there: the records' "
                "gains may differ by up to the rate times the periods from their start)"
            )
        return (
            "the output's gain drifts over each record, its loop scaled period by period in a straight line "
            f"with no change of its shape and no decay: {rows} (% of the gain at the record's start); {how}; "
            "on copies, every record kept; the values' standard errors do not include the rate's error"
        )


def _rss(x: np.ndarray, y: np.ndarray) -> tuple[float, np.ndarray]:
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    return float(np.sum((y - x @ coef) ** 2)), coef


def _f_p(more: float, less: float, dof1: int, dof2: int) -> float:
    """The F-test's p of ``dof1`` columns that took the residual sum of squares from ``less`` to ``more``."""
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    if not (dof1 > 0 and dof2 > 0 and more > 0):
        return 1.0
    return float(fdtrc(dof1, dof2, max(less - more, 0.0) / dof1 / (more / dof2)))


def _read(
    source: str, t: np.ndarray, y: np.ndarray, omega: float, periods: float, record: tuple[float, float]
) -> Optional[Record]:
    """:class:`Record` of a steady stretch (``t``, ``y``; ``omega`` rad/s, ``periods`` of it) by least
    squares on the periodic columns, the same times ``tau`` (periods from its middle) and ``tau^2``;
    ``record``: the whole record's first sample's time and its length in periods. The gain's rate is
    read relative to the stretch's mean gain and said relative to the gain at the record's start."""
    from scipy.special import stdtr

    n = int(periods)
    k = min(HARMONICS, int(t.size / max(periods, 1.0)) // 2 - 1)
    if n < MIN_PERIODS or k < 1:
        return None
    tau = (t - 0.5 * (t[0] + t[-1])) * omega / (2.0 * math.pi)
    b = harmonic_basis(omega * t, k)  # the periodic columns: 1, cos and sin of harmonics 1..k
    curve = (tau**2 - np.mean(tau**2))[:, None] * b
    full, coef = _rss(np.hstack([b, tau[:, None] * b, curve]), y)
    dof = y.size - 3 * b.shape[1]
    mean = b @ coef[: b.shape[1]]
    if not (full > 0 and float(mean @ mean) > 0 and dof > 0):
        return None
    gain_only, _ = _rss(np.hstack([b, (tau * mean)[:, None], curve]), y)  # the slope along the loop alone
    straight, _ = _rss(np.hstack([b, tau[:, None] * b]), y)
    x = np.hstack([b, (tau * mean)[:, None]])
    rest, cg = _rss(x, y)
    cov = np.linalg.pinv(x.T @ x) * rest / (y.size - x.shape[1])
    rate, se = float(cg[-1]), math.sqrt(max(float(cov[-1, -1]), 0.0))
    period = 2.0 * math.pi / omega
    back = 1.0 - rate * (0.5 * (t[0] + t[-1]) - record[0]) / period  # the start's gain over the mean's
    if not back > 0:
        return None
    return Record(
        source=source,
        rate=rate / back,
        se=se / back**2,
        periods=n,
        record_periods=int(round(record[1])),
        gain_p=float(2.0 * stdtr(y.size - x.shape[1], -abs(rate) / se)) if se > 0 else 1.0,
        shape_p=_f_p(full, gain_only, b.shape[1] - 1, dof),
        curve_p=_f_p(full, straight, b.shape[1], dof),
        start=record[0],
        period=period,
        reach=(0.5 * (t[0] + t[-1]) - record[0]) / period,
    )


def _records(item: Any, i: int) -> list[Record]:
    """The :class:`Record` of a Recording (its periods after settling), or of a lab Measurement with one
    steady segment (its own, by the library's segmenting); [] for anything else or too short a stretch."""
    from ..measurement import Measurement
    from ..model import Recording

    if isinstance(item, Recording):
        p, s = int(item.samples_per_period), int(item.settle_periods)
        n = int(item.whole_periods) - s
        t, y = (np.asarray(a, dtype=np.float64)[s * p : (s + n) * p] for a in (item.t, item.y))
        name = str(item.metadata.get("name", f"recording {i}"))
        whole = (float(item.t[0]), float(item.whole_periods))
        got = _read(name, t, y, float(item.frequency), n, whole) if n > 0 and p >= 8 else None
        return [got] if got else []
    if not isinstance(item, Measurement):
        return []
    from ..signal import average_segments

    try:
        seg = average_segments(item)
    except Exception:  # a measurement the segmenting refuses: not read here (the diagnosis says why)
        return []
    if len(seg.report.kept) != 1:
        return []
    kept, fit, ap = seg.report.kept[0], seg.report.fits[0], seg.periods[0]
    t, y = (np.asarray(a, dtype=np.float64)[kept.start : kept.stop] for a in (item.t, item.y))
    w = float(fit.frequency)
    whole = (float(item.t[0]), (float(item.t[-1]) - float(item.t[0])) * w / (2.0 * math.pi))
    got = _read(str(ap.source), t, y, w, (t[-1] - t[0]) * w / (2.0 * math.pi), whole)
    return [got] if got else []


def _divided(item: Any, r: Record, to_start: bool) -> Any:
    """A copy of ``item`` divided by ``1 + g tau`` (``tau`` in periods from the record's first sample): each
    record at the gain of its start, where a sensor is zeroed and calibrated (a gain left different
    between records, each at its own mean, is a misfit the plain model cannot take: review 47's L had
    viscous damping and a sensor lag named beside an inertia on x that way)."""
    from ..measurement import Measurement

    t, y = np.asarray(item.t, dtype=np.float64), np.asarray(item.y, dtype=np.float64)
    if to_start:
        y = y / (1.0 + r.rate * (t - r.start) / r.period)
    else:  # at its mean gain over the periods read: the same line, divided by its value there
        y = y * (1.0 + r.rate * r.reach) / (1.0 + r.rate * (t - r.start) / r.period)
    return item._replace(item.t, item.u, y) if isinstance(item, Measurement) else replace(item, y=y)


def read(experiments: Sequence[Any], left_out: Sequence[str]) -> Optional[GainDrift]:
    """The gain drift of the records when it explains the drift of those ``left_out`` (module docstring),
    with the corrected copies; None when it does not, or a left-out record cannot be read."""
    if not ENABLED or not left_out:
        return None
    read_ = {i: rs[0] for i, item in enumerate(experiments) for rs in [_records(item, i)] if rs}
    if not read_ or any(s not in {r.source for r in read_.values()} for s in left_out):
        return None
    level = SHAPE_LEVEL / (2 * len(read_))
    if any(min(r.shape_p, r.curve_p) < level for r in read_.values()):
        return None
    if any(r.gain_p >= GAIN_LEVEL for r in read_.values() if r.source in left_out):
        return None
    clock, rates = _clock(list(read_.values()))
    read_ = {i: replace(r, rate=a, se=e) for (i, r), (a, e) in zip(read_.items(), rates)}
    items = tuple(
        _divided(item, read_[i], bool(clock)) if i in read_ else item for i, item in enumerate(experiments)
    )
    return GainDrift(read_, items, clock)


#: Each clock a drifting gain may keep: a record's rate per period is the shared rate times this.
CLOCKS: dict[str, Callable[[Record], float]] = {
    "over each record": lambda r: 1.0 / max(r.record_periods, 1),
    "a period": lambda r: 1.0,
    "a second": lambda r: r.period,
}


def _clock(rs: list[Record]) -> tuple[str, list[tuple[float, float]]]:
    """``(clock, [(rate, se)])``: the records' rates (per period, of the gain at their start) from ONE rate
    on the clock of :data:`CLOCKS` they agree on best (chi-square of the rates about it, p at least
    :data:`CLOCK_LEVEL`), which brings each record to its start's gain with that rate's small error; else
    ``("", their own)``, each record then kept at its mean gain over the periods read (no extrapolation:
    one record's own rate, taken back to its start, scaled a long-settled record's averaged period by its
    error times the periods back, 0.4 to 0.9 % on review 47's L, and a null there had a weak remainder)."""
    from scipy.special import chdtrc

    own = [(r.rate, r.se) for r in rs]
    if len(rs) < 2 or any(not r.se > 0 for r in rs):
        return "", own
    best: tuple[float, str, list[tuple[float, float]]] = (-1.0, "", own)
    for name, factor in CLOCKS.items():
        f = np.array([factor(r) for r in rs])
        a, w = np.array([r.rate for r in rs]), np.array([1.0 / r.se**2 for r in rs])
        shared = float(np.sum(w * f * a) / np.sum(w * f * f))
        se = 1.0 / math.sqrt(float(np.sum(w * f * f)))
        p = float(chdtrc(len(rs) - 1, float(np.sum(w * (a - shared * f) ** 2))))
        if p > best[0]:
            best = (p, name, [(shared * fi, se * fi) for fi in f])
    return (best[1], best[2]) if best[0] >= CLOCK_LEVEL else ("", own)


def _span(values: Sequence[float], unit: str) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:+.2g} % {unit}" if f"{lo:+.2g}" == f"{hi:+.2g}" else f"{lo:+.2g} to {hi:+.2g} % {unit}"


#: What to do about a drifting sensor gain.
WHAT_TO_DO = "calibrate the sensor, or record shorter or at a steady temperature"


def clause(g: GainDrift) -> str:
    """The verdict's clause on the gain drift (said second, after the headline)."""
    rs = [r for r in g.records.values() if r.gain_p < GAIN_LEVEL] or list(g.records.values())
    per = _span([100 * r.rate for r in rs], "a period")
    whole = _span([100 * r.rate * r.record_periods for r in rs], "over each record")
    return (
        f"; the output's gain drifts {per} ({whole}): a sensor or amplifier drift, not settling (the "
        "periods' drift is the loop scaled, its shape unchanged, no decay), divided out of every record and "
        f"each kept ({WHAT_TO_DO})"
    )


def rediagnosed(
    d: Diagnosis,
    experiments: Sequence[Any],
    left: Sequence[str],
    again: Callable[[list[Any]], tuple[Diagnosis, list[Any], tuple[str, str]]],
) -> Optional[tuple[Diagnosis, list[Any], tuple[str, str]]]:
    """``again`` (the diagnosis) on the gain-corrected copies of ``experiments`` with the gain drift said,
    when :func:`read` reads one and the corrected diagnosis leaves none of ``left`` out; else None. Not
    when degradation's test fitted the drift of the whole set (``d``'s left-out note says so): the drift
    then has a physical reading the gain's does not rule out."""
    from .deg_unnamed import KEY
    from .left_out import left as left_of

    g = None if d.settings.get(KEY) else read(experiments, left)
    if g is None:
        return None
    d2, items, units = again(list(g.items))
    if set(left_of(d2)) & set(left):
        return None
    rates = {r.source: {"rate_per_period": r.rate, "se": r.se, "p": r.gain_p} for r in g.records.values()}
    d2 = replace(
        d2,
        verdict=after_headline(d2.verdict, clause(g)),
        notes=(g.note(), *d2.notes),
        settings={**d2.settings, SETTING: rates},
    )
    return d2, items, units


__all__ = ["ENABLED", "SETTING", "WHAT_TO_DO", "GainDrift", "Record", "clause", "read", "rediagnosed"]

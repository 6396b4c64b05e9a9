"""Which periods and experiments are fit to diagnose: the settling trimmed, sizes and responses checked, the
noise floors bounded below (quantisation, numerical accuracy), and the experiments whose loop still drifts.

Moved out of ``run.py`` (layout headroom, issue 18); ``run`` imports these names, so they stay importable
from there too.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import TransientWarning
from .data import NUMERICAL_RTOL as NUMERICAL_RTOL  # moved to data.py (outliers.py needs them); kept here
from .data import (
    QUANTISED_LEVELS as QUANTISED_LEVELS,  # moved to data.py (data.prepare needs them); kept here
)
from .data import SIMULATION_ERROR_C as SIMULATION_ERROR_C
from .data import DiagExperiment
from .data import numerical_rtol as numerical_rtol
from .data import quantisation_step as quantisation_step


def _settled(experiments: Any) -> tuple[Any, list[str]]:
    """The recordings with their start-up transient trimmed, as ``identify`` trims it (TransientWarning), on
    departures clipped at a few robust sd (outliers.py: a spike is no transient); gross outliers are noted.

    A recording whose first periods differ from its steady ones beyond the noise (``transient_periods``)
    is trimmed when the rest then shows no trend (:func:`_trending`): a transient decays, a drift goes on.
    A drift that goes on through the record
    (a degrading specimen, a loop still settling slowly) is left for the degradation test and the
    per-experiment drift test (:func:`_unsettled`), which keep physics from being named from it.
    """
    from ..model import Recording
    from .outliers import outlier_notes, transient_periods  # robust to spikes (review 36)

    seq = list(experiments) if isinstance(experiments, (list, tuple)) else [experiments]
    notes: list[str] = []
    out: list[Any] = []
    for i, item in enumerate(seq):
        if not isinstance(item, Recording):
            out.append(item)
            continue
        p, s = item.samples_per_period, item.settle_periods
        n = item.whole_periods - s
        extra = transient_periods(item.y, p, s, n)
        if extra and _within_quantisation(item.y, p, s, n, extra):
            extra = 0  # a difference within the output's quantisation is no transient
        if extra and n - extra >= 4 and not _trending(item.y, p, s + extra, n - extra):
            source = item.metadata.get("name", f"recording {i}")
            msg = (
                f"{source}: the first {extra} of the {n} periods after {s} settling ones are still transient "
                f"(they differ from the steady periods beyond the noise); they were dropped, settle_periods "
                f"= {s + extra} is used"
            )
            warnings.warn(msg + ". Pass recordings with more settle_periods to choose", TransientWarning, 3)
            notes.append(msg)
            item = replace(item, settle_periods=s + extra)
        out.append(item)
    return out, [*notes, *outlier_notes(out)]


#: Level of the trend test that keeps a drift (which goes on after the trimmed periods) from being trimmed
#: as a transient: generous, so that a degradation is not cut away.
TREND_LEVEL = 0.05


def _within_quantisation(y: Any, p: int, s: int, n: int, extra: int) -> bool:
    """True when ``y`` is quantised and its first ``extra`` periods differ from the steady ones (the last
    half) by no more than the quantisation noise, ``2 q^2 / 12`` per sample (identify's transient test has
    only the period-to-period spread as its noise, which is 0 for a quantised output that repeats)."""
    q = quantisation_step(y)
    if q <= 0.0:
        return False
    seg = np.asarray(y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p)
    ref = seg[n // 2 :].mean(axis=0)
    dev = np.mean((seg[:extra] - ref) ** 2, axis=1)
    return bool(np.all(dev <= 2.0 * q * q / 12.0))


def _trending(y: Any, p: int, s: int, n: int) -> bool:
    """Whether periods ``s .. s + n`` still trend (per-period DC or fundamental amplitude against the
    period index, locate's t-test, at :data:`TREND_LEVEL`)."""
    from .data import _period_features
    from .locate import _t_sf2, _trend
    from .outliers import clipped

    rows = np.asarray(y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p)
    dc, h1 = _period_features(clipped(rows, p))  # a spike moves one period's DC: no trend (review 36)
    amp = np.abs(h1)
    _, ht, dof = _trend(amp / (float(np.mean(amp)) or 1.0))
    _, dt, _ = _trend(dc)
    return min(_t_sf2(ht, dof), _t_sf2(dt, dof)) < 0.5 * TREND_LEVEL


def _check_sizes(experiments: Any) -> None:
    """Refuse, before any arithmetic on them, inputs and outputs whose squares leave the floating-point
    range (U = 1e300 overflowed in the noise floor, the input's waveform and prepare.py)."""
    from .._text import item_label
    from ..errors import ZeroAmplitudeError
    from ..prepare import SCALE_MAX, SCALE_MIN

    seq = experiments if isinstance(experiments, (list, tuple)) else [experiments]
    for i, item in enumerate(seq):
        sizes = []
        if hasattr(item, "amplitude"):
            sizes.append(("input amplitude", abs(float(item.amplitude)), SCALE_MIN))
        for name, what in (("u", "input"), ("y", "output"), ("ybar", "output")):
            v = getattr(item, name, None)
            if isinstance(v, np.ndarray) and v.size:
                peak = float(np.max(np.abs(v)))
                sizes.append((what, peak, SCALE_MIN if name == "u" else 0.0))
        for what, size, low in sizes:
            if not low <= size <= SCALE_MAX:
                raise ZeroAmplitudeError(
                    f"{item_label(i, item)}: the {what} is of size {size:.3e}, outside [{low:g}, "
                    f"{SCALE_MAX:g}]: squares of it leave the floating-point range; express the data in "
                    "units that keep it there"
                )


def _check_experiments(exps: Sequence[DiagExperiment]) -> None:
    """Refuse, as ``identify`` does, an output with no response at the excitation (a wrong channel, pure
    noise: nothing physical can be named from it) and sizes whose squares leave the floating-point range."""
    from ..errors import ZeroAmplitudeError
    from ..prepare import SCALE_MAX, SCALE_MIN, _check_response

    for e in exps:
        peak = float(np.max(np.abs(e.ybar)))
        for what, size in (("input amplitude", abs(e.amplitude)), ("output", peak)):
            if not SCALE_MIN <= size <= SCALE_MAX:
                raise ZeroAmplitudeError(
                    f"{e.source}: the {what} is of size {size:.3e}, outside [{SCALE_MIN:g}, {SCALE_MAX:g}]: "
                    "express the data in units that keep it there (e.g. mm instead of km)"
                )
        dc = float(np.mean(e.ybar))
        _check_response(e.ybar - dc, abs(dc), e.noise_var, e.periods, e.source)


def _noise_floors(items: Any, exps: list[DiagExperiment]) -> tuple[list[DiagExperiment], list[str]]:
    """Every experiment's noise variance at least a simulated loop's numerical accuracy,
    ``(numerical_rtol(P) max |ybar|)^2``, and, on a quantised output (step q), raised by the rounding error
    that repeats every period (:func:`_locked_floors`); when it is below q^2/12, at least ``N q^2 / 12`` (the
    averaged period's error is then the repeated quantisation error, q^2/12).

    Quantised outputs can repeat a period exactly: the variance from neighbouring periods is then 0 (or far
    below a step) and a weight ``N / sigma^2`` absurd (a degradation chi-square of 1.4e26 on the MR damper's
    1 A files); noise-free data have a floor of rounding, far below what any model reproduces. The notes
    say where a floor applied (the tests there are conservative, and a numerical floor is no measured
    noise).
    """
    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    q = max((quantisation_step(it.y) for it in seq if hasattr(it, "y")), default=0.0)
    locked, lnote = _locked_floors(seq, exps, q)
    out, notes = [], []
    for e, lk in zip(exps, locked, strict=True):
        rtol = numerical_rtol(e.samples_per_period)
        numerical = (rtol * float(np.max(np.abs(e.ybar)))) ** 2
        floor = numerical
        if e.noise_var < q * q / 12.0:
            # Without noise to dither it, the quantisation error repeats every period: the averaged period
            # keeps all of it (variance q^2/12), so its weight is at most 12 / q^2.
            floor = max(floor, e.periods * q * q / 12.0)
        if lk is not None:  # the locked part of the rounding error, harmonic by harmonic (dither.py)
            raised = e.noise_var + lk[0]
            base = e.adequacy_var if e.adequacy_var.size == lk[1].size else np.full(lk[1].size, e.noise_var)
            lv = np.maximum(base + lk[1], floor)
            e = replace(
                e, noise_var=max(raised, floor), spread_var=max(e.spread_var, raised, floor), adequacy_var=lv
            )
        elif e.noise_var < floor:
            what = (
                f"below the output's quantisation step q = {q:.3g}: the quantisation error repeats every "
                "period and does not average out, so the averaged period's error is taken as q^2/12 (noise "
                f"variance {floor:.3g}); the tests on this experiment are conservative"
                if floor > numerical
                else f"below a simulated loop's numerical accuracy ({rtol:.2g} of the output's peak at "
                f"{e.samples_per_period} samples per period); the "
                f"noise floor is taken as that accuracy, variance {floor:.3g} (noise-free data: the tests "
                "compare the model with its own precision, not with a measured noise)"
            )
            notes.append(f"{e.source}: the period-to-period noise (variance {e.noise_var:.3g}) is {what}")
            # No harmonic's level below the floor either: the adequacy test's weights (adequacy_chi2.py)
            # would otherwise weigh rounding at the quiet harmonics by up to 1e18 (noise-free data).
            lv = np.maximum(e.adequacy_var, floor) if e.adequacy_var.size else e.adequacy_var
            e = replace(e, noise_var=floor, spread_var=max(e.spread_var, floor), adequacy_var=lv)
        out.append(e)
    return out, [*lnote, *notes]


def _locked_floors(seq: list[Any], exps: list[DiagExperiment], q: float) -> tuple[list[Any], list[str]]:
    """Each experiment's locked rounding error ``m`` as ``(N mean(m^2), N P |M_k|^2 at harmonics 0..P/2)``,
    what its ``noise_var`` and ``adequacy_var`` gain (per-sample units, N its periods), or None where
    nothing is locked; and the note that says it. One dither sd for the output, fitted from how every
    recording's periods fall on the levels (dither.fit_sigma_counts); nothing when there is no quantisation
    step or the dither is q/2 or more."""
    from . import dither

    none: list[Any] = [None] * len(exps)
    if q <= 0.0 or not exps:
        return none, []
    recorded = [it for it in seq if hasattr(it, "y")]
    offset = dither.grid_offset(np.concatenate([np.ravel(it.y) for it in recorded]), q)
    rows = [_steady_rows(it) for it in recorded]
    spread = [float(np.mean(np.diff(r, axis=0) ** 2)) / 2.0 for r in rows if r.shape[0] > 1]  # drift-free
    if not spread or float(np.mean(spread)) >= (SCREEN_RATIO**2 + 1.0 / 12.0) * q * q:
        return none, []  # a dither this wide locks nothing (and the level count would be long to fit)
    sigma = dither.fit_sigma_counts(rows, q, offset)
    if sigma >= dither.NO_LOCK_RATIO * q:
        return none, []
    smooth = [dither.smooth_part(e.ybar, e.spread_var / max(e.periods, 1.0)) for e in exps]
    out, rms = [], []
    for e, y in zip(exps, smooth, strict=True):
        m = dither.mean_error(y, q, sigma, offset)
        out.append((e.periods * float(np.mean(m * m)), e.periods * dither.harmonic_power(m)))
        rms.append(math.sqrt(float(np.mean(m * m))))
    if max(lk[0] / max(e.noise_var, 1e-300) for lk, e in zip(out, exps)) < LOCKED_SAID:
        return (
            out,
            [],
        )  # raised, but by too little to change a test: no note, and the noise counts as measured
    below = (
        f"noise of sd about {sigma / q:.2f} q before the converter dithers it only in part"
        if sigma >= 0.005 * q
        else "no noise before the converter dithers it"
    )
    note = (
        f"the output's quantisation step is q = {q:.3g}, and {below}: part of the rounding error repeats "
        f"every period and does not average out (r.m.s. {min(rms):.2g}-{max(rms):.2g} in the averaged "
        "periods); it is taken into the noise floor, so the tests are conservative"
    )
    return out, [note]


#: Share of an experiment's noise variance the locked rounding error must add for the note to say it (and for
#: the noise floor to count as not measured: gate.plain_gate then skips the targeted step). At N = 20 periods
#: the share is about 0.6 at a dither of q/4, 0.04 at 0.35 q and 0.008 at 0.4 q.
LOCKED_SAID = 0.05

#: A quantised output's period-to-period variance per sample at or above ``(SCREEN_RATIO^2 + 1/12) q^2``
#: (a dither of about this many steps) locks nothing: the dither is not fitted.
SCREEN_RATIO = 0.75


def _steady_rows(item: Any) -> Any:
    """A recording's averaged periods as rows (N, P) after its settling ones (one row when it has none)."""
    y = np.asarray(item.y, dtype=np.float64).ravel()
    p = int(getattr(item, "samples_per_period", y.size))
    s = int(getattr(item, "settle_periods", 0))
    n = int(getattr(item, "whole_periods", y.size // max(p, 1))) - s
    return y[s * p : (s + n) * p].reshape(max(n, 0), p) if n > 0 else y[None, :]


def trend_p(e: DiagExperiment) -> float:
    """The p of the trend test of ``e``'s per-period DC and fundamental amplitude (locate's t-test, the
    smaller of the two doubled: Bonferroni over them), each slope's standard error at least what the noise
    floor gives (rounding in noise-free data trends "significantly" against its own scatter); NaN under 4
    periods."""
    from .locate import _t_sf2, _trend

    n, p = e.h1.size, e.samples_per_period
    if n < 4:
        return float("nan")
    k2 = float(n * (n * n - 1) / 12.0)  # sum of the centred period indices squared
    amp = np.abs(e.h1)
    ref = float(np.mean(amp)) or 1.0
    pvals = []
    for values, sd in (
        (amp / ref, math.sqrt(2.0 * e.noise_var / p) / ref),
        (e.dc, math.sqrt(e.noise_var / p)),
    ):
        slope, t, dof = _trend(np.asarray(values, dtype=np.float64))
        se = abs(slope / t) if t and math.isfinite(t) else 0.0
        se = max(se, sd / math.sqrt(k2))
        pvals.append(_t_sf2(slope / se, dof) if se > 0 else 1.0)
    return min(1.0, 2.0 * min(pvals))


def drift_p(exps: Sequence[DiagExperiment]) -> list[float]:
    """Each experiment's :func:`trend_p` adjusted over the tested ones by Holm (drift_said.holm); NaN for
    one too short to test."""
    from .drift_said import holm

    raw = [trend_p(e) for e in exps]
    tested = [i for i, v in enumerate(raw) if math.isfinite(v)]
    out = [float("nan")] * len(exps)
    for i, v in zip(tested, holm([raw[i] for i in tested])):
        out[i] = v
    return out


def _unsettled(exps: Sequence[DiagExperiment]) -> list[int]:
    """Indices of the experiments whose loop drifts from period to period: :func:`drift_p` (the trend
    test, Holm over the experiments) below half the level (locate.LEVEL / 2, as before session 45's Holm:
    Bonferroni at the same family-wise level)."""
    from .locate import LEVEL

    return [i for i, v in enumerate(drift_p(exps)) if math.isfinite(v) and v < 0.5 * LEVEL]


#: Where :func:`.run.diagnose` records the experiments it left out as not settled (its ``settings``), so that
#: ``diagnose_across`` given that diagnosis leaves out the same ones.
LEFT_OUT = "left_out"


#: Where :func:`.run.diagnose` records each left-out experiment's adjusted p (:func:`drift_p`; settings).
LEFT_OUT_P = "left_out_p"

#: How a verdict ends when experiments were left out as still drifting (:func:`left_out_note` says more).
LEFT_OUT_TAIL = "left out (not settled, or a drifting sensor)"
#: The same when some left-out record's drift is not firm (drift_said.FIRM): it may drift.
LEFT_OUT_MAY = "left out (may drift: not settled, or a drifting sensor)"


def left_out_tail(p_adjusted: Sequence[float]) -> str:
    """:data:`LEFT_OUT_TAIL` when every record's drift is firm (or no p is known), else
    :data:`LEFT_OUT_MAY`."""
    from .drift_said import firm

    return LEFT_OUT_MAY if any(not firm(p) for p in p_adjusted) else LEFT_OUT_TAIL


def left_out_note(
    names: str, records: Sequence[str] = (), p_adjusted: Sequence[float] = (), why_not: str = ""
) -> str:
    """The note on experiments left out of a diagnosis as not settled (:func:`_unsettled`), one wording for
    :func:`.run.diagnose` and ``diagnose_across``.  A sensor whose gain or zero drifts over the record looks
    the same to the drift test (review 34: a 2 % gain drift), so both readings are said; with the records'
    adjusted p (:func:`drift_p`, in ``records``' order) the drift is said at drift_said's standard, each
    record with its p. ``why_not``: what degradation's test found (deg_unnamed.clause; "no degradation
    explains it" when empty)."""
    from .deg_unnamed import NONE_EXPLAINS
    from .drift_said import records_drift

    said = records_drift(records, p_adjusted) if p_adjusted else "the loop still drifts from period to period"
    deg = why_not or NONE_EXPLAINS
    tail = "" if deg == NONE_EXPLAINS else ", or that degradation"
    return (
        f"left out of the diagnosis: {names} ({said} and {deg}: a transient not yet settled, or a sensor "
        f"whose gain or zero drifts over the record{tail}); record more settling periods, or check the "
        "sensor's calibration over the record"
    )


def settled_only(exps: Sequence[DiagExperiment], degradation_named: bool) -> tuple[list[int], list[int]]:
    """``(kept, drifting)`` indices of ``exps``: every one kept when degradation is named (the drift is
    its), else those whose loop still drifts (:func:`_unsettled`) left out; diagnose's rule, read by both
    paths."""
    drifting = [] if degradation_named else _unsettled(exps)
    return [i for i in range(len(exps)) if i not in drifting], drifting

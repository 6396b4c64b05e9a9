"""A baseline that wanders: taken out of the recordings before averaging (issue 18, honest verdicts).

A load cell's zero that drifts with temperature, or any random walk added to the output, moves the loop's
centre from period to period without changing its shape. It is not hysteresis, and it is not stationary:
no noise level makes its trend chance, and in 16 periods it cannot be told from a centre that drifts. Left
in, the trend test of the period DCs called the loops "not settled", their centres differed between
experiments, and an output offset fitted part of it with a value that differed between experiments:
"unexplained" on 16 of 20 noise-only sets of the designs bench's ``walk`` rows.

So the set is tested first (:func:`detect`, on the periods after settling): the period DCs' spread about a
quadratic trend in the period index against the white noise (the periods' own spread with each period's
mean taken out), pooled over the recordings (chi-square, :data:`WANDER_ALPHA`), and their lag-1 correlation,
pooled (at least :data:`WANDER_CORRELATION`: more than the stationary correction of ``data.py`` is for),
and the first test again over the last half of the periods (records of 8 periods or more: a transient has
died out there, a wander goes on). A rough wander passes all three; white noise fails the first, a smooth
settling of the centre (a transient) the first (the quadratic takes it) or, faster, the third, a stationary
noise correlated over a period (AR(1), phi = 0.99 at 128 samples per
period: r about 0.45) the second.

When it wanders, each period's mean is the baseline (:func:`removed`): it is taken out of every whole period
of every recording, and the set's common centre put back in its place when it stands out of the spread of
the recordings' centres (a t-test with m - 1 degrees of freedom at the level of one candidate: an output
offset is then still named, with that spread as its standard error), else 0. The harmonics 1.. of every
period are untouched, so the loop, its degradation (the fundamental's trend) and its noise level there are
measured as before; the DC of each period is spent (its degrees of freedom are taken off the noise floor's,
``data.py``, and the DC is left out of the drift test, ``drift.harmonic_weights``). What the records cannot
tell (an output offset within the wander, a loop whose centre drifts, an asymmetry's DC) the verdict says.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np

from .data import BASELINE_MARK, common_centre, cross_period_correlation
from .result import Diagnosis, NamedTerm

#: Level of the pooled chi-square of the period DCs about a quadratic trend (as the colour check's).
WANDER_ALPHA = 1e-3
#: Smallest pooled lag-1 correlation of the period DCs read as a wander: a random walk's, bias-corrected, is
#: 0.68-0.96 over 10 recordings of 16 periods (a short series' estimate falls short of 1); AR(1) noise with
#: phi = 0.99 at 128 samples per period gives about 0.45, which data.py's stationary correction covers.
WANDER_CORRELATION = 0.6
#: The metadata key that marks a recording whose period means were taken out (read by ``data.py``).
MARK = BASELINE_MARK


@dataclass(frozen=True)
class Wander:
    """The set's wander test and what was kept of its centres."""

    correlation: float  # pooled lag-1 correlation of the period DCs
    late_p_value: float  # the chi-square's p-value over the last half of the periods alone
    chi2: float  # pooled chi-square of the period DCs about their quadratic trends (white-noise units)
    dof: int
    p_value: float
    centre: float  # the common centre kept (0.0 when not kept)
    centre_se: float  # its standard error: the spread of the recordings' centres over sqrt(m)
    centre_p: float  # the t-test of the common centre (NaN: fewer than 2 recordings)
    kept: bool
    level: float = math.nan  # the t-test's level (alpha over the candidates: one candidate's share)
    #: a smooth wander of the zero alone (``dc_wander.py``): the chi-square about each recording's best
    #: settling transient, its dof and p, and the fundamental's trend p; None: this module's test took it
    smooth: Optional[tuple[float, int, float, float]] = None
    #: per item of the set, the degree of the smooth curve taken out of its period means
    #: (``wander_curve.py``), or None: taken out period by period with a random walk's leak
    curves: tuple[Optional[int], ...] = ()

    def note(self) -> str:
        if self.smooth is not None:
            sx2, sdof, sp, loop_p = self.smooth
            return (
                "the baseline wanders: the period means move from period to period (lag-1 correlation "
                f"{self.correlation:.2g}) beyond a settling transient (a level and an exponential approach "
                f"per recording: chi-square {sx2:.3g} on {sdof} dof, p = {sp:.2g}), while the "
                f"loop itself does not trend (fundamental amplitude p = {loop_p:.2g}): a zero that wanders "
                f"smoothly over the record (a drifting sensor zero, for example); {self._taken()}"
            )
        return (
            "the baseline wanders: the period means trend beyond a quadratic (chi-square "
            f"{self.chi2:.3g} on {self.dof} dof, p = {self.p_value:.2g}) with a lag-1 correlation of "
            f"{self.correlation:.2g}, and on over the last half of the periods (p = "
            f"{self.late_p_value:.2g}): a baseline that moves from period to period (a drifting sensor zero, "
            "for example); each period's mean was "
            "taken as baseline and removed before averaging (one degree of freedom per period, from the "
            "noise floor), the harmonics of every period kept as measured"
        )

    def _taken(self) -> str:
        """How a smooth wander was taken out (``curves``)."""
        degrees = [d for d in self.curves if d is not None]
        steps = "each period's mean was taken as baseline and removed before averaging (one degree of "
        steps += "freedom per period, from the noise floor)"
        if not degrees:
            return f"{steps}, the harmonics of every period kept as measured"
        rest = len(self.curves) - len(degrees)
        head = "in every recording" if rest == 0 else f"in {len(degrees)} of {len(self.curves)} recordings"
        tail = "" if rest == 0 else f"; in the others (their period means are not smooth) {steps}"
        return (
            f"{head} a smooth curve through the period means (a polynomial in time of degree "
            f"{min(degrees)}-{max(degrees)}, chosen by AIC) was taken out sample by sample, its ramp within "
            "each period too, then what was left of each period's mean (one degree of freedom per period, "
            f"from the noise floor){tail}"
        )

    def clause(self) -> str:
        head = "; the baseline wanders (removed period by period): "
        if self.kept:
            return (
                f"{head}the common centre {self.centre:.4g} ± {self.centre_se:.3g} (the recordings' "
                f"centres' spread, t-test p = {self.centre_p:.2g}) was kept; a drift of the loop's centre "
                "cannot be told from the wander, nor can each experiment's own DC (an asymmetry's)"
            )
        tail = (
            " (the centres' common part, against the spread of the recordings' centres: p = "
            f"{self.centre_p:.2g}, not below {self.level:.2g}, one candidate's level)"
            if math.isfinite(self.centre_p)
            else ""
        )
        return (
            f"{head}an output offset, a drift of the loop's centre or each experiment's own DC (an "
            f"asymmetry's) cannot be told from it{tail}"
        )


def _rows(rec: Any) -> tuple[np.ndarray, int]:
    p, s = int(rec.samples_per_period), int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    return np.asarray(rec.y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p), p


def detect(items: Any, level: float) -> Optional[Wander]:
    """The set's wander test (module docstring) on its Recordings; None when it does not wander, or with
    fewer than 4 periods after settling in every recording. ``level`` is the common centre's t-test level."""
    st = _statistics(items)
    if st is None:
        return None
    chi2, dof, pval, r, pl, centres = st
    if not (pval < WANDER_ALPHA and r >= WANDER_CORRELATION and pl < WANDER_ALPHA):
        return None
    c, se, cp, kept = common_centre(centres, level)
    return Wander(r, pl, chi2, dof, pval, c if kept else 0.0, se, cp, kept, level)


def _statistics(items: Any) -> Optional[tuple[float, int, float, float, float, list[float]]]:
    """The wander test's numbers (chi-square, dof, p, pooled lag-1 correlation, the last half's p (NaN: no
    recording of 8 periods or more), the recordings' centres); None when nothing can be tested."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    from ..model import Recording

    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    recs = [r for r in seq if isinstance(r, Recording)]
    chi2, dof, late, late_dof, rs, weights, centres = 0.0, 0, 0.0, 0, [], [], []
    for rec in recs:
        try:
            rows, p = _rows(rec)
        except Exception:  # no whole-period grid: prepare() names the problem
            return None
        n = rows.shape[0]
        if n < 4 or p < 2:
            continue
        dc = rows.mean(axis=1)
        white = float(np.mean(np.diff(rows - dc[:, None], axis=0) ** 2)) / 2.0 * p / (p - 1)
        if not (white > 0 and math.isfinite(white)):
            continue
        x2, d2 = _rough(dc, p / white)
        chi2, dof = chi2 + x2, dof + d2
        if n >= 8:  # the last half alone: a transient has died out there, a wander goes on
            x2, d2 = _rough(dc[n // 2 :], p / white)
            late, late_dof = late + x2, late_dof + d2
        rs.append(cross_period_correlation(dc))
        weights.append(float(n))
        centres.append(float(dc.mean()))
    if dof == 0:
        return None
    pval = float(chdtrc(dof, chi2))
    r = float(np.average(rs, weights=weights))
    pl = float(chdtrc(late_dof, late)) if late_dof else math.nan
    return chi2, dof, pval, r, pl, centres


def short_note(items: Any) -> Optional[str]:
    """A note when the period DCs look like a wander (rough beyond a quadratic, correlated from period to
    period) but no recording has the 8 periods after settling that tell a wander from a transient (the
    last half's test): the baseline is then not removed, and the verdict's tests of the centre may read it
    as a drift or a transient. None otherwise."""
    st = _statistics(items)
    if st is None:
        return None
    chi2, dof, pval, r, pl, _ = st
    if not (pval < WANDER_ALPHA and r >= WANDER_CORRELATION) or math.isfinite(pl):
        return None
    return (
        f"the period means may wander (chi-square {chi2:.3g} on {dof} dof about a quadratic trend, p = "
        f"{pval:.2g}, lag-1 correlation {r:.2g}), but no recording has the 8 periods after settling that "
        "tell a wandering baseline from a settling transient: the baseline was not removed, and a drift or a "
        "transient of the loop's centre may be that wander; record more periods"
    )


def _rough(dc: np.ndarray, weight: float) -> tuple[float, int]:
    """The period DCs' chi-square about a quadratic trend in the period index (``weight`` = P / sigma^2)."""
    idx = np.arange(dc.size, dtype=np.float64)
    trend = np.vander(idx - idx.mean(), 3)
    res = dc - trend @ np.linalg.lstsq(trend, dc, rcond=None)[0]
    return float(res @ res) * weight, dc.size - 3


def removed(items: Any, wander: Any) -> Any:
    """``items`` with each Recording's period means replaced by the kept centre (every whole period, the
    settling ones too, and the tail after the last whole period by the last one's), marked for ``data.py``;
    ``items`` as they are when the set does not wander. ``wander`` is a :class:`Wander` or a
    ``zero_drift.Drift`` (each recording's straight line is then taken out first, and no walk is left)."""
    from ..model import Recording
    from . import wander_curve
    from .zero_drift import detrended, lab_detrended

    if wander is None or getattr(wander, "per_record", False):  # record_zeros.py: the records as they are
        return items
    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    slopes = getattr(wander, "slopes", None)  # a zero drifting in a straight line (zero_drift.py)
    curves = getattr(wander, "curves", ())  # a smooth wander's curves (wander_curve.py)
    out = []
    lab = getattr(wander, "lab", ())
    for j, rec in enumerate(seq):
        if j < len(lab) and lab[j] is not None:  # a lab Measurement's line (zero_drift.py)
            out.append(lab_detrended(rec, float(np.asarray(slopes)[j]), lab[j], wander.centre))
            continue
        if not isinstance(rec, Recording):
            out.append(rec)
            continue
        if j < len(curves) and curves[j] is not None:  # a smooth wander: its curve, no walk
            out.append(wander_curve.removed(rec, int(curves[j]), wander.centre))
            continue
        p, n = int(rec.samples_per_period), int(rec.whole_periods)
        y = np.array(rec.y, dtype=np.float64) if slopes is None else detrended(rec, slopes[j])
        dc = y[: n * p].reshape(n, p).mean(axis=1)
        shift = np.concatenate([np.repeat(dc, p), np.full(y.size - n * p, dc[-1] if n else 0.0)])
        walk = step_variance(rec) if slopes is None else 0.0  # a straight line is no walk
        meta = {**dict(rec.metadata), MARK: repr(walk)}  # metadata holds strings
        new = y - shift + wander.centre
        out.append(replace(rec, y=new, metadata=meta))
    return out


def step_variance(rec: Any) -> float:
    """The walk's step variance per sample ``s^2`` of a recording, from its period DCs after settling: the
    means of neighbouring periods of a random walk differ by ``s^2 (2 P^2 + 1) / (3 P)`` in variance, white
    noise adds ``2 sigma^2 / P`` (sigma^2 from the periods less their means). 0.0 with fewer than 3
    periods. Its leak into the harmonics is ``data.walk_levels``."""
    rows, p = _rows(rec)
    n = rows.shape[0]
    if n < 3 or p < 2:
        return 0.0
    dc = rows.mean(axis=1)
    white = float(np.mean(np.diff(rows - dc[:, None], axis=0) ** 2)) / 2.0 * p / (p - 1)
    step = float(np.mean(np.diff(dc) ** 2))
    return max(step - 2.0 * white / p, 0.0) * 3.0 * p / (2.0 * p * p + 1.0)


def marked(rec: Any) -> bool:
    """Whether ``rec``'s period means were taken out here (:func:`removed`)."""
    return bool(getattr(rec, "metadata", {}).get(MARK, False))


def offset_se(wander: Any, se: float) -> float:
    """A named output offset's standard error under ``wander`` (a :class:`Wander`, a zero's drift or the
    recordings' own zeros, ``record_zeros.RecordZeros``; or None): the spread of the recordings' centres over
    sqrt(m) when their common centre was kept, else ``se`` (the fit's own, from the noise, which does not see
    a zero that moves between records). :func:`adjusted` and the diagnosis across conditions read it."""
    if wander is None or not getattr(wander, "kept", False) or not math.isfinite(wander.centre_se):
        return se
    return float(wander.centre_se)


def adjusted(d: Diagnosis, wander: Any, offset_kind: str) -> Diagnosis:
    """The diagnosis ``d`` with the wander's clause, and a named output offset's standard error the spread of
    the recordings' centres (:func:`offset_se`: the fit's own, from the white noise, does not see the
    wander)."""
    if wander is None:
        return d

    verdict = d.verdict

    def fix(terms: Sequence[NamedTerm]) -> tuple[NamedTerm, ...]:
        nonlocal verdict
        out = []
        for t in terms:
            se = offset_se(wander, t.standard_error)
            if t.term == offset_kind and se != t.standard_error:
                new = replace(t, standard_error=se)
                verdict = verdict.replace(str(t), str(new))  # the verdict names it with that error too
                t = new
            out.append(t)
        return tuple(out)

    named, partial, final = fix(d.named), fix(d.partial), replace(d.final, terms=fix(d.final.terms))
    return replace(d, verdict=verdict + wander.clause(), named=named, partial=partial, final=final)


__all__ = [
    "Wander",
    "detect",
    "removed",
    "marked",
    "adjusted",
    "offset_se",
    "short_note",
    "WANDER_ALPHA",
    "WANDER_CORRELATION",
]

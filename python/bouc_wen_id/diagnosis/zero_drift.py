"""A zero that drifts in a straight line: taken out of the recordings as a wandering baseline is (issue 18).

A sensor's zero that creeps with temperature over the minutes of a record moves every period's mean by a
little more than the last, linearly, without changing the loop. The wander test (``baseline.py``) does not
see it (a straight line is no roughness beyond a quadratic), and left in it did three kinds of harm: the
averaged period's DC is off by half the drift in each experiment (its sign per experiment), which a DC
known to ``sigma / sqrt(N P)`` reads as structure at the DC even at a tenth of a noise sd of drift; the
within-period ramp repeats in every period; and the settling test read the trend as a loop that has not
settled ("record more settling periods": the wrong advice, the loop is periodic). A blind test
(benches/blind.py, noise ``drift``: 1 noise sd from the first sample to the last) failed 38 of 40 library
cases and 4 of 4 nulls.

:func:`detect` (on the periods after settling, recordings of 8 periods or more) calls the zero drifting when

* the period means trend, pooled over the recordings (each recording's slope t-test, its standard error
  the larger of the residual scatter's and the white noise's, turned to a chi-square of one degree of
  freedom, summed: p below :data:`DRIFT_ALPHA`);
* the trend goes on: in no recording whose own slope is significant is the first half's slope steeper than
  the last half's (one-sided, :data:`DECAY_LEVEL` over those recordings): a settling transient decays, a
  drift does not;
* the loop itself does not trend (the fundamental's amplitude, pooled the same way, p at least
  :data:`DRIFT_ALPHA`): a degradation, or a loop still settling, moves its harmonics too. Unless
  :data:`BESIDE_LOOP_TREND` (session 29, ``drift.py``): then a zero that drifts while the loop trends is
  taken out too (``Drift.loop_trends``), the period means with it, and the loop's own trend is left to the
  degradation test on harmonics 1.. (the DC, where the two cannot be told apart, spent) and to the
  settling test (a loop still settling is still left out).

Then each recording's straight line (its slope per sample, from the period means) and each period's mean are
taken out (:func:`baseline.removed`), the recordings marked and the fits given each experiment's DC free, as
for a wander; the verdict says "the output's zero drifts by ... over the record; its DC is not used".

Lab Measurements (a fixed sampling rate, no whole number of samples per period; :func:`_lab`) are tested the
same way on each whole period of their one averaged stretch (DC and fundamental by least squares on the
input's phase, the averaged period taken out first); a drifting one has its line (per second) and its
stretch's mean taken out and is marked (:func:`lab_detrended`, ``data.py`` then leaves its DC free).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from .data import common_centre, cross_period_inflation

#: Level of the pooled trend test of the period means (as the wander's).
DRIFT_ALPHA = 1e-3
#: Level (over the recordings that trend) of the one-sided test that the first half's slope is steeper than
#: the last half's: generous, so that a settling transient is not taken for a drift.
DECAY_LEVEL = 0.05
#: The trend test of each recording's own slope that admits it to the decay test.
OWN_LEVEL = 0.05
#: Fewest periods after settling for a recording to be tested (two halves of 4).
MIN_PERIODS = 8
#: Take a drifting zero out also when the loop trends (a degradation beside a drifting zero; the blind
#: bench's degradation under a 1 sd drift was "not settled" with the drift left in).
BESIDE_LOOP_TREND = True


@dataclass(frozen=True)
class Drift:
    """The set's zero-drift test and what was kept of its centres (read as a ``baseline.Wander`` is)."""

    slopes: tuple[float, ...]  # per item: the zero's slope per sample (0.0 for items not tested)
    chi2: float  # pooled chi-square of the period means' slopes
    dof: int
    p_value: float
    loop_p: float  # the pooled trend test of the fundamental's amplitude
    decay_p: float  # the smallest one-sided p of "the first half steeper" (NaN: no recording trends)
    largest: float  # the largest drift over a record, output units
    sigma: float  # the noise sd of a sample (the periods' white spread), for the note
    centre: float
    centre_se: float
    centre_p: float
    kept: bool
    level: float = math.nan
    #: per item: a lab Measurement's (time of the line's zero, its averaged stretch's mean), else None; its
    #: slope is then per second (a fixed rate has no whole number of samples per period)
    lab: tuple[Optional[tuple[float, float]], ...] = ()
    #: the loop trends too (:data:`BESIDE_LOOP_TREND`): a degradation or a loop still settling beside it
    loop_trends: bool = False

    def note(self) -> str:
        size = self.largest / self.sigma if self.sigma > 0 else math.nan
        if self.loop_trends:
            return (
                f"the output's zero drifts by up to {self.largest:.3g} (about {size:.2g} noise sd) over the "
                f"record: the period means follow a straight line (pooled chi-square {self.chi2:.3g} on "
                f"{self.dof} dof, p = {self.p_value:.2g}) that goes on to the end of the record (smallest p "
                f"= {self.decay_p:.2g}), and the loop trends too (fundamental amplitude p = "
                f"{self.loop_p:.2g}); each recording's line and each period's mean were taken out, so the "
                "loop's trend is tested as a degradation on its harmonics 1.. only (in the DC a degrading "
                "loop's centre and a drifting zero cannot be told apart); its DC is not used"
            )
        return (
            f"the output's zero drifts by up to {self.largest:.3g} (about {size:.2g} noise sd) over the "
            f"record: the period means follow a straight line (pooled chi-square {self.chi2:.3g} on "
            f"{self.dof} dof, p = {self.p_value:.2g}) that goes on to the end of the record (no recording's "
            f"first half steeper than its last, smallest p = {self.decay_p:.2g}) while the loop itself does "
            f"not trend (fundamental amplitude p = {self.loop_p:.2g}); each recording's line and each "
            "period's mean were taken out before averaging, so the loop's shape is measured as before; its "
            "DC is not used"
        )

    def clause(self) -> str:
        head = "; the output's zero drifts over the record (taken out, its DC not used): "
        if self.kept:
            return (
                f"{head}the common centre {self.centre:.4g} ± {self.centre_se:.3g} (the recordings' centres' "
                f"spread, t-test p = {self.centre_p:.2g}) was kept; each experiment's own DC (an "
                "asymmetry's) cannot be told from the drift"
            )
        return f"{head}an output offset or each experiment's own DC (an asymmetry's) cannot be told from it"


def _rows(rec: Any) -> Optional[tuple[np.ndarray, int, int]]:
    p, s = int(rec.samples_per_period), int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    if n < MIN_PERIODS or p < 4:
        return None
    return np.asarray(rec.y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p), p, s


def _slope(values: np.ndarray, floor_var: float) -> tuple[float, float, int]:
    """Least-squares slope per period, its standard error (at least the white noise's, times the residuals'
    cross-period inflation: noise correlated over a period, AR(1) with phi = 0.99 at 128 samples per period,
    has period means correlated about 0.45, and their slope varies 2-3 times more than white) and dof."""
    n = values.size
    k = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
    kk = float(k @ k)
    b = float(k @ (values - values.mean())) / kk
    res = values - values.mean() - b * k
    s2 = float(res @ res) / (n - 2)
    return b, math.sqrt(max(s2, floor_var) * cross_period_inflation(res) / kk), n - 2


def _chi2_1(t: float, dof: int) -> float:
    """A t statistic on ``dof`` degrees of freedom as the chi-square (1 dof) of the same p-value."""
    from scipy.special import chdtri, stdtr  # type: ignore[import-untyped]

    p = float(2.0 * stdtr(dof, -abs(t)))
    return float(chdtri(1, p)) if p > 0 else math.inf


def _recording(rows: np.ndarray, p: int) -> tuple[float, float, float, float, float]:
    """One recording's numbers: slope t as chi-square, its p, the decay test's one-sided p, the loop's
    chi-square, the slope per period and the white noise variance of a sample."""
    from scipy.special import ndtr

    n = rows.shape[0]
    spec = np.fft.rfft(rows, axis=1) / p
    dc, amp = spec[:, 0].real, 2.0 * np.abs(spec[:, 1])
    white = float(np.mean(np.diff(rows - dc[:, None], axis=0) ** 2)) / 2.0 * p / (p - 1)
    b, se, dof = _slope(dc, white / p)
    h = n // 2
    b1, se1, _ = _slope(dc[:h], white / p)
    b2, se2, _ = _slope(dc[n - h :], white / p)
    decay = float(ndtr(-(b1 - b2) * math.copysign(1.0, b) / math.hypot(se1, se2)))
    la, lse, ldof = _slope(amp, 2.0 * white / p)
    return _chi2_1(b / se, dof), decay, _chi2_1(la / lse, ldof), b, white


_Numbers = tuple[float, float, float, float, float, float, float, Any]


def _numbers(rec: Any) -> Optional[_Numbers]:
    """An item's test numbers (:func:`_recording`'s), its slope (per sample, per second on the lab path),
    centre, span (samples or seconds) and, on the lab path, where its line is zero; None when not tested."""
    from ..measurement import Measurement
    from ..model import Recording

    if isinstance(rec, Recording):
        got = _rows(rec)
        if got is None:
            return None
        rows, p, _ = got
        x2, decay, l2, b, white = _recording(rows, p)
        return x2, decay, l2, b / p, white, float(rows.mean()), float(np.asarray(rec.y).size), None
    if isinstance(rec, Measurement):
        return _lab(rec)
    return None


def _lab(meas: Any) -> Optional[_Numbers]:
    """The lab path (a fixed sampling rate): each whole period's DC and fundamental by least squares on the
    input's phase after the averaged period is taken out (as ``lab_colour.levels`` fits them), tested as
    :func:`_recording` tests a recording's period means. One averaged stretch per measurement, else None."""
    from scipy.special import ndtr

    from ..signal import average_measurement
    from .data import TWO_PI

    try:
        aps = average_measurement(meas)
    except Exception:  # noqa: BLE001 - a record the averaging refuses is not tested here; prepare says why
        return None
    if len(aps) != 1:
        return None
    ap = aps[0]
    omega = float(ap.frequency)
    seg_t = np.asarray(meas.t, dtype=np.float64)[ap.start : ap.stop] - float(ap.time_origin)
    seg_y = np.asarray(meas.y, dtype=np.float64)[ap.start : ap.stop]
    th = omega * seg_t
    k = np.floor(th / TWO_PI).astype(np.int64)
    ybar = np.asarray(ap.ybar, dtype=np.float64) + float(ap.offset_y)
    c = np.fft.rfft(ybar) / ybar.size
    c[1:] *= 2.0
    if ybar.size % 2 == 0:
        c[-1] /= 2.0
    resid = seg_y - (np.exp(1j * np.outer(th, np.arange(c.size))) @ c).real
    counts = np.bincount(k - k.min()) if k.size else np.zeros(0, np.int64)
    full = int(counts.max(initial=0))
    kept = [j + int(k.min()) for j in range(counts.size) if counts[j] >= max(full - 1, 8)]
    white = float(ap.noise_var)
    if len(kept) < MIN_PERIODS or not (white > 0 and math.isfinite(white)):
        return None
    dc, amp = np.empty(len(kept)), np.empty(len(kept))
    for row, j in enumerate(kept):
        sel = k == j
        basis = np.column_stack([np.ones(int(np.count_nonzero(sel))), np.cos(th[sel]), np.sin(th[sel])])
        a = np.linalg.lstsq(basis, resid[sel], rcond=None)[0]
        dc[row], amp[row] = a[0], abs(c[1] + complex(a[1], -a[2]))
    m = float(np.mean(counts[counts > 0]))
    b, se, dof = _slope(dc, white / m)
    n, h = dc.size, dc.size // 2
    b1, se1, _ = _slope(dc[:h], white / m)
    b2, se2, _ = _slope(dc[n - h :], white / m)
    decay = float(ndtr(-(b1 - b2) * math.copysign(1.0, b) / math.hypot(se1, se2)))
    la, lse, ldof = _slope(amp, 2.0 * white / m)
    per_second = b * omega / TWO_PI
    t = np.asarray(meas.t, dtype=np.float64)
    mid = float(np.mean(seg_t)) + float(ap.time_origin)
    where = (mid, float(np.mean(seg_y)))
    x2, l2 = _chi2_1(b / se, dof), _chi2_1(la / lse, ldof)
    return x2, decay, l2, per_second, white, float(np.mean(seg_y)), float(t[-1] - t[0]), where


def detect(items: Any, level: float) -> Optional[Drift]:
    """The set's zero-drift test (module docstring) on its Recordings; None when the zero does not drift or
    no recording has :data:`MIN_PERIODS` periods after settling. ``level`` is the common centre's t-test's."""
    from scipy.special import chdtrc

    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    chi2, loop, dof, decays, slopes, centres, largest, sig = 0.0, 0.0, 0, [], [], [], 0.0, []
    lab: list[Optional[tuple[float, float]]] = []
    for rec in seq:
        got = _numbers(rec)
        if got is None:
            slopes.append(0.0)
            lab.append(None)
            continue
        x2, decay, l2, slope, white, centre, span, where = got
        chi2, loop, dof = chi2 + x2, loop + l2, dof + 1
        if float(chdtrc(1, x2)) < OWN_LEVEL:
            decays.append(decay)
        slopes.append(slope)
        lab.append(where)
        centres.append(centre)
        largest = max(largest, abs(slope) * span)
        sig.append(white)
    if dof == 0:
        return None
    pval, loop_p = float(chdtrc(dof, chi2)), float(chdtrc(dof, loop))
    decay_p = min(decays) if decays else math.nan
    trends = loop_p < DRIFT_ALPHA
    loop_ok = BESIDE_LOOP_TREND or not trends
    if not (pval < DRIFT_ALPHA and loop_ok and decays and decay_p >= DECAY_LEVEL / len(decays)):
        return None
    c, se, cp, kept = common_centre(centres, level)
    sigma = math.sqrt(float(np.mean(sig)))
    return Drift(
        tuple(slopes),
        chi2,
        dof,
        pval,
        loop_p,
        decay_p,
        largest,
        sigma,
        c if kept else 0.0,
        se,
        cp,
        kept,
        level,
        tuple(lab),
        trends,
    )


def detrended(rec: Any, slope: float) -> np.ndarray:
    """``rec.y`` less the straight line of ``slope`` per sample, centred on the periods after settling (so
    that their mean is unchanged)."""
    y = np.array(rec.y, dtype=np.float64)
    p, s = int(rec.samples_per_period), int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    mid = s * p + (n * p - 1) / 2.0
    return y - slope * (np.arange(y.size, dtype=np.float64) - mid)


def lab_detrended(meas: Any, slope: float, where: tuple[float, float], centre: float) -> Any:
    """A lab Measurement with its straight line (``slope`` per second, zero at ``where[0]``) and its
    averaged stretch's mean ``where[1]`` taken out, ``centre`` put in, marked as ``baseline.removed`` marks
    a recording (``data.py`` then gives its DC no weight)."""
    from ..measurement import Measurement
    from .data import BASELINE_MARK

    t = np.asarray(meas.t, dtype=np.float64)
    y = np.asarray(meas.y, dtype=np.float64) - slope * (t - where[0]) - where[1] + centre
    meta = {**dict(meas.metadata), BASELINE_MARK: repr(0.0)}
    return Measurement(
        meas.t,
        meas.u,
        y,
        nominal_frequency=meas.nominal_frequency,
        units=meas.units,
        channels=meas.channels,
        name=meas.name,
        metadata=meta,
    )


__all__ = ["Drift", "detect", "detrended", "lab_detrended", "DRIFT_ALPHA", "DECAY_LEVEL"]

"""The start-up transient of a lab measurement's steady segments (issue 18; review 34, problems 7 and 8).

A :class:`~bouc_wen_id.measurement.Measurement` is cut into steady segments by the signal analysis
(``find_steady_segments``), whose test is on the input and the whole waveform; a plant still settling (the
hysteretic state leaving its virgin curve, the loop's centre moving to its steady place) can pass it. The
recording path trims such periods (``settling._settled``, with ``prepare.transient_periods``); the lab path
kept them: a two-pole plant with inertia on x, 100.37 samples per period, kept the periods from the second
one of the record, whose DC stood 5.6 noise sd above the steady ones, and the diagnosis named an output
offset y0 = 0.00049 +- 0.0001 (5 se, truth 0) beside the inertia; the same CSV data was "explained" with
amplitude and frequency headers (settle periods given) and "unexplained structure remains" without them.

:func:`averaged` averages each steady segment as ``average_segments`` does, after testing its leading
whole periods: each period's DC and fundamental (least squares on the input's phase, as ``data`` fits
them) against the mean of the segment's last half, scaled by the larger of the averaging's noise and the
last half's own spread (a coloured noise moves the period DCs more than the per-sample noise says). The
leading periods are dropped (when the first lies off the straight line through the record: a transient,
not a drift that goes on) up to the first after which the rest shows no trend (``settling._trending``'s
rule) and whose own chi-square (3 dof) is within :data:`TRANSIENT_LEVEL`; at most half of them, and none
when no such start exists (a drift that goes on, a degrading specimen, is the degradation test's). A
settling that moves the DC by 1-4 noise sd a period over several periods passes any single period's test;
the trend of the rest finds it. A slower settling, about one period's noise sd a period, is not found
(session 37 removed the marginal-standard-error trim built for it: docs/diagnosis.md says why).
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from ..errors import TransientWarning

#: Level of the test of a stretch's first period against its last half.
TRANSIENT_LEVEL = 0.01

#: Level of the trend test that keeps a drift from being trimmed (``settling.TREND_LEVEL``).
TREND_LEVEL = 0.05

#: Level of the test that the first period's DC lies off the record's straight line (a transient, not a
#: drift): strict, since a settled record trims nothing only when this test does not fire by chance.
LINE_LEVEL = 1e-3

#: Fewest whole periods left after a trim (the recording path's ``TRANSIENT_MIN_PERIODS``).
MIN_LEFT = 4

#: Fewest samples in a period for its DC and fundamental fit (as ``data._from_averaged``).
MIN_SAMPLES = 8


def period_fits(t: Any, y: Any, ap: Any) -> tuple[list[int], Any, Any, Any]:
    """``(first sample, dc, h1, samples)`` of each whole period of ``ap``'s stretch (from the input's
    phase zero, ``ap.time_origin``): the first sample's index in the record and the least-squares DC and
    complex fundamental, as ``data._from_averaged`` fits them."""
    omega = float(ap.frequency)
    seg_t = np.asarray(t[ap.start : ap.stop], dtype=np.float64) - float(ap.time_origin)
    k = np.floor(seg_t * omega / (2.0 * math.pi)).astype(np.int64)
    th = omega * seg_t
    seg_y = np.asarray(y[ap.start : ap.stop], dtype=np.float64) - _upper_harmonics(ap, th)
    first, dcs, h1s, ns = [], [], [], []
    # Whole periods only: the stretch may start before the input's phase zero (k = -1, a part of a period
    # whose DC a one-harmonic fit misreads by the loop's higher harmonics) and ends in a part of one.
    for j in range(max(int(k.min()), 0) if k.size else 0, int(k.max()) if k.size else 0):
        idx = np.flatnonzero(k == j)
        if idx.size < MIN_SAMPLES:
            continue
        basis = np.column_stack([np.ones(idx.size), np.cos(th[idx]), np.sin(th[idx])])
        coef = np.linalg.lstsq(basis, seg_y[idx], rcond=None)[0]
        first.append(int(ap.start) + int(idx[0]))
        dcs.append(coef[0])
        h1s.append(complex(coef[1], -coef[2]))
        ns.append(float(idx.size))
    return first, np.array(dcs), np.array(h1s, dtype=np.complex128), np.array(ns)


def _upper_harmonics(ap: Any, th: Any) -> Any:
    """The averaged period's harmonics 2..K at the input phases ``th``: taken out of each period before
    its DC and fundamental are fitted. A period at a non-integer rate holds 100 or 101 samples of 100.37,
    not a whole cycle, and a one-harmonic fit over it reads the loop's higher harmonics into its DC and
    fundamental (0.17 of a period's noise sd every third period, noise-free, at 100.37 samples a period):
    a pattern in the per-period record that no settling made."""
    yb = np.asarray(getattr(ap, "ybar", ()), dtype=np.float64)
    if yb.size < 5:
        return np.zeros(np.shape(th))
    from ..signal._harmonic_ls import harmonic_series

    c = np.fft.rfft(yb) / yb.size
    top = (yb.size - 1) // 2
    d = np.zeros(top + 1, dtype=np.complex128)
    d[2:] = 2.0 * c[2 : top + 1]
    return harmonic_series(th, d)


def _deviates(dc: Any, h1: Any, samples: Any, noise_var: float, k: int) -> bool:
    """Whether period ``k``, or the mean of the quarter of the periods from ``k`` on (a slow settling moves
    each period by less than its noise), differs in DC and fundamental from the last half's mean beyond the
    noise (the larger of the averaging's and the last half's own spread) at :data:`TRANSIENT_LEVEL`."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    m = int(dc.size)
    tail = slice(m // 2, m)
    mt = m - m // 2
    spread_dc = float(np.var(dc[tail], ddof=1))
    spread_h1 = float(np.mean([np.var(h1[tail].real, ddof=1), np.var(h1[tail].imag, ddof=1)]))
    ref_dc, ref_h1 = float(np.mean(dc[tail])), complex(np.mean(h1[tail]))
    for q in sorted({1, max(1, (m - k) // 4)}):
        n = float(np.mean(samples[k : k + q]))
        s_dc = max(noise_var / n, spread_dc) * (1.0 / q + 1.0 / mt)
        s_h1 = max(2.0 * noise_var / n, spread_h1) * (1.0 / q + 1.0 / mt)
        d_dc = float(np.mean(dc[k : k + q])) - ref_dc
        d_h1 = complex(np.mean(h1[k : k + q])) - ref_h1
        if float(chdtrc(3, d_dc**2 / s_dc + abs(d_h1) ** 2 / s_h1)) < TRANSIENT_LEVEL:
            return True
    return False


def _off_the_line(dc: Any, samples: Any, noise_var: float) -> bool:
    """Whether the first period's DC lies off the straight line fitted to all periods beyond
    the noise (the larger of the averaging's and the line's scatter over the last half) at
    :data:`LINE_LEVEL`: a transient decays (its start is above any line through the record), a
    drifting zero goes on along it (zero_drift.py takes it out; trimming it cut 8 of 19 periods). The DC
    only: a degrading loop's fundamental decays too (the blind bench's degradation case lost 9 of 29
    periods to a test on both), and what biased the lab path was the settling centre."""
    from scipy.special import chdtrc

    m = int(dc.size)
    idx = np.arange(m, dtype=np.float64)
    basis = np.column_stack([np.ones(m), idx])
    resid = dc - basis @ np.linalg.lstsq(basis, dc, rcond=None)[0]
    scatter = float(np.var(resid[m // 2 :], ddof=1))
    stat = float(resid[0]) ** 2 / max(noise_var / samples[0], scatter)
    return float(chdtrc(1, stat)) < LINE_LEVEL


def leading_transient(dc: Any, h1: Any, samples: Any, noise_var: float) -> int:
    """Leading periods (at most half) to drop: the fewest after which the rest shows no trend (DC or
    fundamental amplitude, :func:`_trending`) and its first period does not differ from the last half
    (:func:`_deviates`); 0 when no such start is found (a drift that goes on: the degradation test's)."""
    m = int(dc.size)
    if m < 2 * MIN_LEFT or not (math.isfinite(noise_var) and noise_var > 0):
        return 0
    if not _off_the_line(dc, samples, noise_var):
        return 0  # no transient the first period shows alone (a drift goes on along the line)
    for k in range(m // 2 + 1):
        if not _trending(dc[k:], h1[k:]) and not _deviates(dc, h1, samples, noise_var, k):
            return k
    return 0


def _trending(dc: Any, h1: Any) -> bool:
    """``settling._trending``'s rule on a lab stretch's per-period DC and fundamental amplitude: either's
    least-squares slope against the period index, t-tested on its residual scatter, at half of
    :data:`TREND_LEVEL` (written here: this module is imported by ``data``, which ``settling`` and
    ``locate`` import)."""
    from scipy.special import stdtr

    amp = np.abs(h1)
    p = 1.0
    for values in (amp / (float(np.mean(amp)) or 1.0), np.asarray(dc, dtype=np.float64)):
        n = values.size
        k = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
        slope = float(np.dot(k, values - values.mean()) / np.dot(k, k))
        resid = values - values.mean() - slope * k
        s2 = float(np.dot(resid, resid)) / (n - 2)
        se = math.sqrt(s2 / float(np.dot(k, k))) if s2 > 0 else 0.0
        if se > 0:
            p = min(p, float(2.0 * stdtr(n - 2, -abs(slope / se))))
        elif slope:
            p = 0.0
    return p < 0.5 * TREND_LEVEL


def full_band(t: Any, start: int, stop: int, omega: float) -> int:
    """The most harmonics the samples ``t[start:stop]`` support at ``omega``: every harmonic below Nyquist
    (``K < P_s / 2``, ``P_s`` samples per period, at most the averaging's ``MAX_HARMONICS``), as a recording's
    grid of ``P`` samples holds every harmonic up to ``P / 2``.

    The averaging's default keeps ``max(8, 4 K_sig)`` harmonics (``K_sig`` the last one 16 times above its
    noise): a shorter grid, whose adequacy test spans fewer degrees of freedom than the same data's as a
    recording. The same CSV data (viscous on u, five frequencies, 128 samples per period; review 34,
    problem 8) gave final chi2 319.4 on 271 dof (p = 0.024, "unexplained structure remains") as a
    Measurement and 632.7 on 626 (p = 0.42) as a Recording of the same 21 periods: the statistic was the
    same at every harmonic both test, but the lab test stopped at harmonic 20-36 and the recording's at 64.
    On the full band both test the same harmonics (lab: 621 dof, p = 0.34)."""
    from ..signal._averaging import MAX_HARMONICS

    n = int(stop) - int(start)
    ts = np.asarray(t[start:stop], dtype=np.float64)
    if n < 4 or not (omega > 0 and ts[-1] > ts[0]):
        return 0
    p_s = 2.0 * math.pi / omega / ((float(ts[-1]) - float(ts[0])) / (n - 1))
    # floor(P_s / 2 - 1) with a rounding allowance (128 samples of a printed time axis gave P_s = 127.99999
    # and 62): K stays more than 0.99 harmonic below Nyquist.
    return max(1, min(MAX_HARMONICS, math.floor(p_s / 2.0 - 1.0 + 1e-3), (n // 2 - 1) // 2))


def averaged(item: Any) -> list[Any]:
    """The averaged periods of measurement ``item``'s steady segments on every harmonic the sampling supports
    (:func:`full_band`), each re-averaged from its first settled whole period when its leading periods are
    still transient (a TransientWarning says so)."""
    from ..signal import average_segments, synchronous_average

    seg = average_segments(item)
    t, y = np.asarray(item.t), np.asarray(item.y)
    out = []
    for ap, fit in zip(seg.periods, seg.report.fits):
        first, dc, h1, ns = period_fits(t, y, ap)
        extra = leading_transient(dc, h1, ns, float(ap.noise_var))
        if extra:
            warnings.warn(
                f"{ap.source}: the first {extra} of its {dc.size} whole periods are still transient (their "
                "DC or fundamental differ from the steady periods beyond the noise); they were dropped",
                TransientWarning,
                3,
            )
        start = first[extra] if extra else ap.start
        k = full_band(t, start, ap.stop, float(fit.frequency))
        if extra or k > ap.harmonics:
            ap = synchronous_average(t, y, fit, start=start, stop=ap.stop, harmonics=k, source=ap.source)
        out.append(ap)
    return out


__all__ = ["averaged", "full_band", "leading_transient", "period_fits", "TRANSIENT_LEVEL", "MIN_LEFT"]

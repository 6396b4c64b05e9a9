"""Gross outliers in a recording's analysed periods, and a start-up transient test they do not trip.

A transient is a trend the early periods share: the whole of a period (or most of it) departs from the
steady ones, smoothly. An outlier is one sample (or a few) far from the averaged period. identify's transient
test (:func:`..prepare.transient_periods`) compares each early period's mean squared departure from the steady
reference with the reference's period-to-period spread: one spike of 15 noise sd in a period of 128 samples
adds 1.8 sd^2 to that period's mean square and reads as "still transient" (review 36: 3 of 6 nulls with
spikes or Student-t3 noise warned that the first period was transient, 0 of 16 white nulls).

:func:`transient_periods` is that test on departures clipped at :data:`CLIP_SD` robust standard deviations
(the median absolute departure of the steady periods from their average, times 1.4826), with the noise level
taken from the same clipped departures of the steady periods: a sample's weight is bounded, so a few wild
samples cannot make a period transient, while a transient that moves the whole period is unchanged (a large
one is clipped to :data:`CLIP_SD` sd at every sample, still far beyond the noise). Without noise (a robust sd
at a simulated loop's numerical accuracy or below) nothing is clipped: the test is identify's.

Under a noise coloured at the DC (1/f noise, an AR(1) over many samples; :func:`_dc_level`) a period's DC
wanders by far more than the per-sample noise says: 27-35 % of pink noise-only records of 8 periods were
called transient (studies/pink46). There an early period's DC is judged against the DC's own level
(:data:`TRANSIENT_DC_Z` standard errors) and its shape against the noise with its coloured band; 4-5 % are
flagged, and a centre settling from 10 noise sd still is in 92-100 %.

:func:`outlier_notes` counts, in the periods kept, the samples more than a threshold of robust sd from the
mean of their sample over the other periods (under Gaussian noise the departure is Gaussian, which a
median's is not: from the median of 8 periods 5.6 % of white-noise diagnoses reported an outlier) and from
the mean of their two neighbours in time (a spike stands alone, a drift does not). A spike of S sd moves
the other periods' mean by S / (n - 1) sd, so the outliers found are left out of their sample's mean, the
largest first, and the rest retested (review 41: with 8 periods, 5 spikes of 40 sd were counted as 10 on
average, of 100 sd as 39; now 5). The
threshold is set so
that Gaussian noise flags one sample in a whole diagnosis with a chance of at most :data:`OUTLIER_ALPHA`
(Bonferroni over every analysed sample of every recording). The outliers are reported and left in the data:
nothing the user gave is modified, the averaged period carries each one at 1/N of its size (N periods) and
the period-to-period noise floor the tests use includes them; they are not down-weighted because a
heavy-tailed noise (Student t) has many of them and replacing them would understate that noise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Departures from the steady reference are clipped at this many robust sd in the transient test.
CLIP_SD = 4.0
#: Under a noise coloured at the DC, an early period's DC departs from the steady periods' beyond this many
#: standard errors of the DC's own level (:func:`_dc_level`) to count as transient.
TRANSIENT_DC_Z = 4.0
#: Chance, under Gaussian noise, that a diagnosis reports any outlier (Bonferroni over all analysed samples).
OUTLIER_ALPHA = 0.01
#: Robust sd of a Gaussian from its median absolute deviation.
MAD_SD = 1.4826


def _noise_sd(sd: float, y: FloatArray, p: int) -> float:
    """``sd`` raised to the rounding error's sd, q / sqrt(12), of an output quantised with step q (its robust
    sd can be 0 when the noise does not dither it; a spike stays many steps out, and a departure of one step
    stays below the threshold, ~5 sd), or 0 at a simulated loop's numerical accuracy (no noise: nothing is
    clipped or counted). The quantisation step was once a floor below which nothing was tested: with spikes
    put in after the converter the step was not found (review 41); once found, it hid the spikes."""
    from .data import numerical_rtol, quantisation_step

    peak = float(np.max(np.abs(y))) if y.size else 0.0
    sd = max(sd, quantisation_step(y) / math.sqrt(12.0))
    return sd if sd > numerical_rtol(p) * peak else 0.0


def _robust_sd(dev: FloatArray) -> float:
    return MAD_SD * float(np.median(np.abs(dev))) if dev.size else 0.0


def transient_periods(y: Any, p: int, s: int, n: int) -> int:
    """Leading periods of ``y[s p : (s + n) p]`` still in transient (at most ``n // 2``): identify's test
    (each early period's mean squared departure from the average of the last half, against that half's
    period-to-period spread) on departures clipped at :data:`CLIP_SD` robust sd."""
    from ..prepare import TRANSIENT_CHI2_SD, TRANSIENT_MIN_PERIODS, TRANSIENT_RTOL

    if n < TRANSIENT_MIN_PERIODS:
        return 0
    yy = np.asarray(y, dtype=np.float64)
    seg = yy[s * p : (s + n) * p].reshape(n, p)
    tail = seg[n // 2 :]
    m = tail.shape[0]
    ref = tail.mean(axis=0)
    sd = _robust_sd(tail - ref) * math.sqrt(m / (m - 1.0))  # the departure from a mean of m holds 1/m of it
    sd = _noise_sd(sd, seg.ravel(), p)
    bound = CLIP_SD * sd if sd > 0.0 else math.inf
    tail_dev = np.clip(tail - ref, -bound, bound)
    noise = float(np.mean(tail_dev**2)) * m / (m - 1.0)
    centred_power = float(np.mean((ref - ref.mean()) ** 2))
    tol = (
        noise * (1.0 + 1.0 / m) * (1.0 + TRANSIENT_CHI2_SD / math.sqrt(p)) + TRANSIENT_RTOL**2 * centred_power
    )
    early = np.clip(seg[: n // 2] - ref, -bound, bound)
    dev = np.mean(early**2, axis=1)
    levels = _dc_level(seg, p)
    if levels is not None:  # coloured at the DC: the DC against its own level, the shape with its colour
        dc_var, excess = levels
        dc = early.mean(axis=1)
        dc_tol = TRANSIENT_DC_Z**2 * dc_var * (1.0 + 1.0 / m) / p
        shape_tol = tol + excess * (1.0 + 1.0 / m) * (1.0 + TRANSIENT_CHI2_SD / math.sqrt(p))
        dev = np.where((dev - dc**2 > shape_tol) | (dc**2 > dc_tol), np.inf, 0.0)
    k = 0
    while k < dev.size and dev[k] > tol:
        k += 1
    return k


def _dc_level(rows: FloatArray, p: int) -> tuple[float, float] | None:
    """``(dc, excess)`` when the noise of periods ``rows`` is measurably coloured with its largest level at a
    band that holds the DC (data.noise_colour on the departures clipped at :data:`CLIP_SD` robust sd,
    :func:`clipped`; 1/f noise, an AR(1) over many samples), else None. ``dc``: the per-sample level of a
    period's DC, the larger of the period DCs' spread about a quadratic trend (a settling centre taken out)
    and the noise's level at its largest band of harmonics >= 1; ``excess``: what that band adds to a
    period's mean square beyond white noise of the per-sample variance."""
    from .data import _about_trend, noise_colour

    n = rows.shape[0]
    kept = clipped(rows, p)
    white = float(np.mean(np.diff(kept, axis=0) ** 2)) / 2.0
    var, _, band = noise_colour(kept, white, p * (n - 1))
    if not (var > white and band[0] == 0):
        return None
    dcs = kept.mean(axis=1)[:, None].astype(np.complex128)
    own = float(np.sum(_about_trend(dcs)[0].real ** 2)) * p / (n - 3)
    low, _, (a, b) = noise_colour(kept, white, p * (n - 1), dc=False)
    return max(own, low), 2.0 * (b - a + 1) * max(low - white, 0.0) / p if b else 0.0


def clipped(rows: FloatArray, p: int) -> FloatArray:
    """``rows`` (periods by samples) with each sample's departure from its mean over the periods clipped at
    :data:`CLIP_SD` robust sd (a copy): per-period features (DC, fundamental) a spike does not move."""
    n = rows.shape[0]
    if n < 3:
        return np.array(rows, dtype=np.float64)
    mean = rows.mean(axis=0)
    dev = rows - mean
    sd = _noise_sd(_robust_sd(dev) * math.sqrt(n / (n - 1.0)), rows.ravel(), p)
    if not sd > 0.0:
        return np.array(rows, dtype=np.float64)
    out: FloatArray = mean + np.clip(dev, -CLIP_SD * sd, CLIP_SD * sd)
    return out


def threshold(samples: int) -> float:
    """Robust sd beyond which one of ``samples`` Gaussian samples lies with chance :data:`OUTLIER_ALPHA`."""
    from scipy.stats import norm  # type: ignore[import-untyped]

    return float(norm.isf(0.5 * OUTLIER_ALPHA / max(samples, 1)))


def outliers(y: Any, p: int, s: int, n: int, limit: float) -> tuple[int, float, list[int]]:
    """``(count, largest in robust sd, periods holding them)`` of the samples of periods ``s .. s + n`` more
    than ``limit`` robust sd from their sample's mean over the other periods and from the mean of their two
    neighbours in time (a spike stands alone; a drift or a transient does not); ``(0, 0, [])`` without
    noise."""
    if n < 3:
        return 0, 0.0, []
    rows = np.asarray(y, dtype=np.float64)[s * p : (s + n) * p].reshape(n, p)
    hit = np.zeros(rows.shape, dtype=bool)
    for _ in range(n):
        dev = _from_others(rows, hit)
        sd = _noise_sd(_robust_sd(dev), rows.ravel(), p)
        if not sd > 0.0:
            return 0, 0.0, []
        # ... and not shared by its neighbours in time (a drift or a transient moves whole stretches).
        flat = np.pad(dev.ravel(), 1, mode="reflect")
        alone = (flat[1:-1] - 0.5 * (flat[:-2] + flat[2:])).reshape(n, p)
        z = np.abs(dev) / sd
        out = (z > limit) & (np.abs(alone) > limit * _robust_sd(alone))
        # The largest new one of each sample is left out of that sample's mean, and the others retested.
        new = np.where(out & ~hit, z, -1.0)
        cols = np.nonzero(np.max(new, axis=0) > 0.0)[0]
        if cols.size == 0:
            break
        hit[np.argmax(new[:, cols], axis=0), cols] = True
    hit &= out
    periods = sorted({int(j) for j in np.nonzero(hit)[0]})
    return int(np.count_nonzero(hit)), float(np.max(z)), periods


def _from_others(rows: FloatArray, out: NDArray[np.bool_]) -> FloatArray:
    """Each sample's departure from the mean of its sample over the other periods, the samples marked in
    ``out`` left out of that mean (a spike of S sd moves the others' mean by S / (n - 1) sd: with 8 periods
    one of 40 sd put the same sample of the 7 others beyond the threshold; review 41, tests/test_spikes_said);
    a sample every period of which is left out keeps its departure from 0."""
    keep = ~out
    count = keep.sum(axis=0).astype(np.float64)
    total = np.where(keep, rows, 0.0).sum(axis=0)
    others = np.where(keep, (total - rows) / np.maximum(count - 1.0, 1.0), total / np.maximum(count, 1.0))
    dev: FloatArray = rows - others
    return dev


def outlier_notes(items: Sequence[Any]) -> list[str]:
    """One note per Recording in ``items`` whose analysed periods hold gross outliers (:func:`outliers`)."""
    from ..model import Recording

    recs = [(i, it) for i, it in enumerate(items) if isinstance(it, Recording)]
    spans = [
        (i, it, it.samples_per_period, it.settle_periods, it.whole_periods - it.settle_periods)
        for i, it in recs
    ]
    total = sum(p * n for _i, _it, p, _s, n in spans if n >= 3)
    limit = threshold(total)
    notes = []
    for i, it, p, s, n in spans:
        count, top, periods = outliers(it.y, p, s, n, limit)
        if count:
            name = it.metadata.get("name", f"recording {i}")
            where = ", ".join(str(j + 1) for j in periods[:6]) + (", ..." if len(periods) > 6 else "")
            notes.append(
                f"{name}: {count} sample{'s are outliers' if count > 1 else ' is an outlier'} "
                f"(> {limit:.2g} robust sd from the averaged period, the largest {top:.3g} sd; in analysed "
                f"period{'s' if len(periods) > 1 else ''} {where} of {n}; Gaussian noise gives one in the "
                f"whole diagnosis with a chance of {OUTLIER_ALPHA:.0%}): spikes or a heavy-tailed noise, not "
                "a transient; left in (the averaged period carries each at 1/N of its size and the noise "
                "floor includes them): check the sensor or its cabling if they are not expected"
            )
    return notes


__all__ = [
    "transient_periods",
    "clipped",
    "outlier_notes",
    "outliers",
    "threshold",
    "CLIP_SD",
    "OUTLIER_ALPHA",
]

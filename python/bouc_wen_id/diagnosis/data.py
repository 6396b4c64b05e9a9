"""Experiments as the diagnosis sees them: the averaged period with its DC, and the period-by-period record.

The identification removes the output's DC and pools the period-to-period spread into one noise floor.
The diagnosis needs both back: the DC is the signature of an offset or an asymmetry, and the periods one by
one are the only witness of a loop that drifts (degradation, an unsettled transient).  So each experiment
is reduced to

- ``ybar`` with its DC, on the grid ``t_j = j T/P`` whose first sample sits at input phase ``grid_phase``
  (``u_j = U cos(2 pi j/P + grid_phase)``);
- ``noise_var``: the variance of one raw sample; for recordings from differences of neighbouring periods,
  which a slow drift does not inflate (the spread about the mean period, which the identification uses,
  it does); for lab records the averaging's own;
- ``spread_var``: that spread-based variance, for the drift comparison;
- ``dc`` and ``h1``: the DC and the complex fundamental of each period, for the drift test;
- the block record (design.md 10.6): the periods cut into up to ``MAX_BLOCKS`` runs of consecutive ones,
  each run's averaged period as its harmonics 0..``MAX_DRIFT_HARMONIC`` (``block_coef``), with its sample
  count and mean period index, for the degradation fit. Empty for an averaged period alone.
- ``waveform``: the averaged input's harmonics beyond the fundamental, relative to it (design.md 9.5), those
  measurably above the input's own noise; empty for a pure sine (and when the input is not at hand).
- ``colour``: how much larger the noise is at the low harmonics than per sample (1: white, or not measurably
  coloured). Every test here weighs samples with one variance per experiment, which is valid for white noise
  only; a coloured noise (an AR(1) with phi = 0.8 carries 8.6 times its per-sample variance at the
  fundamental of a 128-sample period) made the F-tests of terms acting there anticonservative. So for a
  recording the spread of each harmonic 0..``MAX_DRIFT_HARMONIC`` of the single periods about a quadratic
  trend in the period index (drift taken out) is compared with the per-sample variance; when a band of
  ``COLOUR_BAND`` harmonics is larger beyond chance (:data:`COLOUR_ALPHA`, Bonferroni over the bands), the
  largest band's level is the experiment's noise variance, with its own degrees of freedom (conservative
  at the other harmonics), and the diagnosis says so in its notes. The DC is a band of its own, and its
  level is that of the mean over the periods: a noise correlated across periods (AR(1), phi = 0.99 at 128
  samples per period) makes the period DCs wander together, and their spread alone put the averaged
  period's DC at a tenth of its variance (the bench's "ar1 slow" nulls were called "unexplained": an
  offset whose value differs between experiments, loops "not settled"). The lag-1 correlation of the
  period DCs inflates it (:func:`cross_period_inflation`); such a wander and a drift of the centre cannot
  be told apart in one short record, and the notes say so. With few periods (3 to 6: fewer than
  :data:`FEW_COLOUR_DOF` degrees of freedom per harmonic; 3 periods about their mean, no trend) the DC joins
  its neighbours' band and the check runs at :data:`FEW_COLOUR_ALPHA` (review 34: 3 periods under AR(0.5)
  named terms on 4 of 20 null seeds, 0 of 20 after).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from .._text import item_label
from ..errors import InsufficientDataError, InvalidParameterError, ZeroAmplitudeError
from ..signal._harmonic_ls import harmonic_basis
from . import lab_colour, lab_settle, level_bands

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
TWO_PI = 2.0 * math.pi

#: Blocks of consecutive periods at most in the block record: enough to resolve a linear drift, few
#: enough that each block's average keeps its noise manageable (noise sd / sqrt(periods per block)).
MAX_BLOCKS = 8
#: Highest harmonic kept per block: the localisation's range (a degrading loop's change is in the low
#: harmonics), and a least-squares fit of a lab block stays well posed with few samples per period.
MAX_DRIFT_HARMONIC = 15
#: Harmonics per band of the colour check (centred: +-2), as the law test smooths its periodogram.
COLOUR_BAND = 5
#: False-alarm level of the colour check per experiment (Bonferroni over its bands): white noise keeps the
#: per-sample variance (and its degrees of freedom) in all but about 1e-3 of experiments.
COLOUR_ALPHA = 1e-3
#: The metadata key of a recording whose period means were taken out as a wandering baseline
#: (``baseline.removed``): its DC carries no noise, and its noise floor is that of harmonics 1.. alone.
#: A private key (the package's own prefix): a user's metadata is free-form and may hold "baseline_removed".
BASELINE_MARK = "_bouc_wen_id.baseline_removed"
#: Highest harmonic of the input kept in its waveform (design.md 9.5).
WAVEFORM_MAX_HARMONIC = 10
#: A harmonic of the averaged input is kept when its amplitude exceeds this many standard deviations of its
#: noise (each DFT bin of the mean period: variance ``2 sigma_u^2 / (N P)`` per real and imaginary part)...
WAVEFORM_NOISE_SD = 5.0
#: ... and this fraction of the fundamental (below, its loop contribution is far below any output noise,
#: and quantisation or rounding in a noise-free input must not turn a pure sine into a "distorted" one).
WAVEFORM_MIN_RELATIVE = 1e-4


def input_waveform(rows: FloatArray) -> FloatArray:
    """The normalised harmonics ``[Re c_2, Im c_2, ...]`` of an input given period by period (N, P).

    ``u = |C_1| Re[e^{i z} + sum_k c_k e^{i k z}]``, ``z = 2 pi j/P + arg C_1``: ``c_k = C_k / (|C_1|
    e^{i k arg C_1})`` with ``C_k`` the complex amplitude of harmonic k of the mean period. A harmonic is kept
    when it stands above the input's noise (differences of neighbouring periods) and above
    :data:`WAVEFORM_MIN_RELATIVE`; the waveform is trimmed after the last kept one (zeros in between).
    """
    n, p = rows.shape
    mean = rows.mean(axis=0)
    spec = 2.0 * np.fft.rfft(mean) / p
    var_u = float(np.mean(np.diff(rows, axis=0) ** 2)) / 2.0 if n >= 2 else 0.0
    # |C_k| of pure noise: sd sqrt(2 var / (N P)) per real and imaginary part.
    floor = WAVEFORM_NOISE_SD * math.sqrt(2.0 * 2.0 * var_u / (n * p))
    kmax = min(WAVEFORM_MAX_HARMONIC, (p - 1) // 2)
    return _normalised(spec[1 : kmax + 1].astype(np.complex128), floor)


@dataclass(frozen=True, eq=False)
class DiagExperiment:
    """One sine experiment reduced for the diagnosis (see the module docstring)."""

    frequency: float
    amplitude: float
    grid_phase: float
    ybar: FloatArray = field(repr=False)
    periods: float
    noise_var: float
    spread_var: float
    noise_dof: int
    dc: FloatArray = field(repr=False)
    h1: ComplexArray = field(repr=False)
    source: str
    #: (B, K + 1) harmonics ``c_0`` (real DC), ``c_k`` (``y = sum Re c_k e^{i k theta}``) of each block's
    #: averaged period, on the grid of ``ybar``; B = 0 without a period-by-period record.
    block_coef: ComplexArray = field(default_factory=lambda: np.zeros((0, 1), np.complex128), repr=False)
    #: Raw samples in each block (the weight of its average is ``samples / noise_var``).
    block_samples: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: Mean period index of each block (periods from the first averaged one).
    block_center: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: Periods each block spans (empty when unknown): its samples over this are its samples per period,
    #: which tell a block cut mid-period from one that only holds fewer periods (blocks of 2 and 1 periods
    #: when the periods do not divide into MAX_BLOCKS equal runs).
    block_periods: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: Periods of excitation recorded before the first averaged one (settling), NaN when unknown: the
    #: energy a degrading specimen has dissipated before the averaged stretch (design.md 10.6).
    lead_periods: float = math.nan
    #: Unrecorded age: periods of this experiment's own drive the specimen had degraded by before
    #: ``lead_periods``, beyond the youngest experiment's (estimated by ``age.py`` when a strength
    #: degradation is named; 0 when the record starts as declared).
    age_periods: float = 0.0

    @property
    def blocks(self) -> int:
        """Blocks in the block record (0 or 1: no drift can be resolved)."""
        return int(self.block_coef.shape[0])

    waveform: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: The noise's level at the low harmonics over its per-sample level when the noise is measurably
    #: coloured (then ``noise_var`` is that low-harmonic level), else 1.0 (see the module docstring).
    colour: float = 1.0
    #: The harmonics (first, last) of the band where the coloured noise is largest ((0, 0) when white).
    colour_band: tuple[int, int] = (0, 0)
    #: The period DCs' lag-1 correlation, bias-corrected, unclipped (:func:`cross_period_correlation`; 0.0
    #: when the noise is white or it is not measured).
    cross_period: float = 0.0
    #: Each harmonic 0..K's own noise level (per-sample units, as ``noise_var``) when the noise is coloured:
    #: the level of :func:`harmonic_levels`, for the drift test's weights; empty when white (``noise_var``
    #: at every harmonic).
    harmonic_var: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: Each harmonic 0..P/2's own noise level (per-sample units) when the noise is measurably coloured: the
    #: adequacy test's weights (adequacy_chi2.py); empty when white (``noise_var`` at every harmonic).
    adequacy_var: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: The input's own mean over the averaged periods (units of u) and its standard error (0.0 when the input
    #: is not at hand): the fits see ``u`` without it; ``input_dc.py`` reads it (a drive with a preload).
    input_dc: float = 0.0
    input_dc_se: float = 0.0

    @property
    def baseline_removed(self) -> bool:
        """Whether the period means were taken out as a wandering baseline (``baseline.py``): the DC of
        ``ybar`` is then set, not measured (no weight in the drift test, one degree of freedom less)."""
        return bool(self.harmonic_var.size) and math.isinf(float(self.harmonic_var[0]))

    @property
    def samples_per_period(self) -> int:
        return int(self.ybar.size)

    @property
    def weight(self) -> float:
        """``N / sigma^2``: the weight of one squared residual of ``ybar``."""
        floor = (1e-13 * float(np.max(np.abs(self.ybar)))) ** 2 + np.finfo(float).tiny
        return self.periods / max(self.noise_var, floor)

    @property
    def distorted(self) -> bool:
        """Whether the input carries measurable harmonics (the ``distortion`` term has something to test)."""
        return bool(self.waveform.size)

    def input(self) -> FloatArray:
        """``u_j`` on the averaged grid (without the input's DC), with its measured harmonics."""
        z = TWO_PI * np.arange(self.samples_per_period) / self.samples_per_period + self.grid_phase
        c = np.asarray(self.waveform, dtype=np.float64).reshape(-1, 2)
        k = np.arange(2, 2 + c.shape[0])
        harm = (c[:, 0, None] * np.cos(k[:, None] * z) - c[:, 1, None] * np.sin(k[:, None] * z)).sum(axis=0)
        out: FloatArray = self.amplitude * (np.cos(z) + harm)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "blocks": self.blocks,
            "frequency": self.frequency,
            "amplitude": self.amplitude,
            "samples_per_period": self.samples_per_period,
            "periods": self.periods,
            "noise_sd": math.sqrt(self.noise_var) if self.noise_var >= 0 else math.nan,
            "dc": float(np.mean(self.ybar)),
        }


def _period_features(rows: FloatArray) -> tuple[FloatArray, ComplexArray]:
    """DC and complex fundamental ``c_1`` of each row (one period on a uniform grid)."""
    spec = np.fft.rfft(rows, axis=1) / rows.shape[1]
    return spec[:, 0].real.copy(), (2.0 * spec[:, 1]).astype(np.complex128)


def _harmonics_of(p: int) -> int:
    return max(0, min(p // 2 - 1, MAX_DRIFT_HARMONIC))


def _recording_blocks(rows: FloatArray) -> tuple[ComplexArray, FloatArray, FloatArray, FloatArray]:
    """Up to MAX_BLOCKS runs of consecutive periods: their averaged period's harmonics, sizes, centres and
    periods."""
    n, p = rows.shape
    k = _harmonics_of(p)
    runs = np.array_split(np.arange(n), min(MAX_BLOCKS, n))
    spec = np.stack([np.fft.rfft(rows[r].mean(axis=0)) / p for r in runs])[:, : k + 1]
    spec[:, 1:] *= 2.0
    spec[:, 0] = spec[:, 0].real
    return (
        spec.astype(np.complex128),
        np.array([float(r.size * p) for r in runs]),
        np.array([float(r.mean()) for r in runs]),
        np.array([float(r.size) for r in runs]),
    )


#: Fewest periods whose spread measures the noise's colour (:func:`noise_colour`): 3 leave 2 degrees of
#: freedom per harmonic about their mean. Without it a 3-period recording's floor was the per-sample level
#: of white noise whatever the colour: AR(0.5) noise (3 times that level at the low harmonics) named terms
#: in 3 of 8 null seeds (review 34, problem 3).
MIN_COLOUR_PERIODS = 3


#: Fewest degrees of freedom per harmonic (N - 3 about the quadratic trend, N - 1 about the mean) at
#: which the DC's spread is a band of its own and the colour check keeps :data:`COLOUR_ALPHA`.
FEW_COLOUR_DOF = 4

#: The colour check's level with fewer (3 to 6 periods): a missed colour under-states the floor at the low
#: harmonics, where the loop and the candidates live, and names terms on nothing (AR(0.5): 3 times the
#: per-sample level there; at 1e-3 the check missed it in 4 of 10 noise-only 3-period records), while a
#: false colour only raises the floor to a band's level; so the check errs towards colour with few periods.
FEW_COLOUR_ALPHA = 0.05


def _about_trend(raw: ComplexArray) -> tuple[ComplexArray, int]:
    """``(residual, dof)``: the periods' harmonics ``raw`` (N, K + 1) about a quadratic trend in the period
    index (a drift or a settling loop taken out; N - 3 degrees of freedom) when N >= 4, about their mean
    (N - 1) with fewer (3 periods leave no spread about a quadratic; a drift then counts as noise, which
    errs towards a larger floor, not towards named terms)."""
    n = raw.shape[0]
    idx = np.arange(n, dtype=np.float64)
    trend = np.vander(idx - idx.mean(), 3 if n >= 4 else 1)
    c = raw - trend @ np.linalg.lstsq(trend, raw, rcond=None)[0]
    return c, n - trend.shape[1]


def noise_colour(
    rows: FloatArray, white_var: float, white_dof: int, dc: bool = True
) -> tuple[float, int, tuple[int, int]]:
    """The noise's level at the low harmonics of periods ``rows`` (N, P), when measurably above
    ``white_var`` (the per-sample variance, ``white_dof`` degrees of freedom): ``(variance, dof, band)``;
    ``(white_var, white_dof, (0, 0))`` when not (or when N < 3 leaves no spread; :func:`_about_trend`).

    Each period's harmonic ``c_k = sum_j y_j e^{-2 pi i jk/P} / P`` (``c_0`` the DC) has variance ``s2/P``
    (DC) or ``s2/(2P)`` per real and imaginary part for white noise of variance ``s2``; about a quadratic
    trend in the period index (a drift or a settling loop taken out) their spread gives ``s2`` at each
    harmonic with ``N - 3`` (DC) or ``2 (N - 3)`` degrees of freedom, pooled over bands of
    :data:`COLOUR_BAND` harmonics, and the DC alone (a band of its own: a red noise is largest there).

    When the noise is measurably coloured, the DC's level is also inflated for the correlation of the
    periods' DCs across periods (:func:`cross_period_inflation`): a noise correlated over a period or more
    (an AR(1) with phi = 0.99 at 128 samples per period) wanders slowly, and the spread of the period DCs
    then underestimates the variance of their mean (2.6 times on average, about the quadratic trend).

    ``dc=False``: the period means were taken out (a wandering baseline, ``baseline.py``): the DC is no band
    and counts in none (its spread is 0 by construction, not a quiet noise).
    """
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    n, p = rows.shape
    k = _harmonics_of(p)
    if n < MIN_COLOUR_PERIODS or k < 1 or not (white_var > 0 and math.isfinite(white_var)):
        return white_var, white_dof, (0, 0)
    raw = np.fft.rfft(rows, axis=1)[:, : k + 1] / p
    c, free = _about_trend(raw)
    ss = np.empty(k + 1)
    ss[0] = p * float(np.sum(c[:, 0].real ** 2))
    ss[1:] = 2.0 * p * np.sum(np.abs(c[:, 1:]) ** 2, axis=0)  # c_k = rfft/P: E|c_k|^2 = s2/P per period
    dof = np.full(k + 1, 2.0 * free)
    dof[0] = free if dc else 0.0
    half = COLOUR_BAND // 2
    first = 0 if dc else 1
    # Without the DC (period means taken out: a random walk's leak falls as 1/k^2 from the fundamental, and
    # the band 1-3 put the fundamental's level at 0.6 of its own) the fundamental is a band of its own.
    # Few periods (FEW_COLOUR_DOF): the DC's spread alone is too noisy to be a band (2 dof at 3 periods:
    # the largest level was then most often the DC's by chance, and its F(., 2) floor took the gate's power).
    own_dc = dc and free >= FEW_COLOUR_DOF
    bands = ([(0, 0)] if own_dc else [] if dc else [(1, 1)]) + [
        (max(first, lo - half), min(k, lo + half)) for lo in range(first, k + 1)
    ]
    levels = []
    for a, b in bands:
        d = float(np.sum(dof[a : b + 1]))
        v = float(np.sum(ss[a : b + 1])) / d
        levels.append((v, d, (a, b), float(fdtrc(d, max(white_dof, 1), v / white_var))))
    top = max(levels, key=lambda t: t[0])
    level = COLOUR_ALPHA if free >= FEW_COLOUR_DOF else FEW_COLOUR_ALPHA
    if top[0] <= white_var or min(1.0, len(bands) * min(t[3] for t in levels)) >= level:
        return white_var, white_dof, (0, 0)
    if not own_dc:
        return top[0], int(top[1]), top[2]
    # Coloured: the DC's level for its mean over the periods, the largest level the noise variance.
    infl = cross_period_inflation(raw[:, 0].real)
    v0, d0, _, _ = levels[0]
    levels[0] = (v0 * infl, max(1.0, d0 / infl), (0, 0), 0.0)
    best = max(levels, key=lambda t: t[0])
    return best[0], int(best[1]), best[2]


#: Smallest harmonic level :func:`harmonic_levels` returns, relative to the per-sample variance.
HARMONIC_FLOOR = 0.01


def harmonic_levels(
    rows: FloatArray, white_var: float, dc: bool = True, k: Optional[int] = None
) -> FloatArray:
    """Each harmonic 0..K's noise level of periods ``rows`` (N, P), in per-sample units: the spread of the
    drift test's blocks about a quadratic trend pooled over at most the :data:`COLOUR_BAND` harmonics
    around it whose single-period spreads agree (:func:`level_bands.band_levels`: a narrow-band peak is not
    smeared into its neighbours; the DC alone, its single periods' spread inflated for the correlation of
    the period DCs, :func:`cross_period_inflation`), never
    below :data:`HARMONIC_FLOOR` times ``white_var`` (a red noise is below its per-sample level at the
    higher harmonics). Empty when N < 3. ``dc=False`` (the period means taken out, ``baseline.py``): the DC's
    level is infinite (no weight in the drift test) and no band counts it. ``k``: the last harmonic
    (default the drift test's, ``MAX_DRIFT_HARMONIC`` at most; ``P // 2`` for the adequacy test's weights).
    """
    n, p = rows.shape
    k = _harmonics_of(p) if k is None else min(int(k), p // 2)
    if n < MIN_COLOUR_PERIODS or k < 1:
        return np.zeros(0)
    raw = np.fft.rfft(rows, axis=1)[:, : k + 1] / p
    c, free = _about_trend(raw)
    ss = 2.0 * p * np.sum(np.abs(c) ** 2, axis=0)
    half = COLOUR_BAND // 2
    out = np.empty(k + 1)
    out[0] = p * float(np.sum(c[:, 0].real ** 2)) / free * cross_period_inflation(raw[:, 0].real)
    if free < FEW_COLOUR_DOF:  # the DC pooled with its neighbours, as noise_colour's bands
        out[0] = (p * float(np.sum(c[:, 0].real ** 2)) + float(np.sum(ss[1 : half + 1]))) / (
            free * (1 + 2 * min(half, k))
        )
    # Harmonics 1..K at the blocks' length, pooled only over neighbours that agree (level_bands.py); without
    # the DC the fundamental is a band of its own, as noise_colour's.
    out[1:] = level_bands.band_levels(c, raw, free, p, (COLOUR_BAND, MAX_BLOCKS, not dc))[1:]
    out = np.maximum(out, HARMONIC_FLOOR * white_var)
    if not dc:
        out[0] = np.inf
    return out


#: Largest cross-period lag-1 correlation :func:`cross_period_inflation` allows (an inflation of 9).
MAX_CROSS_PERIOD_CORRELATION = 0.8


def common_centre(centres: Sequence[float], level: float) -> tuple[float, float, float, bool]:
    """``(mean, se, p, kept)`` of the recordings' centres after a wander or a drift is taken out: the
    two-sided t-test of their mean against 0 (NaN se and p with fewer than 2), kept when ``p < level`` (an
    output offset that stands out of their spread; baseline.py, zero_drift.py)."""
    from scipy.special import stdtr

    m = len(centres)
    c, se, cp = float(np.mean(centres)), math.nan, math.nan
    if m >= 2:
        se = float(np.std(centres, ddof=1)) / math.sqrt(m)
        cp = float(2.0 * stdtr(m - 1, -abs(c) / se)) if se > 0 else (0.0 if c else 1.0)
    return c, se, cp, bool(math.isfinite(cp) and cp < level)


def cross_period_correlation(series: FloatArray) -> float:
    """The lag-1 autocorrelation of ``series`` (one value per period, mean removed) with the first-order bias
    of a short series taken off (``E r_hat = r - (1 + 3 r) / N``, Marriott and Pope 1954); 0.0 when N < 4
    or the series is constant. Unclipped: about 0 with sd ``1 / sqrt(N)`` for independent periods."""
    n = series.size
    if n < 4:
        return 0.0
    x = series - series.mean()
    den = float(np.dot(x, x))
    if not den > 0:
        return 0.0
    r_hat = float(np.dot(x[1:], x[:-1])) / den
    return r_hat + (1.0 + 3.0 * r_hat) / n


def cross_period_inflation(series: FloatArray) -> float:
    """``(1 + r) / (1 - r)``: how much more the mean of ``series`` (one value per period) varies than its
    spread says, for an AR(1) across periods with lag-1 correlation ``r``
    (:func:`cross_period_correlation` clipped to ``[0, MAX_CROSS_PERIOD_CORRELATION]``): 1 for independent
    periods.
    """
    r = min(max(cross_period_correlation(series), 0.0), MAX_CROSS_PERIOD_CORRELATION)
    return (1.0 + r) / (1.0 - r)


def _from_recording(i: int, rec: Any) -> DiagExperiment:
    p = int(rec.samples_per_period)
    s = int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    if n < 3:
        raise InsufficientDataError(
            f"{item_label(i, rec, 'recording')} leaves {n} periods after {s} settling ones; the diagnosis "
            "needs at least 3 (the noise floor and the drift test come from differences of neighbouring "
            "periods)"
        )
    rows = np.asarray(rec.y[s * p : (s + n) * p], dtype=np.float64).reshape(n, p)
    urows = np.asarray(rec.u[s * p : (s + n) * p], dtype=np.float64).reshape(n, p)
    ybar = rows.mean(axis=0)
    spread = float(np.mean(np.var(rows, axis=0, ddof=1)))
    diff = float(np.mean(np.diff(rows, axis=0) ** 2)) / 2.0
    dc, h1 = _period_features(rows)
    coef, samples, center, nper = _recording_blocks(rows)
    dof = p * (n - 1)
    walk = getattr(rec, "metadata", {}).get(BASELINE_MARK, None)
    flat = walk is not None
    if flat:  # the period means were spent on the baseline: the differences hold P - 1 components each
        diff, dof = diff * p / max(p - 1, 1), (p - 1) * (n - 1)
    var, cdof, band = noise_colour(rows, diff, dof, dc=not flat)
    hvar = _levels(rows, diff, var, flat)
    if flat and hvar.size > 1:  # the walk's own leak into each harmonic, never below its steps' (baseline.py)
        hvar = np.maximum(hvar, diff + walk_levels(float(str(walk)), p, hvar.size - 1))
        if float(hvar[1]) > var:
            var, cdof, band = float(hvar[1]), n - 1, (1, 1)  # the level of the walk's n - 1 steps
    name = rec.metadata.get("name", f"recording {i}") if hasattr(rec, "metadata") else f"recording {i}"
    return DiagExperiment(
        frequency=float(rec.frequency),
        amplitude=float(rec.amplitude),
        grid_phase=float(np.mod(rec.frequency * float(rec.t[0]), TWO_PI)),
        ybar=ybar,
        periods=float(n),
        noise_var=var,
        spread_var=max(spread, var),
        noise_dof=cdof,
        dc=dc,
        h1=h1,
        source=str(name),
        block_coef=coef,
        block_samples=samples,
        block_center=center,
        block_periods=nper,
        lead_periods=float(s),
        waveform=input_waveform(urows),
        colour=var / diff if diff > 0 else 1.0,
        colour_band=band,
        cross_period=cross_period_correlation(dc) if var > diff and not flat else 0.0,
        harmonic_var=hvar,
        adequacy_var=_adequacy_levels(rows, diff, var, walk),
        input_dc=float(np.mean(urows)),
        input_dc_se=math.sqrt(float(np.mean(np.diff(urows, axis=0) ** 2)) / 2.0 / (n * p)),
    )


#: Fewest periods whose spread sets the adequacy test's per-harmonic weights (adequacy_chi2.py): below it the
#: levels rest on too few degrees of freedom (N - 3 per harmonic about the quadratic trend) and the test
#: keeps the fit's one weight. At 5 periods the weights' estimation noise alone read chi2/dof 1.2-1.3 on
#: white noise (p 1e-8) - a false alarm, not a colour.
MIN_ADEQUACY_PERIODS = 10


def adequacy_levels(rows: FloatArray, white_var: float, dc: bool = True) -> FloatArray:
    """Each harmonic 0..P/2's noise level of periods ``rows`` (N, P) for the adequacy test's weights, in
    per-sample units: the spread about the quadratic trend (as :func:`harmonic_levels`) pooled over a band
    that widens with the harmonic (``COLOUR_BAND`` harmonics, or a quarter of the harmonic's number either
    side: a red spectrum is smooth in log frequency, and the higher harmonics, where the weights are largest,
    get the most degrees of freedom), scaled by ``nu / (nu - 2)`` for the band's ``nu`` degrees of freedom
    so that ``1 / level`` is unbiased (``E[nu / chi2_nu] = nu / (nu - 2)``), never below
    :data:`HARMONIC_FLOOR` times ``white_var``. The DC as :func:`harmonic_levels` (infinite when ``dc`` is
    False). Empty with fewer than :data:`MIN_ADEQUACY_PERIODS` periods."""
    n, p = rows.shape
    k = p // 2
    if n < MIN_ADEQUACY_PERIODS or k < 1:
        return np.zeros(0)
    dc_level = harmonic_levels(rows, white_var, dc=dc, k=1)
    raw = np.fft.rfft(rows, axis=1)[:, : k + 1] / p
    c, free = _about_trend(raw)
    ss = 2.0 * p * np.sum(np.abs(c) ** 2, axis=0)
    out = np.empty(k + 1)
    out[0] = dc_level[0] if dc_level.size else np.inf
    for j in range(1, k + 1):
        half = max(COLOUR_BAND // 2, j // 4)
        a, b = max(1, j - half), min(k, j + half)
        nu = 2.0 * free * (b - a + 1)
        out[j] = float(np.sum(ss[a : b + 1])) / nu * nu / (nu - 2.0)
    return np.maximum(out, HARMONIC_FLOOR * white_var)


def _adequacy_levels(rows: FloatArray, white: float, var: float, walk: Any) -> FloatArray:
    """``DiagExperiment.adequacy_var`` of a recording: :func:`adequacy_levels` when the noise is coloured
    (empty when white); with the period means taken out (``walk`` not None) the DC's is infinite and no level
    is below the walk's own leak, as ``harmonic_var``."""
    if not var > white:
        return np.zeros(0)
    p = rows.shape[1]
    out = adequacy_levels(rows, white, dc=walk is None)
    if walk is not None and out.size > 1:
        out = np.maximum(out, white + walk_levels(float(str(walk)), p, out.size - 1))
    return out


def walk_levels(s2: float, p: int, k: int) -> np.ndarray:
    """A random walk's variance at harmonics 0..k of single periods whose means were taken out, in
    per-sample units (as the white noise's ``sigma^2``): ``s^2 / (2 sin^2(pi j / P))`` at harmonic j (a
    period's walk is its steps summed: ``E|c_j|^2 = 2 s^2 / (P 4 sin^2(pi j / P))``, white noise's
    ``sigma^2 / P``); infinite at the DC. At 0.05 noise sd per step and 128 samples per period: 2.1 times
    the white noise's variance at the fundamental, 0.52 at the second harmonic, 0.23 at the third."""
    j = np.arange(k + 1, dtype=np.float64)
    out = np.full(k + 1, np.inf)
    out[1:] = s2 / (2.0 * np.sin(np.pi * j[1:] / p) ** 2)
    return out


def _levels(rows: FloatArray, white: float, var: float, flat: bool) -> FloatArray:
    """``DiagExperiment.harmonic_var`` of a recording: :func:`harmonic_levels` when the noise is coloured,
    empty when white, and with an infinite DC level when the period means were taken out."""
    if var > white:
        return harmonic_levels(rows, white, dc=not flat)
    if not flat:
        return np.zeros(0)
    out = np.full(_harmonics_of(rows.shape[1]) + 1, white)
    out[0] = np.inf
    return out


def _normalised(c: ComplexArray, floor: float) -> FloatArray:
    """``[Re c_2, Im c_2, ...]`` from complex amplitudes ``c[k - 1]`` of harmonics k = 1.. (see
    :func:`input_waveform`), keeping those above ``floor`` and :data:`WAVEFORM_MIN_RELATIVE`."""
    c1 = complex(c[0])
    if abs(c1) == 0.0:
        return np.zeros(0)
    rot = c1 / abs(c1)
    out = np.zeros(2 * max(c.size - 1, 0))
    last = 0
    for k in range(2, c.size + 1):
        ck = complex(c[k - 1])
        if abs(ck) > floor and abs(ck) > WAVEFORM_MIN_RELATIVE * abs(c1):
            v = ck / (abs(c1) * rot**k)
            out[2 * (k - 2)], out[2 * (k - 2) + 1] = v.real, v.imag
            last = k - 1
    return out[: 2 * last]


def _lab_waveform(th: FloatArray, u: FloatArray) -> FloatArray:
    """The input's waveform (as :func:`input_waveform`) from raw samples at phase ``th = omega t``: least
    squares on the DC and harmonics 1..:data:`WAVEFORM_MAX_HARMONIC`, noise from the fit's residual."""
    kmax = WAVEFORM_MAX_HARMONIC
    if u.size < 4 * (2 * kmax + 1):
        return np.zeros(0)
    basis = harmonic_basis(th, kmax)
    coef, *_ = np.linalg.lstsq(basis, u, rcond=None)
    resid = u - basis @ coef
    var_u = float(resid @ resid) / (u.size - basis.shape[1])
    # Each coefficient's sd ~ sqrt(2 var / n) on whole periods; |C_k| of noise about sqrt(2) times that.
    floor = WAVEFORM_NOISE_SD * math.sqrt(2.0 * 2.0 * var_u / u.size)
    c = coef[1::2] - 1j * coef[2::2]
    return _normalised(c.astype(np.complex128), floor)


def _from_averaged(
    ap: Any, t: FloatArray | None, y: FloatArray | None, u: FloatArray | None = None
) -> DiagExperiment:
    """A lab period (any sampling rate); with the raw samples, the per-period DC and fundamental too.

    The noise floor stays the averaging's (the residual of its harmonic fit over the stretch): a lab record
    holds too few samples per period for a within-period fit of every harmonic the loop needs, and the
    drift test on the per-period record is the guard against a floor a drift inflates.
    """
    ybar = np.asarray(ap.ybar, dtype=np.float64) + float(ap.offset_y)
    blocks: tuple[ComplexArray, FloatArray, FloatArray, FloatArray] | None = None
    empty = (np.zeros((0, 1), np.complex128), np.zeros(0), np.zeros(0))
    lead = math.nan
    waveform = np.zeros(0)
    dc = np.array([float(np.mean(ybar))])
    h1 = np.array([complex(2.0 * np.fft.rfft(ybar)[1] / ybar.size)])
    var, dof, band = float(ap.noise_var), int(ap.noise_dof), (0, 0)
    hvar = np.zeros(0)
    if t is not None and y is not None:
        omega = float(ap.frequency)
        seg_t = t[ap.start : ap.stop] - float(ap.time_origin)
        seg_y = y[ap.start : ap.stop]
        # Whole periods from the input's phase zero: DC and fundamental by least squares on each.
        k = np.floor(seg_t * omega / TWO_PI).astype(np.int64)
        th = omega * seg_t
        dcs, h1s, kept = [], [], []
        for j in range(int(k.min()) if k.size else 0, int(k.max()) if k.size else 0):
            sel = k == j
            if np.count_nonzero(sel) < 8:
                continue
            basis = np.column_stack([np.ones(np.count_nonzero(sel)), np.cos(th[sel]), np.sin(th[sel])])
            coef = np.linalg.lstsq(basis, seg_y[sel], rcond=None)[0]
            dcs.append(coef[0])
            h1s.append(complex(coef[1], -coef[2]))
            kept.append(j)
        if len(dcs) >= 3:
            dc, h1 = np.array(dcs), np.array(h1s, dtype=np.complex128)
        blocks = _lab_blocks(k, th, seg_y, kept, ybar.size)
        rules = (COLOUR_BAND, COLOUR_ALPHA, cross_period_inflation)  # as noise_colour on recordings
        models: dict[int, FloatArray] = {}  # each period's averaged-period values, computed once for both
        coloured = lab_colour.levels(k, th, seg_y, kept, var, dof, ybar, rules, models)
        if coloured is not None:
            var, dof, band = coloured
        # Each harmonic's own level for the drift test's blocks, coloured or not: a colour too weak for the
        # check above (AR(1), phi = 0.3: 1.6-1.9 times the per-sample level at every block harmonic) put
        # that experiment's block chi-square at 1.8 of its dof, and the gate called 45 % of nulls drifting.
        hrules = (_harmonics_of(ybar.size), COLOUR_BAND, HARMONIC_FLOOR, cross_period_inflation)
        hvar = lab_colour.harmonic_levels(k, th, seg_y, kept, float(ap.noise_var), ybar, hrules, models)
        if kept:  # periods from the record's first sample to the first whole period used
            lead = float((float(ap.time_origin) - float(t[0])) * omega / TWO_PI) + float(kept[0])
        if u is not None:
            waveform = _lab_waveform(th, np.asarray(u[ap.start : ap.stop], dtype=np.float64))
    return DiagExperiment(
        frequency=float(ap.frequency),
        amplitude=float(ap.amplitude),
        grid_phase=0.0,
        ybar=ybar,
        periods=float(ap.periods),
        noise_var=var,
        spread_var=var,
        noise_dof=dof,
        dc=dc,
        h1=h1,
        source=str(ap.source),
        lead_periods=lead,
        block_coef=empty[0] if blocks is None else blocks[0],
        block_samples=empty[1] if blocks is None else blocks[1],
        block_center=empty[2] if blocks is None else blocks[2],
        block_periods=empty[2] if blocks is None else blocks[3],
        waveform=waveform,
        colour=var / float(ap.noise_var) if band != (0, 0) or var > float(ap.noise_var) else 1.0,
        colour_band=band,
        harmonic_var=hvar,
        input_dc=float(getattr(ap, "offset_u", 0.0)),
        input_dc_se=math.nan,  # the averaging keeps no spread of u's mean: input_dc.py uses its size alone
    )


def _lab_blocks(
    k: NDArray[np.int64], th: FloatArray, y: FloatArray, kept: Sequence[int], p: int
) -> tuple[ComplexArray, FloatArray, FloatArray, FloatArray] | None:
    """Block record of a lab stretch: harmonics 0..K by least squares over each run of whole periods.

    ``th`` is the input's phase (``u = U cos th``), the frame of the averaged grid (grid phase 0).
    """
    if len(kept) < 2:
        return None
    harm = _harmonics_of(p)
    runs = np.array_split(np.asarray(kept), min(MAX_BLOCKS, len(kept)))
    coefs, samples, centers, nper = [], [], [], []
    for r in runs:
        sel = np.isin(k, r)
        n = int(np.count_nonzero(sel))
        if n < 2 * (2 * harm + 1):
            return None  # too few samples for the block's harmonics: no block record
        sol = np.linalg.lstsq(harmonic_basis(th[sel], harm), y[sel], rcond=None)[0]
        c = np.empty(harm + 1, np.complex128)
        c[0] = sol[0]
        c[1:] = sol[1::2] - 1j * sol[2::2]
        coefs.append(c)
        samples.append(float(n))
        centers.append(float(np.mean(r)) - float(kept[0]))
        nper.append(float(len(r)))
    return np.stack(coefs), np.array(samples), np.array(centers), np.array(nper)


def _lab_marked(e: DiagExperiment) -> DiagExperiment:
    """A lab experiment whose drifting zero was taken out (``zero_drift.lab_detrended``): its DC set, not
    measured (an infinite level at the DC), the noise's level at every harmonic."""
    hv = np.full(e.samples_per_period // 2 + 1, e.noise_var)
    hv[0] = math.inf
    return replace(e, harmonic_var=hv)


#: Fewest distinct output levels, relative to the samples, below which the output is read as quantised.
QUANTISED_LEVELS = 0.25
#: Largest share of samples off the grid of a quantised output (spikes added after the converter).
OFF_GRID = 0.01


#: The numerical accuracy of a simulated loop relative to the output's peak: below it a noise floor is
#: rounding, not noise. Noise-free data carry their generator's discretisation error (measured: 4e-8 of the
#: peak for the demo plant at 1024 samples per period, 2e-6 for a resonant G with a delay at 64 samples and
#: 8 substeps), which a floor of rounding (1e-15) turned into "unexplained structure remains". 1e-5 of the
#: peak is below a 16-bit converter's own quantisation noise (4e-6 of its full range).
NUMERICAL_RTOL = 1e-5
#: ... and at least ``SIMULATION_ERROR_C / P^2`` of the peak at P samples per period: the rms error of a
#: steady period simulated by RK4 with one step per sample (the coarsest a simulator on the grid uses).
#: Measured (/tmp/ic_err2.py of review 31a item 6: 4096 samples and 8 steps per sample as the reference; the
#: demo plant, a resonant G with a delay, a first-order G with mu = 1.2) at N = 32 ... 4096 RK4 steps per
#: period: N^2 times the error is 0.8-2.05 (its order is 2, not 4: the loop's reversals are not smooth);
#: at 128 samples per period and 2 steps per sample the demo plant's error is 1.2e-5 of its peak, above
#: NUMERICAL_RTOL, and noise-free data from the library's own simulator read as "unexplained structure".
SIMULATION_ERROR_C = 2.1


def numerical_rtol(p: int) -> float:
    """The relative noise floor of noise-free data at ``p`` samples per period (see the constants)."""
    return max(NUMERICAL_RTOL, SIMULATION_ERROR_C / float(max(p, 1)) ** 2)


def quantisation_step(y: Any) -> float:
    """The output's quantisation step (0 when the samples are not on a grid of steps)."""
    v = np.asarray(y, dtype=np.float64).ravel()
    finite = v[np.isfinite(v)]
    levels, counts = np.unique(finite, return_counts=True)
    if levels.size < 2 or levels.size > QUANTISED_LEVELS * v.size:
        return 0.0
    # The step most levels are apart by, when all but OFF_GRID of the samples lie on its grid (counted from
    # the most frequent level): spikes added after the converter put a few samples off it (review 41), and
    # a spike of 0.2 x a peak on the grid lies on a grid 5 times finer, which the least gap would find.
    q = float(np.median(np.diff(levels)))
    k = (finite - levels[np.argmax(counts)]) / q
    if float(np.mean(np.abs(k - np.round(k)) > 1e-6 * max(1.0, float(np.max(np.abs(k)))))) <= OFF_GRID:
        return q
    q = float(np.min(np.diff(levels)))
    k = (levels - levels[0]) / q
    tol = 1e-6 * max(1.0, float(k[-1]))
    return q if float(np.max(np.abs(k - np.round(k)))) <= tol else 0.0


def prepare(items: Any) -> list[DiagExperiment]:
    """Reduce Recordings, Measurements or AveragedPeriods (or a mix) to :class:`DiagExperiment`.

    Raises
    ------
    InvalidParameterError
        For an item of another type.
    InsufficientDataError
        When nothing is left to diagnose or a recording is too short.
    """
    from ..measurement import Measurement
    from ..model import Recording
    from ..signal import AveragedPeriod

    seq: Sequence[Any] = items if isinstance(items, (list, tuple)) else [items]
    out: list[DiagExperiment] = []
    for i, item in enumerate(seq):
        if isinstance(item, Recording):
            out.append(_from_recording(i, item))
        elif isinstance(item, Measurement):
            for ap in lab_settle.averaged(item):  # average_measurement, its start-up transient trimmed
                e = _from_averaged(ap, np.asarray(item.t), np.asarray(item.y), np.asarray(item.u))
                out.append(_lab_marked(e) if BASELINE_MARK in item.metadata else e)
        elif isinstance(item, AveragedPeriod):
            out.append(_from_averaged(item, None, None))
        elif isinstance(item, DiagExperiment):
            out.append(item)
        else:
            raise InvalidParameterError(
                f"item {i} is a {type(item).__name__}; diagnose takes Recording, Measurement or "
                "AveragedPeriod objects"
            )
    if not out:
        raise InsufficientDataError("nothing to diagnose: no item gave an averaged period")
    # A quantised output without noise repeats its periods exactly (variance 0): settling._noise_floors
    # gives it the quantisation floor N q^2 / 12, as the docs promise, rather than refusing it.
    quantised = any(quantisation_step(it.y) > 0 for it in seq if hasattr(it, "y"))
    for e in out:
        if not (math.isfinite(e.noise_var) and (e.noise_var > 0 or (quantised and e.noise_var == 0))):
            if e.ybar.size and float(np.ptp(e.ybar)) == 0.0:  # a dead channel: identify's error, the README's
                raise ZeroAmplitudeError(
                    f"{e.source}: the output's averaged period is constant ({float(e.ybar[0]):.6g} at every "
                    "sample): a dead or wrong channel, with no response to the excitation to diagnose"
                )
            raise InsufficientDataError(
                f"{e.source}: no noise floor (noise-free or single-period data); the diagnosis tests every "
                "claim against the period-to-period noise and needs noisy, repeated periods"
            )
    return out


#: One-sided normal quantile (0.1 %) of the pooled cross-period correlation from which the notes say the
#: periods are correlated (phi = 0.99 at 128 samples per period: r about 0.45, z about 5 over 10
#: experiments of 16 periods; phi = 0.8: r about 0).
CROSS_PERIOD_Z = 3.09


def colour_notes(exps: Sequence[DiagExperiment]) -> list[str]:
    """What the diagnosis says of experiments whose noise is coloured (:func:`noise_colour`)."""
    out = []
    for e in exps:
        if not e.colour > 1.0:
            continue
        where = (
            "at the DC (the loop's centre) its mean over the periods varies"
            if e.colour_band == (0, 0)
            else f"at harmonics {e.colour_band[0]}-{e.colour_band[1]} its spread from period to period "
            "(about a quadratic trend) is"
        )
        text = (
            f"{e.source}: the output is not white noise about its mean period: {where} {e.colour:.3g} times "
            "the per-sample variance (1 for white noise): a coloured noise, or a loop that changes faster "
            "than a quadratic trend; the tests on this experiment take that larger level as its noise (valid "
            "where the model and its terms act, conservative at the other harmonics)"
        )
        out.append(text)
    # Pooled over the experiments (one noise process; 16 periods alone hardly tell r = 0.3 from 0): the
    # mean correlation against its sd for independent periods, 1 / sqrt(sum of periods).
    dcs = [e for e in exps if e.colour > 1.0 and e.colour_band == (0, 0) and e.periods >= 4]
    if dcs:
        r = float(np.mean([e.cross_period for e in dcs]))
        z = r * math.sqrt(sum(e.periods for e in dcs))
        if z >= CROSS_PERIOD_Z:
            out.append(
                f"the noise is correlated across periods: the period DCs' lag-1 correlation is {r:.2g} "
                f"(mean over {len(dcs)} experiments, z = {z:.2g}), so their mean varies about "
                f"{(1 + r) / (1 - r) if r < 1 else math.inf:.2g} times more than their spread says; a slow "
                "wander of the loop's centre and a drift of it cannot be told apart in these records, and "
                "the centres are judged against that wander (longer records would separate them)"
            )
    return out

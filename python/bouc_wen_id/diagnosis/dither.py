"""The error a partly dithered quantiser locks into every period (review 44, CAUSES section 2).

A converter of step q records ``y_rec = q round((y + n) / q)``; on an output that sits on a grid, the noise
``n`` came before the converter and acts as dither. With ``n`` Gaussian of sd sigma, the error at a level y
has the mean ``m(y) = E[y_rec] - y`` and the variance ``v(y) = Var[y_rec]``. Averaging N periods takes
``v`` down as ``v / N`` but keeps ``m``: it depends on y alone and repeats every period. In Fourier form
(``r = sigma / q``)

    m(y) = (q / pi) sum_k (-1)^k exp(-2 pi^2 k^2 r^2) sin(2 pi k y / q) / k,

and over a level spread evenly across a step
``mean m^2 = L = q^2 / (2 pi^2) sum_k exp(-4 pi^2 k^2 r^2) / k^2``
(``q^2 / 12`` at sigma = 0: the undithered quantiser's whole error; below ``1e-4 q^2 / 12`` at sigma = q / 2).
:func:`mean_error` computes ``m`` exactly, as a sum over the few levels the converter can return
(``P_j = Phi((j + 1/2 - x) / r) - Phi((j - 1/2 - x) / r)`` at ``x = y / q``), which holds at sigma = 0 too;
:func:`locked_power` is the series.

``L`` falls steeply with sigma (5 % per 0.01 q at sigma = q / 4), so sigma must be read to a few thousandths
of q. :func:`fit_sigma_counts` reads it from how each sample's periods fall on the levels (a likelihood with
the sample's unknown level integrated out): 0.255 q on review 44's null-0-C-12 (sigma = q / 4), where matching
the measured period-to-period variance with ``v(y; sigma)`` at a smoothed averaged period read 0.265-0.27 q
(the smoothing's error blurs the dwell near mid-step levels that raises ``v``) and the uniform-level formula
``sigma^2 + q^2 / 12 - L`` 0.35 q on a loop that dwells there. ``m`` is then evaluated along an averaged
period at :func:`smooth_part` (the harmonics that stand above the noise), since the averaged period itself
already carries ``m`` and its noise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Dither (sigma / q) at and above which nothing is locked that a test could see (``L < 1e-4 q^2 / 12``).
NO_LOCK_RATIO = 0.5

#: A harmonic of the averaged period is taken as the output's own (not noise) when its power stands this many
#: times above the averaged noise's level there (an amplitude 3 noise sd): the levels ``m`` is evaluated at.
SMOOTH_SNR = 9.0


def _level_probabilities(e: FloatArray, r: float) -> FloatArray:
    """``P_j`` of the levels ``e`` steps above the clean level (``e = j - x``) at dither ``r = sigma / q``,
    each difference of normal tails taken on the side where it does not cancel."""
    from scipy.special import ndtr  # type: ignore[import-untyped]

    hi, lo = (e + 0.5) / r, (e - 0.5) / r
    upper = lo > 0.0
    out: FloatArray = np.where(upper, ndtr(-lo) - ndtr(-hi), ndtr(hi) - ndtr(lo))
    return out


def mean_error(y: FloatArray, q: float, sigma: float, offset: float = 0.0) -> FloatArray:
    """``m(y)``: the converter's mean error at the levels ``y`` (the part that repeats every period), for
    a grid of step ``q`` through ``offset`` and a dither sd ``sigma``: ``q sum_j P_j (j - x)`` (x = y / q)."""
    x = (np.asarray(y, dtype=np.float64) - offset) / q
    if sigma <= 0.0:
        return q * (np.round(x) - x)
    span = int(math.ceil(8.0 * sigma / q)) + 1
    e = np.floor(x)[..., None] + np.arange(-span, span + 2) - x[..., None]  # each level's error, in steps
    out: FloatArray = q * np.sum(_level_probabilities(e, sigma / q) * e, axis=-1)
    return out


def locked_power(q: float, sigma: float, terms: int = 200) -> float:
    """``L``: the mean square of ``m`` over levels spread evenly across a step (the Fourier series)."""
    k = np.arange(1, terms + 1, dtype=np.float64)
    r = sigma / q
    return float(q * q * np.sum(np.exp(-4.0 * math.pi**2 * k * k * r * r) / (k * k)) / (2.0 * math.pi**2))


#: Grid of ``x = y / q`` over which :func:`fit_sigma_counts` integrates each sample's unknown level (steps).
X_GRID = 0.01


#: A record whose spread about its mean period is this many times what neighbouring periods differ by drifts
#: (a degrading specimen): its levels move over the record, which a level shared by all its periods reads as
#: dither (stiffness degradation at 30x in config C read 0.70 q for 0.25 q), so :func:`fit_sigma_counts`
#: gives each pair of its periods a level of its own (0.27 q there). A steady record keeps one level a sample
#: over all its periods: pairs read 0.267 q on null-0-C-12 where the whole record reads 0.255 q.
DRIFT_RATIO = 1.2


def _blocks(k: NDArray[np.int64]) -> list[NDArray[np.int64]]:
    """Rows ``k`` (N, P) as one run of periods when steady, else cut into pairs (:data:`DRIFT_RATIO`)."""
    n = k.shape[0]
    if n < 2:
        return []
    spread = float(np.mean(np.var(k, axis=0, ddof=1)))
    step = float(np.mean(np.diff(k, axis=0) ** 2)) / 2.0
    if spread <= DRIFT_RATIO * step or n < 4:
        return [k]
    return [k[i : i + 2] for i in range(0, n - 1, 2)]


def fit_sigma_counts(rows: Sequence[FloatArray], q: float, offset: float = 0.0, top: float = 0.7) -> float:
    """The dither sd from the recorded levels themselves: each sample's periods (``rows``, (N, P) per
    experiment; in pairs when it drifts, :func:`_blocks`) fall on the levels ``j`` with the probabilities
    ``P_j(x; sigma)``; the likelihood of sigma with each sample's ``x = y / q`` integrated out over an even
    prior (its level is unknown, and no estimate of it is fitted per sample: with 20 periods a fitted level
    takes up a twentieth of the spread). Maximised over sigma in ``(0, top q]``; 0 when every sample repeats
    one level."""
    from scipy.optimize import minimize_scalar  # type: ignore[import-untyped]
    from scipy.special import logsumexp

    runs = [
        (b - b.min(axis=0)).T
        for r in rows
        for b in _blocks(np.round((np.asarray(r, dtype=np.float64) - offset) / q).astype(np.int64))
    ]
    width = max((int(k.max()) + 1 for k in runs), default=1)
    counts = np.zeros((sum(k.shape[0] for k in runs), width))
    start = 0
    for k in runs:  # each sample's count of periods at each level, from its run's lowest
        idx = np.repeat(np.arange(start, start + k.shape[0]), k.shape[1])
        np.add.at(counts, (idx, k.ravel()), 1.0)
        start += k.shape[0]
    patterns, times = np.unique(counts, axis=0, return_counts=True)
    if patterns.shape[0] == 0 or np.all(np.count_nonzero(patterns, axis=1) <= 1):
        return 0.0
    x = np.arange(-3.0, width + 2.0, X_GRID)
    e = np.arange(width)[None, :] - x[:, None]  # (X, width)

    def minus_loglik(r: float) -> float:
        logp = np.log(np.maximum(_level_probabilities(e, r), 1e-300))  # (X, width)
        ll = logsumexp(patterns @ logp.T, axis=1)  # each pattern, its level integrated out
        return -float(np.sum(times * ll))

    grid = np.linspace(0.02, top, 35)
    best = int(np.argmin([minus_loglik(r) for r in grid]))
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    res = minimize_scalar(minus_loglik, bounds=(lo, hi), method="bounded", options={"xatol": 1e-4})
    return float(res.x) * q


def smooth_part(ybar: FloatArray, noise_level: float) -> FloatArray:
    """``ybar`` keeping its DC, fundamental and the harmonics whose power (per-sample units, as the noise's
    ``noise_level`` of the averaged period) stands :data:`SMOOTH_SNR` times above that level."""
    p = ybar.size
    c = np.fft.rfft(ybar)
    keep = p * np.abs(c / p) ** 2 > SMOOTH_SNR * noise_level
    keep[:2] = True
    return np.fft.irfft(np.where(keep, c, 0.0), n=p)


def harmonic_power(m: FloatArray) -> FloatArray:
    """``P |M_k|^2`` at harmonics 0..P/2 of a period ``m`` (``M_k = rfft(m)_k / P``): its level in the
    adequacy test's per-sample units (adequacy_chi2.py): weighed by 2 for the two-sided harmonics (1 for the
    DC and the Nyquist one), their sum over P is ``mean(m^2)`` (Parseval)."""
    p = m.size
    return p * np.abs(np.fft.rfft(m) / p) ** 2


def grid_offset(y: FloatArray, q: float) -> float:
    """Where the grid of step ``q`` lies: the most frequent recorded level, modulo ``q``."""
    v = np.asarray(y, dtype=np.float64)
    v = v[np.isfinite(v)]
    levels, counts = np.unique(v, return_counts=True)
    return float(np.mod(levels[np.argmax(counts)], q)) if levels.size else 0.0


__all__ = [
    "NO_LOCK_RATIO",
    "fit_sigma_counts",
    "grid_offset",
    "harmonic_power",
    "locked_power",
    "mean_error",
    "smooth_part",
]

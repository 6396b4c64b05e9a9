"""Noise levels per harmonic that follow the spectrum: a harmonic is pooled only with neighbours that agree.

:func:`data.harmonic_levels` weighs the drift test's blocks harmonic by harmonic. Its levels came from the
single periods' spread pooled over the ``COLOUR_BAND`` harmonics around each. Two things went wrong under a
narrow-band noise (review 46: AR(2), poles 0.95 e^{+-0.3i} a sample, 40 samples a period, its peak on
harmonic 2; nuar46's ``calib46.py``):

- Pooling across the peak smeared it: the level at harmonic 2 came out about 3 times too low (a term acting
  there looked significant on noise), the levels at harmonics 1 and 3-4 2-16 times too high.
- A single period's harmonics hold the leak of the whole spectrum through the period's edges (its first and
  last samples do not join), which falls with the window's length: at the blocks' length (2-3 periods) the
  harmonics 5-15 carry about 0.5 of a single period's level.

So :func:`band_levels` measures each harmonic's level at the blocks' length (:func:`block_spread`) and
pools it over the widest band of at most ``COLOUR_BAND`` harmonics (+-2, then +-1, then the harmonic alone)
whose single-period spreads (2 (N - 3) degrees of freedom each, more than the blocks') Bartlett's test does
not call unequal at :data:`BAND_ALPHA`. Where the spectrum is smooth the band stays whole; a peak stands.
Each level is scaled by ``nu / (nu - 2)`` for its ``nu`` degrees of freedom (as ``data.adequacy_levels``):
the test weighs with ``1 / level``, and ``E[nu / chi2_nu] = nu / (nu - 2)``.

What is left (``studies/levels47``): under that AR(2) the blocks' chi-square still sits at 0.6-0.8 of its
dof at harmonics 5-15. Neighbouring blocks share an edge, so their leaks anti-correlate, and the spread of
the blocks about a steady fit is below what their own levels say; no estimate from 8 blocks tells that
apart from a drift.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Level of Bartlett's test at which a band's harmonics are too unequal to pool (per harmonic and width).
#: A cut only narrows the band: the level keeps its mean (``nu / (nu - 2)``) and gains variance, so the test
#: errs towards cutting. At 1e-3 harmonic 1 of AR(2) above stayed pooled with the peak (its blocks'
#: chi-square at 0.58 of its dof) and AR(1)'s (phi = 0.9, 40 samples a period) with harmonic 2 (1.17);
#: at 0.05, 0.77 and 0.98, and white noise reads 0.987 of its dof either way (``studies/levels47``).
BAND_ALPHA = 0.05
#: Fewest degrees of freedom about the trend (periods less 3) at which a band may be cut: with fewer the
#: single periods' spreads are too noisy to tell a peak from chance, and the band stays whole (as before).
MIN_CUT_DOF = 4


def bartlett_p(ss: FloatArray, dof: float) -> float:
    """Bartlett's test that the variances ``ss / dof`` (each on ``dof`` degrees of freedom) are equal: p."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    m = ss.size
    if m < 2 or not np.all(ss > 0):
        return 1.0
    v = ss / dof
    stat = dof * (m * math.log(float(np.mean(v))) - float(np.sum(np.log(v))))
    stat /= 1.0 + (m + 1.0) / (3.0 * m * dof)
    return float(chdtrc(m - 1, stat))


def band(ss: FloatArray, j: int, half: int, first: int, dof: float, cut: bool) -> tuple[int, int]:
    """The widest band ``(a, b)`` around harmonic ``j`` (at most +-``half``, within ``first..ss.size - 1``)
    whose single-period spreads ``ss`` (``dof`` each) Bartlett's test does not call unequal; the whole band
    when ``cut`` is False."""
    last = ss.size - 1
    for h in range(half, -1, -1):
        a, b = max(first, j - h), min(last, j + h)
        if not cut or b == a or bartlett_p(ss[a : b + 1], dof) >= BAND_ALPHA:
            return a, b
    return j, j


def block_spread(raw: ComplexArray, p: int, blocks: int) -> tuple[FloatArray, float]:
    """``(ss, free)``: the spread at harmonics 0..K of the single periods' harmonics ``raw`` (N, K + 1) at
    the drift test's blocks' length: ``ss_j / (2 free)`` is the per-sample level at harmonic ``j`` (white
    noise: its variance). The periods are averaged over up to ``blocks`` runs of consecutive ones (as the
    blocks); the differences of neighbouring runs, each scaled to the variance of one run of one period
    for white noise (by ``1 / n_i + 1 / n_(i+1)``), are taken about their mean: a steady loop cancels, a
    linear drift is their mean. ``free`` is ``B - 1 - 1 / (B - 1)`` for ``B`` runs (the expectation for white
    noise: neighbouring differences share a run). With fewer than 4 runs: the runs about their mean, each
    scaled by the square root of its periods (``B - 1``). The spread of the runs about a quadratic trend
    (as the single periods') read white noise at 0.95 of its level in the blocks' chi-square; this reads it
    at 0.99 (``studies/levels47``)."""
    n = raw.shape[0]
    runs = np.array_split(np.arange(n), min(blocks, n))
    size = np.array([float(r.size) for r in runs])
    mean = np.stack([raw[r].mean(axis=0) for r in runs])
    if len(runs) < 4:
        dev = (mean - mean.mean(axis=0)) * np.sqrt(size)[:, None]
        return 2.0 * p * np.sum(np.abs(dev) ** 2, axis=0), len(runs) - 1.0
    d = np.diff(mean, axis=0) / np.sqrt(1.0 / size[1:] + 1.0 / size[:-1])[:, None]
    d = d - d.mean(axis=0)
    m = len(runs) - 1.0
    return 2.0 * p * np.sum(np.abs(d) ** 2, axis=0), m - 1.0 / m


def band_levels(
    resid: ComplexArray, raw: ComplexArray, free: int, p: int, rules: tuple[int, int, bool]
) -> FloatArray:
    """Levels at harmonics 1..K (index 0 unset) of the single periods' harmonics ``raw`` (N, K + 1), whose
    spread about their trend is ``resid`` (``free`` degrees of freedom; P samples a period): the blocks'
    spread (:func:`block_spread`)
    pooled over the band :func:`band` picks from the single periods' spreads (2 ``free`` degrees of freedom
    each), times ``nu / (nu - 2)``. ``rules`` is ``(COLOUR_BAND, MAX_BLOCKS, fundamental_alone)``; with
    ``fundamental_alone`` (the period means taken out) harmonic 1 is a band of its own."""
    width, blocks, alone = rules
    k = resid.shape[1] - 1
    single = 2.0 * p * np.sum(np.abs(resid) ** 2, axis=0)
    ss, bfree = block_spread(raw, p, blocks)
    cut = free >= MIN_CUT_DOF
    out = np.zeros(k + 1)
    for j in range(1, k + 1):
        a, b = (1, 1) if alone and j == 1 else band(single, j, width // 2, 1, 2.0 * free, cut)
        nu = 2.0 * bfree * (b - a + 1)
        out[j] = float(np.sum(ss[a : b + 1])) / nu * (nu / (nu - 2.0) if nu > 2.0 else 1.0)
    return out


__all__ = [
    "BAND_ALPHA",
    "MIN_CUT_DOF",
    "band",
    "band_levels",
    "bartlett_p",
    "block_spread",
]

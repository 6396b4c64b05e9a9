"""Coloured noise on the lab-measurement path (any sampling rate, ``bouc_wen_id.measurement``; issue 18).

On recordings ``data.noise_colour`` compares the spread of each period's low harmonics (about a quadratic
trend in the period index) with the per-sample variance, and when the noise is measurably coloured takes the
largest band's level as the noise floor. Lab measurements had no such check: their floor stayed the
averaging's per-sample residual variance, so an AR(1) noise (phi 0.5-0.85: 3-12 times that level at the
low harmonics) left every fixed-rate null of the blind bench "unexplained structure at harmonics DC, 1-6"
(7 of 7), while the same noise on recordings was adequate.

:func:`levels` is that check on a lab stretch: each whole period's harmonics 0..K by least squares on the
input's phase (as the per-period DC and fundamental are fitted), scaled by the square root of its samples
(a white noise of per-sample variance ``s2`` then gives ``s2`` at the DC and ``s2 / 2`` per part at each
harmonic), their spread about a quadratic trend pooled in the bands of ``noise_colour``, the DC's inflated
for its correlation across periods, each tested against the averaging's variance (F, ``COLOUR_ALPHA``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..signal._harmonic_ls import harmonic_basis

#: Most harmonics fitted per period (and never more than a quarter of its samples allow).
MAX_HARMONIC = 7


def _model(
    models: Optional[dict[int, NDArray[np.float64]]],
    j: int,
    ph: NDArray[np.float64],
    c: NDArray[np.complex128],
) -> NDArray[np.float64]:
    """The averaged period (its harmonics ``c``) at period ``j``'s phases ``ph``; kept in ``models`` (when
    given) for the other function on the same stretch, which computes the same values (exact)."""
    if models is not None and j in models:
        return models[j]
    model: NDArray[np.float64] = (np.exp(1j * np.outer(ph, np.arange(c.size))) @ c).real
    if models is not None:
        models[j] = model
    return model


def levels(
    k: NDArray[np.int64],
    th: NDArray[np.float64],
    y: NDArray[np.float64],
    kept: Sequence[int],
    white_var: float,
    white_dof: int,
    ybar: NDArray[np.float64],
    rules: tuple[int, float, Callable[[NDArray[np.float64]], float]],
    models: Optional[dict[int, NDArray[np.float64]]] = None,
) -> Optional[tuple[float, int, tuple[int, int]]]:
    """``(variance, dof, band)`` of the noise's largest low-harmonic level when measurably above
    ``white_var`` (per-sample, ``white_dof`` dof), else None (white, or fewer than 4 whole periods).

    The averaged period ``ybar`` (on its grid, phase 0 at ``th = 0``) is taken out first, evaluated at each
    sample's phase as its trigonometric polynomial: the loop's harmonics above K would otherwise leak into
    the fitted ones differently in every period (the phases of a fixed rate move from period to period).
    ``rules`` are ``data.py``'s band width, level and cross-period inflation; ``models``: each period's
    averaged-period values at its samples, by period (:func:`_model`), filled and shared with
    :func:`harmonic_levels` on the same stretch."""
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    colour_band, colour_alpha, cross_period_inflation = rules  # data.py's (no import cycle)
    counts = {j: int(np.count_nonzero(k == j)) for j in kept}
    full = max(counts.values(), default=0)
    kept = [j for j in kept if counts[j] >= full - 1]  # whole periods only (the first may be cut)
    if len(kept) < 4 or not (white_var > 0 and math.isfinite(white_var)):
        return None
    sizes = [counts[j] for j in kept]
    harm = min(MAX_HARMONIC, min(sizes) // 4 - 1)
    if harm < 1:
        return None
    c = np.fft.rfft(ybar) / ybar.size
    c[1:] *= 2.0
    if ybar.size % 2 == 0:
        c[-1] /= 2.0
    coef = np.empty((len(kept), 2 * harm + 1))
    for row, j in enumerate(kept):
        sel = k == j
        ph = th[sel]
        model = _model(models, j, ph, c)
        coef[row] = np.linalg.lstsq(harmonic_basis(ph, harm), y[sel] - model, rcond=None)[0]
    out = _bands(coef, sizes, harm, white_var, white_dof, colour_band, fdtrc)
    top = max(out, key=lambda t: t[0])
    if top[0] <= white_var or min(1.0, len(out) * min(t[3] for t in out)) >= colour_alpha:
        return None
    # A colour must hold over the last half of the periods too: a transient that is still settling when
    # the stretch starts (a decaying DC is no quadratic) raises the first periods' spread only, and taken
    # as the floor it would hide the loop's "not settled" (the review's 10 sd transient, tau 3 periods:
    # floor 1.5-97 times the noise). Stationary coloured noise raises both halves.
    late = len(kept) // 2
    if len(kept) - late < 4:
        return None
    tail = _bands(coef[late:], sizes[late:], harm, white_var, white_dof, colour_band, fdtrc)
    if min(1.0, len(tail) * min(t[3] for t in tail)) >= colour_alpha:
        return None
    v0, d0, _, _ = out[0]
    trend = _trend(coef.shape[0])
    infl = cross_period_inflation(coef[:, 0] - trend @ np.linalg.lstsq(trend, coef[:, 0], rcond=None)[0])
    out[0] = (v0 * infl, max(1.0, d0 / infl), (0, 0), 0.0)
    best = max(out, key=lambda t: t[0])
    return best[0], int(best[1]), best[2]


def harmonic_levels(
    k: NDArray[np.int64],
    th: NDArray[np.float64],
    y: NDArray[np.float64],
    kept: Sequence[int],
    white_var: float,
    ybar: NDArray[np.float64],
    rules: tuple[int, int, float, Callable[[NDArray[np.float64]], float]],
    models: Optional[dict[int, NDArray[np.float64]]] = None,
) -> NDArray[np.float64]:
    """Each harmonic 0..K's noise level on a lab stretch (per-sample units, as ``white_var``), for the drift
    test's block weights (``DiagExperiment.harmonic_var``); empty with fewer than 4 whole periods.

    :func:`levels` gives one number, the largest band's, which became the noise floor of every harmonic:
    under AR(1) noise the blocks' harmonics 2..15 were weighed by the fundamental's (or the DC's) level, 2-40
    times their own, and the block chi-square of a degrading record sat below its dof (blind
    ``degradation:10:0``: 982 on 1302). As :func:`data.harmonic_levels` on recordings: each whole period's
    harmonics 0..K by least squares on the input's phase (the averaged period taken out), their spread about
    a quadratic trend (a drift does not count) pooled over the ``COLOUR_BAND`` harmonics around each, the
    DC alone and inflated for the period DCs' correlation, never below ``floor`` times ``white_var``.
    Harmonics above those a period's samples resolve get the highest one's level. ``rules`` is
    ``(K, COLOUR_BAND, HARMONIC_FLOOR, cross_period_inflation)``.
    """
    kmax, colour_band, floor, cross_period_inflation = rules
    counts = {j: int(np.count_nonzero(k == j)) for j in kept}
    full = max(counts.values(), default=0)
    kept = [j for j in kept if counts[j] >= full - 1]
    harm = min(kmax, min((counts[j] for j in kept), default=0) // 4 - 1)
    if len(kept) < 4 or harm < 1 or not (white_var > 0 and math.isfinite(white_var)):
        return np.zeros(0)
    c = np.fft.rfft(ybar) / ybar.size
    c[1:] *= 2.0
    if ybar.size % 2 == 0:
        c[-1] /= 2.0
    coef = np.empty((len(kept), 2 * harm + 1))
    sizes = np.empty(len(kept))
    for row, j in enumerate(kept):
        sel = k == j
        ph = th[sel]
        model = _model(models, j, ph, c)
        coef[row] = np.linalg.lstsq(harmonic_basis(ph, harm), y[sel] - model, rcond=None)[0]
        sizes[row] = ph.size
    n = len(kept)
    trend = _trend(n)
    res = (coef - trend @ np.linalg.lstsq(trend, coef, rcond=None)[0]) * np.sqrt(sizes)[:, None]
    ss = 0.5 * (res[:, 1::2] ** 2 + res[:, 2::2] ** 2).sum(axis=0)  # each part: variance 2 s2 (scaled)
    out = np.empty(kmax + 1)
    out[0] = float(np.sum(res[:, 0] ** 2)) / (n - 3) * cross_period_inflation(res[:, 0] / np.sqrt(sizes))
    half = colour_band // 2
    for j in range(1, harm + 1):
        a, b = max(1, j - half), min(harm, j + half)
        out[j] = float(np.sum(ss[a - 1 : b])) / (2.0 * (n - 3) * (b - a + 1))
    out[harm + 1 :] = out[harm]
    lev: NDArray[np.float64] = np.maximum(out, floor * white_var)
    return lev


def _trend(n: int) -> NDArray[np.float64]:
    idx = np.arange(n, dtype=np.float64)
    return np.vander(idx - idx.mean(), 3)


def _bands(
    coef: NDArray[np.float64],
    sizes: Sequence[int],
    harm: int,
    white_var: float,
    white_dof: int,
    colour_band: int,
    fdtrc: Callable[..., float],
) -> list[tuple[float, float, tuple[int, int], float]]:
    """Each band's level, dof and F-test p against ``white_var``: the periods' harmonics about a quadratic
    trend in the period index, scaled by the square root of each period's samples."""
    n = coef.shape[0]
    trend = _trend(n)
    res = (coef - trend @ np.linalg.lstsq(trend, coef, rcond=None)[0]) * np.sqrt(np.asarray(sizes))[:, None]
    ss = np.empty(harm + 1)
    ss[0] = float(np.sum(res[:, 0] ** 2))
    ss[1:] = 0.5 * np.sum(res[:, 1::2] ** 2 + res[:, 2::2] ** 2, axis=0)  # each part: variance 2 s2
    dof = np.full(harm + 1, 2.0 * (n - 3))
    dof[0] = n - 3
    half = colour_band // 2
    bands = [(0, 0)] + [(max(0, lo - half), min(harm, lo + half)) for lo in range(0, harm + 1)]
    out = []
    for a, b in bands:
        d = float(np.sum(dof[a : b + 1]))
        v = float(np.sum(ss[a : b + 1])) / d
        out.append((v, d, (a, b), float(fdtrc(d, max(white_dof, 1), v / white_var))))
    return out


__all__ = ["levels", "harmonic_levels", "MAX_HARMONIC"]

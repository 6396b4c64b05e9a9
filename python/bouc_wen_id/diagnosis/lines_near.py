"""A line nearly locked to the input: a steady sinusoid within :data:`~.lines.GUARD_BINS` record bins of a
harmonic of the input, which the search of :mod:`.lines` skips.

Review 46: 50 Hz mains hum on a 2 rad/s drive is 157.08 cycles a period; over 6 steady periods it sits 0.48
record bins from the 157th harmonic, inside the guard that keeps a drifting loop's sidebands out of the
search, and the search's quadratic drift in the period index takes most of it too. The period average keeps
0.67 of it (a coherent wave in the averaged period) while the neighbouring-period differences see a quarter
of its power: every such null read "unexplained structure remains spread over the cycle" (p ~ 1e-190).

Here the residual about the periodic mean alone (no drift) is searched in the guarded bins. A line is kept
when its least-squares fit (jointly with the periodic mean, frequency refined) stands out of the noise's
level beyond chance (Bonferroni over the guarded bins and the far ones) and when the loop's own harmonic
next to it (the periodic mean after the line is taken out) is smaller than the line: a drifting or
settling loop makes sidebands only at harmonics it has, and at most as large as them.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .lines import (
    MAX_COHERENCE,
    MIN_HARMONIC,
    PAD,
    FloatArray,
    _fit,
    _level,
    _orth,
    _spectrum,
    limit,
)

#: Least distance of a searched near-harmonic line from its harmonic, in record bins (closer, its fit and
#: the periodic mean cannot be told apart: :data:`~.lines.MAX_COHERENCE`).
NEAR_LEAST_BINS = 0.2


def _loop_harmonic(y: FloatArray, f: float, amp: complex, n: int, p: int) -> float:
    """Amplitude of the periodic mean's harmonic nearest ``f`` once the line ``amp`` at ``f`` is taken out."""
    j = np.arange(y.size, dtype=np.float64)
    ybar = (y - (amp * np.exp(2j * math.pi * f * j)).real).reshape(n, p).mean(axis=0)
    k = int(round(f * p))
    return float(2.0 * abs(np.sum(ybar * np.exp(-2j * math.pi * k * np.arange(p) / p))) / p)


def without(y: FloatArray, f: float, n: int, p: int) -> FloatArray:
    """The steady record ``y`` less its line at ``f`` (fitted jointly with the periodic mean)."""
    amp = _fit(_orth(y, n, p, drift=False), f, n, p, drift=False)[0]
    j = np.arange(y.size, dtype=np.float64)
    out: FloatArray = y - (amp * np.exp(2j * math.pi * f * j)).real
    return out


def near_candidate(y: FloatArray, n: int, p: int, alpha: float) -> Optional[float]:
    """The strongest line of the steady record ``y`` (``n`` periods of ``p`` samples) in the bins the far
    search skips near the input's harmonics, in cycles per sample, or None (see the module docstring)."""
    from scipy.optimize import minimize_scalar

    m = y.size
    r = _orth(y, n, p, drift=False)
    per, freq, harm, far = _spectrum(r, n, p)
    off = np.abs(freq - harm) * m
    near = ~far & (freq * p >= MIN_HARMONIC) & (off >= NEAR_LEAST_BINS)
    if not near.any() or not far.any():
        return None
    k = int(np.argmax(np.where(near, per, 0.0)))
    level, worth = _level(per, far, k, n)
    if not level > 0:
        return None
    step = 1.0 / (PAD * m)
    best = minimize_scalar(
        lambda f: -_fit(r, f, n, p, drift=False)[1], bounds=(freq[k] - step, freq[k] + step), method="bounded"
    )
    f0 = float(best.x)
    amp, power, coh = _fit(r, f0, n, p, drift=False)
    if coh > MAX_COHERENCE or abs(f0 - round(f0 * p) / p) * m < NEAR_LEAST_BINS:
        return None
    bins = float(np.count_nonzero(near) + np.count_nonzero(far)) / PAD  # independent bins, both searches
    if 0.5 * power / level < limit(alpha / bins, worth):  # the fit's power is twice a periodogram bin's
        return None
    if _loop_harmonic(y, f0, amp, n, p) >= abs(amp):  # a sideband of the loop's own harmonic
        return None
    return f0


__all__ = ["near_candidate", "without", "NEAR_LEAST_BINS"]

"""Whether a line found by :mod:`.lines` keeps its amplitude and phase across the record: a line (mains hum,
a fan) is a constant-amplitude sinusoid, narrow-band noise a band whose phase wanders.

Review 46's H null: AR(2) noise with poles 0.95 e^(+-0.3 i) a sample (a band about 0.05 rad a sample wide:
its phase forgets itself in some 20 samples) was called "a steady sinusoid ... e.g. mains hum at 2.07 Hz"
in 4 of 8 seeds. The search's level is the median periodogram over a band of many record bins, below the
noise's own level at the band's peak; its halves test asks the two halves' amplitudes to agree within half
their size, which two independent draws of the band do often enough among the many bins searched.

Here the record (its steady periods, the periodic mean taken out) is cut into up to :data:`SEGMENTS` runs
of whole periods and the line's complex amplitude is fitted in each (the projection on ``e^(-2 pi i f j)``
at the record's own sample index ``j``, so a steady line has one phase in all). Their scatter about their
weighted mean measures the noise at the line's own frequency, whatever its colour elsewhere; the weighted
mean's power over that scatter is F(2, 2 (K - 1)) distributed under noise alone (K segments): a line stands
out of it, a band's peak does not. :mod:`.lines` asks for the same chance as its search.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

#: Most segments the record is cut into (runs of whole periods): more give the scatter more degrees of
#: freedom (the F tail nearer the exponential's), fewer keep each one several cycles of the band long.
SEGMENTS = 16


def segment_f(r: NDArray[np.float64], f: float, n: int, p: int) -> tuple[float, float]:
    """``(F, dof)``: the line at ``f`` cycles per sample in ``r`` (``n`` periods of ``p`` samples, the
    periodic mean out), its segments' weighted-mean power over their scatter, and half the scatter's degrees
    of freedom (``K - 1``; the tail is ``(1 + F / dof)^-dof``). ``(inf, 0)`` under two segments."""
    k = min(SEGMENTS, n)
    if k < 2:
        return math.inf, 0.0
    rows = r[: n * p].reshape(n, p)
    phase = np.exp(-2j * math.pi * f * np.arange(n * p, dtype=np.float64)).reshape(n, p)
    amps, weights = [], []
    for block in np.array_split(np.arange(n), k):
        seg, ph = rows[block].ravel(), phase[block].ravel()
        amps.append(2.0 * complex(np.sum(seg * ph)) / seg.size)
        weights.append(float(seg.size))
    a, w = np.asarray(amps), np.asarray(weights)
    mean = complex(np.sum(w * a) / np.sum(w))
    scatter = float(np.sum(w * np.abs(a - mean) ** 2)) / (k - 1)
    if not scatter > 0:
        return math.inf, float(k - 1)
    return float(np.sum(w)) * abs(mean) ** 2 / scatter, float(k - 1)

"""The steady stretches of a record that the line search (:mod:`.lines`) reads: whole periods of the input
on a grid of ``p`` samples a period, with where a line found there is taken out of the item's samples.

A Recording has one: its periods after ``settle_periods``. A lab Measurement (what ``bw.load`` returns for
files, the command line's input) has one per steady segment of its signal analysis (its averaging's
segments): the output and input from the segment's first phase zero of the input, linearly interpolated to
the nearest whole number of samples a period (a lab period holds 100.37 samples). Before session 47 only
Recordings were searched: the same samples loaded from files got no line search, and a hum near-locked to
a slow drive (review 46's G null) went into the lab noise floor (the spread about the mean: 1.97e-4 against
the noise's 1e-4) instead of being found and taken out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Stretch:
    """Whole steady periods of one record, as the line search reads them."""

    #: The record's name for reports (a segment's source for a Measurement).
    source: str
    #: Output and input, ``n`` whole periods of ``p`` samples.
    y: FloatArray
    u: FloatArray
    p: int
    n: int
    #: The grid's sample step (units of t) and the time of its sample 0.
    dt: float
    t0: float
    #: The item's samples ``[start, stop)`` a line found here is taken out of.
    span: tuple[int, int]
    #: Whole periods of the record before the stretch (a Recording's settle periods).
    lead: int


def stretches(item: Any) -> list[Stretch]:
    """The steady stretches of a Recording (one) or a Measurement (one per steady segment); none of others."""
    from ..measurement import Measurement
    from ..model import Recording

    if isinstance(item, Recording):
        return [_recording(item)]
    if isinstance(item, Measurement):
        return _segments(item)
    return []


def _recording(rec: Any) -> Stretch:
    p, s = int(rec.samples_per_period), int(rec.settle_periods)
    n = max(int(rec.whole_periods) - s, 0)
    t = np.asarray(rec.t, dtype=np.float64)
    dt = float(t[1] - t[0]) if t.size > 1 else math.nan
    cut = slice(s * p, (s + n) * p)
    y, u = (np.asarray(v, dtype=np.float64)[cut] for v in (rec.y, rec.u))
    t0 = float(t[0]) + s * p * dt if t.size else 0.0
    name = str(rec.metadata.get("name", "")) or "recording"
    return Stretch(name, y, u, p, n, dt, t0, (0, t.size), s)


def _segments(item: Any) -> list[Stretch]:
    from ..signal import average_segments

    t = np.asarray(item.t, dtype=np.float64)
    dt = (float(t[-1]) - float(t[0])) / max(t.size - 1, 1)
    out = []
    for ap in average_segments(item).periods:
        period = 2.0 * math.pi / float(ap.frequency)
        p = int(round(period / dt))
        m = int((float(t[ap.stop - 1]) - float(ap.time_origin)) // period)
        if p < 8 or m < 1:
            continue
        grid = float(ap.time_origin) + np.arange(m * p) * (period / p)
        y, u = (np.interp(grid, t, np.asarray(v, dtype=np.float64)) for v in (item.y, item.u))
        lead = int((float(ap.time_origin) - float(t[0])) // period)
        span = (int(ap.start), int(ap.stop))
        out.append(Stretch(str(ap.source), y, u, p, m, period / p, float(ap.time_origin), span, lead))
    return out


__all__ = ["Stretch", "stretches"]


#: Harmonics of the input on each side of a line's nearest one fitted with it on the raw samples (with the
#: DC and the first three): a line over whole periods is nearly orthogonal to the harmonics farther away.
NEAR_HARMONICS = 3


def raw_amplitude(item: Any, st: Stretch, hz: float) -> complex:
    """The complex amplitude (at ``st.t0``) of a line at ``hz`` cycles per unit of t, fitted on the item's
    own samples in the stretch's whole periods jointly with the input's nearby harmonics. A Measurement's
    stretch is interpolated: linear interpolation at a fractional sample shifts and shrinks a line (by up to
    ``cos(pi f)``, 0.88 for review 46's hum at 0.157 cycles a sample), and its remainder was left in."""
    t = np.asarray(item.t, dtype=np.float64)[st.span[0] : st.span[1]]
    y = np.asarray(item.y, dtype=np.float64)[st.span[0] : st.span[1]]
    period = st.p * st.dt
    keep = (t >= st.t0) & (t < st.t0 + st.n * period)
    tau, y = t[keep] - st.t0, y[keep]
    k0 = int(round(hz * period))
    ks = sorted({1, 2, 3} | set(range(max(1, k0 - NEAR_HARMONICS), k0 + NEAR_HARMONICS + 1)))
    waves = [2.0 * math.pi * k / period * tau for k in ks] + [2.0 * math.pi * hz * tau]
    x = np.column_stack([np.ones_like(tau)] + [g(a) for a in waves for g in (np.cos, np.sin)])
    beta = np.linalg.lstsq(x, y, rcond=None)[0]
    return complex(beta[-2], -beta[-1])

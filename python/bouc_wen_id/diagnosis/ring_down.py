"""A free ring-down of G still in the averaged periods (review 44, failure 1): no physics is named from it.

A lightly damped G (zeta 0.05 at 6 rad/s) started from rest rings at its own damped frequency, not the
drive's, and that free oscillation falls geometrically from period to period. With 10 settle periods and 4
averaged ones (review 44's design D) it was still there: the transient test (``outliers.transient_periods``)
may not trim 2 of 4 periods (``n - extra >= 4`` in ``settling._settled``) and, its reference being the last
half of the same ringing periods, often did not see it at all; the drift it left was fitted as stiffness
degradation, "explained" on null plants.

What tells the two apart is how the loop changes from period to period over the whole record (settle
periods included): a degradation moves it by about the same amount each period (it grows with the energy
dissipated, which a steady drive dissipates at a steady rate), so the RMS change between consecutive periods
stays level; a ring-down's change falls by a constant factor each period. :func:`ringing` fits the log of
that RMS change over the record's last :data:`WINDOW` changes against the period index and calls it a
ring-down when it falls significantly (one-sided p below :data:`LEVEL`) and by at least :data:`FALL` over the
window: noise about a settled or a degrading loop gives a level line (the log of an RMS over hundreds of
samples scatters by about 0.1, so a fall of 2 over 8 periods is far outside it).

An experiment found ringing is not diagnosed (:func:`.run._with_wander` leaves it out, as a drift no
degradation explains); when most or all ring, the verdict says that the loop has not settled, names
nothing, and says how many more settle periods would let the ring-down die out (:func:`said`). A
ring-down that dies out within the first half of the averaged periods is trimmed as before
(``settling._settled``: the rest is steady); one still falling in the record's last periods is in every
averaged period, and no trim helps.

A lab :class:`~bouc_wen_id.measurement.Measurement` carries its samples, not whole periods: each steady
segment its averaging finds is read from its first phase zero, interpolated to a whole number of samples a
period (:func:`lab_records`), over its first :data:`LEAST_PERIODS` periods (all of them averaged: a ring-down
is largest there). A segment shorter than that is not checked (:func:`checked` lists it; ring_unchecked.py
says where that matters: not on every lab record of 1-7 periods, session 46) (the steady-segment
test of the signal analysis refuses a stretch still ringing strongly: review 44's design D as measurements,
14 periods, had none steady). diagnose_across runs the same check per condition (across_ring.py).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..errors import TransientWarning

#: How many of the last period-to-period changes are read.
WINDOW = 8

#: One-sided level of the test that the change falls. The fall (:data:`FALL`) is the main guard: on review
#: 44's settled records (its designs A, B, E and D with 60 settle periods, nulls and degradation) the fitted
#: ratio over the window was 0.83-1.51; its ring-downs gave 0.10-0.33, those beating with the drive (G's
#: 6 rad/s against a 7 rad/s drive) scattered about their fall (0.17-0.22 at p 3e-3 to 1e-2).
LEVEL = 0.02

#: Least fall of the fitted change over the window for a ring-down (a level line's scatter gives ~0.9).
FALL = 0.5

#: Share of each period's largest changes left out of its RMS change (spikes, outliers: a few samples).
SPIKE_SHARE = 0.05

#: The ring-down's size, relative to its size in the first averaged period, that enough settling reaches.
TARGET = 0.01


@dataclass(frozen=True)
class Ring:
    """A ring-down found in one recording: ``rate`` its fall per period, ``more`` the settle periods more
    that would bring it to :data:`TARGET` of its size in the first averaged period."""

    source: str
    rate: float
    more: int
    #: A lab measurement's steady segment (:func:`lab_records`): its periods are not "settle" and "averaged".
    lab: bool = False

    def note(self, settle: int, averaged: int) -> str:
        if self.lab:
            return (
                f"{self.source}: the loop has not settled: {settle} periods into the record the change "
                f"from one period to the next still falls by a factor {self.rate:.2f} a period through the "
                f"first {averaged} whole periods of the steady segment averaged (a free ring-down of the "
                "dynamics before the hysteresis, not a change of the loop); about "
                f"{self.more} more periods of drive before the segment would bring it to {TARGET:.0%} of "
                "its size; nothing is named from this experiment"
            )
        return (
            f"{self.source}: the loop has not settled: after {settle} settle periods the change from one "
            f"period to the next still falls by a factor {self.rate:.2f} a period through the {averaged} "
            "averaged ones (a free ring-down of the dynamics before the hysteresis, at their own frequency, "
            "not a change of the loop); about "
            f"{self.more} more settle periods would bring it to {TARGET:.0%} of its size; nothing is named "
            "from this experiment"
        )


def ringing(y: Any, p: int, periods: int) -> float:
    """The fall per period of the RMS change between consecutive periods of ``y`` (its first ``periods``
    whole periods of ``p`` samples) when it falls as a ring-down does (see the module's docstring), else 0."""
    from .data import numerical_rtol
    from .locate import _t_sf2, _trend

    rows = np.asarray(y[: periods * p], dtype=np.float64).reshape(periods, p)
    # The RMS change between consecutive periods (the first two: the virgin loading) without the largest
    # SPIKE_SHARE of its samples: a ring moves every sample, a spike or an outlier a few, which the whole RMS
    # read as a loop falling 0.85 a period (tests/test_spikes_said.py: spikes at random positions).
    a = np.sort(np.abs(np.diff(rows, axis=0)), axis=1)[:, : max(1, int(round((1.0 - SPIKE_SHARE) * p)))]
    change = np.sqrt(np.mean(a**2, axis=1))[2:]
    if change.size < WINDOW or not np.all(change > 0.0):
        return 0.0
    if float(np.max(change[-WINDOW:])) < numerical_rtol(p) * float(np.max(np.abs(rows))):
        # Below a simulated loop's numerical accuracy (data.numerical_rtol, the floor noise-free data get):
        # the arithmetic's, not a ring-down that a test could see (a start-up transient of 1e-6 of the peak
        # in noise-free data falls geometrically too; tests/test_diagnosis.py's noise-free plant).
        return 0.0
    slope, t, dof = _trend(np.log(change[-WINDOW:]))
    if not (math.isfinite(t) and slope < 0.0 and 0.5 * _t_sf2(t, dof) < LEVEL):
        return 0.0
    rate = math.exp(slope)
    return rate if rate ** (WINDOW - 1) < FALL else 0.0


def lab_records(item: Any) -> list[tuple[str, Any, int, int, int]]:
    """``(source, y, p, periods, lead)`` of each steady segment of the Measurement ``item`` (its averaging's
    segments, :func:`bouc_wen_id.signal.average_segments`): the output from the segment's first phase zero
    of the input, linearly interpolated to ``p`` samples a period (the nearest whole number to the
    sampling's: a lab period holds 100.37 samples, not a whole number), its ``periods`` whole periods, and
    ``lead`` the whole periods of the record before them. What :func:`ringing` reads of a recording."""
    from .line_stretch import stretches

    return [(st.source, st.y, st.p, st.n, st.lead) for st in stretches(item)]


#: Fewest whole periods :func:`ringing` reads: the two of the virgin loading and :data:`WINDOW` changes.
LEAST_PERIODS = WINDOW + 3


def _records(i: int, item: Any) -> list[tuple[str, Any, int, int, int, bool]]:
    """``(source, y, p, periods, settle, lab)`` of what ``item`` (the i-th) holds period by period: a
    recording's whole record, each steady segment of a measurement (:func:`lab_records`); none of an
    averaged period."""
    from ..measurement import Measurement
    from ..model import Recording

    if isinstance(item, Recording):
        name = item.metadata.get("name", f"recording {i}")
        return [(name, item.y, item.samples_per_period, item.whole_periods, item.settle_periods, False)]
    if isinstance(item, Measurement):
        # A segment's first periods (all averaged): a ring-down in them is largest there, and its last ones
        # may be at the noise long before the segment ends (a recording's window ends in the few averaged).
        return [(src, y, p, min(m, LEAST_PERIODS), lead, True) for src, y, p, m, lead in lab_records(item)]
    return []


def checked(items: Any) -> tuple[list[Ring], list[str], list[str], int]:
    """``(rings, notes, short, n)`` of the recordings and measurement segments in ``items`` whose averaged
    periods still hold a ring-down (:func:`ringing`), a note and a TransientWarning on each; ``short``: the
    measurement segments too short for the test, "name (periods)" (the ring-down not checked there; said
    where it matters by ring_unchecked.py); ``n``: how many records were read (a measurement's segments
    each one, as the diagnosis counts its experiments)."""
    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    found, notes, short, n = [], [], [], 0
    for i, item in enumerate(seq):
        for source, y, p, periods, s, lab in _records(i, item):
            n += 1
            if lab and periods < LEAST_PERIODS:
                short.append(f"{source} ({periods})")
                continue
            rate = ringing(y, p, periods)
            if rate <= 0.0:
                continue
            more = math.ceil(math.log(TARGET) / math.log(rate))
            ring = Ring(source, rate, more, lab)
            msg = ring.note(s, periods if lab else periods - s)
            warnings.warn(msg, TransientWarning, 3)
            found.append(ring)
            notes.append(msg)
    return found, notes, short, n


def rings(items: Any) -> tuple[list[Ring], list[str]]:
    """``(rings, notes)`` of :func:`checked` (the segments too short for the test not said)."""
    found, notes, _, _ = checked(items)
    return found, notes


def left_out(found: list[Ring], sources: list[str]) -> list[int]:
    """Indices of ``sources`` (the experiments' names) that ring (``found``)."""
    names = {r.source for r in found}
    return [i for i, s in enumerate(sources) if s in names]


def not_settled(found: list[Ring], total: int) -> str:
    """The verdict's words when most of the ``total`` experiments still ring (the verdict would rest on a
    minority, or on none): the loop has not settled, in which experiments (``found``), and how many more
    settle periods would help; "" when fewer ring. Shared by :func:`said` and diagnose_across
    (across_ring.py), so that every entry point says the same."""
    from .drift_majority import most

    if not found or not (len(found) == total or most(len(found), total)):
        return ""
    names = ", ".join(r.source for r in found)
    more = max(r.more for r in found)
    return (
        f"not settled: {len(found)} of {total} experiments ({names}) still hold the free ring-down of the "
        "dynamics from the start of the record (a change from period to period that falls geometrically, "
        f"not a change of the loop); nothing is named from a loop that has not settled: about {more} more "
        "settle periods would let it die out"
    )


def said(d: Any, found: list[Ring], total: int) -> Any:
    """``d``, or, when most of the ``total`` experiments still ring (:func:`not_settled`) and ``d`` is not
    "adequate", ``d`` with nothing named: the verdict says that the loop has not settled, in which
    experiments, and how many more settle periods would help (each one's note says more). An adequate ``d``
    stands: it names nothing, and its notes say which experiments ring."""
    verdict = not_settled(found, total)
    if not verdict or d.status == "adequate":
        return d  # an adequate verdict names nothing and claims no physics: the notes say the ring-down
    return replace(d, status="unexplained", verdict=verdict, named=(), partial=(), alternatives=())

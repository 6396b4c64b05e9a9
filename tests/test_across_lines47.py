"""diagnose_across searches each condition for a line not locked to the input (lines.py) with the search's
false-alarm budget shared by its K conditions (session 47, across47; diagnosis/across_checks.py).

Main ran lines.removed at its full LINE_ALPHA at every condition: over K conditions the verdict's chance of a
line made by noise was K times diagnose's. The records here are made apart from every generator: a sine
through a first-order lag written in closed form, white noise from a seed, and at one condition of three a
sine at a frequency no harmonic of the drive, sized by bisection on lines.removed itself (main's own search at
one condition) to just pass the per-condition search: a line that stands out at one set's level but not at
the three conditions' one. Over three conditions it is not taken out; twice its size it is.
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import numpy as np

P, SETTLE, PERIODS, SD = 128, 2, 12, 0.01
#: The drive (rad/s) of each condition's two records.
OMEGAS = (2.0, 5.0)
#: The added line's frequency, in cycles per unit of t (no harmonic of either drive).
HUM_HZ = 3.37


def _records(seed: int, hum: float) -> list[Any]:
    """Two records: u = cos(om t) through 1 / (0.05 s + 1) (its steady response in closed form), white noise
    of ``SD``, a line of amplitude ``hum`` at :data:`HUM_HZ`."""
    rng = np.random.default_rng(seed)
    out = []
    for k, om in enumerate(OMEGAS):
        t = np.arange((SETTLE + PERIODS) * P) * (2 * math.pi / om / P)
        g = 1.0 / complex(1.0, 0.05 * om)
        y = abs(g) * np.cos(om * t + math.atan2(g.imag, g.real)) + rng.normal(0.0, SD, t.size)
        y = y + hum * np.sin(2 * math.pi * HUM_HZ * t + 0.3)
        meta = {"name": f"s{seed}r{k}"}
        out.append(bw.Recording(t, np.cos(om * t), y, 1.0, om, settle_periods=SETTLE, metadata=meta))
    return out


def _threshold(seed: int) -> float:
    """The smallest line (bisection on its amplitude) that one condition's search alone takes out."""
    from bouc_wen_id.diagnosis import lines

    lo, hi = 0.0, 10 * SD
    assert lines.removed(_records(seed, hi))[1], "the strong line must be found"
    for _ in range(30):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if lines.removed(_records(seed, mid))[1] else (mid, hi)
    return hi


def test_a_line_that_passes_one_conditions_search_alone_is_not_taken_out_over_three() -> None:
    from bouc_wen_id.diagnosis import across_checks, lines

    a0 = _threshold(4713)
    weak = [_records(4710, 0.0), _records(4713, 1.02 * a0), _records(4712, 0.0)]
    assert lines.removed(weak[1])[1], "at one condition's level the line stands out (main's search)"
    _, notes = across_checks.lines_removed(weak, ["0", "1", "2"])
    assert notes == [], notes  # main: "1: a steady sinusoid ... taken out" at the per-condition level
    strong = [_records(4710, 0.0), _records(4713, 2.0 * a0), _records(4712, 0.0)]
    kept, notes = across_checks.lines_removed(strong, ["0", "1", "2"])
    assert len(notes) == 1 and notes[0].startswith("1: "), notes
    assert kept[0][0] is strong[0][0] and kept[1][0] is not strong[1][0]  # only where the line is

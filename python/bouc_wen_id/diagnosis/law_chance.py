"""A refused law near the test's level: the term itself, refused by chance, is one of the readings.

The law test's null is "this term is the truth" (:func:`.law.law_test`), so at :data:`.select.LAW_ALPHA`
(1 %) it refuses a true term in 1 % of cases by construction; calibrated on 1798 bench cases, the truth's law
p never fell below 5.9e-4 (docs/diagnosis.md, "Calibration of the law test"), while physics outside the
library fails it far lower (the Iwan rows: 6.8e-22 to 8e-4). When a step names nothing and its best
candidate (the lowest cost among those that passed their F test) was refused with a law p between
:data:`.select.PREFERRED_LAW_FLOOR` and ``LAW_ALPHA``, the verdict's "it stands in for physics outside the
library" is one reading, not a finding: the term itself, refused by chance, is the other. The bench's
sensor lag 10x seed 35004 (law p 0.0076, the lag removing chi2 24.8 in the targeted step) and series
dashpot 10x seed 56015 (0.0024, chi2 28.6) are such cases: the true model's own fit to the noisy data is
adequate (p 0.87, 0.15) and its F test far below the step's level (benches/oracle.py). The verdict now
says so, with the experiment that separates the readings: the same experiments repeated (a new noise
draw) refuse a true term's law again in 1 % of cases, and physics outside the library almost always.
The status is unchanged ("unexplained": nothing is named on a refused law).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..terms import TERMS


def by_chance(steps: Sequence[Any]) -> dict[str, float]:
    """The terms refused by chance as :mod:`this module <.law_chance>` reads it: per step that named
    nothing (no term, no pair), its best passed candidate by cost, when its law failed with a p in
    ``[PREFERRED_LAW_FLOOR, LAW_ALPHA)``; term -> law p, in step order."""
    from .select import LAW_ALPHA, PREFERRED_LAW_FLOOR

    out: dict[str, float] = {}
    for st in steps:
        if getattr(st, "chosen", None) is not None or bool(getattr(st, "pair", None)):
            continue
        passed = [
            t
            for t in st.trials
            if getattr(t, "passed", False) and math.isfinite(getattr(t, "cost", math.nan))
        ]
        if not passed:
            continue
        best = min(passed, key=lambda t: float(t.cost))
        p = float(getattr(best, "law_p_value", math.nan))
        failed = getattr(st, "law_failed", ())
        if best.term in failed and math.isfinite(p) and PREFERRED_LAW_FLOOR <= p < LAW_ALPHA:
            out.setdefault(best.term, p)
    return out


def text(steps: Sequence[Any]) -> str:
    """The verdict's clause for :func:`by_chance` (``""`` when there is none)."""
    from .select import LAW_ALPHA, PREFERRED_LAW_FLOOR

    got = by_chance(steps)
    if not got:
        return ""
    what = ", ".join(f"{TERMS[t].place_label()} (p = {p:.2g})" for t, p in got.items())
    return (
        f"; or the best-fitting of them is the term itself, its law refused by chance: {what} lies between "
        f"{PREFERRED_LAW_FLOOR:g} and {LAW_ALPHA:g}, where the law test refuses a true term in "
        f"{100 * LAW_ALPHA:g} % of cases; to separate them: repeat the same experiments (a new noise "
        f"draw): a true term's law is refused again in only {100 * LAW_ALPHA:g} % of cases"
    )


__all__ = ["by_chance", "text"]

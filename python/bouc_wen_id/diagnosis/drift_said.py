"""How firmly a verdict says that a record drifts: as a fact only at a strong level, else as a possibility
with its p.

The drift tests (the degradation test on period blocks, drift.py; the per-experiment trend test of the
fundamental and the DC, locate.py) name or gate at the diagnosis' alpha (5 %, Bonferroni within their
family). At that level a record that does not drift passes them about once in 20 families: review 43 had
periodic data (a Kelvin element on x, a first-order G with a 3 ms delay, AR(1) and white noise) read "the
period record drifts, and an output gain drifting over each record ... (adjusted p = 0.044)". A p of 0.044
is evidence, not a finding: the clause says "may drift" and gives the p. A drift is said as a fact below
:data:`FIRM`, the level this package already asks before it says a fact of the noise (the colour test,
data.COLOUR_ALPHA, and the zero's wander, baseline.WANDER_ALPHA, both 1e-3).

The per-record trend test that leaves a record out as not settled (settling._unsettled) runs once per
record: its p-values are adjusted over the records by Holm's step-down (:func:`holm`), and the words on a
record left out follow the same standard (:func:`records_drift`): "still drifts" below :data:`FIRM`, else
"may drift" with each record's adjusted p (session 45, honest45: a settled record left out at an adjusted p
of 0.01 was said to "still drift", and its data were dropped without a number).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

#: The adjusted p below which a drift is said as a fact (module docstring).
FIRM = 1e-3


def firm(p_adjusted: float) -> bool:
    """Whether a drift at ``p_adjusted`` (Bonferroni within its family) is said as a fact."""
    return math.isfinite(p_adjusted) and p_adjusted < FIRM


def drifts(subject: str, p_adjusted: float, test: str, how: str = "") -> str:
    """``subject`` + " drifts" + ``how`` below :data:`FIRM`, else " may drift" + ``how`` + " (``test``:
    adjusted p = ...)"."""
    if firm(p_adjusted):
        return f"{subject} drifts{how}"
    return f"{subject} may drift{how} ({test}: adjusted p = {p_adjusted:.2g})"


def holm(p: Sequence[float]) -> list[float]:
    """Holm's step-down adjusted p-values of ``p`` (one test per record), in ``p``'s order: the k-th
    smallest times ``(m - k + 1)``, made non-decreasing, at most 1 (NaN counts as 1)."""
    vals = [v if math.isfinite(v) else 1.0 for v in p]
    m = len(vals)
    out = [1.0] * m
    run = 0.0
    for k, i in enumerate(sorted(range(m), key=vals.__getitem__)):
        run = max(run, min(1.0, (m - k) * vals[i]))
        out[i] = run
    return out


def records_drift(names: Sequence[str], p_adjusted: Sequence[float], test: str = "trend test") -> str:
    """ "the loop still drifts from period to period (``test``, Holm over the records: adjusted p = ...)"
    when every record's adjusted p is below :data:`FIRM`, else "the loop may drift from period to period"
    with the same numbers: each record's p, so a record left out keeps its evidence said."""
    ps = ", ".join(f"{n} {p:.2g}" for n, p in zip(names, p_adjusted))
    verb = "still drifts" if p_adjusted and all(firm(p) for p in p_adjusted) else "may drift"
    return f"the loop {verb} from period to period ({test}, Holm over the records: adjusted p = {ps})"


__all__ = ["FIRM", "drifts", "firm", "holm", "records_drift"]

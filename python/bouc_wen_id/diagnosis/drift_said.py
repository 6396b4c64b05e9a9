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
"""

from __future__ import annotations

import math

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


__all__ = ["FIRM", "drifts", "firm"]

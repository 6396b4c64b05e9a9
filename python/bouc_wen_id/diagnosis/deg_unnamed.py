"""What a left-out note says of degradation when its test fitted the drift but a gate stopped it (levels47).

A record left out as still drifting was said to drift with "no degradation explains it". Under AR(2) noise
(review 46, nu-10-H-1..3) the degradation test fitted a 10x strength degradation at p adj 1e-43 and was
stopped only by its share gate (the block chi-square below its dof: share 0), so that clause was false.
:func:`clause` gives the words that are true: no degradation was tested or its fit was not significant, or
it was significant and which gate stopped it.
"""

from __future__ import annotations

import math
from typing import Any

#: The clause when no degradation test was significant (or none was run).
NONE_EXPLAINS = "no degradation explains it"


def stopped_by(deg: Any) -> str:
    """Which of the test's gates stopped a significant degradation fit ``deg`` (drift.DegradationTest)."""
    from .drift import DRIFT_MATERIAL_SHARE

    if float(deg.share) < DRIFT_MATERIAL_SHARE:
        return (
            f"it explains {max(float(deg.share), 0.0):.0%} of the drift's excess over the noise, "
            f"{DRIFT_MATERIAL_SHARE:.0%} needed"
        )
    if deg.held_out_before and sum(deg.held_out_after) >= sum(deg.held_out_before):
        return "it does not lower the held-out cost"
    return "a check after its test (its held-out or gain-drift check) kept it out"


def clause(deg: Any, alpha: float) -> str:
    """The words for degradation in a left-out note: :data:`NONE_EXPLAINS` unless ``deg`` (the whole set's
    degradation test, or None) fitted the drift below ``alpha`` (adjusted) and was not named."""
    p = float(getattr(deg, "p_adjusted", math.nan)) if deg is not None else math.nan
    if not (math.isfinite(p) and p < alpha):
        return NONE_EXPLAINS
    term = str(deg.term).replace("_", " ")
    return f"{term} fits the drift (p adj {p:.1e}) but was not named ({stopped_by(deg)})"


#: The settings key that keeps :func:`clause`'s words when they are not :data:`NONE_EXPLAINS` (left_out.py).
KEY = "left_out_degradation"


def evidence(words: str) -> dict[str, str]:
    """The settings entry for :func:`clause`'s ``words``: none when no degradation fitted the drift."""
    return {} if words == NONE_EXPLAINS else {KEY: words}


def detail(text: str, settings: Any) -> str:
    """A left-out record's detail ``text`` with :data:`NONE_EXPLAINS` replaced by what the test found."""
    words = str((settings or {}).get(KEY, ""))
    return text.replace(NONE_EXPLAINS, words) if words else text


__all__ = ["KEY", "NONE_EXPLAINS", "clause", "detail", "evidence", "stopped_by"]

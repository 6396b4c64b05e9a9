"""A value outside a term's physical range is "not physical" only when it lies beyond that range by more
than its uncertainty (review 36b's ``placeflat``).

The verdict declines to name a term fitted outside its physical range and says "not physical" with what
such a value would mean (a negative damping: energy supplied). On a nearly flat G a term was fitted at a
slightly negative value, 0.46 se below zero, and the verdict called it "not physical (a negative
damping)": an active element, on a value the data cannot tell from zero. A value within its uncertainty of
the range is no evidence of anything beyond it; such a term is not named either (nothing shows it is
there), and the verdict says it is indistinguishable from its range's end. "Not physical" is kept for a
value beyond the range by more than :func:`margin` standard errors: the one-sided Wald test at the level a
term's own value is tested at (:func:`.select.away_from_null`, ``alpha``; one-sided because the side is
known). Without a finite standard error the old rule stands (any value outside is not physical).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..terms import TERMS, physical_value
from .select import ALPHA


def margin(alpha: float = ALPHA) -> float:
    """Standard errors beyond the range a value must lie to be "not physical": ``z_(1 - alpha)``."""
    from scipy.special import ndtri  # type: ignore[import-untyped]

    return float(-ndtri(alpha))


def clearly_outside(term: str, value: float, se: float, alpha: float = ALPHA) -> bool:
    """Whether ``value`` of ``term`` lies outside its physical range by more than :func:`margin` ``se``
    (module docstring); False inside the range, True outside it when ``se`` is not a positive number."""
    if not math.isfinite(value) or physical_value(term, value):
        return False
    if not (math.isfinite(se) and se > 0):
        return True
    lo, hi = TERMS[term].physical
    beyond = lo - value if value < lo else value - hi
    return beyond > margin(alpha) * se


def within(term: str, value: float, se: float, alpha: float = ALPHA) -> bool:
    """Outside the physical range, but within :func:`margin` ``se`` of it (not named, not "not physical")."""
    return (
        math.isfinite(value)
        and not physical_value(term, value)
        and not clearly_outside(term, value, se, alpha)
    )


def _end(term: str, value: float) -> str:
    lo, hi = TERMS[term].physical
    end = lo if value < lo else hi
    return "zero" if end == 0.0 else f"the end of its physical range ({end:g})"


def text(terms: Sequence[Any]) -> str:
    """The verdict's clause for terms (:class:`.result.NamedTerm`) fitted just outside their range ('' for
    none): not named, the value indistinguishable from the range's end, so no sign of an active element."""
    if not terms:
        return ""
    what = "; ".join(f"{t} (indistinguishable from {_end(t.term, t.value)})" for t in terms)
    return (
        f"; within its uncertainty of its physical range, so not named (no evidence of an element beyond "
        f"it): {what}"
    )


__all__ = ["margin", "clearly_outside", "within", "text"]

"""The "explained" verdict's clause on a loop that drifts from period to period after the final model.

Before, the clause was "the loop drifts from period to period (not modelled)" whenever the after-record's
drift test (:func:`.locate.locate`: a linear trend of each experiment's fundamental amplitude and DC over its
periods) fired, also when degradation was named: that record is the one with the named drift taken out
(:func:`.drift.detrended`), so what it still shows is drift *beyond* the named term, and "not modelled" read
as if the drift itself were (review 32: degradation named at 0.0185 for 0.02, the clause beside it).
With a drift term named, the clause now says what drifts beyond it: which experiments, by how much per
period, against how much the record drifted before the named term was taken out.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from .drift import DRIFT_TERMS
from .drift_said import drifts
from .locate import LEVEL, DriftFinding, Localisation

if TYPE_CHECKING:  # a type only: result imports adequacy, which reads this module's clause
    from .result import NamedTerm


def _fired(drift: Sequence[DriftFinding]) -> list[DriftFinding]:
    """The experiments whose trend test fires at :func:`.locate._drift`'s level (half ``LEVEL``,
    Bonferroni over the experiments)."""
    return [d for d in drift if d.p_value < 0.5 * LEVEL / max(len(drift), 1)]


def _moves(d: DriftFinding, before: dict[str, DriftFinding]) -> str:
    """One experiment's drift left: its fundamental's amplitude (relative) or its DC (output units),
    whichever trend test is the stronger, beside the same trend before the named drift was taken out."""
    b = before.get(d.source)
    if abs(d.h1_t) >= abs(d.dc_t):
        was = f" ({100 * b.h1_slope:+.2g} % before)" if b is not None else ""
        return f"{d.source}'s fundamental by {100 * d.h1_slope:+.2g} % per period{was}, t = {d.h1_t:.1f}"
    was = f" ({b.dc_slope:+.2g} before)" if b is not None else ""
    return f"{d.source}'s DC by {d.dc_slope:+.2g} per period (output units){was}, t = {d.dc_t:.1f}"


#: How the clause on a drift left beyond a named drift term begins.
BEYOND = "; beyond the named"


def beyond(text: str) -> bool:
    """Whether ``text`` (:func:`clause`'s) says a drift is left beyond a named drift term: the named terms
    then do not explain the record, and the verdict is "explained in part" (review 36: "explained by:
    degradation" beside "the loop still drifts ... t = -13.8; not explained by the named terms")."""
    return text.startswith(BEYOND)


def clause(after: Localisation, before: Localisation, named: Sequence[NamedTerm]) -> str:
    """The clause ('' when the after-record does not drift): "not modelled" without a named drift term
    (the loop "may drift", with the trend test's p, short of :data:`.drift_said.FIRM`);
    with one, the drift left beyond it, per experiment whose trend fires (module docstring)."""
    if not after.drift_detected:
        return ""
    drift_named = [t.term for t in named if t.term in DRIFT_TERMS]
    if not drift_named:
        # Said as a fact only at a strong level (drift_said.py): the trend test fires at 2.5 % (Bonferroni).
        p = min(1.0, min(d.p_value for d in after.drift) * len(after.drift)) if after.drift else 0.0
        return f"; {drifts('the loop', p, 'trend test', ' from period to period')} (not modelled)"
    was = {d.source: d for d in before.drift}
    where = "; ".join(_moves(d, was) for d in _fired(after.drift)) or "below each experiment's own test"
    return (
        f"{BEYOND} {' and '.join(drift_named)}, the loop still drifts from period to period once "
        f"its drift is taken out ({where}; not explained by the named terms)"
    )


__all__ = ["BEYOND", "beyond", "clause"]

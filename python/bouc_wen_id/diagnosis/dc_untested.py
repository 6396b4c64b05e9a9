"""An "adequate" headline whose DC was taken out says that an output offset was not tested (review 45).

When the output's zero wanders (``baseline.py``) or drifts in a line (``zero_drift.py``) and no common
centre stands out of the recordings' spread, each period's mean is taken out and the DC is not used: an
output offset is then not tested at all. The verdict said so in a detail only, and its headline read
"adequate: the plain Wiener-Bouc-Wen model fits at the noise floor", which a user reads as "no offset":
review 45's ``offset-10-C-1`` (an output offset of 2.4 noise sd under a drifting zero; the same offset under
white noise, ``offset-10-Cw-1``, is named within 1.2 se). So an "adequate" headline on such a record carries
the caveat itself (:func:`headlined`); a record whose DC was used (no wander, or a common centre kept, where
an offset is still named against the centres' spread) keeps its headline as before.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, TypeVar

from .baseline import Wander
from .verdict_text import after_headline
from .zero_drift import Drift


def why(wander: Any) -> str:
    """What took the DC out, in words, when an output offset could not be tested under ``wander`` (a
    ``baseline.Wander``, a ``zero_drift.Drift``, or another record of the zeros); "" when the DC was used:
    no wander, a common centre kept, or the recordings' own zeros (an offset there was refused for its law,
    record_zeros.py, so it was tested)."""
    if not isinstance(wander, (Wander, Drift)) or wander.kept:
        return ""
    if isinstance(wander, Wander):
        return "the baseline wanders from period to period"
    if wander.too_short or wander.loop_trends:
        return "the period means trend over the record"
    return "the output's zero drifts over the record"


_D = TypeVar("_D", bound=Any)


def headlined(d: _D, wander: Any, where: str = "") -> _D:
    """``d`` (a Diagnosis, or an AcrossDiagnosis with ``where`` the conditions, " at 1 A, 2 A") with the
    caveat in its headline (the verdict's first clause) when it is "adequate" and the DC was taken out
    (:func:`why`); ``d`` unchanged otherwise."""
    cause = why(wander)
    if d.status != "adequate" or not cause:
        return d
    words = f" (an output offset cannot be tested{where}: {cause}, so its DC was taken out)"
    return replace(d, verdict=after_headline(d.verdict, words))


__all__ = ["headlined", "why"]

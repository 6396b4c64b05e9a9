"""A named value near its detection limit is biased away from zero (review 36 problem 6).

A term is named only when its first-step test passes, that is when its estimate clears the threshold that
its 50 % detection limit (:attr:`.limits.DetectionLimit.limit`) marks. With the estimate ``c^ ~ N(c, se^2)``
and the threshold ``L50`` (about 3 se at the usual level), the values named have the mean
``c + se phi(a) / Phi(a)``, ``a = (c - L50) / se``: 0.8 se above the truth at ``c = L50``, 1.3 se at 0.75
``L50``, 0.14 se at 1.5 ``L50`` and nothing at 2 ``L50``. So a value named within :data:`NEAR` times its 50 %
limit may be one whose draw was high; the verdict says so beside it. What it does not cover: a value far
above its limit that is a tail draw of the noise (review 36: cu_mid seed 2, c = 0.001291 +- 0.000128 at a
true 0.0008, 3.6x its 50 % limit; not selection).

The argument needs the limit to be the threshold of the value's own test, a few se (:data:`SPAN_SE`): the
bias is 0.14 se or more only within about 1.5 se of it. Where the limit is many se of the named value it
marks something else: a term the plain model absorbs almost wholly (a parallel stiffness on u behind a
first-order G) is found half the time only at a value far above what its test in the final model resolves
(review 38, d1: k = 0.4806 +- 0.0131, its limit 0.91, 33 se away), and the value is no high draw; nothing
is said there. A value without a finite se keeps the note on the factor alone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .limits import DetectionLimit
from .result import NamedTerm

#: A named value within this factor of its 50 % detection limit carries the note.
NEAR = 2.0
#: The note needs the value within this many of its se of the limit (module docstring).
SPAN_SE = 3.0
#: The words of the note (after the term and its value).
MARK = "near its detection limit"


def text(named: Sequence[NamedTerm], lims: Sequence[DetectionLimit]) -> str:
    """The clauses (each opening with "; ") on the ``named`` terms whose value lies within :data:`NEAR` times
    their finite 50 % detection limit in ``lims`` and within :data:`SPAN_SE` of its se of it; ``""`` when
    none."""
    by = {lim.term: lim for lim in lims}
    out = []
    for t in named:
        lim = by.get(t.term)
        if lim is None or not (math.isfinite(lim.limit) and lim.limit != 0.0 and math.isfinite(t.value)):
            continue
        se = t.standard_error
        far = math.isfinite(se) and se > 0.0 and abs(abs(t.value) - abs(lim.limit)) > SPAN_SE * se
        if abs(t.value) <= NEAR * abs(lim.limit) and not far:
            out.append(
                f"; {t.label} {t.symbol} = {t.value:.4g} is {MARK} (50 % power at {abs(lim.limit):.2g}): "
                "values named there are biased away from zero (a term is named when its draw is high)"
            )
    return "".join(out)


__all__ = ["MARK", "NEAR", "SPAN_SE", "text"]

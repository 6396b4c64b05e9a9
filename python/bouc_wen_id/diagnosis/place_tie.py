"""Which place goes first when candidates at two places tie: the place the named terms already act at.

A mechanical term can act on the measured input u or across the hysteretic element on x (issue 18 item 1).
Through a first-order G, ``u = (1 + s / w_c) e^{s tau} x``, so a spring on u is a spring on x plus a dashpot
on x of ``k / w_c`` (the delay alone tells them apart): once a spring on x is named, a spring on u and a
dashpot on x remove the same misfit to within the noise. The selection took the lower cost, a coin toss
between readings of equal evidence, and named a spring at two places (review 43's d2f, a Kelvin element on x
through a first-order G with a 3 ms delay under AR(1) noise: stiffness on x with stiffness on u; measured
here, corner 3 Hz, the step's improvements 59.14 (stiffness on u) and 58.89 (viscous damping on x), two
candidates tied within their uncertainty).

Where the best candidate acts at a place no named mechanical term acts at, and a candidate that ties with it
(:func:`.select._tied`, the rule that makes a rival an alternative) acts at the one place the named ones
share, that candidate goes first: one element at one place is the simpler reading of data that cannot tell
them apart. The best candidate stays, as the alternative the step reports (a tied rival), with the
experiment that separates them; it is still chosen where the moved candidate fails its law or the held-out
test. Untied, the cost decides as before.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Optional, Protocol, TypeVar

from ..terms import TERMS


class _Candidate(Protocol):
    @property
    def term(self) -> str: ...


T = TypeVar("T", bound=_Candidate)


def _place(term: str) -> Optional[str]:
    """Where ``term`` acts, when it may act at more than one place (a mechanical term); else None."""
    cls = TERMS.get(term)
    return cls.acts_on.value if cls is not None and len(cls.places) > 1 else None


def named_place_first(order: list[T], named: Sequence[str], tied: Callable[[T, T], bool]) -> list[T]:
    """``order`` (the step's candidates that passed, best first) with the first candidate tied with the best
    (``tied(best, other)``) moved first where it acts at the one place the ``named`` mechanical terms share
    and the best acts elsewhere (module docstring); ``order`` unchanged otherwise."""
    places = {p for p in map(_place, named) if p is not None}
    if len(order) < 2 or len(places) != 1:
        return order
    best = _place(order[0].term)
    if best is None or best in places:
        return order
    here = next((tr for tr in order[1:] if _place(tr.term) in places and tied(order[0], tr)), None)
    if here is None:
        return order
    return [here, *(tr for tr in order if tr is not here)]

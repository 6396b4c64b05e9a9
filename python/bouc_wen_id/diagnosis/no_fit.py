"""Why a candidate has no fit (a ``nan`` row of the step table; review 31a item 10).

``fitting.fit_with`` gives None in two cases: no start reached a valid model (every fit of the core failed:
the state left its range, the iteration diverged), or, for a two-term element (Dahl friction), the best fit
sat at a limit of its shape, where the element is the simpler term it tends to (its spring or its dry
friction, tried on their own). The row says which of these can apply to the term.
"""

from __future__ import annotations

from ..terms import TERMS
from .fitting import LIMIT_SHAPES


def no_fit_reason(term: str) -> str:
    """The reason a trial of ``term`` has no fit, as the step table and the JSON record say it."""
    cls = TERMS.get(term)
    if cls is not None and cls.companion:
        lo, hi = LIMIT_SHAPES
        return (
            f"no fit: the element's shape sigma A / Fc ran outside [{lo:g}, {hi:g}] at every experiment (its "
            "spring or dry-friction limit, tried as that term), or no start reached a valid model"
        )
    return "no fit: no start reached a valid model (each fit of the core failed or diverged)"

"""A term at its null value in the final model is not named (review 35's cu_h2fo).

A term is named for what it adds to the model. A later step can pull an earlier one's value to its null
(0, or the lower end of a range confined to ``>= 0``): review 35's cu_h2fo (viscous damping on u, a 2 %
third harmonic, first-order G) had Dahl friction on u named at step 1 beside a parallel stiffness; after the
viscous damping and the drive's term joined, the Dahl element sat at ``fc = 1.5e-21``, ``sigma = 0`` and was
still named ("explained in part by: Dahl friction ... fc = 1.492e-21") beside the right c. The model with
such a term is the model without it: :func:`terms` finds them (with an element's own second parameter),
and the verdict says they are not named (:func:`text`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..augmented import AugFit
from ..terms import TERMS
from .select import at_null

#: A value within this of its null in the fit's scaled units (parameters of order one) is at its null: a
#: bounded search stops a rounding's width from the bound, not on it (cu_h2fo's fc = 1.5e-21).
NULL_SCALED = 1e-12


def _at_null(fit: AugFit, term: str) -> bool:
    if at_null(fit, term):
        return True
    k = fit.params.terms.index(term)
    v = float(fit.params.values[k])
    lo = float(TERMS[term].bounds[0])
    null = lo if lo == 0.0 else 0.0
    return abs(v - null) <= NULL_SCALED


def terms(fit: Any) -> frozenset[str]:
    """The final model's terms at their null value: an element's first parameter at its null takes its
    second with it (a Dahl element with no friction level has no pre-sliding stiffness to name)."""
    params = getattr(fit, "params", None)
    if params is None:
        return frozenset()
    null = {t for t in params.terms if _at_null(fit, t)}
    null |= {t for t in params.terms if TERMS[t].part_of and TERMS[t].part_of in null}
    return frozenset(null)


def text(null: Sequence[Any]) -> str:
    """The verdict's clause for the named terms left out at their null value ('' for none)."""
    if not null:
        return ""
    what = ", ".join(
        f"{TERMS[t.term].label} ({t.symbol} = {t.value:.3g})" for t in null if not TERMS[t.term].part_of
    )
    return f"; at its null value, so not named (the model with it is the model without it): {what}"

"""A term named beside Dahl's element must show an effect of its own (issue 18).

Dahl's element (a two-parameter element, :func:`shape.has_branch`) is named with the caveat that another
Dahl exponent, or a distribution of stops, fits such loops too (``caveats.py``): its branch shape passed
its test (:func:`shape.shape_test`, exponent 1) when it was named, with the rest of the loop's misfit
still in the residual. A term tried at a LATER step can then fill what is left of that branch's misfit:
the bench's Dahl loop of exponent 2 (outside the library) was named Dahl friction and then pinching at 30x
(3 of 20 cases), pinching's band and law holding. Yet on the plain model the same pinching explained
nothing (its share of the misfit 0.000 in all three): it was needed only to bend the element's branch
towards another exponent, an interaction with the element's shape, not a slip of its own.

The rule (:func:`only_beside`): beside a Dahl element, a term is named only if it also had an effect of
its own on the plain model, the first step's partial F test of that term (unadjusted) below ``alpha``. A
real second effect beside Dahl's loop shows there too (its own columns reduce the plain model's misfit,
the other effect's misfit only widening the F test's denominator); a term that fits nothing until the
element is in explains the element's branch, and what it filled is the element's family's, which its
caveat names. The structure stays unexplained rather than named after the wrong physics.

The rule is conservative on purpose: a real second effect whose own trace on the plain model is below
``alpha`` (swamped there by the element's misfit) is refused too. So it is never silent: the step records
the refused term (``Step.beside``, ``JointStep.beside`` across conditions) and the verdict names it with
its plain-model p and why (:func:`text`), for the user to test it on its own (a design where the element's
loop is small, or the term's effect large). Both diagnoses apply it through :func:`only_beside`
(:func:`.select.forward_select`, :func:`.across.diagnose_across`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..augmented import AugFit
from ..terms import TERMS
from .shape import has_branch


def elements_beside(fit: AugFit, term: str) -> list[str]:
    """The two-parameter elements (Dahl friction) in ``fit`` other than ``term`` and its companion."""
    par = fit.params
    own = {term, TERMS[term].companion if term in TERMS else ""}
    present = set(par.terms) - own
    return [t for t in par.terms if t not in own and has_branch(t) and TERMS[t].companion in present]


def only_beside(current: AugFit, term: str, p_alone: float, alpha: float) -> bool:
    """Whether ``term``, tried on ``current`` (which holds a Dahl element), had no effect of its own on the
    plain model: its first-step partial F p-value ``p_alone`` (unadjusted; NaN when that fit failed) not
    below ``alpha`` (module docstring). False where no Dahl element is in ``current``."""
    if not elements_beside(current, term):
        return False
    return not (math.isfinite(p_alone) and p_alone < alpha)


def text(steps: Sequence[Any]) -> str:
    """The verdict's clause for the terms :func:`only_beside` refused (each step's ``beside``; the steps of
    :func:`.select.forward_select` or of the joint selection across conditions): each with its first-step
    p on the plain model and the element it sat beside. Empty when the rule never fired."""
    first = {tr.term: tr.p_value for tr in steps[0].trials} if steps else {}
    elements: list[str] = []
    refused: dict[str, str] = {}
    for st in steps:
        for t in getattr(st, "beside", ()):
            if t not in refused and elements:
                refused[t] = elements[-1]
        if st.chosen is not None and has_branch(st.chosen):
            elements.append(st.chosen)
    if not refused:
        return ""

    def p_text(t: str) -> str:
        p = first.get(t, math.nan)
        return f"p = {p:.2g}" if math.isfinite(p) else "its fit failed"

    what = "; ".join(
        f"{TERMS[t].place_label()} beside {TERMS[e].place_label()} (on the plain model {p_text(t)})"
        for t, e in refused.items()
    )
    return (
        f"; not named: {what}: it passes its F test only with the element in, so it bends the element's "
        "branch (another Dahl exponent or a distribution of stops fits such loops) rather than showing an "
        "effect of its own; to name it, it must show on the plain model (conservative: a real effect "
        "swamped by the element's misfit is refused too)"
    )


__all__ = ["elements_beside", "only_beside", "text"]

"""A plain model that passes its global test, whose only leftover is loop centres of both signs.

Issue 18's blind bench, design ``few_periods`` (4-6 periods per experiment after a 4-period settle, a slow
mode of G still there): on nulls the plain model passed its global test (chi2/dof 0.69, p = 1), the targeted
step then found the experiments' DCs beyond the noise, and the DC's terms (the output offset, the
asymmetry, whose evidence is the loop centre) fitted it only with a value that differs between experiments
(their law failed, p = 0.0027 and 1.9e-8). The verdict was "unexplained structure remains spread over the
cycle" although the only structure was each experiment's own centre, of both signs: a loop still settling
or a zero that changes between experiments, which the verdict's centre clause
(:func:`.fit_notes.centre_clause`) already named. Neither is device physics, and "unexplained" on a plain
model that fits everything but the centres is a false alarm.

:func:`clause` reads that case as the plain model adequate for the device, the centres said: the global
test passed, nothing was named, every candidate whose law failed is a term of the loop centre
(:data:`CENTRE_TERMS`), and the residual DCs differ in sign beyond the noise. Any other law-failed
candidate (a stand-in for physics outside the library at the harmonics) keeps the verdict "unexplained".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..terms import TERMS, Asymmetry, Offset
from .data import DiagExperiment
from .fit_notes import centre_clause

#: The terms whose evidence on a steady loop is the loop centre (the DC of each experiment).
CENTRE_TERMS = frozenset({Offset.kind, Asymmetry.kind})


def clause(
    passes: bool,
    has_terms: bool,
    steps: Sequence[Any],
    exps: Sequence[DiagExperiment],
    outputs: Sequence[Any],
) -> str:
    """The verdict's clause when the plain model's only leftover is loop centres of both signs ("" when not:
    the global test failed, a term was named, no candidate failed its law, one that did is not a centre
    term, or the residual DCs do not differ in sign beyond the noise)."""
    if not passes or has_terms:
        return ""
    failed: dict[str, float] = {}
    for st in steps:
        for tr in st.trials:
            if tr.term in st.law_failed:
                failed.setdefault(tr.term, float(tr.law_p_value))
    if not failed or not set(failed) <= CENTRE_TERMS:
        return ""
    centres = centre_clause(exps, outputs, 1.0)
    if not centres:
        return ""
    what = ", ".join(
        f"{TERMS[t].place_label()}" + (f" (law p = {p:.2g})" if math.isfinite(p) else "")
        for t, p in failed.items()
    )
    return (
        f"{centres}; the DC's terms ({what}) fit it only with a value that differs between experiments, so "
        "the loop centres are not read as device physics"
    )


__all__ = ["CENTRE_TERMS", "clause"]

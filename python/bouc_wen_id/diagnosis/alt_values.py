"""The other named values under each alternative the verdict offers for a named term.

When the experiments cannot tell a named term from a rival (:func:`.caveats.alternatives_text`), the other
named terms' values depend on which of the two is chosen: with a first-order G, ``k u = k x + k tau xdot``,
so a spring on u beside viscous damping on x is the same model as a spring on x beside a larger damper on x
(review 38, d1: c on x = 0.00997 with the spring on u, 0.0196 with it on x; truth 0.02). The verdict gave the
first with its +- (0.00026) and no word that it holds only for that choice.

:func:`said` adds, for each alternative whose rival is a single library term, the final structure refitted
with the rival in the named term's place (the named term dropped, :func:`.restarts.without`, then the rival
fitted in, :func:`.fitting.fit_with`) and the other named terms' values there, and says that each named
value and its +- hold for the model named. At most :data:`MAX_REFITS` refits (about a second each).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Optional

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS
from .caveats import alternatives_text, rivals_of
from .fitting import Scale, fit_from, fit_with, physical
from .restarts import without
from .result import NamedTerm, term_symbol_unit
from .select import Alternative

#: The most alternatives refitted in one diagnosis.
MAX_REFITS = 3


def swapped(
    exps: Sequence[AugExperiment], final: AugFit, term: str, rival: str, substeps: int
) -> Optional[AugFit]:
    """``final``'s structure with ``rival`` in ``term``'s place, refitted; None when a fit fails."""
    reduced = fit_from(exps, without(final.params, term), substeps)
    return None if reduced is None else fit_with(exps, reduced, rival, substeps)


def values_text(
    alternatives: Sequence[Alternative],
    named: Sequence[NamedTerm],
    exps: Sequence[AugExperiment],
    final: AugFit,
    at: tuple[Scale, int, tuple[str, str]],
) -> str:
    """The clause with the other named values under each single-term rival (module docstring); empty when
    only one term is named or no rival refits."""
    s, substeps, units = at
    rivals, _ = rivals_of(alternatives, [t.term for t in named])
    parts: list[str] = []
    pairs = [(t, r) for t, rs in rivals.items() for r in rs if r in TERMS and r not in final.params.terms]
    for term, rival in pairs[:MAX_REFITS] if len(named) > 1 else ():
        if term not in final.params.terms or (fit := swapped(exps, final, term, rival, substeps)) is None:
            continue
        vals = []
        for o in named:
            if o.term != term and o.term in fit.params.terms:
                v, se = physical(fit, s, o.term)
                sym, unit = term_symbol_unit(o.term, *units)
                vals.append(f"{o.label} {sym} = {v:.4g} ± {se:.3g} {unit}".rstrip())
        if vals:
            parts.append(
                f"with {TERMS[rival].place_label()} in place of {TERMS[term].place_label()}: "
                + ", ".join(vals)
            )
    if not parts:
        return ""
    return (
        "; the other named values depend on that choice (each named value and its ± hold for the model "
        "named): " + "; ".join(parts)
    )


def said(
    alternatives: Sequence[Alternative],
    named: Sequence[NamedTerm],
    exps: Sequence[AugExperiment],
    final: AugFit,
    at: tuple[Scale, int, tuple[str, str]],
) -> str:
    """:func:`.caveats.alternatives_text` and, after it, :func:`values_text`."""
    return alternatives_text(alternatives, named) + values_text(alternatives, named, exps, final, at)


__all__ = ["said", "values_text", "swapped", "MAX_REFITS"]

"""What the single diagnosis says of its own honesty, said of the diagnosis across conditions (issue 18,
"nothing false said"): :func:`said` adds to an :class:`.across.AcrossDiagnosis` what :func:`.run.diagnose`
says through :mod:`.bounds_said`, :mod:`.design_twin`, :mod:`.clean_value`, :mod:`.input_note` and
:mod:`.output_clip`, so that the verdict across never says less than its conditions on these points:

- a joint first-step candidate beyond its physical range that removes clearly more than the kept structure
  opens the verdict with its value at each condition (:mod:`.across_bounds`; the kept structure is then
  not named, :func:`.across_verdict.judged`);
- a named term's design twins: a physical one among the alternatives, one outside its range said with its
  value at each condition and what would separate them (:mod:`.across_twin`);
- the values at a condition with inputs that are not sines refitted on its clean experiments, the input
  said, and a clipped output said, per condition (:mod:`.across_clean`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any, TypeVar

from . import across_bounds, across_clean, across_moved, across_place, across_twin
from .across_verdict import UNEXPLAINED, explained_fraction
from .caveats import alternatives_text
from .result import NamedTerm

#: The joint search's clause when it named nothing, dropped when the place-free structure is named.
NOTHING = "; nothing named (no candidate passes all its tests jointly at every condition)"

_A = TypeVar("_A", bound=Any)


def _opened(verdict: str, head: str) -> str:
    """``head`` after the verdict's "across N conditions...: " opening."""
    first, sep, rest = verdict.partition(": ")
    return f"{first}{sep}{head}{rest}" if sep and first.startswith("across ") else head + verdict


def said(
    out: _A,
    groups: Sequence[Any],
    items: Mapping[str, Sequence[Any]],
    y_unit: str,
    u_unit: str,
    units: Mapping[str, str],
) -> _A:
    """``out`` with the clauses above (``groups``: the prepared conditions, their final fits current;
    ``items``: each condition's recordings as given, by its label; the units as
    :func:`.across.diagnose_across` takes and finds them). When no condition was prepared (too few settled),
    ``out`` as it was."""
    if not groups or len(groups) != len(out.conditions):
        return out
    un = (y_unit or units.get("y", ""), u_unit or units.get("u", ""))
    verdict, status = out.verdict, out.status
    held = bool(out.settings.get("held_out_test", True))  # the user's --no-held-out
    if out.status != "adequate":
        b = across_bounds.found(groups, out.steps)
        if across_bounds.demotes(b, bool(groups[0].current.params.terms)):
            kept = [t.label for t in (*out.terms, *out.partial)]
            verdict = _opened(
                verdict, across_bounds.text(b, groups, un, explained_fraction(groups), kept, out.steps, held)
            )
            # named with its place per condition
            sib, pf = across_moved.found(groups, out.steps, b.found[0], held)
            if pf is not None and pf.named:
                status = across_place.status(pf, groups, out.settings["alpha"], sib, b.found[0])
                verdict = verdict.replace(UNEXPLAINED + NOTHING, "").replace(NOTHING, "")
                conds = across_place.conditions(pf, groups, out.conditions, sib, b.found[0])
                out = replace(out, conditions=tuple(conds))
    as_named = [NamedTerm(t.term, t.symbol, math.nan, math.nan, t.unit) for t in out.terms]
    found = across_twin.twins(groups, out.steps, out.named)
    steps, added = across_twin.with_alternatives(out.steps, found)
    if added:  # the alternatives' clause with the physical twins among them
        old = alternatives_text(out.alternatives, as_named)
        new = alternatives_text([a for st in steps for a in st.alternatives], as_named)
        verdict = verdict.replace(old, new, 1) if old and old in verdict else verdict + new
    verdict += across_twin.text(found, un)
    alpha = out.settings["alpha"]
    terms, partial, clean = across_clean.values(out.terms, out.partial, groups, out.status, alpha)
    verdict += clean + across_clean.inputs_text(groups, out.status, out.terms)
    labels = [g.label for g in groups]
    verdict += across_clean.outputs_text(labels, [items.get(str(lab), ()) for lab in labels])
    return replace(out, status=status, verdict=verdict, steps=steps, terms=terms, partial=partial)


__all__ = ["said"]

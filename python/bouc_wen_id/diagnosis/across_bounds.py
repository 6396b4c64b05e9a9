"""A candidate beyond its physical range, across conditions: :mod:`.bounds_said`'s rule on the joint first
step of :func:`.across.diagnose_across` (issue 18, "nothing false said").

A joint first-step candidate that passes every test of the step (its combined F test at the step's level,
a material share of the summed excess, present at some condition, its value away from its null wherever it
is present) but whose value lies outside the term's physical range at a condition where it is present (a
negative stiffness) is refused by the joint selection (:func:`.across._trial`), in silence before this
module: three conditions of a negative stiffness on u were diagnosed one by one as "not explained within
the terms' physical ranges: parallel stiffness on u k = -0.0666 would remove 100 % of the excess" at two of
them, and across as a structure of stand-ins. As :func:`.bounds_said.found`: when the best such candidate
removes most of the summed excess (:data:`.bounds_said.MOST`) and no less than the final joint structure
(within :func:`.bounds_said._tie`'s margin), it is said with its value at each condition; when it removes
clearly more than the structure the selection kept (or that structure is empty), the kept terms stand in
for it and are not named (:func:`demotes`, read by :func:`.across_verdict.judged`). mu held at its
bracket's end is said per condition by :func:`.bounds_said.across_text`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..terms import TERMS
from . import across_moved
from .bounds_said import MOST, _suggests, _tie
from .fitting import physical
from .result import term_symbol_unit
from .select import MATERIAL_SHARE, _admissible, at_null, away_from_null, dof_of


@dataclass(frozen=True)
class BeyondAcross:
    """The joint candidates beyond their range the verdict says (best first) and whether the best removes
    clearly more than the final joint structure."""

    found: tuple[Any, ...] = ()  #: their joint trials (:class:`.across.JointTrial`)
    beats_final: bool = False


def refused_by_bound(groups: Sequence[Any], tr: Any, level: float) -> bool:
    """Whether joint trial ``tr`` passed its step's tests at ``level`` and was refused only because its value
    lies outside the term's physical range at some condition where it is present."""
    if not tr.fits or any(f is None for f in tr.fits) or not any(tr.present):
        return False
    if not (math.isfinite(tr.p_adjusted) and tr.p_adjusted < level and tr.share >= MATERIAL_SHARE):
        return False
    here = [(g, f) for g, f, pr in zip(groups, tr.fits, tr.present) if pr]
    if all(_admissible(f, tr.term) for _, f in here):
        return False
    return all(
        not at_null(f, tr.term) and away_from_null(f, tr.term, level, f.cost / max(dof_of(g.sx, f), 1))
        for g, f in here
    )


def _improvement(tr: Any) -> float:
    return float(sum(tr.improvements))


def found(groups: Sequence[Any], steps: Sequence[Any]) -> BeyondAcross:
    """The first step's candidates refused only by their bound that remove most of the summed excess and no
    less than the final joint structure (each condition's current model) within the tie margin."""
    if not steps or not groups:
        return BeyondAcross()
    st = steps[0]
    level = getattr(st, "level", math.nan)  # a step that records no level refuses nothing here
    level = level if math.isfinite(level) else 0.0
    hits = sorted(
        (tr for tr in st.trials if refused_by_bound(groups, tr, level) and tr.share >= MOST),
        key=lambda tr: -_improvement(tr),
    )
    if not hits:
        return BeyondAcross()
    best = hits[0]
    before = [f.cost + d for f, d in zip(best.fits, best.improvements)]  # the step's base at each condition
    final_cost = sum(g.current.cost for g in groups)
    imp_final = sum(before) - final_cost
    dof = sum(dof_of(g.sx, g.current) for g in groups)
    if _improvement(best) < imp_final and not _tie(imp_final, _improvement(best), final_cost, dof):
        return BeyondAcross()  # the final structure removes clearly more: no reading of it
    terms = bool(groups[0].current.params.terms)
    best_cost = sum(f.cost for f in best.fits)
    clear = not _tie(_improvement(best), imp_final, best_cost, dof)
    beats = terms and clear and _improvement(best) > imp_final
    keep = tuple(tr for tr in hits if _tie(_improvement(best), _improvement(tr), best_cost, dof))
    return BeyondAcross(keep, bool(beats))


def demotes(b: BeyondAcross, has_terms: bool) -> bool:
    """Whether the kept structure is demoted to stand-ins (:func:`.bounds_said.apply`'s rule)."""
    return bool(b.found) and (b.beats_final or not has_terms)


def _outside(groups: Sequence[Any], tr: Any) -> list[int]:
    """The conditions (indices) at which joint trial ``tr``'s value lies outside the term's physical range."""
    return [i for i, f in enumerate(tr.fits[: len(groups)]) if f is not None and not _admissible(f, tr.term)]


def _where(groups: Sequence[Any], tr: Any, values: Sequence[float]) -> str:
    """'' when ``tr``'s value is beyond its range at every condition, else at which conditions only and that
    its value crosses the range's edge (zero when it changes sign) between them (review 35m, F7: k_u =
    -0.045, -0.015, +0.03 was said "beyond its physical range" at all three, +0.0305 being physical)."""
    out = _outside(groups, tr)
    if not out or len(out) == len(groups):
        return ""
    inside = [i for i in range(len(groups)) if i not in out]
    edge = "zero" if min(values) < 0.0 < max(values) else "the range's edge"
    return (
        f" at {', '.join(str(groups[i].label) for i in out)} only (within it at "
        f"{', '.join(str(groups[i].label) for i in inside)}: its value crosses {edge} between the conditions)"
    )


def text(
    b: BeyondAcross,
    groups: Sequence[Any],
    units: tuple[str, str],
    fraction: float,
    kept: Sequence[str],
    steps: Sequence[Any] = (),
    held: bool = True,
) -> str:
    """The verdict's opening on the candidates beyond their range, each with its value at every condition
    (``kept``: the labels of the terms the selection kept, said as stand-ins; ``fraction``: the share of
    the summed excess they remove). When the best one is beyond its range at some conditions only and its
    physics at its other place fits those with a physical value (``steps``: the joint selection's, whose
    first step holds every candidate's trial), that reading opens instead (:mod:`.across_moved`; ``held``: the
    user's ``held_out_test``)."""
    if not b.found:
        return ""
    labels = ", ".join(str(g.label) for g in groups)
    what = []
    for tr in b.found:
        sym, unit = term_symbol_unit(tr.term, *units)
        values = [physical(f, g.scale, tr.term)[0] for g, f in zip(groups, tr.fits)]
        vals = ", ".join(f"{v:.4g}" for v in values)
        what.append(
            f"{TERMS[tr.term].place_label()} {sym} = {vals} {unit} at {labels} would remove "
            f"{100 * tr.share:.0f} % of the summed excess alone (p adj = {tr.p_adjusted:.2g}), beyond its "
            f"physical range{_where(groups, tr, values)}: {_suggests(tr.term)}".replace("  ", " ")
        )
    out = _outside(groups, b.found[0])
    at = f" at {', '.join(str(groups[i].label) for i in out)}" if 0 < len(out) < len(groups) else ""
    instead = (
        f"; the terms the selection kept within the ranges ({', '.join(kept)}) remove {100 * fraction:.0f} % "
        f"of the summed excess and stand in for it{at}, not named"
        if kept
        else ""
    )
    moved = across_moved.text(groups, steps, b.found[0], units, held)
    if moved:
        return f"{moved}{instead}; "
    return f"not explained within the terms' physical ranges: {'; '.join(what)}{instead}; "


__all__ = ["BeyondAcross", "demotes", "found", "refused_by_bound", "text"]

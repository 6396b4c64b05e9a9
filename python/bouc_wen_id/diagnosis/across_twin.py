"""Design twins across conditions: :mod:`.design_twin`'s rule on the joint steps of
:func:`.across.diagnose_across` (issue 18, "nothing false said").

A named term and a rival are twins of the design when, each fitted alone on the same base at every
condition (the joint step's trials), the two fitted models' averaged periods differ by less than noise
makes, summed over the conditions: ``D = sum_k D_k`` (:func:`.design_twin.distance` at each condition)
below :data:`.select.PLACE_CHI2` times the chosen structure's pooled chi2/dof when above 1. At one
frequency inertia is exactly a stiffness of ``-m omega^2``: the single-condition diagnosis says the twin
with its value and the experiment that separates them; across conditions it was not said (the same
conditions, diagnosed one by one, said it at each). What is said here, as :mod:`.design_twin` says it:

- a twin with a physical value at every condition is an alternative of the named term (an
  :class:`.select.Alternative` with the separating experiment at the first condition where the named term
  is present), added to its step's alternatives;
- a twin outside its physical range is said with its value at each condition, why it is not physical and
  what would separate them (:func:`text`);
- a step's "other place, not physical" whose own twin is a physical candidate is no "no alternative"
  (:func:`filtered`, :func:`.design_twin.filtered`'s rule on the summed distance).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

from ..errors import BudgetExceededError
from ..terms import TERMS
from .design_twin import distance, rival_item, unphysical_by_term
from .fitting import physical
from .select import PLACE_CHI2, Alternative, _separating, at_null, dof_of, place_admissible


@dataclass(frozen=True)
class TwinAcross:
    """A rival whose joint fit gives the named term's averaged periods at every condition."""

    term: str
    rival: str
    #: ``D`` summed over the conditions (chi-square units).
    distance: float
    #: Whether the rival's value is physical and not its null at every condition.
    physical: bool
    #: The rival's value at each condition (physical units) and the conditions' labels.
    values: tuple[float, ...]
    labels: tuple[str, ...]
    separating_experiment: str


def _limit(groups: Sequence[Any], fits: Sequence[Any]) -> float:
    """PLACE_CHI2 times the pooled chi2/dof of ``fits`` (one per condition) when above 1."""
    cost = sum(f.cost for f in fits)
    dof = sum(dof_of(g.sx, f) for g, f in zip(groups, fits))
    return PLACE_CHI2 * (max(1.0, cost / dof) if dof > 0 else 1.0)


def _joint_distance(groups: Sequence[Any], a: Sequence[Any], b: Sequence[Any]) -> float:
    return float(sum(distance(g.sx, fa, fb) for g, fa, fb in zip(groups, a, b)))


def _complete(tr: Any) -> bool:
    return bool(tr.fits) and all(f is not None and tr.term in f.params.terms for f in tr.fits)


def _separation(groups: Sequence[Any], chosen: Any, rival: Any) -> str:
    """The separating experiment at the first condition where the chosen term is present."""
    k = next((i for i, p in enumerate(chosen.present) if p), 0)
    g = groups[k]
    try:
        sep = _separating(g.sx, chosen.fits[k], rival.fits[k], g.substeps)
    except BudgetExceededError:
        raise
    except Exception:  # noqa: BLE001 - a design no model reaches separates nothing we can say
        return ""
    return f"at {g.label}: {sep}" if sep else ""


def twins(
    groups: Sequence[Any], steps: Sequence[Any], named: Sequence[str], separate: bool = True
) -> tuple[TwinAcross, ...]:
    """The design twins of every named single term (a joint step's chosen trial, not a pair's); without
    ``separate``, no separating experiment is sought (:func:`filtered` needs none)."""
    out: list[TwinAcross] = []
    labels = tuple(str(g.label) for g in groups)
    for st in steps:
        if st.chosen is None or st.chosen not in named or bool(getattr(st, "pair", ())):
            continue
        chosen = next((t for t in st.trials if t.term == st.chosen and _complete(t)), None)
        if chosen is None:
            continue
        limit = _limit(groups, chosen.fits)
        cost = sum(f.cost for f in chosen.fits)
        for tr in st.trials:
            if tr.term == chosen.term or not _complete(tr):
                continue
            if not abs(sum(f.cost for f in tr.fits) - cost) < limit:
                continue
            dist = _joint_distance(groups, chosen.fits, tr.fits)
            if not dist < limit:
                continue
            values = tuple(physical(f, g.scale, tr.term)[0] for g, f in zip(groups, tr.fits))
            ok = place_admissible(list(tr.fits), tr.term)
            sep = _separation(groups, chosen, tr) if separate else ""
            out.append(TwinAcross(chosen.term, tr.term, dist, ok, values, labels, sep))
    return tuple(out)


def alternatives(found: Sequence[TwinAcross], have: Sequence[Alternative]) -> tuple[Alternative, ...]:
    """The physical twins not already among ``have``, as alternatives."""
    seen = {(a.term, a.rival) for a in have} | {(a.rival, a.term) for a in have}
    return tuple(
        Alternative(t.term, t.rival, math.nan, t.separating_experiment)
        for t in found
        if t.physical and (t.term, t.rival) not in seen
    )


def with_alternatives(steps: Sequence[Any], found: Sequence[TwinAcross]) -> tuple[tuple[Any, ...], list[Any]]:
    """``(steps, added)``: each step whose chosen term has a physical twin, with it among its alternatives."""
    out: list[Any] = []
    added: list[Alternative] = []
    for st in steps:
        mine = [t for t in found if t.term == st.chosen]
        new = alternatives(mine, st.alternatives) if mine else ()
        added += new
        out.append(replace(st, alternatives=(*st.alternatives, *new)) if new else st)
    return tuple(out), added


def _values(t: TwinAcross, unit: str) -> str:
    vals = ", ".join(f"{v:.4g}" for v in t.values)
    return f"{vals} {unit} at {', '.join(t.labels)}".replace("  ", " ")


def text(found: Sequence[TwinAcross], units: tuple[str, str]) -> str:
    """The verdict's word on twins outside their physical range, as :func:`.design_twin.text` says it, with
    the rival's value at each condition (the physical ones are alternatives)."""
    parts = []
    for term, ts in unphysical_by_term(found).items():
        items = [rival_item(t, units, _values) for t in sorted(ts, key=lambda t: t.distance)]
        parts.append(
            f"; in this design {TERMS[term].place_label()} gives the same averaged periods at every "
            f"condition as {' and as '.join(items)}: the data cannot tell the named term from these "
            "readings, though they are not physical"
        )
    return "".join(parts)


def filtered(groups: Sequence[Any], steps: Sequence[Any], found: Sequence[TwinAcross]) -> list[Any]:
    """``steps`` without the "other place, not physical" whose twin in the same step is a physical
    candidate said as an alternative or a twin (:func:`.design_twin.filtered`, the distance summed over the
    conditions)."""
    out = []
    for st in steps:
        places = tuple(getattr(st, "unphysical_places", ()))
        if not places:
            out.append(st)
            continue
        said = {a.rival for a in st.alternatives} | {t.rival for t in found if t.physical}
        by = {t.term: t for t in st.trials if _complete(t)}
        keep = []
        for r in places:
            tr = by.get(r)
            twin = tr is not None and any(
                o.term != r
                and o.term in said
                and place_admissible(list(o.fits), o.term)
                and not any(at_null(f, o.term) for f in o.fits)
                and _joint_distance(groups, tr.fits, o.fits) < _limit(groups, tr.fits)
                for o in by.values()
            )
            if not twin:
                keep.append(r)
        out.append(st if len(keep) == len(places) else replace(st, unphysical_places=tuple(keep)))
    return out


__all__ = ["TwinAcross", "twins", "alternatives", "with_alternatives", "text", "filtered"]

"""Design twins: candidates whose effect on the averaged periods is the same function in this design.

A named term and a rival are *twins* of the design when, each fitted alone on the same base (the step's
trials, every nuisance parameter refitted: G's gain and phase per experiment, the Bouc-Wen shape), the two
fitted models' averaged periods differ by less than noise makes: ``D = sum_i w_i |y_T,i - y_R,i|^2`` (chi-
square units, the fits' weights; each free DC left out) below :data:`.select.PLACE_CHI2` times the chosen
model's chi2/dof when above 1. The data then cannot tell them apart at all, whatever their tests said: at one
frequency inertia is exactly a stiffness of ``-m omega^2`` at the same place (review 34, problem 6: one
frequency, six amplitudes, a spring on x named "inertia on u m = 0.0015 +- 0.0003" with no word of it), and
an inertia on x with a negative mass is a spring on x with a positive stiffness (the verdict called it "not
physical, so no alternative").

What is said (issue 18: "both are reported as alternatives with the experiment that would separate them"):
- a twin with a physical value is an alternative of the named term (:class:`.select.Alternative`, no one
  parameter correlation, the separating design by :func:`.select._separating`: for inertia against
  stiffness, another frequency);
- a twin whose value is outside its physical range is said in the verdict with its value (a negative
  stiffness reads the data as well as the named positive mass; what would separate them), not dropped;
- a step's "other place, not physical" (:func:`.caveats.unphysical_places_text`) whose own twin is a
  physical candidate is not called "no alternative": the physical twin stands for it (:func:`filtered`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..augmented import AugExperiment, AugFit
from ..errors import BudgetExceededError
from ..terms import TERMS
from . import free_dc
from .fitting import Scale, physical
from .result import NamedTerm, term_symbol_unit
from .select import PLACE_CHI2, Alternative, Step, Trial, _separating, at_null, dof_of, place_admissible


def separating_text(
    exps: Sequence[AugExperiment],
    a: AugFit,
    b: AugFit,
    substeps: int,
    separating: Callable[[Sequence[AugExperiment], AugFit, AugFit, int], str] = _separating,
) -> str:
    """The design that separates ``a`` from ``b`` (:func:`.select._separating`, or ``separating`` given by a
    caller that keeps its own patchable name), "" when it cannot be computed; a budget overrun raises."""
    try:
        return separating(exps, a, b, substeps)
    except BudgetExceededError:
        raise
    except Exception:  # noqa: BLE001 - a design no model reaches separates nothing we can say
        return ""


@dataclass(frozen=True)
class Twin:
    """A rival whose fit alone gives the named term's averaged periods (module docstring)."""

    term: str
    rival: str
    #: ``D``, the two fitted models' chi-square distance on the averaged periods.
    distance: float
    #: Whether the rival's value is in its physical range and not its null value.
    physical: bool
    value: float
    standard_error: float
    separating_experiment: str


def _diff(exps: Sequence[AugExperiment], a: AugFit, b: AugFit) -> list[Any]:
    """Per experiment, ``b``'s outputs less ``a``'s, each free DC left out, times sqrt(weight)."""
    out = []
    for e, ya, yb in zip(exps, a.outputs, b.outputs):
        d = free_dc.centred(e, np.asarray(yb, dtype=np.float64) - np.asarray(ya, dtype=np.float64))
        out.append(d * math.sqrt(e.weight))
    return out


def distance(exps: Sequence[AugExperiment], a: AugFit, b: AugFit) -> float:
    """``D``: the chi-square distance between two fitted models' averaged periods."""
    if len(a.outputs) != len(exps) or len(b.outputs) != len(exps):
        return math.inf
    return float(sum(np.sum(d**2) for d in _diff(exps, a, b)))


def _limit(exps: Sequence[AugExperiment], fit: AugFit, cost: float) -> float:
    """The twin threshold: PLACE_CHI2 times the chosen model's chi2/dof when above 1."""
    dof = dof_of(exps, fit)
    return PLACE_CHI2 * (max(1.0, cost / dof) if dof > 0 else 1.0)


def _twins_of(exps: Sequence[AugExperiment], st: Step, chosen: Trial, s: Scale, substeps: int) -> list[Twin]:
    """The twins of one step's chosen trial among the step's other trials."""
    assert chosen.fit is not None
    limit = _limit(exps, chosen.fit, chosen.cost)
    out = []
    for tr in st.trials:
        if tr.term == chosen.term or tr.fit is None or tr.term not in tr.fit.params.terms:
            continue
        if not (math.isfinite(tr.cost) and abs(tr.cost - chosen.cost) < limit):
            continue
        dist = distance(exps, chosen.fit, tr.fit)
        if not dist < limit:
            continue
        sep = separating_text(exps, chosen.fit, tr.fit, substeps)
        v, se = physical(tr.fit, s, tr.term)
        ok = place_admissible([tr.fit], tr.term)
        out.append(Twin(chosen.term, tr.term, dist, ok, v, se, sep))
    return out


def twins(
    exps: Sequence[AugExperiment], steps: Sequence[Step], named: Sequence[NamedTerm], s: Scale, substeps: int
) -> tuple[Twin, ...]:
    """The design twins of every named single term (a step's chosen trial, not a pair's)."""
    kinds = {t.term for t in named}
    out: list[Twin] = []
    for st in steps:
        if st.chosen is None or st.chosen not in kinds or st.pair:
            continue
        chosen = next((t for t in st.trials if t.term == st.chosen and t.fit is not None), None)
        if chosen is None:
            continue
        out += _twins_of(exps, st, chosen, s, substeps)
    return tuple(out)


def alternatives(found: Sequence[Twin], have: Sequence[Alternative]) -> tuple[Alternative, ...]:
    """The physical twins not already among ``have``, as alternatives."""
    seen = {(a.term, a.rival) for a in have}
    return tuple(
        Alternative(t.term, t.rival, math.nan, t.separating_experiment)
        for t in found
        if t.physical and (t.term, t.rival) not in seen
    )


def _sep(t: Any) -> str:
    return f"; to separate them: {t.separating_experiment}" if t.separating_experiment else ""


#: A distance below which the two fits are the same function (numerically), not only within the noise.
EXACT = 1e-6


def unphysical_by_term(found: Sequence[Any]) -> dict[str, list[Any]]:
    """The twins outside their physical range (:class:`Twin` or across_twin's), by the named term."""
    by: dict[str, list[Any]] = {}
    for t in found:
        if not t.physical:
            by.setdefault(t.term, []).append(t)
    return by


def rival_item(t: Any, units: tuple[str, str], values: Callable[[Any, str], str]) -> str:
    """One twin said: its place, ``sym = values(t, unit)``, how close, why not physical, what separates it."""
    sym, unit = term_symbol_unit(t.rival, *units)
    why = (TERMS[t.rival].unphysical or "a value outside its physical range").split(":")[0]
    how = "exactly" if t.distance <= EXACT else "within the noise"
    return f"{TERMS[t.rival].place_label()} with {sym} = {values(t, unit)} ({how}; {why}{_sep(t)})"


def _value(t: Twin, unit: str) -> str:
    return f"{t.value:.4g} {unit}"


def text(found: Sequence[Twin], units: tuple[str, str]) -> str:
    """The verdict's word on twins outside their physical range (the physical ones are alternatives): one
    clause per named term, each twin with its value, why it is not physical and what would separate it."""
    parts = []
    for term, ts in unphysical_by_term(found).items():
        items = [rival_item(t, units, _value) for t in sorted(ts, key=lambda t: t.distance)]
        parts.append(
            f"; in this design {TERMS[term].place_label()} gives the same averaged periods as "
            f"{' and as '.join(items)}: the data cannot tell the named term from these readings, though "
            "they are not physical"
        )
    return "".join(parts)


def filtered(exps: Sequence[AugExperiment], steps: Sequence[Step], found: Sequence[Twin]) -> list[Step]:
    """``steps`` without the "other place, not physical" whose twin in the same step is a physical
    candidate said as the chosen term's alternative or twin (an inertia on x with a negative mass at one
    frequency is a spring on x): that place is no "no alternative", its physical twin stands for it."""
    out = []
    for st in steps:
        said = {a.rival for a in st.alternatives} | {t.rival for t in found if t.physical}
        places = tuple(getattr(st, "unphysical_places", ()))
        if not places:
            out.append(st)
            continue
        by = {t.term: t for t in st.trials if t.fit is not None}
        keep = []
        for r in places:
            tr = by.get(r)
            twin = (
                tr is not None
                and tr.fit is not None
                and any(
                    o.term != r
                    and o.term in said
                    and o.fit is not None
                    and o.term in o.fit.params.terms
                    and place_admissible([o.fit], o.term)
                    and not at_null(o.fit, o.term)
                    and distance(exps, tr.fit, o.fit) < _limit(exps, tr.fit, tr.cost)
                    for o in by.values()
                )
            )
            if not twin:
                keep.append(r)
        out.append(st if len(keep) == len(places) else replace(st, unphysical_places=tuple(keep)))
    return out


@dataclass(frozen=True)
class Said:
    """What the diagnosis says of the design twins: the steps for the "not physical" clause
    (:func:`filtered`), the steps' alternatives with the physical twins added, the verdict's clause."""

    steps: list[Step]
    alternatives: tuple[Alternative, ...]
    text: str
    found: tuple[Twin, ...]

    @staticmethod
    def of(
        exps: Sequence[AugExperiment],
        steps: Sequence[Step],
        named: Sequence[NamedTerm],
        s: Scale,
        substeps: int,
        units: tuple[str, str],
    ) -> Said:
        found = twins(exps, steps, named, s, substeps)
        have = [a for st in steps for a in st.alternatives]
        alts = (*have, *alternatives(found, have))
        return Said(filtered(exps, steps, found), alts, text(found, units), found)


__all__ = ["Said", "Twin", "twins", "alternatives", "text", "filtered", "distance", "EXACT"]

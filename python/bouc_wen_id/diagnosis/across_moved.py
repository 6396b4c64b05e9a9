"""A term whose place differs between conditions (review 36b, problem 1): the reading
:mod:`.across_bounds` gives before "beyond its physical range".

The joint search tries one place per term shared by every condition. Viscous damping on u at one condition
and across the hysteretic element (on x) at the others was fitted as viscous@x everywhere, negative at the
first condition (c = -0.00097, 0.0101, 0.00999), and said as "energy supplied each cycle: an active element
... or a phase error between the recorded channels", though each condition alone named the right term at
the right place. When the same physics at its other place (:func:`.select.siblings`) fits each condition
where the joint candidate is beyond its range with a physical value away from its null, removing no less
there than the joint candidate, the verdict says that the place differs between the conditions, with each
condition's value at its place, and names no active element. The two places are not fitted jointly with
the place free per condition, so the reading is said, not named.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Optional

from ..terms import TERMS
from . import across_place
from .fitting import physical
from .result import term_symbol_unit
from .select import _admissible, at_null, away_from_null, dof_of, siblings


def _fits_there(g: Any, f: Any, term: str, level: float) -> bool:
    return (
        f is not None
        and _admissible(f, term)
        and not at_null(f, term)
        and away_from_null(f, term, level, f.cost / max(dof_of(g.sx, f), 1))
    )


def elsewhere(groups: Sequence[Any], steps: Sequence[Any], tr: Any) -> tuple[str, tuple[int, ...]]:
    """The sibling of joint trial ``tr``'s term (same physics, other place) that fits, at every condition
    where ``tr``'s value is beyond its range, with a physical value and an improvement no smaller than
    ``tr``'s there; and those conditions. ``("", ())`` when there is none (or ``tr`` is beyond its range
    at every condition or none)."""
    if not steps or not groups:
        return "", ()
    out = tuple(
        i for i, f in enumerate(tr.fits[: len(groups)]) if f is not None and not _admissible(f, tr.term)
    )
    if not out or len(out) == len(groups):
        return "", ()
    level = float(getattr(steps[0], "level", 0.0) or 0.0)
    by_term = {t.term: t for t in steps[0].trials}
    for sib in siblings(tr.term):
        s = by_term.get(sib)
        if s is None or len(s.fits) < len(groups) or len(s.improvements) < len(groups):
            continue
        if all(
            _fits_there(groups[i], s.fits[i], sib, level)
            and s.improvements[i] >= max(tr.improvements[i], 0.0)
            for i in out
        ):
            return sib, out
    return "", ()


_MEMO: dict[tuple[int, int, bool], tuple[Any, Any, Optional[across_place.PlaceFree]]] = {}


def found(
    groups: Sequence[Any], steps: Sequence[Any], tr: Any, held: bool = True
) -> tuple[Any, Optional[across_place.PlaceFree]]:
    """``(sibling trial, its place-free structure)`` for the joint trial ``tr`` beyond its range at some
    conditions (:func:`elsewhere`); ``(None, None)`` when there is no such sibling or the
    conditions are not prepared ones (no plain fit). Fitted once per trial pair and ``held`` (the user's
    ``held_out_test``: without it no held-out cost, :func:`.across_place.fit`)."""
    sib_term, out = elsewhere(groups, steps, tr)
    if not sib_term or not all(hasattr(g, "plain") for g in groups):
        return None, None
    sib = next(t for t in steps[0].trials if t.term == sib_term)
    key = (id(tr), id(sib), held)
    hit = _MEMO.get(key)
    if hit is not None and hit[0] is tr and hit[1] is sib:
        return sib, hit[2]
    pf = across_place.fit(groups, tr, sib, out, float(getattr(steps[0], "level", 0.0) or 0.0), held)
    _MEMO.clear()  # one run's pair at a time: no object kept past its run
    _MEMO[key] = (tr, sib, pf)
    return sib, pf


def text(
    groups: Sequence[Any], steps: Sequence[Any], tr: Any, units: tuple[str, str], held: bool = True
) -> str:
    """'' or the reading that ``tr``'s physics sits at its other place at the conditions where ``tr`` is
    beyond its range: "the place of viscous damping differs between the conditions: on the measured input u
    at 0 (c = 0.0099 s), across the hysteretic element (on x) at 0.5, 1 (c = 0.0101, 0.00999 s) ..."."""
    sib, out = elsewhere(groups, steps, tr)
    if not sib:
        return ""
    s = next(t for t in steps[0].trials if t.term == sib)
    sym, unit = term_symbol_unit(tr.term, *units)
    inside = [i for i in range(len(groups)) if i not in out]

    def at(term: str, fits: Sequence[Any], idx: Sequence[int]) -> str:
        labels = ", ".join(str(groups[i].label) for i in idx)
        vals = ", ".join(f"{physical(fits[i], groups[i].scale, term)[0]:.4g}" for i in idx)
        return f"{TERMS[term].acts_on.label} at {labels} ({sym} = {vals} {unit})".replace(" )", ")")

    shared = ", ".join(f"{physical(tr.fits[i], groups[i].scale, tr.term)[0]:.4g}" for i in out)
    at_out = ", ".join(str(groups[i].label) for i in out)
    _, pf = found(groups, steps, tr, held)  # the places fitted jointly, free per condition
    if pf is not None:
        return across_place.text(pf, groups, tr, s, units)
    name = TERMS[TERMS[tr.term].base_kind].label
    return (
        f"the place of {name} differs between the conditions: {at(sib, s.fits, out)}, "
        f"{at(tr.term, tr.fits, inside)} - each condition fits it at its own place with a physical value "
        f"(one place shared by every condition gives {sym} = {shared} at {at_out}, beyond its physical "
        f"range; the places were not fitted jointly with the place free per condition, so not named)"
    )


__all__ = ["elsewhere", "found", "text"]
